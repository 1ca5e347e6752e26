//! The short requests: greeting (with the version check), ping and cancel.

use crate::client::{Client, ClientConfig, MIN_CHUNK};
use crate::error::LinkError;
use crate::transport::Transport;
use planner_core::wire::{DeviceInfo, ReplyBody, RequestBody, MAX_CHUNK, PROTOCOL_VERSION};
use std::time::{Duration, Instant};

impl<T: Transport> Client<T> {
    /// Asks the device who it is; fails on a protocol version mismatch.
    pub fn hello(&mut self) -> Result<DeviceInfo, LinkError> {
        self.begin();
        let id = self.new_id();
        let info = self.exchange("hello", id, &RequestBody::Hello, |b| match b {
            ReplyBody::Hello(info) => Some(info.clone()),
            _ => None,
        })?;
        if info.protocol != PROTOCOL_VERSION {
            return Err(LinkError::Version {
                device: info.protocol,
            });
        }
        self.max_chunk = usize::from(info.max_chunk).clamp(MIN_CHUNK, MAX_CHUNK);
        self.chunk = self.chunk.min(self.max_chunk);
        Ok(info)
    }

    /// Greets a device that may not listen yet: a new hello every `interval` until one is
    /// answered or `patience` has passed. An emulated STM32 USART drops the bytes that arrive
    /// before the firmware has enabled its receiver, so the first hellos are lost; one attempt
    /// per hello keeps that silence from shrinking the chunk size as a noisy line would.
    pub fn hello_within(
        &mut self,
        patience: Duration,
        interval: Duration,
    ) -> Result<DeviceInfo, LinkError> {
        let config = self.config;
        self.config = ClientConfig {
            timeout: interval,
            retries: 0,
            deadline: None,
        };
        let start = Instant::now();
        let deadline = start + patience;
        let mut sent = 0u32;
        let result = loop {
            match self.hello() {
                Err(LinkError::NoAnswer { tries, .. }) if Instant::now() < deadline => {
                    sent = sent.saturating_add(tries.sent);
                }
                Err(LinkError::NoAnswer {
                    what,
                    offset,
                    mut tries,
                    why,
                }) => {
                    tries.sent = sent.saturating_add(tries.sent);
                    tries.elapsed = start.elapsed();
                    break Err(LinkError::NoAnswer {
                        what,
                        offset,
                        tries,
                        why,
                    });
                }
                other => break other,
            }
        };
        self.config = config;
        result
    }

    /// Round-trip time of one ping.
    pub fn ping(&mut self) -> Result<Duration, LinkError> {
        self.begin();
        let id = self.new_id();
        let nonce = u32::from(id) << 16 | 0x5A5A;
        let start = Instant::now();
        self.exchange("ping", id, &RequestBody::Ping { nonce }, |b| {
            matches!(b, ReplyBody::Pong { nonce: n } if *n == nonce).then_some(())
        })?;
        Ok(start.elapsed())
    }

    /// Stops request `id` on the device; true if something was running.
    pub fn cancel(&mut self, id: u16) -> Result<bool, LinkError> {
        self.begin();
        self.cancel_inner(id)
    }

    /// `cancel` within the operation already under way.
    pub(crate) fn cancel_inner(&mut self, id: u16) -> Result<bool, LinkError> {
        self.exchange("cancel", id, &RequestBody::Cancel, |b| match b {
            ReplyBody::Cancelled { was_active } => Some(*was_active),
            _ => None,
        })
    }
}
