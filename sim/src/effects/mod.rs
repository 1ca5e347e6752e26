//! The world the controller does not know: effects of real insertions that the planner's own
//! model leaves out (a 5-DOF sensor, a biased tracker and a misregistered image, layered
//! tissue that punctures, a target the needle pushes and imaging that sees it late, a tracker
//! pose that is old when it arrives). Each is a documented key of [`WorldEffects`] with its
//! literature source; each is off by default, and with every one off the world is exactly the
//! [`Perturbation`](crate::Perturbation)'s (bit for bit: no effect draws from the physics or
//! the tracker stream, each has its own).
//!
//! One module per effect: [`bias`] (field distortion and registration), [`layers`] (curvature
//! per layer and punctures), [`push`] (the target pushed by the needle), [`delay`] (the
//! tracker's latency and the target's imaging); [`keys`] parses and checks the keys.

pub mod bias;
pub mod delay;
pub mod depths;
pub mod keys;
pub mod layers;
pub mod push;
mod state;

pub use depths::{LayerDepths, LAYER_DEPTHS_KEY};
pub use keys::{EffectsError, WORLD_KEYS};
pub(crate) use state::Active;
pub use state::EffectsDrawn;

use serde::Serialize;

/// The insertion speed the world assumes when neither the key nor the driver says one
/// (mm/s): the driver's default.
pub const DEFAULT_INSERTION_SPEED_MM_S: f32 = 2.5;

/// The rotation speed the world's clock assumes when the driver says none (deg/s): the
/// driver's default.
pub const DEFAULT_ROTATION_SPEED_DEG_S: f32 = 360.0;

