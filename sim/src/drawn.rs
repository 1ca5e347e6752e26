//! What a run drew: the values of the perturbation (per run and per executed step) and of the
//! world's effects, as `--detail` reports them.

use serde::Serialize;

/// What one step drew and did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct StepDraw {
    /// Curvature factor of the segment (arcs; 0 for other steps).
    pub segment_factor: f32,
    /// True advance minus commanded advance (mm).
    pub length_error_mm: f32,
    /// Line drift across the heading, along e1 and e2 (mm per mm; lines only).
    pub drift: [f32; 2],
    /// How far the tip turned (degrees): a rotation's lagged angle, a spin's net turn.
    pub tip_rotation_deg: f32,
}

/// The values drawn for one run.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Drawn {
    /// The run's curvature factor on 1/r.
    pub curvature_factor: f32,
    /// Entry point error (mm).
    pub entry_offset_mm: [f32; 3],
    /// Entry direction error about e1 and e2 (degrees).
    pub entry_tilt_deg: [f32; 2],
    /// Target displacement (mm).
    pub target_shift_mm: [f32; 3],
    /// Per executed step.
    pub steps: Vec<StepDraw>,
    /// What the world's effects drew (absent when every effect is off).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub effects: Option<crate::effects::EffectsDrawn>,
}
