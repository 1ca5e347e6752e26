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

/// What the controller assumes where `[steering]` is silent: a real tracker and real tissue,
/// not the simulator's tidy default world (`SteerConfig::DEFAULT`, which assumes neither).
///
/// - `registration_mm = 0.42`: an error between the tracker and the imaging that no fix shows:
///   a point-based registration's target registration error of 0.5 mm RMS, 0.29 mm per axis
///   (Fitzpatrick & West 2001, IEEE TMI 20(9)), and an electromagnetic field's bias of 0.3 mm
///   per axis (Hummel et al. 2005, Med Phys 32(7); Franz et al. 2014, IEEE TMI 33(8)), in
///   quadrature.
/// - `target_speed_walk = 0.02`: soft tissue pushes the target ahead of the tip (DiMaio &
///   Salcudean 2003; Lagerburg et al. 2005, Radiother Oncol 77(3)), told so the estimate follows
///   it.
/// - `curvature_walk = 0.02`: layered tissue (skin, fat, muscle, capsule: Abolhassani et al.
///   2007, Med Eng Phys 29(4)) bends the needle by radii tens of percent apart (Majewicz et al.
///   2012, IEEE TBME 59(2)), so the curvature estimate keeps learning.
///
/// Each figure is the set-up the clinical examples use (docs/execution.md, "The clinical
/// world"); a file that knows its tracker and tissue better says so under `[steering]` (0 turns
/// a walk off).
pub const ASSUMED_STEERING: SteerConfig = {
    let mut c = SteerConfig::DEFAULT;
    c.noise.registration_mm = 0.42;
    c.noise.target_speed_walk = 0.02;
    c.noise.curvature_walk = 0.02;
    c
};

/// The controller's configuration a scenario file asks for, where `[steering]` is silent:
/// [`ASSUMED_STEERING`], or `SteerConfig::DEFAULT` for a file planned for open-loop execution
/// (`execution.mode = "open_loop"`). The assumptions need the curvature a closed-loop plan keeps
/// in hand: told an error no fix shows, the controller keeps a wider berth and reads an offset,
/// and a path planned at the needle's full curvature has no bend to spare for either (the
/// paper's optimum, steered so in the default world, reached 71 of 100 targets instead of 100).
pub fn steering_of(file: &ScenarioFile) -> Result<SteerConfig> {
    let mut config = if file.planned_open_loop() {
        SteerConfig::DEFAULT
    } else {
        ASSUMED_STEERING
    };
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
        assert_eq!(parse("").unwrap(), ASSUMED_STEERING);
        let told_nothing =
            "[steering]\nregistration_mm = 0\ntarget_speed_walk = 0\ncurvature_walk = 0\n";
        assert_eq!(parse(told_nothing).unwrap(), SteerConfig::DEFAULT);
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
            assert_ne!(c, ASSUMED_STEERING, "{} sets nothing", key.name);
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