/// Effects of the world beyond the [`Perturbation`](crate::Perturbation), all off by default
/// ([`WorldEffects::default`] is today's world). Spreads are standard deviations.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct WorldEffects {
    /// Degrees of freedom of the tip sensor: 6 (position, heading and roll) or 5 (no roll: the
    /// reading's bevel is `None`).
    ///
    /// Default 6. The electromagnetic coils that fit inside a steerable needle (NDI Aurora
    /// 5-DOF sensors, 0.3–0.5 mm across) measure position and the coil's axis only (NDI Aurora
    /// sensor catalogue; Franz et al. 2014, IEEE TMI 33(8), "Electromagnetic tracking in
    /// medicine: a review"). Clinical: 5.
    pub tracker_dof: u8,
    /// Bias of the tracked position from field distortion, per axis (mm): a smooth error field
    /// drawn per run (a constant offset and three sinusoidal modes of 100–300 mm wavelength, of
    /// this RMS in all), added to every measured tip position. Its gradient also tilts the
    /// measured heading by about a thousandth of a radian per 0.3 mm; that is left out.
    ///
    /// Default 0. Metal near the field generator biases Aurora readings by a millimetre or more,
    /// smoothly across the volume (Hummel et al. 2005, Med Phys 32(7), "Design and application
    /// of an assessment protocol for electromagnetic tracking systems"; Franz et al. 2014).
    /// Clinical: 0.3.
    pub tracker_bias_mm: f32,
    /// Rigid registration error between the tracker's frame and the imaging frame in which the
    /// target and the obstacles are given: a translation N(0, this) per axis and a rotation of
    /// N(0, this / 100 mm) radians about each axis through the workspace centre (the midpoint of
    /// entry and target), drawn per run and applied to every tracker pose.
    ///
    /// Default 0. Point-based registration leaves a target registration error of 0.5–2 mm
    /// (Fitzpatrick & West 2001, IEEE TMI 20(9), "The distribution of target registration error
    /// in rigid-body point-based registration"). That error is a distance (the RMS of the 3-D
    /// displacement), and this key is per axis: clinical 0.29 = 0.5 / √3, a translation of
    /// 0.5 mm RMS (about 0.53 mm at a target 45 mm from the centre, with the rotation).
    pub registration_error_mm: f32,
    /// Tissue boundaries crossed along the insertion (0 to 8), drawn per run uniformly over the
    /// planned insertion's length (or at `layer_depths_mm`). Each starts a layer with its own
    /// curvature factor and is punctured (`puncture_mm`).
    ///
    /// Default 0. Skin, fat, muscle and an organ's capsule (Abolhassani et al. 2007, Med Eng Phys
    /// 29(4), "Needle insertion into soft tissue: a survey"). Clinical: 3.
    pub layers: u8,
    /// The boundaries given instead of drawn (mm along the tip's path, ascending; `None`:
    /// drawn). Giving them sets `layers` to their count; setting `layers` draws them again.
    ///
    /// Default `None`: a scenario that knows its anatomy (skin at 5 mm, a capsule at 60 mm)
    /// says so.
    pub layer_depths_mm: Option<LayerDepths>,
    /// Relative spread of each layer's curvature factor (1 + N(0, this), at least
    /// [`MIN_FACTOR`](crate::MIN_FACTOR)), multiplying the arcs' curvature while the tip is in
    /// the layer (the tissue before the first boundary keeps factor 1).
    ///
    /// Default 0. Majewicz et al. 2012 (IEEE TBME 59(2)) measure radii differing by tens of
    /// percent between tissues. Clinical: 0.2.
    pub layer_curvature_spread: f32,
    /// Mean stall at a boundary (mm): the tip stops at the boundary for an exponential draw of
    /// this mean while the robot keeps inserting (the tissue deforms), then the membrane gives
    /// and the tip catches up at once.
    ///
    /// Default 0. Okamura et al. 2004 (IEEE TBME 51(10)) and DiMaio & Salcudean 2003 (IEEE TRA
    /// 19(5)) show the force rising over millimetres of deformation before a capsule is
    /// punctured, then dropping. Clinical: 1.
    pub puncture_mm: f32,
    /// The most the needle pushes the target (mm): within 10 mm of the target the target moves
    /// ahead of the tip, along the heading and a drawn share (up to 0.3) across it, by this ×
    /// a drawn compliance (uniform in [0.25, 1]) × how far the tip has come into those 10 mm.
    ///
    /// Default 0. Soft tissue ahead of a needle deforms and carries the target millimetres
    /// (DiMaio & Salcudean 2003; Lagerburg et al. 2005, Radiother Oncol 77(3), prostate
    /// displacement during needle insertion). Clinical: 2.
    pub target_push_mm: f32,
    /// Rate at which imaging sees the target (Hz; 0: at every reading, as today). Readings
    /// between two images carry no target.
    ///
    /// Default 0. Ultrasound at 10–30 Hz; CT once per step. Clinical: 20.
    pub target_imaging_hz: f32,
    /// Age of an image when it arrives (ms): it shows the target where it was this long ago.
    ///
    /// Default 0. Ultrasound video through PLUS arrives tens of milliseconds late (Lasso et al.
    /// 2014, IEEE TBME 61(10), "PLUS: open-source toolkit for ultrasound-guided intervention
    /// systems"). Clinical: 50.
    pub target_imaging_delay_ms: f32,
    /// Age of a tracker pose when it arrives (ms): the pose is the tip as it was this long
    /// ago, during a push latency × insertion speed mm of insertion earlier (and after a
    /// rotation, part of the way through it when the rotation took less than this).
    ///
    /// Default 0. PLUS/OpenIGTLink stream tracker poses tens of milliseconds late (Lasso et al.
    /// 2014; Tokuda et al. 2009, Int J Med Robot 5(4), "OpenIGTLink"). Clinical: 30.
    pub tracker_latency_ms: f32,
    /// Insertion speed of the world's clock, which turns the latencies and imaging's rate into
    /// insertion (mm/s; 0: the scenario's driver's `insert_speed`, 2.5 mm/s by default).
    /// Rotations take their time at the driver's `rotate_speed`.
    pub insertion_speed_mm_s: f32,
}

impl Default for WorldEffects {
    fn default() -> Self {
        WorldEffects {
            tracker_dof: 6,
            tracker_bias_mm: 0.0,
            registration_error_mm: 0.0,
            layers: 0,
            layer_depths_mm: None,
            layer_curvature_spread: 0.0,
            puncture_mm: 0.0,
            target_push_mm: 0.0,
            target_imaging_hz: 0.0,
            target_imaging_delay_ms: 0.0,
            tracker_latency_ms: 0.0,
            insertion_speed_mm_s: 0.0,
        }
    }
}

