//! A minimal protocol driver for measuring: it plans a scenario on the device and sends nothing
//! while the device plans (no status polls), so the firmware's per-plan instruction count is the
//! planner's work plus decoding the request and encoding the result, independent of timing.

use anyhow::{anyhow, bail, Context, Result};
use planner_core::wire::{
    encode_frame, Chunk, DeviceInfo, FrameDecoder, Header, PlanRequest, PlanResult, Reply,
    ReplyBody, Request, RequestBody, ENCODE_SCRATCH, MAX_CHUNK, MAX_FRAME, MAX_PLAN_REQUEST,
};
use planner_core::Scenario;
use std::io::{ErrorKind, Read, Write};
use std::net::TcpStream;
use std::time::{Duration, Instant};

/// A device on a TCP byte stream (QEMU's `-serial tcp:...`).
pub struct Device {
    stream: TcpStream,
    decoder: FrameDecoder<MAX_FRAME>,
    next_id: u16,
    /// Longest a plan may take before the device is declared stuck.
    pub plan_timeout: Duration,
}

impl Device {
    /// Wraps a connected stream.
    pub fn new(stream: TcpStream) -> Result<Self> {
        stream.set_nodelay(true)?;
        Ok(Device {
            stream,
            decoder: FrameDecoder::for_replies(),
            next_id: 1,
            plan_timeout: Duration::from_secs(600),
        })
    }

    fn send(&mut self, id: u16, body: RequestBody) -> Result<()> {
        let request = Request {
            header: Header::new(id),
            body,
        };
        let mut scratch = [0u8; ENCODE_SCRATCH];
        let mut frame = Vec::new();
        encode_frame(&request, &mut scratch, &mut |b: &[u8]| {
            frame.extend_from_slice(b)
        })
        .map_err(|e| anyhow!("cannot encode request: {e:?}"))?;
        self.stream
            .write_all(&frame)
            .context("writing to the device")
    }

    /// Waits for the next reply frame with request id `id` (faults about unreadable frames carry
    /// id 0 and are returned too).
    fn receive(&mut self, id: u16, timeout: Duration) -> Result<Option<ReplyBody>> {
        let deadline = Instant::now() + timeout;
        let mut byte = [0u8; 1];
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return Ok(None);
            }
            self.stream.set_read_timeout(Some(left))?;
            match self.stream.read(&mut byte) {
                Ok(0) => bail!("the device closed the connection"),
                Ok(_) => {}
                Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {
                    return Ok(None)
                }
                Err(e) => return Err(e).context("reading from the device"),
            }
            let Some(frame) = self.decoder.push(byte[0]) else {
                continue;
            };
            let Ok(payload) = frame else { continue };
            let Ok(reply) = postcard::from_bytes::<Reply>(payload) else {
                continue;
            };
            if reply.header.id == id || reply.header.id == 0 {
                return Ok(Some(reply.body));
            }
        }
    }

    fn fresh_id(&mut self) -> u16 {
        let id = self.next_id;
        self.next_id = self.next_id.wrapping_add(1).max(1);
        id
    }

    /// Asks for the device's identity, repeating the hello until it answers (an emulated STM32
    /// USART drops bytes that arrive before the firmware has enabled its receiver).
    pub fn hello(&mut self, patience: Duration) -> Result<DeviceInfo> {
        let deadline = Instant::now() + patience;
        while Instant::now() < deadline {
            let id = self.fresh_id();
            self.send(id, RequestBody::Hello)?;
            if let Some(ReplyBody::Hello(info)) = self.receive(id, Duration::from_millis(300))? {
                return Ok(info);
            }
        }
        bail!("the device did not answer a hello within {patience:?}")
    }

    /// Plans `scenario` on the device: upload, wait for the result, fetch it.
    pub fn plan(&mut self, scenario: &Scenario) -> Result<PlanResult> {
        let id = self.fresh_id();
        let mut encoded = vec![0u8; MAX_PLAN_REQUEST];
        let total = postcard::to_slice(&PlanRequest::new(scenario), &mut encoded)
            .map_err(|e| anyhow!("cannot encode the scenario: {e}"))?
            .len();
        let crc = planner_core::wire::crc::crc32(&encoded[..total]);
        let step = Duration::from_secs(5);
        for (i, chunk) in encoded[..total].chunks(MAX_CHUNK).enumerate() {
            let offset = (i * MAX_CHUNK) as u16;
            let data = Chunk::from_slice(chunk).map_err(|_| anyhow!("chunk over capacity"))?;
            self.send(
                id,
                RequestBody::Upload {
                    offset,
                    total: total as u16,
                    crc,
                    data,
                },
            )?;
            match self.receive(id, step)? {
                Some(ReplyBody::Uploaded { received, .. })
                    if usize::from(received) == usize::from(offset) + chunk.len() => {}
                other => bail!("upload at {offset}: unexpected answer {other:?}"),
            }
        }
        let deadline = Instant::now() + self.plan_timeout;
        let (len, crc) = loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.receive(id, left)? {
                Some(ReplyBody::Progress { .. }) => continue,
                Some(ReplyBody::Finished { len, crc }) => break (len, crc),
                Some(other) => bail!("while planning: unexpected answer {other:?}"),
                None => bail!("no plan within {:?}", self.plan_timeout),
            }
        };
        let mut result = Vec::with_capacity(usize::from(len));
        while result.len() < usize::from(len) {
            let offset = result.len() as u16;
            self.send(
                id,
                RequestBody::Fetch {
                    offset,
                    max_len: MAX_CHUNK as u16,
                },
            )?;
            match self.receive(id, step)? {
                Some(ReplyBody::Part {
                    offset: o, data, ..
                }) if o == offset && !data.is_empty() => result.extend_from_slice(&data),
                other => bail!("fetch at {offset}: unexpected answer {other:?}"),
            }
        }
        if planner_core::wire::crc::crc32(&result) != crc {
            bail!("the reassembled result fails its CRC");
        }
        postcard::from_bytes::<PlanResult>(&result).map_err(|e| anyhow!("undecodable result: {e}"))
    }
}
