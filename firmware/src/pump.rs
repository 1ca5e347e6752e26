//! The service loop: bytes from the link into the service, reply bytes from the service out.
//!
//! Work is measured per request: every `poll` runs inside a marker region, and a region counts
//! when it belongs to a request (the poll found work, or work was already pending). Idle polls
//! while bytes trickle in are not counted, so the figure does not depend on how the host's bytes
//! were split in time. Reply bytes are staged in [`Outbox`] and sent outside the regions, so the
//! figure does not depend on the line either.

use crate::link::Link;
use crate::marker;
use planner_core::service::DeviceService;

/// Reply bytes staged between polls (a plan reply fits; a larger burst is flushed early).
pub struct Outbox {
    buf: [u8; OUTBOX_BYTES],
    len: usize,
}

const OUTBOX_BYTES: usize = 2048;

impl Outbox {
    /// An empty outbox.
    pub const fn new() -> Self {
        Outbox {
            buf: [0; OUTBOX_BYTES],
            len: 0,
        }
    }

    fn push(&mut self, mut bytes: &[u8], link: &mut impl Link) {
        while !bytes.is_empty() {
            if self.len == self.buf.len() {
                self.flush(link);
            }
            let n = bytes.len().min(self.buf.len() - self.len);
            self.buf[self.len..self.len + n].copy_from_slice(&bytes[..n]);
            self.len += n;
            bytes = &bytes[n..];
        }
    }

    fn flush(&mut self, link: &mut impl Link) {
        if self.len > 0 {
            link.write_all(&self.buf[..self.len]);
            self.len = 0;
        }
    }
}

/// Serves requests forever.
pub fn run(link: &mut impl Link, service: &mut DeviceService, outbox: &mut Outbox) -> ! {
    let mut rx = [0u8; 64];
    let mut busy = false;
    loop {
        link.service();
        let n = link.read(&mut rx);
        if n > 0 {
            service.receive(&rx[..n]);
        }
        marker::begin();
        let pending = service.poll(&mut |bytes| outbox.push(bytes, link));
        if pending || busy {
            marker::end();
        }
        if busy && !pending {
            marker::report();
        }
        busy = pending;
        outbox.flush(link);
    }
}
