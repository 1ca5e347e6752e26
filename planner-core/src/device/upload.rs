//! Upload: the encoded plan request arrives in chunks; a repeated or out-of-order chunk is
//! answered with where to continue, and the whole is checked by its CRC-32 before planning.

use super::{Core, Job};
use crate::wire::{Fault, ReplyBody, MAX_PLAN_REQUEST};

/// What identifies an upload: its length and CRC (with the request id).
#[derive(Clone, Copy)]
pub(super) struct Upload {
    pub(super) offset: u16,
    pub(super) total: u16,
    pub(super) crc: u32,
}

impl Core {
    /// Takes one chunk of the upload of request `id`.
    pub(super) fn upload(&mut self, id: u16, up: Upload, data: &[u8], tx: &mut dyn FnMut(&[u8])) {
        let Upload { offset, total, crc } = up;
        let ack = |received, total| ReplyBody::Uploaded { received, total };
        match self.job {
            // A repeated chunk of an upload already complete: the ack was lost.
            Job::Planning {
                id: a,
                total_bytes,
                request_crc,
                ..
            }
            | Job::Finished {
                id: a,
                total_bytes,
                request_crc,
                ..
            } if a == id && total_bytes == total && request_crc == crc => {
                return self.send(id, ack(total, total), tx);
            }
            Job::Planning { id: active, .. } => {
                return self.fault(id, Fault::Busy { active }, tx);
            }
            Job::Uploading {
                id: a,
                total: t,
                crc: c,
                received,
            } if a == id && t == total && c == crc => {
                if offset != received {
                    // A repeat or a gap: tell the host where to continue.
                    return self.send(id, ack(received, total), tx);
                }
            }
            _ => {
                if offset != 0 {
                    return self.send(id, ack(0, total), tx);
                }
                if usize::from(total) > MAX_PLAN_REQUEST {
                    let capacity = MAX_PLAN_REQUEST as u16;
                    return self.fault(
                        id,
                        Fault::TooLarge {
                            len: total,
                            capacity,
                        },
                        tx,
                    );
                }
            }
        }
        let start = usize::from(offset);
        let end = start + data.len();
        if end > usize::from(total) {
            let fault = Fault::BadOffset { offset, len: total };
            return self.fault(id, fault, tx);
        }
        self.upload[start..end].copy_from_slice(data);
        let received = end as u16;
        self.job = Job::Uploading {
            id,
            total,
            crc,
            received,
        };
        if received < total {
            return self.send(id, ack(received, total), tx);
        }
        let whole = &self.upload[..usize::from(total)];
        if crate::wire::crc::crc32(whole) != crc {
            self.job = Job::Idle;
            return self.fault(id, Fault::BadUploadCrc, tx);
        }
        self.send(id, ack(received, total), tx);
        self.start_plan(id, up, tx);
    }
}
