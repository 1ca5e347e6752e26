//! The estimator's noise model: what the controller assumes about the tissue, the tracker and
//! the target, from what a lab knows (never from the simulated world's draws).

/// The estimator's noise model: what the controller assumes about tissue and tracker. These are
/// the controller's own constants (from the same literature as the simulator's defaults, see
/// docs/execution.md), never read from the simulated world.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct NoiseModel {
    /// Tracker position noise, per axis (mm).
    pub position_mm: f32,
    /// Tracker orientation noise, per axis (degrees).
    pub orientation_deg: f32,
    /// Prior spread of the entry point, per axis (mm).
    pub entry_position_mm: f32,
    /// Prior spread of the entry direction (degrees).
    pub entry_direction_deg: f32,
    /// Prior spread of the curvature factor (relative).
    pub curvature_spread: f32,
    /// Added spread of the curvature factor at each new arc (relative).
    pub segment_curvature_spread: f32,
    /// Play of the tip's roll behind the base, per mm of depth (degrees per mm).
    pub torsion_lag_deg_per_mm: f32,
    /// Heading random walk while spinning a line (degrees per square-root mm).
    pub line_walk_deg: f32,
    /// Advance error over 100 mm (mm).
    pub insertion_error_mm: f32,
    /// Prior spread of the target, per axis (mm).
    pub target_mm: f32,
    /// Random walk of the target per square-root millimetre of insertion (mm): the tissue
    /// moves as the needle pushes it, so the target estimate never freezes.
    pub target_walk_mm: f32,
    /// Random walk of the target's speed (mm of its motion per mm of insertion) per
    /// square-root millimetre of insertion (0 or more): a needle pushing the tissue moves the
    /// target as it goes in, and the filter follows that speed instead of lagging behind it.
    pub target_speed_walk: f32,
    /// Random walk of the curvature factor per square-root millimetre of insertion (relative;
    /// 0 or more): tissue layers change the curvature within an arc, not only between arcs.
    pub curvature_walk: f32,
    /// The tracker's error against the imaging frame that no fix reveals, per axis (mm; 0 or
    /// more): the registration and the field's distortion. Kept clear of the obstacles on top
    /// of the estimate's own spread; above 0 the offset is also read near the entry and taken
    /// off later fixes (`steer::offset`).
    pub registration_mm: f32,
}

impl NoiseModel {
    /// The defaults: the literature figures docs/execution.md cites for each.
    pub const DEFAULT: NoiseModel = NoiseModel {
        position_mm: 0.5,
        orientation_deg: 0.5,
        entry_position_mm: 0.2,
        entry_direction_deg: 0.5,
        curvature_spread: 0.03,
        segment_curvature_spread: 0.01,
        torsion_lag_deg_per_mm: 0.2,
        line_walk_deg: 0.15,
        insertion_error_mm: 0.3,
        target_mm: 0.5,
        target_walk_mm: 0.01,
        target_speed_walk: 0.0,
        curvature_walk: 0.0,
        registration_mm: 0.0,
    };

    /// Every figure finite and positive.
    pub fn is_valid(&self) -> bool {
        [
            self.position_mm,
            self.orientation_deg,
            self.entry_position_mm,
            self.entry_direction_deg,
            self.curvature_spread,
            self.segment_curvature_spread,
            self.torsion_lag_deg_per_mm,
            self.line_walk_deg,
            self.insertion_error_mm,
            self.target_mm,
            self.target_walk_mm,
        ]
        .iter()
        .all(|v| v.is_finite() && *v > 0.0)
            && [
                self.target_speed_walk,
                self.curvature_walk,
                self.registration_mm,
            ]
            .iter()
            .all(|v| v.is_finite() && *v >= 0.0)
    }
}

impl Default for NoiseModel {
    fn default() -> Self {
        NoiseModel::DEFAULT
    }
}
