//! Layer boundaries given rather than drawn (`layer_depths_mm=12,30,55`): at most
//! [`MAX_LAYERS`] depths along the tip's path, ascending, each in [0, 1000] mm.

use serde::{Serialize, Serializer};
use std::fmt;

/// The most tissue boundaries a run may cross.
pub const MAX_LAYERS: u8 = 8;

/// The key of given layer boundaries.
pub const LAYER_DEPTHS_KEY: &str = "layer_depths_mm";

/// Deepest boundary that may be given (mm).
const DEEPEST_MM: f32 = 1000.0;

/// Given layer boundaries (mm along the tip's path, ascending); serialised as a list.
#[derive(Clone, Copy, PartialEq)]
pub struct LayerDepths {
    depths: [f32; MAX_LAYERS as usize],
    count: u8,
}

impl fmt::Debug for LayerDepths {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.as_slice().fmt(f)
    }
}

impl fmt::Display for LayerDepths {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let text: Vec<String> = self.as_slice().iter().map(f32::to_string).collect();
        f.write_str(&text.join(","))
    }
}

impl Serialize for LayerDepths {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.as_slice().serialize(s)
    }
}

impl LayerDepths {
    /// The depths.
    pub fn as_slice(&self) -> &[f32] {
        &self.depths[..usize::from(self.count)]
    }

    /// How many.
    pub fn count(&self) -> u8 {
        self.count
    }

    /// Depths from a list (1 to [`MAX_LAYERS`] of them, ascending, each in [0, 1000] mm); the
    /// error says what is wrong, starting with the key.
    pub fn new(depths: &[f32]) -> Result<LayerDepths, String> {
        if depths.is_empty() || depths.len() > usize::from(MAX_LAYERS) {
            return Err(format!(
                "{LAYER_DEPTHS_KEY}: give 1 to {MAX_LAYERS} depths, not {}",
                depths.len()
            ));
        }
        if let Some(d) = depths
            .iter()
            .find(|d| !(d.is_finite() && (0.0..=DEEPEST_MM).contains(*d)))
        {
            return Err(format!(
                "{LAYER_DEPTHS_KEY}: {d} is outside [0, {DEEPEST_MM}]"
            ));
        }
        if depths.windows(2).any(|w| w[1] < w[0]) {
            return Err(format!("{LAYER_DEPTHS_KEY}: the depths must ascend"));
        }
        let mut out = LayerDepths {
            depths: [0.0; MAX_LAYERS as usize],
            count: depths.len() as u8,
        };
        out.depths[..depths.len()].copy_from_slice(depths);
        Ok(out)
    }

    /// Depths from `12,30,55` (commas or spaces between).
    pub fn parse(text: &str) -> Result<LayerDepths, String> {
        let values: Result<Vec<f32>, String> = text
            .split(|c: char| c == ',' || c.is_whitespace())
            .filter(|p| !p.is_empty())
            .map(|p| {
                p.parse::<f32>()
                    .map_err(|_| format!("{LAYER_DEPTHS_KEY}: `{p}` is not a number"))
            })
            .collect();
        LayerDepths::new(&values?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn depths_parse_and_refuse_what_is_wrong() {
        let d = LayerDepths::parse("12, 30,55").unwrap();
        assert_eq!(d.as_slice(), [12.0, 30.0, 55.0]);
        assert_eq!(d.to_string(), "12,30,55");
        for (bad, says) in [
            ("", "give 1 to 8"),
            ("1,2,3,4,5,6,7,8,9", "give 1 to 8"),
            ("10,5", "ascend"),
            ("-1", "outside"),
            ("NaN", "outside"),
            ("3,x", "`x` is not a number"),
        ] {
            let e = LayerDepths::parse(bad).unwrap_err();
            assert!(
                e.starts_with(LAYER_DEPTHS_KEY) && e.contains(says),
                "{bad}: {e}"
            );
        }
    }
}
