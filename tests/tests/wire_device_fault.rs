//! A device that reports an internal fault (what the firmware's panic handler sends) makes the
//! host stop with a clear error at once, instead of retrying into a timeout.

use needle_link::{Client, ClientConfig, Transport};
use planner_core::wire::{encode_frame, Fault, Header, Reply, ReplyBody, FAULT_SCRATCH};
use std::io;
use std::time::{Duration, Instant};

/// A link on which the device answers anything with the panic handler's frame.
struct PanickedDevice {
    pending: Vec<u8>,
    requests: usize,
}

impl Transport for PanickedDevice {
    fn send(&mut self, _bytes: &[u8]) -> io::Result<()> {
        self.requests += 1;
        let fault = Reply {
            header: Header::new(0),
            body: ReplyBody::Fault(Fault::Internal),
        };
        let mut scratch = [0u8; FAULT_SCRATCH];
        let mut frame = vec![0u8];
        encode_frame(&fault, &mut scratch, &mut |b: &[u8]| {
            frame.extend_from_slice(b)
        })
        .expect("a fault fits FAULT_SCRATCH, as in the firmware");
        self.pending.extend(frame);
        Ok(())
    }

    fn recv(&mut self, buf: &mut [u8], _timeout: Duration) -> io::Result<usize> {
        let n = buf.len().min(self.pending.len());
        buf[..n].copy_from_slice(&self.pending[..n]);
        self.pending.drain(..n);
        Ok(n)
    }
}

#[test]
fn an_internal_fault_ends_the_request_with_a_clear_error() {
    let device = PanickedDevice {
        pending: Vec::new(),
        requests: 0,
    };
    let config = ClientConfig {
        timeout: Duration::from_secs(5),
        retries: 3,
        deadline: None,
    };
    let mut client = Client::new(device, config);
    let start = Instant::now();
    let err = client
        .hello()
        .expect_err("a device that faulted gives no hello");
    assert!(
        start.elapsed() < Duration::from_secs(1),
        "no waiting for timeouts"
    );
    assert_eq!(client.link().requests, 1, "no retries after a device fault");
    let message = err.to_string();
    assert!(
        message.contains("internal error") && message.contains("restarting"),
        "{message}"
    );
}
