//! The device and its line in one object, for tests: no threads, no clock. Reading runs the
//! device until it has nothing left to do, so a "timeout" costs no time at all.

use crate::axes::SimulatedAxes;
use crate::line::{FaultyLine, LineConfig, LineStats};
use needle_motion::MotionError;
use planner_core::device::{DeviceService, DeviceStats};
use planner_core::wire::{
    encode_frame, FrameDecoder, Header, Reply, Request, RequestBody, ENCODE_SCRATCH, MAX_FRAME,
};
use std::collections::HashSet;

/// Checks that no frame damaged on the line is ever accepted: every payload a receiver's decoder
/// accepts must be one the other side actually sent.
struct Audit {
    sent: HashSet<Vec<u8>>,
    clean: Box<FrameDecoder<MAX_FRAME>>,
    line: Box<FrameDecoder<MAX_FRAME>>,
    accepted: u64,
    forged: u64,
}

impl Audit {
    /// An audit of the frames travelling to the device (`replies` false) or to the host.
    fn new(replies: bool) -> Self {
        let decoder = || {
            Box::new(if replies {
                FrameDecoder::for_replies()
            } else {
                FrameDecoder::for_requests()
            })
        };
        Audit {
            sent: HashSet::new(),
            clean: decoder(),
            line: decoder(),
            accepted: 0,
            forged: 0,
        }
    }

    fn sent(&mut self, clean: &[u8]) {
        for &b in clean {
            if let Some(Ok(p)) = self.clean.push(b) {
                self.sent.insert(p.to_vec());
            }
        }
    }

    fn arrived(&mut self, bytes: &[u8]) {
        for &b in bytes {
            if let Some(Ok(p)) = self.line.push(b) {
                self.accepted += 1;
                if !self.sent.contains(p) {
                    self.forged += 1;
                }
            }
        }
    }
}

/// What the audit found, per direction.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AuditReport {
    /// Frames the device's decoder accepted.
    pub accepted_by_device: u64,
    /// Of those, frames the host never sent (damaged frames that got through).
    pub forged_to_device: u64,
    /// Frames the host's decoder accepted.
    pub accepted_by_host: u64,
    /// Of those, frames the device never sent.
    pub forged_to_host: u64,
}

/// A simulated device reached through a (possibly faulty) line in each direction.
pub struct InProcess {
    device: Box<DeviceService>,
    /// The simulated stages behind the device's motion core, if it drives any.
    axes: Option<SimulatedAxes>,
    to_device: FaultyLine,
    to_host: FaultyLine,
    inbox: Vec<u8>,
    scratch: Vec<u8>,
    outbox: Vec<u8>,
    audit: Option<Box<(Audit, Audit)>>,
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
            axes: None,
            to_device: FaultyLine::new(to_device),
            to_host: FaultyLine::new(to_host),
            inbox: Vec::new(),
            scratch: Vec::new(),
            outbox: Vec::new(),
            audit: None,
        }
    }

    /// The device drives the bench's simulated stages ([`SimulatedAxes`]); they move only as
    /// [`InProcess::advance`] lets simulated time pass.
    pub fn with_axes(mut self) -> Result<Self, MotionError> {
        self.axes = Some(SimulatedAxes::attach(&mut self.device)?);
        Ok(self)
    }

    /// `ms` of simulated time for the stages (nothing without axes).
    pub fn advance(&mut self, ms: u32) {
        if let Some(axes) = &mut self.axes {
            axes.advance(&mut self.device, ms);
        }
    }

    /// Presses the stages' e-stop input (nothing without axes); the core sees it at the next
    /// [`InProcess::advance`].
    pub fn press_estop(&mut self) {
        if let Some(axes) = &mut self.axes {
            axes.plant_mut().estop = true;
        }
    }

    /// The simulated stages, if the device drives any.
    pub fn axes(&self) -> Option<&SimulatedAxes> {
        self.axes.as_ref()
    }

    /// Starts checking every frame accepted in either direction against the frames sent.
    pub fn audited(mut self) -> Self {
        self.audit = Some(Box::new((Audit::new(false), Audit::new(true))));
        self
    }

    /// What the audit found (zeros if it is off).
    pub fn audit_report(&self) -> AuditReport {
        match &self.audit {
            None => AuditReport::default(),
            Some(a) => AuditReport {
                accepted_by_device: a.0.accepted,
                forged_to_device: a.0.forged,
                accepted_by_host: a.1.accepted,
                forged_to_host: a.1.forged,
            },
        }
    }

    /// Bytes from the host: they cross the line and reach the device.
    pub fn write(&mut self, bytes: &[u8]) {
        self.scratch.clear();
        self.to_device.carry(bytes, &mut self.scratch);
        if let Some(a) = &mut self.audit {
            a.0.sent(bytes);
            a.0.arrived(&self.scratch);
        }
        // Like a UART driver with flow control: when the queue is full the device works first.
        let mut rest = &self.scratch[..];
        while !rest.is_empty() {
            let n = self.device.receive_partial(rest);
            rest = &rest[n..];
            if n == 0 {
                let out = &mut self.outbox;
                self.device.poll(&mut |b: &[u8]| out.extend_from_slice(b));
            }
        }
    }

    /// Runs the device until it is idle and moves what it sent into `buf`; 0 means silence.
    pub fn read(&mut self, buf: &mut [u8]) -> usize {
        if self.inbox.is_empty() {
            let Self {
                device,
                to_host,
                inbox,
                audit,
                outbox,
                ..
            } = self;
            let mut sent = std::mem::take(outbox);
            // Bounded: every poll consumes input or plans a form, and both run out.
            while device.poll(&mut |b: &[u8]| sent.extend_from_slice(b)) {}
            let before = inbox.len();
            to_host.carry(&sent, inbox);
            if let Some(a) = audit {
                a.1.sent(&sent);
                a.1.arrived(&inbox[before..]);
            }
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

/// One request (id `id`) straight into `device`, no line and no clock; the replies it gives
/// until it has nothing more to do. For tests that drive a device's state by hand.
pub fn answer(device: &mut DeviceService, id: u16, body: RequestBody) -> Vec<Reply> {
    let mut scratch = [0u8; ENCODE_SCRATCH];
    let mut bytes = Vec::new();
    let request = Request {
        header: Header::new(id),
        body,
    };
    // A request that does not encode (over the frame's size) reaches the device as nothing.
    let _ = encode_frame(&request, &mut scratch, &mut |b: &[u8]| {
        bytes.extend_from_slice(b)
    });
    device.receive(&bytes);
    let mut out = Vec::new();
    while device.poll(&mut |b: &[u8]| out.extend_from_slice(b)) {}
    let mut decoder = FrameDecoder::<MAX_FRAME>::for_replies();
    let mut replies = Vec::new();
    for &b in &out {
        if let Some(Ok(payload)) = decoder.push(b) {
            replies.extend(postcard::from_bytes::<Reply>(payload).ok());
        }
    }
    replies
}
