//! The scenario's `[steering]` table: what a lab knows about its tracker and its insertion, told
//! to the closed-loop controller (`SteerConfig`: the estimator's noise model and when to re-plan
//! or stop). Never read from the simulated world: `[execution]` describes the world, this table
//! what the controller assumes of it, and the two may differ, as they do in a lab.

use super::file::ScenarioFile;
use anyhow::{bail, Context, Result};
use planner_core::steer::SteerConfig;
use std::collections::BTreeMap;

/// A key of `[steering]`: its name, where it lives, and whether zero is allowed.
struct Key {
    name: &'static str,
    field: fn(&mut SteerConfig) -> &mut f32,
    zero_allowed: bool,
}

/// Every key, in the order docs/scenario.md lists them.
const KEYS: &[Key] = &[
    Key {
        name: "tracker_position_mm",
        field: |c| &mut c.noise.position_mm,
        zero_allowed: false,
    },
    Key {
        name: "tracker_heading_deg",
        field: |c| &mut c.noise.orientation_deg,
        zero_allowed: false,
    },
    Key {
        name: "target_mm",
        field: |c| &mut c.noise.target_mm,
        zero_allowed: false,
    },
    Key {
        name: "target_walk_mm",
        field: |c| &mut c.noise.target_walk_mm,
        zero_allowed: false,
    },
    Key {
        name: "entry_position_mm",
        field: |c| &mut c.noise.entry_position_mm,
        zero_allowed: false,
    },
    Key {
        name: "entry_direction_deg",
        field: |c| &mut c.noise.entry_direction_deg,
        zero_allowed: false,
    },
    Key {
        name: "curvature_spread",
        field: |c| &mut c.noise.curvature_spread,
        zero_allowed: false,
    },
    Key {
        name: "segment_curvature_spread",
        field: |c| &mut c.noise.segment_curvature_spread,
        zero_allowed: false,
    },
    Key {
        name: "torsion_lag_deg_per_mm",
        field: |c| &mut c.noise.torsion_lag_deg_per_mm,
        zero_allowed: false,
    },
    Key {
        name: "line_walk_deg",
        field: |c| &mut c.noise.line_walk_deg,
        zero_allowed: false,
    },
    Key {
        name: "insertion_error_mm",
        field: |c| &mut c.noise.insertion_error_mm,
        zero_allowed: false,
    },
    Key {
        name: "target_speed_walk",
        field: |c| &mut c.noise.target_speed_walk,
        zero_allowed: true,
    },
    Key {
        name: "curvature_walk",
        field: |c| &mut c.noise.curvature_walk,
        zero_allowed: true,
    },
    Key {
        name: "registration_mm",
        field: |c| &mut c.noise.registration_mm,
        zero_allowed: true,
    },
    Key {
        name: "replan_error_mm",
        field: |c| &mut c.replan_error_mm,
        zero_allowed: false,
    },
    Key {
        name: "tracking_lost_after_mm",
        field: |c| &mut c.max_gap_mm,
        zero_allowed: false,
    },
    Key {
        name: "reach_tolerance_mm",
        field: |c| &mut c.reach_tolerance_mm,
        zero_allowed: false,
    },
    Key {
        name: "rotation_dead_band_deg",
        field: |c| &mut c.rotation_dead_band_deg,
        zero_allowed: true,
    },
];

/// The controller's configuration a scenario file asks for: the defaults
/// (`SteerConfig::DEFAULT`) where `[steering]` is silent.
pub fn steering_of(file: &ScenarioFile) -> Result<SteerConfig> {
    let mut config = SteerConfig::DEFAULT;
    for (name, value) in file.steering.iter().flatten() {
        let number = value
            .as_float()
            .or_else(|| value.as_integer().map(|i| i as f64))
            .with_context(|| format!("steering.{name} is `{value}`, not a number"))?;
        set(&mut config, name, number).map_err(|e| anyhow::anyhow!("steering.{e}"))?;
    }
    Ok(config)
}

/// `config` with `KEY=VALUE` applied (`needle simulate --steer`), a key of `[steering]`.
pub fn apply(config: &mut SteerConfig, assignment: &str) -> Result<()> {
    let (name, value) = assignment
        .split_once('=')
        .with_context(|| format!("`{assignment}` is not KEY=VALUE"))?;
    let number: f64 = value
        .trim()
        .parse()
        .ok()
        .with_context(|| format!("{name} is `{value}`, not a number"))?;
    set(config, name.trim(), number)
}

/// Every key of `[steering]` with its value in `config` (what the controller was told; `needle
/// simulate --closed-loop --json` prints it as `controller`).
pub fn steering_keys(config: &SteerConfig) -> BTreeMap<&'static str, f32> {
    let mut config = *config;
    let mut out: BTreeMap<&'static str, f32> = KEYS
        .iter()
        .map(|k| (k.name, *(k.field)(&mut config)))
        .collect();
    out.insert("iterations", config.iterations as f32);
    out
}

