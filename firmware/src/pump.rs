//! The service loop: bytes from the link into the service, reply bytes from the service out.
//!
//! Work is measured per plan: a `poll` runs inside a marker region, and the region counts when
//! the service was planning before or after it, that is from the poll that takes the request's
//! last chunk (decode the scenario, start the plan) through each form to the poll that encodes the
//! result. Received bytes reach the service a whole frame at a time ([`Inbox`]), so the poll that
//! decodes the last chunk always finds all of it, however the line split it in time. The report marker fires when planning stops. Upload and fetch frames, idle polls and
//! the time bytes take on the line are not counted; frames the host sends *during* planning
//! (status queries) would be, so `cargo xtask device-bench` sends none. Each poll that answers a
//! steering reading is a region reported on its own: the instructions of one reading. Reply bytes are staged in
//! [`Outbox`] and sent to the link outside the regions.

use crate::axes::Axes;
use crate::link::Link;
use crate::marker;
use heapless::Vec;
use planner_core::device::DeviceService;
use planner_core::wire::MAX_WIRE_FRAME;

/// Received bytes held until a frame delimiter (0x00) arrives, then handed to the service.
pub struct Inbox(Vec<u8, MAX_WIRE_FRAME>);

impl Inbox {
    /// An empty inbox.
    pub const fn new() -> Self {
        Inbox(Vec::new())
    }

    fn take(&mut self, bytes: &[u8], service: &mut DeviceService) {
        for &b in bytes {
            if self.0.push(b).is_err() {
                // Longer than any frame: pass it on, the service reports it as too long.
                service.receive(&self.0);
                self.0.clear();
                // Cannot fail: just cleared.
                let _ = self.0.push(b);
            }
            if b == 0 {
                service.receive(&self.0);
                self.0.clear();
            }
        }
    }
}

/// Reply bytes staged between polls (a plan reply fits; a larger burst is flushed early).
pub struct Outbox(Vec<u8, OUTBOX_BYTES>);

// Holds every reply of a measured poll (a status, a steering answer: under 200 bytes); a longer
// reply (a result chunk) is flushed as it fills, outside any measured region.
const OUTBOX_BYTES: usize = 1024;

impl Outbox {
    /// An empty outbox.
    pub const fn new() -> Self {
        Outbox(Vec::new())
    }

    fn push(&mut self, mut bytes: &[u8], link: &mut impl Link) {
        while !bytes.is_empty() {
            if self.0.is_full() {
                self.flush(link);
            }
            let n = bytes.len().min(OUTBOX_BYTES - self.0.len());
            // Cannot fail: `n` bytes are free.
            let _ = self.0.extend_from_slice(&bytes[..n]);
            bytes = &bytes[n..];
        }
    }

    fn flush(&mut self, link: &mut impl Link) {
        if !self.0.is_empty() {
            link.write_all(&self.0);
            self.0.clear();
        }
    }
}

/// Serves requests forever; the axes run between polls, outside the measured regions.
pub fn run(
    link: &mut impl Link,
    axes: &mut impl Axes,
    service: &mut DeviceService,
    inbox: &mut Inbox,
    outbox: &mut Outbox,
) -> ! {
    let mut rx = [0u8; 64];
    loop {
        link.service();
        let n = link.read(&mut rx);
        inbox.take(&rx[..n], service);
        let was_planning = service.is_planning();
        let (readings, moves) = (service.stats().steer_readings, service.stats().motion_moves);
        marker::begin();
        service.poll(&mut |bytes| outbox.push(bytes, link));
        let planning = service.is_planning();
        // A steering reading (one estimate update and at most one replan) is its own region, and
        // so is a move request (every move checked against the soft limits, the first set up).
        let steered = service.stats().steer_readings != readings;
        let moved = service.stats().motion_moves != moves;
        if was_planning || planning || steered || moved {
            marker::end();
        }
        if (was_planning && !planning) || steered || moved {
            marker::report();
        }
        outbox.flush(link);
        axes.advance(service);
    }
}
