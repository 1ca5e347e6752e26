//! The world effects' keys as `KEY=VALUE` (the flags of `needle simulate`): each key's range,
//! and typed errors that start with the key.

use super::depths::{LayerDepths, LAYER_DEPTHS_KEY, MAX_LAYERS};
use super::WorldEffects;
use std::fmt;

/// A key and the closed range it accepts; `whole` keys take whole numbers only.
struct Spec {
    key: &'static str,
    min: f32,
    max: f32,
    whole: bool,
}

const fn spec(key: &'static str, min: f32, max: f32, whole: bool) -> Spec {
    Spec {
        key,
        min,
        max,
        whole,
    }
}

const SPECS: [Spec; 11] = [
    spec("tracker_dof", 5.0, 6.0, true),
    spec("tracker_bias_mm", 0.0, 50.0, false),
    spec("registration_error_mm", 0.0, 50.0, false),
    spec("layers", 0.0, MAX_LAYERS as f32, true),
    spec("layer_curvature_spread", 0.0, 1.0, false),
    spec("puncture_mm", 0.0, 20.0, false),
    spec("target_push_mm", 0.0, 20.0, false),
    spec("target_imaging_hz", 0.0, 1000.0, false),
    spec("target_imaging_delay_ms", 0.0, 10_000.0, false),
    spec("tracker_latency_ms", 0.0, 10_000.0, false),
    spec("insertion_speed_mm_s", 0.0, 100.0, false),
];

/// The keys of numbers, in the order of the fields and of the JSON (beside them
/// [`LAYER_DEPTHS_KEY`], a list).
pub const WORLD_KEYS: [&str; 11] = [
    "tracker_dof",
    "tracker_bias_mm",
    "registration_error_mm",
    "layers",
    "layer_curvature_spread",
    "puncture_mm",
    "target_push_mm",
    "target_imaging_hz",
    "target_imaging_delay_ms",
    "tracker_latency_ms",
    "insertion_speed_mm_s",
];

/// Why a world effect is refused.
#[derive(Clone, Debug, PartialEq)]
pub enum EffectsError {
    /// Not one of [`WORLD_KEYS`].
    UnknownKey(String),
    /// Not a known world (`default`, `clinical`).
    UnknownPreset(String),
    /// Bad given layer boundaries (the message starts with the key).
    Depths(String),
    /// Given layer boundaries whose count is not `layers`.
    DepthsCount {
        /// `layers`.
        layers: u8,
        /// Boundaries given.
        given: u8,
    },
    /// Not of the form `KEY=VALUE`.
    Syntax(String),
    /// The value is not a number.
    NotANumber {
        /// The key.
        key: &'static str,
        /// What was given.
        value: String,
    },
    /// The value is non-finite, outside the key's range, or not whole for a count.
    OutOfRange {
        /// The key.
        key: &'static str,
        /// What was given.
        value: f32,
        /// Smallest allowed.
        min: f32,
        /// Largest allowed.
        max: f32,
        /// Whole numbers only.
        whole: bool,
    },
}

impl fmt::Display for EffectsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            EffectsError::UnknownKey(k) => write!(
                f,
                "unknown world effect `{k}` (known: {}, {LAYER_DEPTHS_KEY})",
                WORLD_KEYS.join(", ")
            ),
            EffectsError::UnknownPreset(w) => {
                write!(f, "unknown world `{w}` (known: default, clinical)")
            }
            EffectsError::Depths(e) => f.write_str(e),
            EffectsError::DepthsCount { layers, given } => write!(
                f,
                "layers = {layers} but {LAYER_DEPTHS_KEY} gives {given} boundaries"
            ),
            EffectsError::Syntax(s) => write!(f, "`{s}` is not KEY=VALUE"),
            EffectsError::NotANumber { key, value } => {
                write!(f, "{key}: `{value}` is not a number")
            }
            EffectsError::OutOfRange {
                key,
                value,
                min,
                max,
                whole,
            } => {
                let what = if *whole { " (a whole number)" } else { "" };
                write!(f, "{key} = {value} is outside [{min}, {max}]{what}")
            }
        }
    }
}

impl std::error::Error for EffectsError {}

fn index(key: &str) -> Result<usize, EffectsError> {
    SPECS
        .iter()
        .position(|s| s.key == key)
        .ok_or_else(|| EffectsError::UnknownKey(key.into()))
}

fn check(s: &Spec, value: f32) -> Result<(), EffectsError> {
    let whole_ok = !s.whole || value.fract() == 0.0;
    if value.is_finite() && (s.min..=s.max).contains(&value) && whole_ok {
        Ok(())
    } else {
        Err(EffectsError::OutOfRange {
            key: s.key,
            value,
            min: s.min,
            max: s.max,
            whole: s.whole,
        })
    }
}

impl WorldEffects {
    /// Whether `key` is a world effect's key.
    pub fn knows(key: &str) -> bool {
        WORLD_KEYS.contains(&key.trim()) || key.trim() == LAYER_DEPTHS_KEY
    }

    /// Gives the layer boundaries (and so their count).
    pub fn set_depths(&mut self, depths: LayerDepths) {
        self.layers = depths.count();
        self.layer_depths_mm = Some(depths);
    }

