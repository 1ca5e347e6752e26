//! The receive queue: bytes from the transport wait in a fixed queue until a poll hands them to
//! the frame decoder; an overflow is remembered and reported once.

use crate::wire::MAX_WIRE_FRAME;
use heapless::Deque;

/// Received bytes the service buffers between polls: two full frames.
pub const RX_QUEUE: usize = 2 * MAX_WIRE_FRAME;

/// Received bytes not yet decoded, and whether some were lost.
pub(super) struct Inbox {
    queue: Deque<u8, RX_QUEUE>,
    overrun: bool,
}

impl Inbox {
    pub(super) const fn new() -> Self {
        Inbox {
            queue: Deque::new(),
            overrun: false,
        }
    }

    /// Queues what fits; the rest is lost and remembered as an overrun.
    pub(super) fn receive(&mut self, bytes: &[u8]) {
        for &b in bytes {
            if self.queue.push_back(b).is_err() {
                self.overrun = true;
                return;
            }
        }
    }

    /// Queues as many of `bytes` as there is room for and returns how many.
    pub(super) fn receive_partial(&mut self, bytes: &[u8]) -> usize {
        let n = bytes.len().min(RX_QUEUE - self.queue.len());
        self.receive(&bytes[..n]);
        n
    }

    /// Whether bytes were lost since the last call.
    pub(super) fn take_overrun(&mut self) -> bool {
        core::mem::take(&mut self.overrun)
    }

    /// The oldest queued byte.
    pub(super) fn pop(&mut self) -> Option<u8> {
        self.queue.pop_front()
    }

    /// Whether bytes are still queued.
    pub(super) fn pending(&self) -> bool {
        !self.queue.is_empty()
    }
}
