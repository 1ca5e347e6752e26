//! The axes and the timer: units, steps, speed and acceleration limits, soft limits.

pub use crate::fields::{Axis, ConfigField};
use crate::MotionError;

/// One axis: how units become steps and what it may do.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxisConfig {
    /// Motor steps (microsteps) per unit (mm or degree).
    pub steps_per_unit: f32,
    /// Largest speed (units/s).
    pub max_speed: f32,
    /// Largest acceleration (units/s²).
    pub max_accel: f32,
    /// Lowest commanded position (units).
    pub min: f32,
    /// Highest commanded position (units).
    pub max: f32,
}

/// The speeds the driver's schedule was made for (planner-core's `Driver`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rates {
    /// Insertion speed (mm/s).
    pub insert_mm_s: f32,
    /// Speed of a bevel rotation (deg/s).
    pub rotate_deg_s: f32,
    /// Spin while inserting (rev/s).
    pub spin_rev_s: f32,
}

/// The whole motion set-up.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotionConfig {
    /// Step timer ticks per second.
    pub tick_hz: u32,
    /// Insertion and rotation, in [`Axis`] order.
    pub axes: [AxisConfig; 2],
    /// The schedule's speeds.
    pub rates: Rates,
    /// Speed of the insertion stage while it seeks the home switch (mm/s).
    pub homing_mm_s: f32,
    /// Farthest the stage travels back looking for the home switch (mm).
    pub homing_travel_mm: f32,
}

/// Fewest ticks between two steps of one axis at its top speed: room for the step interrupt.
pub const MIN_STEP_TICKS: f32 = 8.0;

/// Largest position of an axis in steps: positions and moves fit an `i32` with room to add.
pub const MAX_POSITION_STEPS: f32 = 1.0e9;

impl MotionConfig {
    /// A bench set-up: 1 MHz timer; a 2 mm lead screw and a shaft motor, both 200 steps × 16
    /// microsteps a turn; insertion 0 to `needle_mm`, twist within ±`max_twist_deg`.
    pub fn bench(needle_mm: f32, max_twist_deg: f32, rates: Rates) -> MotionConfig {
        MotionConfig {
            tick_hz: 1_000_000,
            axes: [
                AxisConfig {
                    steps_per_unit: 1600.0,
                    max_speed: 10.0,
                    max_accel: 50.0,
                    min: 0.0,
                    max: needle_mm,
                },
                AxisConfig {
                    steps_per_unit: 3200.0 / 360.0,
                    max_speed: 1800.0,
                    max_accel: 36_000.0,
                    min: -max_twist_deg,
                    max: max_twist_deg,
                },
            ],
            rates,
            homing_mm_s: 2.0,
            homing_travel_mm: needle_mm + 10.0,
        }
    }

    /// Every value finite, positive where it must be, and within what the step timing holds.
    pub fn validate(&self) -> Result<(), MotionError> {
        let bad = |f| Err(MotionError::Config(f));
        if self.tick_hz < 1000 {
            return bad(ConfigField::TickRate);
        }
        let f = self.tick_hz as f32;
        for axis in Axis::BOTH {
            let a = &self.axes[axis as usize];
            if !(a.steps_per_unit > 0.0 && a.steps_per_unit < 1e6) {
                return bad(ConfigField::StepsPerUnit(axis));
            }
            let top = a.max_speed * a.steps_per_unit;
            if !(top >= 1.0 && f / top >= MIN_STEP_TICKS) {
                return bad(ConfigField::MaxSpeed(axis));
            }
            let acc = a.max_accel * a.steps_per_unit;
            if !(1.0..1e9).contains(&acc) {
                return bad(ConfigField::MaxAccel(axis));
            }
            let span = MAX_POSITION_STEPS / a.steps_per_unit;
            if !(a.min < a.max && a.min >= -span && a.max <= span) {
                return bad(ConfigField::SoftLimits(axis));
            }
        }
        let r = &self.rates;
        for v in [r.insert_mm_s, r.rotate_deg_s, r.spin_rev_s] {
            if !(v > 0.0 && v < 1e6) {
                return bad(ConfigField::Rate);
            }
        }
        let h = self.homing_mm_s * self.axes[0].steps_per_unit;
        let travel = self.homing_travel_mm * self.axes[0].steps_per_unit;
        let homing_ok = h >= 1.0 && self.homing_mm_s <= self.axes[0].max_speed;
        if !homing_ok || !(1.0..=MAX_POSITION_STEPS).contains(&travel) {
            return bad(ConfigField::Homing);
        }
        Ok(())
    }

    /// `units` of `axis` in whole steps (nearest), saturating.
    pub fn to_steps(&self, axis: Axis, units: f64) -> i32 {
        let s = units * f64::from(self.axes[axis as usize].steps_per_unit);
        libm::round(s) as i32
    }

    /// `steps` of `axis` in its units.
    pub fn to_units(&self, axis: Axis, steps: i32) -> f32 {
        steps as f32 / self.axes[axis as usize].steps_per_unit
    }

    /// The soft limits of `axis` in steps (lowest, highest).
    pub fn limit_steps(&self, axis: Axis) -> (i32, i32) {
        let a = &self.axes[axis as usize];
        (
            self.to_steps(axis, f64::from(a.min)),
            self.to_steps(axis, f64::from(a.max)),
        )
    }
}