    /// The value of `key`.
    pub fn get(&self, key: &str) -> Result<f32, EffectsError> {
        Ok(match index(key)? {
            0 => f32::from(self.tracker_dof),
            1 => self.tracker_bias_mm,
            2 => self.registration_error_mm,
            3 => f32::from(self.layers),
            4 => self.layer_curvature_spread,
            5 => self.puncture_mm,
            6 => self.target_push_mm,
            7 => self.target_imaging_hz,
            8 => self.target_imaging_delay_ms,
            9 => self.tracker_latency_ms,
            _ => self.insertion_speed_mm_s,
        })
    }

    /// Sets `key` to `value`, checked against its range.
    pub fn set(&mut self, key: &str, value: f32) -> Result<(), EffectsError> {
        let i = index(key)?;
        check(&SPECS[i], value)?;
        match i {
            // Whole and within [5, 6] or [0, 8]: the casts are exact.
            0 => self.tracker_dof = value as u8,
            1 => self.tracker_bias_mm = value,
            2 => self.registration_error_mm = value,
            3 => {
                self.layers = value as u8;
                self.layer_depths_mm = None;
            }
            4 => self.layer_curvature_spread = value,
            5 => self.puncture_mm = value,
            6 => self.target_push_mm = value,
            7 => self.target_imaging_hz = value,
            8 => self.target_imaging_delay_ms = value,
            9 => self.tracker_latency_ms = value,
            _ => self.insertion_speed_mm_s = value,
        }
        Ok(())
    }

    /// Applies one `KEY=VALUE`.
    pub fn apply(&mut self, assignment: &str) -> Result<(), EffectsError> {
        let (key, value) = assignment
            .split_once('=')
            .ok_or_else(|| EffectsError::Syntax(assignment.into()))?;
        let (key, value) = (key.trim(), value.trim());
        if key == LAYER_DEPTHS_KEY {
            let depths = LayerDepths::parse(value).map_err(EffectsError::Depths)?;
            self.set_depths(depths);
            return Ok(());
        }
        let i = index(key)?;
        let v: f32 = value.parse().map_err(|_| EffectsError::NotANumber {
            key: SPECS[i].key,
            value: value.into(),
        })?;
        self.set(key, v)
    }

    /// Every value within its range (effects built field by field).
    pub fn validate(&self) -> Result<(), EffectsError> {
        for s in &SPECS {
            check(s, self.get(s.key)?)?;
        }
        if let Some(d) = &self.layer_depths_mm {
            LayerDepths::new(d.as_slice()).map_err(EffectsError::Depths)?;
            if d.count() != self.layers {
                return Err(EffectsError::DepthsCount {
                    layers: self.layers,
                    given: d.count(),
                });
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_specs_and_fields_agree() {
        for (k, s) in WORLD_KEYS.iter().zip(&SPECS) {
            assert_eq!(*k, s.key);
        }
        WorldEffects::default().validate().unwrap();
        WorldEffects::clinical().validate().unwrap();
        assert!(WorldEffects::default().is_off());
        for k in WORLD_KEYS {
            let mut w = WorldEffects::default();
            let v = if k == "tracker_dof" { 5.0 } else { 1.0 };
            w.set(k, v).unwrap();
            assert_eq!(w.get(k).unwrap(), v, "{k}");
            assert!(!w.is_off(), "{k}");
        }
    }

    #[test]
    fn bad_assignments_are_typed_errors_naming_the_key() {
        let mut w = WorldEffects::default();
        assert!(matches!(
            w.apply("latency=3"),
            Err(EffectsError::UnknownKey(_))
        ));
        assert!(matches!(w.apply("layers"), Err(EffectsError::Syntax(_))));
        assert!(matches!(
            w.apply("layers=many"),
            Err(EffectsError::NotANumber { .. })
        ));
        for bad in [
            "tracker_dof=4",
            "tracker_dof=5.5",
            "layers=9",
            "layers=1.5",
            "tracker_bias_mm=-1",
            "tracker_latency_ms=NaN",
            "target_imaging_hz=inf",
        ] {
            let e = w.apply(bad).unwrap_err();
            assert!(matches!(e, EffectsError::OutOfRange { .. }), "{bad}: {e}");
            let key = bad.split('=').next().unwrap();
            assert!(e.to_string().starts_with(key), "{e}");
        }
        assert!(w.is_off(), "a refused value changes nothing");
        w.apply(" layers = 3 ").unwrap();
        assert_eq!(w.layers, 3);
        w.apply("layer_depths_mm=10,20").unwrap();
        assert_eq!(w.layers, 2, "given boundaries set the count");
        w.validate().unwrap();
        w.layers = 4;
        assert!(w
            .validate()
            .unwrap_err()
            .to_string()
            .starts_with("layers = 4"));
        w.apply("layers=1").unwrap();
        assert_eq!(
            w.layer_depths_mm, None,
            "a count draws the boundaries again"
        );
        let e = w.apply("layer_depths_mm=9,1").unwrap_err();
        assert!(e.to_string().starts_with("layer_depths_mm"), "{e}");
        assert!(WorldEffects::preset("lab").is_err());
        assert_eq!(
            WorldEffects::preset("clinical").unwrap().0,
            WorldEffects::clinical()
        );
    }
}
