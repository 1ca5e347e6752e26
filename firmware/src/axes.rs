//! The board's axes, as the main loop sees them: between polls it lets them run for the time
//! that passed (or, where interrupts step them, reads their inputs at rest). A board whose
//! axes failed to set up answers motion requests with `NoMotion`.

use planner_core::device::DeviceService;

/// What the main loop does for the axes between polls.
pub trait Axes {
    /// Lets the service's motion core run the axes for the time since the last call.
    fn advance(&mut self, service: &mut DeviceService);
}

/// Axes the board may have failed to set up.
impl<A: Axes> Axes for Option<A> {
    fn advance(&mut self, service: &mut DeviceService) {
        if let Some(axes) = self {
            axes.advance(service);
        }
    }
}
