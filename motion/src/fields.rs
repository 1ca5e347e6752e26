//! The two axes and the names of the configuration's fields: what the configuration, its errors
//! and the safety machine all speak of, kept apart so that none of them imports another for it.

/// The two axes of a needle driver.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Axis {
    /// The insertion stage (a lead screw), in millimetres.
    Insertion = 0,
    /// The shaft's rotation, in degrees.
    Rotation = 1,
}

impl Axis {
    /// Both axes, in index order.
    pub const BOTH: [Axis; 2] = [Axis::Insertion, Axis::Rotation];
}

/// What a configuration value is wrong about.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ConfigField {
    /// The timer's tick rate.
    TickRate,
    /// An axis' steps per unit.
    StepsPerUnit(Axis),
    /// An axis' maximum speed.
    MaxSpeed(Axis),
    /// An axis' maximum acceleration.
    MaxAccel(Axis),
    /// An axis' soft limits (min must lie below max, both finite, within the step counter).
    SoftLimits(Axis),
    /// A rate of the driver (insert speed, rotate speed or spin rate).
    Rate,
    /// The homing speed or travel.
    Homing,
}
