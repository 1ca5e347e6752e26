//! Boards: each brings up its clocks, its link and its axes, and says how to stop after a fault.

#[cfg(feature = "mps2-an386")]
mod mps2_an386;
#[cfg(feature = "mps2-an386")]
mod mps2_an386_axes;
#[cfg(feature = "mps2-an386")]
pub use mps2_an386::{axes, fatal_stop, init, panic_link, NAME};

#[cfg(feature = "stm32f4")]
mod stm32f4;
#[cfg(feature = "stm32f4")]
pub use stm32f4::{axes, fatal_stop, init, panic_link, NAME};
