//! Errors that tell the truth: every figure of a failed exchange (times sent, damaged frames,
//! elapsed time, silence) is what the transport saw, and each bound of the retry policy
//! (silence, count, deadline) is the one named. Also: stale replies are dropped, not failures.

use needle_link::{Client, ClientConfig, GaveUp, LinkError, Transport};
use planner_core::wire::{encode_frame, Header, Reply, ReplyBody, Request, ENCODE_SCRATCH};
use planner_core::wire::{FrameDecoder, RequestBody, MAX_FRAME};
use std::io;
use std::time::{Duration, Instant};

/// What a scripted device does with request number `n` (from 0): the bytes it answers with.
type Script = Box<dyn FnMut(usize, &Request) -> Vec<u8>>;

/// A device on a real clock: answers each request as scripted, and waits out `recv`'s
/// timeout in full (with a real sleep) when it has nothing to say.
struct Scripted {
    decoder: FrameDecoder<MAX_FRAME>,
    script: Script,
    pending: Vec<u8>,
    requests: usize,
    /// Delay before each answer's bytes become readable.
    delay: Duration,
    ready_at: Instant,
}

impl Scripted {
    fn new(delay: Duration, script: Script) -> Self {
        Scripted {
            decoder: FrameDecoder::for_requests(),
            script,
            pending: Vec::new(),
            requests: 0,
            delay,
            ready_at: Instant::now(),
        }
    }
}

impl Transport for Scripted {
    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        for &b in bytes {
            if let Some(Ok(payload)) = self.decoder.push(b) {
                let req: Request = postcard::from_bytes(payload).expect("a request");
                let answer = (self.script)(self.requests, &req);
                self.requests += 1;
                self.pending.extend(answer);
                self.ready_at = Instant::now() + self.delay;
            }
        }
        Ok(())
    }

    fn recv(&mut self, buf: &mut [u8], timeout: Duration) -> io::Result<usize> {
        let now = Instant::now();
        if self.pending.is_empty() {
            std::thread::sleep(timeout);
            return Ok(0);
        }
        if self.ready_at > now {
            let wait = (self.ready_at - now).min(timeout);
            std::thread::sleep(wait);
            if wait < self.ready_at - now {
                return Ok(0);
            }
        }
        let n = buf.len().min(self.pending.len());
        buf[..n].copy_from_slice(&self.pending[..n]);
        self.pending.drain(..n);
        Ok(n)
    }
}

fn frame(id: u16, body: ReplyBody) -> Vec<u8> {
    let reply = Reply {
        header: Header::new(id),
        body,
    };
    let mut scratch = [0u8; ENCODE_SCRATCH];
    let mut out = vec![0u8];
    encode_frame(&reply, &mut scratch, &mut |b: &[u8]| {
        out.extend_from_slice(b)
    })
    .unwrap();
    out
}

/// A frame that fails its CRC.
fn damaged() -> Vec<u8> {
    vec![0, 7, 1, 2, 3, 4, 5, 6, 0]
}

fn config(timeout_ms: u64, retries: u32, deadline_ms: Option<u64>) -> ClientConfig {
    ClientConfig {
        timeout: Duration::from_millis(timeout_ms),
        retries,
        deadline: deadline_ms.map(Duration::from_millis),
    }
}

/// Pings and returns the error, the time it took, and the requests the device saw.
fn failed_ping(cfg: ClientConfig, delay: Duration, script: Script) -> (LinkError, Duration, usize) {
    let mut client = Client::new(Scripted::new(delay, script), cfg);
    let start = Instant::now();
    let err = client.ping().expect_err("no pong");
    (err, start.elapsed(), client.link().requests)
}

fn tries_of(err: &LinkError) -> (needle_link::Tries, GaveUp) {
    match err {
        LinkError::NoAnswer {
            what: "ping",
            tries,
            why,
            ..
        } => (*tries, *why),
        other => panic!("expected NoAnswer for the ping, got {other}"),
    }
}

