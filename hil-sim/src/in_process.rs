//! The device and its line in one object, for tests: no threads, no clock. Reading runs the
//! device until it has nothing left to do, so a "timeout" costs no time at all.

use crate::line::{FaultyLine, LineConfig, LineStats};
use planner_core::service::{DeviceService, DeviceStats};

/// A simulated device reached through a (possibly faulty) line in each direction.
pub struct InProcess {
    device: Box<DeviceService>,
    to_device: FaultyLine,
    to_host: FaultyLine,
    inbox: Vec<u8>,
    scratch: Vec<u8>,
}

impl InProcess {
    /// A device behind clean lines.
    pub fn new() -> Self {
        Self::with_lines(LineConfig::default(), LineConfig::default())
    }

    /// A device behind lines with these faults (host to device, device to host).
    pub fn with_lines(to_device: LineConfig, to_host: LineConfig) -> Self {
        InProcess {
            device: Box::new(DeviceService::with_identity(crate::IDENTITY)),
            to_device: FaultyLine::new(to_device),
            to_host: FaultyLine::new(to_host),
            inbox: Vec::new(),
            scratch: Vec::new(),
        }
    }

    /// Bytes from the host: they cross the line and reach the device.
    pub fn write(&mut self, bytes: &[u8]) {
        self.scratch.clear();
        self.to_device.carry(bytes, &mut self.scratch);
        self.device.receive(&self.scratch);
    }

    /// Runs the device until it is idle and moves what it sent into `buf`; 0 means silence.
    pub fn read(&mut self, buf: &mut [u8]) -> usize {
        if self.inbox.is_empty() {
            let Self {
                device,
                to_host,
                inbox,
                ..
            } = self;
            let mut sent = Vec::new();
            // Bounded: every poll consumes input or plans a form, and both run out.
            while device.poll(&mut |b: &[u8]| sent.extend_from_slice(b)) {}
            to_host.carry(&sent, inbox);
        }
        let n = buf.len().min(self.inbox.len());
        buf[..n].copy_from_slice(&self.inbox[..n]);
        self.inbox.drain(..n);
        n
    }

    /// The device's counters.
    pub fn device_stats(&self) -> DeviceStats {
        self.device.stats()
    }

    /// What each line did (host to device, device to host).
    pub fn line_stats(&self) -> (LineStats, LineStats) {
        (self.to_device.stats(), self.to_host.stats())
    }
}

impl Default for InProcess {
    fn default() -> Self {
        Self::new()
    }
}
