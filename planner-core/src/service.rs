//! The device-side request handler: bytes in, reply frames out, no knowledge of the transport.
//!
//! The firmware and `hil-sim` drive it the same way: hand every received byte to
//! [`DeviceService::receive`], then call [`DeviceService::poll`] until it returns `false`;
//! `poll` does one bounded unit of work (decode a frame, or plan one form) and passes outgoing
//! bytes to `tx`.
//!
//! (Skeleton: the protocol issue fills in framing, messages and planning.)

/// The device's request handler.
pub struct DeviceService {
    _private: (),
}

impl Default for DeviceService {
    fn default() -> Self {
        Self::new()
    }
}

impl DeviceService {
    /// A service with empty buffers and no request in progress.
    pub const fn new() -> Self {
        DeviceService { _private: () }
    }

    /// Takes received bytes; never blocks and never fails (overflow is reported on the wire).
    pub fn receive(&mut self, bytes: &[u8]) {
        let _ = bytes;
    }

    /// Does one bounded unit of work, writing reply bytes to `tx`; `true` while work is pending.
    pub fn poll(&mut self, tx: &mut dyn FnMut(&[u8])) -> bool {
        let _ = tx;
        false
    }
}
