//! The tracker's faults in a closed-loop run (`needle simulate --fault`), apart from the world's
//! effects: what can go wrong with the readings themselves.

use serde::Serialize;

/// Tracker faults (all off by default): dropouts per millimetre, the others per reading.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct TrackerFaults {
    /// Chance per millimetre of insertion that a dropout starts.
    pub dropout_rate: f32,
    /// Insertion a dropout lasts (mm).
    pub dropout_mm: f32,
    /// Chance that a reading's position is an outlier.
    pub outlier_rate: f32,
    /// How far an outlier is off (mm, in a random direction).
    pub outlier_mm: f32,
    /// Chance that a reading is sent twice (the same sequence number again).
    pub repeat_rate: f32,
    /// Chance that an old reading (an earlier sequence number) arrives after a reading.
    pub stale_rate: f32,
}

impl TrackerFaults {
    /// The keys of `--fault`, in the order of the fields.
    pub const KEYS: [&'static str; 6] = [
        "dropout_rate",
        "dropout_mm",
        "outlier_rate",
        "outlier_mm",
        "repeat_rate",
        "stale_rate",
    ];

    /// Applies one `KEY=VALUE` (rates in [0, 1], lengths in [0, 1000] mm).
    pub fn apply(&mut self, assignment: &str) -> Result<(), String> {
        let (key, value) = assignment
            .split_once('=')
            .ok_or_else(|| format!("`{assignment}` is not KEY=VALUE"))?;
        let (key, value) = (key.trim(), value.trim());
        let v: f32 = value
            .parse()
            .map_err(|_| format!("{key}: `{value}` is not a number"))?;
        let (slot, max) = match key {
            "dropout_rate" => (&mut self.dropout_rate, 1.0),
            "dropout_mm" => (&mut self.dropout_mm, 1000.0),
            "outlier_rate" => (&mut self.outlier_rate, 1.0),
            "outlier_mm" => (&mut self.outlier_mm, 1000.0),
            "repeat_rate" => (&mut self.repeat_rate, 1.0),
            "stale_rate" => (&mut self.stale_rate, 1.0),
            _ => {
                return Err(format!(
                    "unknown fault `{key}` (one of {})",
                    Self::KEYS.join(", ")
                ))
            }
        };
        if !(0.0..=max).contains(&v) {
            return Err(format!("{key} = {v} is out of range (0 to {max})"));
        }
        *slot = v;
        Ok(())
    }
}
