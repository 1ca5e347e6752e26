//! The board's axes, as the main loop sees them: between polls it lets them run for the time
//! that passed. A board without axes answers motion requests with `NoMotion`.

use planner_core::device::DeviceService;

/// What the main loop does for the axes between polls.
pub trait Axes {
    /// Lets the service's motion core run the axes for the time since the last call.
    fn advance(&mut self, service: &mut DeviceService);
}

/// A board that drives no axes.
#[cfg(feature = "stm32f4")]
pub struct NoAxes;

#[cfg(feature = "stm32f4")]
impl Axes for NoAxes {
    fn advance(&mut self, _service: &mut DeviceService) {}
}

/// Axes the board may have failed to set up.
impl<A: Axes> Axes for Option<A> {
    fn advance(&mut self, service: &mut DeviceService) {
        if let Some(axes) = self {
            axes.advance(service);
        }
    }
}
