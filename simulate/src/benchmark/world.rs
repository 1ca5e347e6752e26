//! The world `needle benchmark` executes every scenario in, and what its controller is told: the
//! same flags, with the same meaning and messages, as `needle simulate` (`--world`, `--perturb`
//! over it, `--fault`, `--steer`).

use crate::request::change_world;
use anyhow::{anyhow, Context, Result};
use needle_scenario::steering::ASSUMED_STEERING;
use needle_sim::{Perturbation, TrackerFaults, WorldEffects};
use planner_core::steer::SteerConfig;

/// The world of every run and the controller's settings.
#[derive(Clone, Debug, PartialEq)]
pub struct BenchWorld {
    /// The perturbation of the planner's own model.
    pub perturbation: Perturbation,
    /// The effects beyond it.
    pub effects: WorldEffects,
    /// The tracker's faults (closed loop).
    pub faults: TrackerFaults,
    /// What the closed loop is told (and a steered bound predicts its spread with).
    pub config: SteerConfig,
}

impl BenchWorld {
    /// The named world (`default` when none), changed by `perturb` (`KEY=VALUE`, a perturbation
    /// or a world key) and `faults`; the controller told what it is told steering a scenario
    /// file silent on `[steering]` ([`ASSUMED_STEERING`]: a real tracker and real tissue),
    /// changed by `steer`. The closed-loop plans keep curvature in hand as such a file's do.
    pub fn of(
        world: Option<&str>,
        perturb: &[String],
        faults: &[String],
        steer: &[String],
    ) -> Result<BenchWorld> {
        let (mut effects, mut tracker) =
            WorldEffects::preset(world.unwrap_or("default")).context("--world")?;
        let mut perturbation = Perturbation::default();
        for kv in perturb {
            change_world(&mut perturbation, &mut effects, kv).context("--perturb")?;
        }
        perturbation.validate().context("--perturb")?;
        for kv in faults {
            tracker.apply(kv).map_err(|e| anyhow!("--fault: {e}"))?;
        }
        let mut config = ASSUMED_STEERING;
        for kv in steer {
            needle_scenario::steering::apply(&mut config, kv).context("--steer")?;
        }
        Ok(BenchWorld {
            perturbation,
            effects,
            faults: tracker,
            config,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kv(items: &[&str]) -> Vec<String> {
        items.iter().map(|s| s.to_string()).collect()
    }

    /// The flags build the world `needle simulate` would: the preset, a world key and a
    /// perturbation key over it, a fault, and the controller told a key; each bad one is an
    /// error naming its flag.
    #[test]
    fn the_flags_make_the_world_and_the_told_controller() {
        let w = BenchWorld::of(
            Some("clinical"),
            &kv(&["layers=0", "tracker_position_mm=0.7"]),
            &kv(&["dropout_rate=0.02"]),
            &kv(&["registration_mm=0.42"]),
        )
        .unwrap();
        let mut effects = WorldEffects::clinical();
        effects.layers = 0;
        assert_eq!(w.effects, effects);
        assert_eq!(w.perturbation.tracker_position_mm, 0.7);
        assert_eq!(w.faults.dropout_rate, 0.02);
        assert_eq!(
            w.faults.dropout_mm,
            WorldEffects::clinical_faults().dropout_mm
        );
        assert_eq!(w.config.noise.registration_mm, 0.42);
        let default = BenchWorld::of(None, &[], &[], &[]).unwrap();
        assert!(default.effects.is_off());
        assert_eq!(default.config, ASSUMED_STEERING, "as a plain scenario file");
        let err = |r: Result<BenchWorld>| format!("{:#}", r.unwrap_err());
        assert!(err(BenchWorld::of(Some("mars"), &[], &[], &[])).starts_with("--world"));
        let bad = kv(&["nonsense=1"]);
        assert!(err(BenchWorld::of(None, &bad, &[], &[])).starts_with("--perturb"));
        assert!(err(BenchWorld::of(None, &[], &bad, &[])).starts_with("--fault"));
        assert!(err(BenchWorld::of(None, &[], &[], &bad)).starts_with("--steer"));
    }
}