/// The clinical world's registration error per axis (mm): a target registration error of 0.5 mm
/// (a 3-D RMS distance) spread over three axes, 0.5 / √3 rounded.
pub const CLINICAL_REGISTRATION_PER_AXIS_MM: f32 = 0.29;

/// Twice the clinical world, as `--perturb` keys over `--world clinical`: every spread and
/// effect of the preset doubled (the tracker's bias and noise, the registration, the layers'
/// spread and punctures, the push on the target, the latencies, the needle's own spreads). With
/// [`TWICE_CLINICAL_FAULT_KEYS`] it is the world in which the controller, told only the
/// defaults, must touch no obstacle and end every run it cannot finish in a reported stop
/// (docs/journal/2026-12-05.md, "Twice the world"; scripts/clinical-campaign.py's "clinical x2"
/// row).
pub const TWICE_CLINICAL_KEYS: [&str; 17] = [
    "tracker_bias_mm=0.6",
    "registration_error_mm=0.58",
    "layer_curvature_spread=0.4",
    "puncture_mm=2",
    "target_push_mm=4",
    "tracker_latency_ms=60",
    "target_imaging_delay_ms=100",
    "curvature_spread=0.06",
    "segment_curvature_spread=0.02",
    "torsion_lag_deg_per_mm=0.4",
    "line_drift_mm_per_mm=0.04",
    "insertion_error_mm=0.6",
    "entry_position_mm=0.4",
    "entry_direction_deg=1.0",
    "target_shift_mm=1.0",
    "tracker_position_mm=1.0",
    "tracker_heading_deg=1.0",
];

/// The tracker's faults of twice the clinical world, as `--fault` keys: the preset's dropouts,
/// twice as often and twice as long.
pub const TWICE_CLINICAL_FAULT_KEYS: [&str; 2] = ["dropout_rate=0.02", "dropout_mm=4"];

impl WorldEffects {
    /// The clinical world: a 5-DOF sensor, 0.3 mm of field bias per axis and a 0.5 mm
    /// registration error (RMS distance: 0.29 mm per axis), three punctured layers, a target pushed up to 2 mm and imaged at
    /// 20 Hz 50 ms late, 30 ms of tracker latency (the dropouts are tracker faults:
    /// [`clinical_faults`](WorldEffects::clinical_faults)).
    pub fn clinical() -> Self {
        WorldEffects {
            tracker_dof: 5,
            tracker_bias_mm: 0.3,
            registration_error_mm: CLINICAL_REGISTRATION_PER_AXIS_MM,
            layers: 3,
            layer_depths_mm: None,
            layer_curvature_spread: 0.2,
            puncture_mm: 1.0,
            target_push_mm: 2.0,
            target_imaging_hz: 20.0,
            target_imaging_delay_ms: 50.0,
            tracker_latency_ms: 30.0,
            insertion_speed_mm_s: 0.0,
        }
    }

    /// The clinical world's tracker dropouts: a 2 mm gap starts on 1 % of millimetres (the
    /// line of sight of imaging and the field of a coil near metal are lost now and then).
    pub fn clinical_faults() -> crate::faults::TrackerFaults {
        crate::faults::TrackerFaults {
            dropout_rate: 0.01,
            dropout_mm: 2.0,
            ..crate::faults::TrackerFaults::default()
        }
    }

    /// A named world: `default` (today's) or `clinical`.
    pub fn preset(
        name: &str,
    ) -> Result<(WorldEffects, crate::faults::TrackerFaults), EffectsError> {
        match name.trim() {
            "default" => Ok((
                WorldEffects::default(),
                crate::faults::TrackerFaults::default(),
            )),
            "clinical" => Ok((WorldEffects::clinical(), WorldEffects::clinical_faults())),
            other => Err(EffectsError::UnknownPreset(other.into())),
        }
    }

    /// Every effect off.
    pub fn is_off(&self) -> bool {
        *self == WorldEffects::default()
    }
}