/// Sets the key `name` to `number`, or says why not (the message starts with the key).
fn set(config: &mut SteerConfig, name: &str, number: f64) -> Result<()> {
    if name == "iterations" {
        if !(number.fract() == 0.0 && (1.0..=1000.0).contains(&number)) {
            bail!("iterations is `{number}`: allowed is a whole number from 1 to 1000");
        }
        config.iterations = number as u32;
        return Ok(());
    }
    let Some(key) = KEYS.iter().find(|k| k.name == name) else {
        let names: Vec<&str> = KEYS.iter().map(|k| k.name).collect();
        bail!(
            "{name}: unknown steering key; allowed are {}, iterations",
            names.join(", ")
        );
    };
    let ok = number.is_finite() && (number > 0.0 || (key.zero_allowed && number == 0.0));
    if !ok {
        let least = if key.zero_allowed {
            "0 or more"
        } else {
            "more than 0"
        };
        bail!("{name} = {number}: allowed is a finite number, {least}");
    }
    *(key.field)(config) = number as f32;
    if !config.is_valid() {
        bail!("{name} = {number}: allowed is less than 180");
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(extra: &str) -> Result<SteerConfig> {
        steering_of(&super::super::file::minimal_with(extra)?)
    }

    #[test]
    fn the_table_tells_the_controller_what_the_lab_knows() {
        assert_eq!(parse("").unwrap(), SteerConfig::DEFAULT);
        let c = parse(
            "[steering]\ntracker_position_mm = 1.2\ntracker_heading_deg = 2\n\
             tracking_lost_after_mm = 4\nrotation_dead_band_deg = 0\niterations = 12\n",
        )
        .unwrap();
        assert_eq!(c.noise.position_mm, 1.2);
        assert_eq!(c.noise.orientation_deg, 2.0);
        assert_eq!(c.max_gap_mm, 4.0);
        assert_eq!(c.rotation_dead_band_deg, 0.0);
        assert_eq!(c.iterations, 12);
        assert_eq!(
            c.noise.curvature_spread,
            SteerConfig::DEFAULT.noise.curvature_spread
        );
        for key in KEYS {
            let c = parse(&format!("[steering]\n{} = 3.5\n", key.name)).unwrap();
            assert_ne!(c, SteerConfig::DEFAULT, "{} sets nothing", key.name);
        }
    }

    #[test]
    fn bad_values_name_the_key() {
        for (extra, says) in [
            (
                "[steering]\ntracker_noise = 1\n",
                "steering.tracker_noise: unknown steering key",
            ),
            (
                "[steering]\ntracker_position_mm = 0\n",
                "steering.tracker_position_mm = 0",
            ),
            (
                "[steering]\ntracker_position_mm = -1\n",
                "allowed is a finite number",
            ),
            (
                "[steering]\ntracker_position_mm = nan\n",
                "steering.tracker_position_mm = NaN",
            ),
            (
                "[steering]\nreach_tolerance_mm = \"x\"\n",
                "steering.reach_tolerance_mm is `\"x\"`",
            ),
            (
                "[steering]\nrotation_dead_band_deg = 200\n",
                "less than 180",
            ),
            ("[steering]\niterations = 0\n", "steering.iterations is `0`"),
            (
                "[steering]\niterations = 2.5\n",
                "steering.iterations is `2.5`",
            ),
        ] {
            let e = format!("{:#}", parse(extra).unwrap_err());
            assert!(e.contains(says), "{extra}: {e}");
        }
    }

    #[test]
    fn the_keys_read_back_what_was_set() {
        let c = parse("[steering]\ntracker_position_mm = 1.25\niterations = 7\n").unwrap();
        let keys = steering_keys(&c);
        assert_eq!(keys.len(), KEYS.len() + 1);
        assert_eq!(keys["tracker_position_mm"], 1.25);
        assert_eq!(keys["iterations"], 7.0);
        assert_eq!(keys["tracking_lost_after_mm"], c.max_gap_mm);
    }

    #[test]
    fn a_flag_sets_a_key_as_the_table_does() {
        let mut c = parse("[steering]\ntracker_position_mm = 1.2\n").unwrap();
        apply(&mut c, "tracker_position_mm=0.8").unwrap();
        apply(&mut c, "iterations=5").unwrap();
        assert_eq!(c.noise.position_mm, 0.8);
        assert_eq!(c.iterations, 5);
        for (bad, says) in [
            ("tracker_position_mm", "not KEY=VALUE"),
            ("tracker_position_mm=x", "tracker_position_mm is `x`"),
            ("noise=1", "noise: unknown steering key"),
            ("reach_tolerance_mm=0", "reach_tolerance_mm = 0"),
        ] {
            let e = format!("{:#}", apply(&mut c, bad).unwrap_err());
            assert!(e.contains(says), "{bad}: {e}");
        }
    }
}
