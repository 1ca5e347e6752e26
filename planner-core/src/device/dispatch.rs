//! Dispatch: a received frame is checked (CRC, version, decoding) and its request handed to the
//! part of the service that answers it.

use super::upload::Upload;
use super::{Core, DeviceIdentity, Job};
use crate::wire::{
    DeviceInfo, Fault, FrameError, Header, ReplyBody, Request, RequestBody, MAX_CHUNK,
    MAX_PLAN_REQUEST, PROTOCOL_VERSION,
};
use crate::{DEVICE_MAX_OBSTACLES, FORM_COUNT, MAX_CONTROL_DEGREE};

impl Core {
    /// Answers one received frame (or reports why it cannot be used). Never inlined: its
    /// decoded request and reply (3 KiB) would otherwise sit under every planning step's stack.
    #[inline(never)]
    pub(super) fn handle_frame(
        &mut self,
        event: Result<&[u8], FrameError>,
        tx: &mut dyn FnMut(&[u8]),
    ) {
        let payload = match event {
            Ok(p) => p,
            Err(e) => {
                let fault = match e {
                    FrameError::BadCrc => {
                        self.stats.bad_crc += 1;
                        Fault::BadCrc
                    }
                    FrameError::TooLong => {
                        self.stats.too_long += 1;
                        Fault::FrameTooLong
                    }
                    FrameError::Truncated => {
                        self.stats.truncated += 1;
                        Fault::Truncated
                    }
                };
                return self.fault(0, fault, tx);
            }
        };
        let (header, rest) = match postcard::take_from_bytes::<Header>(payload) {
            Ok(h) => h,
            Err(_) => {
                self.stats.undecodable += 1;
                return self.fault(0, Fault::Undecodable, tx);
            }
        };
        if header.version != PROTOCOL_VERSION {
            self.stats.undecodable += 1;
            let fault = Fault::UnsupportedVersion {
                supported: PROTOCOL_VERSION,
                got: header.version,
            };
            return self.fault(header.id, fault, tx);
        }
        let body = match postcard::take_from_bytes::<RequestBody>(rest) {
            Ok((body, [])) => body,
            _ => {
                self.stats.undecodable += 1;
                return self.fault(header.id, Fault::Undecodable, tx);
            }
        };
        self.stats.frames += 1;
        self.handle(Request { header, body }, tx);
    }

    fn handle(&mut self, req: Request, tx: &mut dyn FnMut(&[u8])) {
        let id = req.header.id;
        match req.body {
            RequestBody::Hello => {
                let info = self.info();
                self.send(id, ReplyBody::Hello(info), tx);
            }
            RequestBody::Ping { nonce } => self.send(id, ReplyBody::Pong { nonce }, tx),
            RequestBody::Upload {
                offset,
                total,
                crc,
                data,
            } => self.upload(id, Upload { offset, total, crc }, &data, tx),
            RequestBody::Status => self.status(id, tx),
            RequestBody::Fetch { offset, max_len } => self.fetch(id, offset, max_len, tx),
            RequestBody::Cancel => {
                let was_active = match self.job {
                    Job::Uploading { id: a, .. } | Job::Planning { id: a, .. } => a == id,
                    _ => false,
                };
                if was_active {
                    self.job = Job::Idle;
                }
                self.send(id, ReplyBody::Cancelled { was_active }, tx);
            }
            RequestBody::SteerStart { config, max_len } => {
                self.steer_start(id, &config, max_len, tx)
            }
            RequestBody::SteerReading { reading, max_len } => {
                self.steer_reading(id, &reading, max_len, tx)
            }
            RequestBody::SteerFetch { offset, max_len } => {
                self.steer_fetch(id, offset, max_len, tx)
            }
            RequestBody::SteerStatus => self.steer_status(id, tx),
            RequestBody::SteerDrive { piece_mm } => self.drive_start(id, piece_mm, tx),
            RequestBody::Motion(m) => self.motion_request(id, &m, tx),
        }
    }

    fn info(&self) -> DeviceInfo {
        let identity = self.identity.unwrap_or(DeviceIdentity::CORE);
        DeviceInfo {
            protocol: PROTOCOL_VERSION,
            name: truncated(identity.name),
            firmware: truncated(identity.firmware),
            build: truncated(identity.build),
            max_obstacles: DEVICE_MAX_OBSTACLES as u16,
            max_control_degree: MAX_CONTROL_DEGREE as u8,
            form_count: FORM_COUNT as u8,
            max_chunk: MAX_CHUNK as u16,
            upload_capacity: MAX_PLAN_REQUEST as u16,
        }
    }
}

/// The longest prefix of `s` that fits `N` bytes, cut at a character boundary.
fn truncated<const N: usize>(s: &str) -> heapless::String<N> {
    let mut out = heapless::String::new();
    for c in s.chars() {
        if out.push(c).is_err() {
            break;
        }
    }
    out
}
