//! Fetching an encoded answer in chunks (a plan's result, a long steering answer), checked
//! against the CRC the device announced.

use crate::client::Client;
use crate::error::LinkError;
use crate::transport::Transport;
use planner_core::wire::crc::crc32;
use planner_core::wire::{ReplyBody, RequestBody};

impl<T: Transport> Client<T> {
    /// The `len` bytes of request `id`'s result; fetched again whole while they fail `crc`.
    pub(crate) fn fetch(&mut self, id: u16, len: u16, crc: u32) -> Result<Vec<u8>, LinkError> {
        self.fetch_parts("fetch", id, len, crc, |offset, max_len| {
            RequestBody::Fetch { offset, max_len }
        })
    }

    /// The `len` bytes `request(offset, max_len)` returns in [`ReplyBody::Part`]s; fetched
    /// again whole while they fail `crc`.
    pub(crate) fn fetch_parts(
        &mut self,
        what: &'static str,
        id: u16,
        len: u16,
        crc: u32,
        request: impl Fn(u16, u16) -> RequestBody,
    ) -> Result<Vec<u8>, LinkError> {
        for _ in 0..=self.config.retries {
            let mut out = Vec::with_capacity(usize::from(len));
            while out.len() < usize::from(len) {
                let offset = out.len() as u16;
                let make = |chunk: usize| request(offset, chunk as u16);
                let data = self.exchange_with(what, Some(offset), id, make, &mut |b| match b {
                    ReplyBody::Part {
                        offset: o,
                        total,
                        data,
                    } if *o == offset && *total == len && !data.is_empty() => Some(data.clone()),
                    _ => None,
                })?;
                out.extend_from_slice(&data);
            }
            out.truncate(usize::from(len));
            if crc32(&out) == crc {
                return Ok(out);
            }
            self.stats.detected += 1;
        }
        Err(LinkError::CorruptResult)
    }
}
