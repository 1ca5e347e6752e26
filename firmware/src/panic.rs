//! The last resort: the firmware is written not to panic on any input, so reaching this is a bug.
//! It tells the host (an error frame on the link, so `needle` reports a device fault rather than a
//! timeout), logs the location, then stops: a reset on a board, a failing exit status under QEMU.

use crate::board;
use crate::link::Link;
use core::panic::PanicInfo;
use planner_core::wire::{encode_frame, Fault, Header, Reply, ReplyBody, FAULT_SCRATCH};

#[panic_handler]
fn panic(info: &PanicInfo) -> ! {
    cortex_m::interrupt::disable();
    let mut link = board::panic_link();
    // A lone delimiter ends any frame the host was receiving, so the error frame stands alone.
    link.write_all(&[0]);
    let fault = Reply {
        header: Header::new(0),
        body: ReplyBody::Fault(Fault::Internal),
    };
    let mut scratch = [0u8; FAULT_SCRATCH];
    // Sized from the message types (a test encodes this very reply into it).
    let _ = encode_frame(&fault, &mut scratch, &mut |bytes: &[u8]| {
        link.write_all(bytes)
    });
    if let Some(location) = info.location() {
        defmt::error!("panic at {=str}:{=u32}", location.file(), location.line());
    } else {
        defmt::error!("panic");
    }
    board::fatal_stop()
}
