//! The safety state machine's states, inputs, settings and faults.
//!
//! ```text
//!             power-up
//!                │
//!                ▼         arm           home                switch
//!          ┌──────────┐ ───────▶ ┌───────┐ ─────▶ ┌────────┐ ───────▶ Armed, homed
//!          │ Disarmed │          │ Armed │        │ Homing │
//!          └──────────┘ ◀─────── └───────┘ ◀───── └────────┘   (no switch in the travel:
//!                ▲        disarm     │ ▲  execute (homed)          fault HomingFailed)
//!  clear_fault   │                   ▼ │ done / stopped
//!  (cause gone)  │              ┌────────┐  hold   ┌─────────┐
//!                │              │ Moving │ ──────▶ │ Holding │ (watchdog: hold, then fault)
//!          ┌─────────┐          └────────┘ ◀────── └─────────┘
//!          │ Faulted │ ◀── e-stop, limit or home switch, following error, link lost,
//!          └─────────┘     from any state; both axes stop at once; reset keeps it
//! ```

use crate::fields::Axis;

/// Where the controller is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum State {
    /// No motion: the power-up state.
    Disarmed,
    /// Motion allowed (moves only once homed); at rest.
    Armed,
    /// Seeking the home switch.
    Homing,
    /// Executing moves.
    Moving,
    /// Decelerating to rest, or at rest, with the rest of the moves kept for a resume.
    Holding,
    /// Stopped by a fault, latched until cleared.
    Faulted,
}

/// Why motion stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FaultCause {
    /// The e-stop input.
    EStop,
    /// An end-of-travel switch.
    LimitSwitch,
    /// The home switch, met while retracting outside homing.
    HomeSwitch,
    /// The encoder of this axis disagrees with the commanded position beyond the band.
    FollowingError(Axis),
    /// No reading or heartbeat from the host for the watchdog's stop time.
    LinkLost,
    /// Homing travelled its whole distance without meeting the home switch.
    HomingFailed,
}

/// A fault: its cause and where both axes were.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FaultRecord {
    /// Why.
    pub cause: FaultCause,
    /// Commanded positions when it happened (steps, [`Axis`] order).
    pub steps: [i32; 2],
    /// The same in units (mm, degrees).
    pub position: [f32; 2],
    /// The encoders' positions, where fitted (steps).
    pub encoder: [Option<i32>; 2],
    /// When (the controller's milliseconds).
    pub at_ms: u32,
}

/// The inputs the board reads.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Inputs {
    /// The e-stop is pressed.
    pub estop: bool,
    /// An end-of-travel switch is closed.
    pub limit: bool,
    /// The insertion stage's home switch (its retracted end) is closed.
    pub home: bool,
    /// Encoder positions in motor steps, where fitted.
    pub encoder: [Option<i32>; 2],
}

/// The safety settings.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SafetyConfig {
    /// Largest disagreement of an encoder with the commanded position (steps, per axis).
    pub following_band: [u32; 2],
    /// Without a heartbeat this long while moving, hold (ms).
    pub watchdog_hold_ms: u32,
    /// Without a heartbeat this long, stop with a fault (ms; more than the hold time).
    pub watchdog_stop_ms: u32,
}

impl SafetyConfig {
    /// Half a millimetre and five degrees of band on the bench axes; hold after 200 ms without
    /// the host, fault after 1 s.
    pub const BENCH: SafetyConfig = SafetyConfig {
        following_band: [800, 44],
        watchdog_hold_ms: 200,
        watchdog_stop_ms: 1000,
    };
}
