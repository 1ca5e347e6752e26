//! What one tracker reading of the simulated world holds (the world makes it in `measure.rs`).

use serde::Serialize;

/// What the tracker reports: the tip and the target as imaging sees them, with noise.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Measurement {
    /// Commanded insertion so far (mm): what the robot knows without the tracker.
    pub depth_mm: f32,
    /// Commanded base rotation so far (degrees, accumulated): the robot's rotation stage.
    pub base_deg: f32,
    /// Measured tip position (mm).
    pub position: [f32; 3],
    /// Measured unit heading.
    pub heading: [f32; 3],
    /// Measured unit bevel direction (arcs curve towards it); reported only when `roll_seen`.
    pub bevel: [f32; 3],
    /// The target as imaging sees it: its displaced position, with the tracker's noise;
    /// reported only when `target_seen`.
    pub target: [f32; 3],
    /// The sensor measures the roll (a 6-DOF coil); a 5-DOF coil does not, and the reading
    /// then carries no bevel.
    pub roll_seen: bool,
    /// A new image of the target arrived for this reading (always, unless imaging runs at its
    /// own rate); without one the reading carries no target.
    pub target_seen: bool,
}
