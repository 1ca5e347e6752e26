//! Sending an encoded plan request in chunks.

use crate::client::Client;
use crate::error::{too_large, LinkError};
use crate::transport::Transport;
use planner_core::wire::crc::crc32;
use planner_core::wire::{Chunk, Fault, ReplyBody, RequestBody};

impl<T: Transport> Client<T> {
    /// Uploads `bytes` as request `id`, chunk by chunk from where the device says it is. An
    /// ack is the answer to the chunk at `offset` if it moves past `offset`, or starts over at 0
    /// (a device that lost the upload); any other ack repeats an earlier one and is dropped.
    pub(crate) fn upload(&mut self, id: u16, bytes: &[u8]) -> Result<(), LinkError> {
        let total = u16::try_from(bytes.len()).map_err(|_| too_large("scenario too large"))?;
        let crc = crc32(bytes);
        let mut offset = 0u16;
        while offset < total {
            let make = |chunk: usize| {
                let start = usize::from(offset);
                let n = chunk.min(usize::from(total - offset));
                RequestBody::Upload {
                    offset,
                    total,
                    crc,
                    data: Chunk::from_slice(&bytes[start..start + n]).unwrap_or_default(),
                }
            };
            let answer = self.exchange_with("upload", Some(offset), id, make, &mut |b| match b {
                ReplyBody::Uploaded { received, total: t }
                    if *t == total && (*received > offset || *received == 0) =>
                {
                    Some(*received)
                }
                _ => None,
            });
            let received = match answer {
                // Still planning a request this client gave up on: stop it and go on.
                Err(LinkError::Device(Fault::Busy { active }))
                    if Some(active) == self.abandoned =>
                {
                    self.cancel_inner(active)?;
                    self.abandoned = None;
                    continue;
                }
                other => other?,
            };
            offset = received.min(total);
        }
        Ok(())
    }
}