#[test]
fn a_silent_device_is_reported_with_the_silence_it_kept() {
    let (err, wall, requests) = failed_ping(
        config(400, 10, None),
        Duration::ZERO,
        Box::new(|_, _| Vec::new()),
    );
    let (tries, why) = tries_of(&err);
    assert_eq!(
        why,
        GaveUp::Silence {
            allowed: Duration::from_millis(400)
        }
    );
    assert_eq!(tries.sent as usize, requests, "{tries:?}");
    assert!(
        requests >= 2,
        "silence is answered by a resend before giving up"
    );
    assert_eq!((tries.damaged, tries.line_faults, tries.stale), (0, 0, 0));
    assert!(tries.silence >= Duration::from_millis(400), "{tries:?}");
    assert!(
        tries.elapsed >= tries.silence && tries.elapsed <= wall,
        "{tries:?} {wall:?}"
    );
    let text = err.to_string();
    assert!(
        text.contains(&format!(
            "sent {requests} times in {:.2} s",
            tries.elapsed.as_secs_f64()
        )),
        "{text}"
    );
    assert!(text.contains("0 damaged frames"), "{text}");
    assert!(text.contains("gave up after 0.40 s of silence"), "{text}");
}

#[test]
fn damaged_answers_are_resent_at_once_and_do_not_use_up_the_silence() {
    // Five damaged answers, 100 ms apart, then silence: 0.5 s of damage do not count against
    // the 0.3 s of silence allowed.
    let (err, wall, requests) = failed_ping(
        config(300, 20, None),
        Duration::from_millis(100),
        Box::new(|n, _| if n < 5 { damaged() } else { Vec::new() }),
    );
    let (tries, why) = tries_of(&err);
    assert!(matches!(why, GaveUp::Silence { .. }), "{why:?}");
    assert_eq!(tries.damaged, 5, "{tries:?}");
    assert_eq!(tries.sent as usize, requests);
    assert!(requests >= 6, "{requests}");
    assert!(tries.elapsed >= Duration::from_millis(800), "{tries:?}");
    assert!(tries.elapsed <= wall && tries.silence >= Duration::from_millis(300));
    assert!(err.to_string().contains("5 damaged frames"), "{err}");
}

#[test]
fn a_device_that_only_sends_damage_is_stopped_by_the_count() {
    let (err, _, requests) = failed_ping(
        config(500, 5, None),
        Duration::ZERO,
        Box::new(|_, _| damaged()),
    );
    let (tries, why) = tries_of(&err);
    assert_eq!(why, GaveUp::Retries { limit: 5 });
    assert_eq!((tries.sent, requests), (6, 6));
    assert_eq!(tries.damaged, 6, "{tries:?}");
    assert!(err.to_string().contains("gave up after 5 repeats"), "{err}");
}

#[test]
fn a_chattering_device_is_stopped_by_the_deadline() {
    let (err, wall, requests) = failed_ping(
        config(1_000, 10_000, Some(500)),
        Duration::from_millis(20),
        Box::new(|_, _| damaged()),
    );
    let (tries, why) = tries_of(&err);
    assert_eq!(
        why,
        GaveUp::Deadline {
            limit: Duration::from_millis(500)
        }
    );
    assert_eq!(tries.sent as usize, requests);
    assert!(tries.elapsed >= Duration::from_millis(500) && tries.elapsed <= wall);
    assert!(tries.damaged + 1 >= tries.sent, "{tries:?}");
}

#[test]
fn stale_and_duplicated_replies_are_dropped_not_failures() {
    let script: Script = Box::new(|_, req| {
        let RequestBody::Ping { nonce } = req.body else {
            return Vec::new();
        };
        let id = req.header.id;
        let mut out = frame(id.wrapping_add(7), ReplyBody::Pong { nonce });
        out.extend(frame(id, ReplyBody::Pong { nonce: !nonce }));
        out.extend(frame(id, ReplyBody::Pong { nonce }));
        out.extend(frame(id, ReplyBody::Pong { nonce }));
        out
    });
    let mut client = Client::new(
        Scripted::new(Duration::ZERO, script),
        config(2_000, 3, None),
    );
    client.ping().expect("the third frame answers");
    let s = client.stats();
    assert_eq!((s.sent, s.retried, s.stale), (1, 0, 2), "{s:?}");
    // The duplicate of the answer is read by the next exchange and dropped there.
    client.ping().expect("a second ping");
    let s = client.stats();
    assert_eq!((s.sent, s.retried, s.stale), (2, 0, 5), "{s:?}");
}
