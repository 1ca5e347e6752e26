//! What the service loop needs from a board: a byte link and a watchdog.

/// A serial link to the host (UART or USB virtual serial port).
pub trait Link {
    /// Copies received bytes into `buf` without blocking; returns how many.
    fn read(&mut self, buf: &mut [u8]) -> usize;
    /// Sends all of `bytes`, blocking until the hardware has taken them (or dropping them when
    /// no host is listening, for USB).
    fn write_all(&mut self, bytes: &[u8]);
    /// Called once per loop: keeps the watchdog and any link housekeeping (USB) going.
    fn service(&mut self) {}
}
