//! The client as `cargo xtask device-bench` drives it: ids from 1, a hello repeated until the device
//! listens, and nothing sent while the device plans (a status query would be counted in the
//! firmware's instructions per plan).

mod wire_support;

use hil_sim::InProcess;
use needle_e2e::example;
use needle_link::{Client, ClientConfig, GaveUp, LinkError, Transport};
use planner_core::wire::{
    encode_frame, FrameDecoder, Header, Reply, ReplyBody, Request, RequestBody, ENCODE_SCRATCH,
    MAX_FRAME,
};
use std::collections::VecDeque;
use std::io::{self, Read};
use std::time::{Duration, Instant};
use wire_support::Sim;

/// The in-process device, with every request the client sent decoded on the way.
struct Recorded {
    sim: Sim,
    decoder: FrameDecoder<MAX_FRAME>,
    requests: Vec<Request>,
}

impl Transport for Recorded {
    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        for &b in bytes {
            if let Some(Ok(payload)) = self.decoder.push(b) {
                self.requests
                    .push(postcard::from_bytes(payload).expect("the client sends requests"));
            }
        }
        self.sim.send(bytes)
    }

    fn recv(&mut self, buf: &mut [u8], timeout: Duration) -> io::Result<usize> {
        self.sim.recv(buf, timeout)
    }
}

const LINK: ClientConfig = ClientConfig {
    timeout: Duration::from_secs(5),
    retries: 0,
    deadline: None,
};

#[test]
fn a_quiet_session_asks_nothing_while_planning_and_numbers_from_one() {
    let link = Recorded {
        sim: Sim(InProcess::new()),
        decoder: FrameDecoder::for_requests(),
        requests: Vec::new(),
    };
    let mut client = Client::new(link, LINK)
        .with_first_id(1)
        .with_quiet_planning(Duration::from_secs(600));
    client
        .hello_within(Duration::from_secs(1), Duration::from_millis(100))
        .expect("hello");
    let paper = needle_scenario::load_scenario(&example("paper")).expect("paper.toml");
    let on_device = client.plan(&paper, &mut |_| {}).expect("plan");
    assert_eq!(
        postcard::to_stdvec(&on_device).unwrap(),
        postcard::to_stdvec(&planner_core::device::plan_as_device(&paper, None)).unwrap(),
        "the device's plan is the host's"
    );

    let requests = &client.link().requests;
    let ids: Vec<u16> = requests.iter().map(|r| r.header.id).collect();
    assert_eq!(ids[0], 1, "the hello is request 1");
    assert!(ids[1..].iter().all(|&id| id == 2), "the plan is request 2");
    assert!(matches!(requests[0].body, RequestBody::Hello));
    assert!(
        requests[1..].iter().all(|r| matches!(
            r.body,
            RequestBody::Upload { .. } | RequestBody::Fetch { .. }
        )),
        "only upload and fetch frames after the hello: {:?}",
        requests.iter().map(|r| &r.body).collect::<Vec<_>>()
    );
    assert_eq!(client.stats().retried, 0);
}

/// A device that never answers (an emulated USART whose receiver is not enabled yet, for ever).
struct Deaf {
    hellos: usize,
}

impl Transport for Deaf {
    fn send(&mut self, _bytes: &[u8]) -> io::Result<()> {
        self.hellos += 1;
        Ok(())
    }

    fn recv(&mut self, _buf: &mut [u8], timeout: Duration) -> io::Result<usize> {
        std::thread::sleep(timeout);
        Ok(0)
    }
}

#[test]
fn hello_within_repeats_the_hello_until_its_patience_runs_out() {
    let mut client = Client::new(Deaf { hellos: 0 }, LINK);
    let start = Instant::now();
    let err = client
        .hello_within(Duration::from_millis(500), Duration::from_millis(100))
        .expect_err("nobody answers");
    let waited = start.elapsed();
    assert!(
        waited >= Duration::from_millis(500) && waited < Duration::from_secs(3),
        "{waited:?}"
    );
    let sent = client.link().hellos;
    // Five when each wait takes its 0.1 s; fewer on a loaded machine, where sleeps run long.
    assert!(
        (2..=6).contains(&sent),
        "{sent} hellos in 0.5 s, 0.1 s apart"
    );
    match err {
        LinkError::NoAnswer {
            what: "hello",
            tries,
            why,
            ..
        } => {
            assert_eq!(tries.sent as usize, sent);
            assert!(tries.elapsed >= Duration::from_millis(500), "{tries:?}");
            assert!(tries.elapsed <= waited, "{tries:?} in {waited:?}");
            assert_eq!(
                why,
                GaveUp::Silence {
                    allowed: Duration::from_millis(100)
                }
            );
        }
        other => panic!("expected NoAnswer, got {other}"),
    }
}

/// A device that takes the upload and then never says another word.
struct Mute {
    decoder: FrameDecoder<MAX_FRAME>,
    requests: Vec<RequestBody>,
    pending: VecDeque<u8>,
}

impl Mute {
    fn new() -> Self {
        Mute {
            decoder: FrameDecoder::for_requests(),
            requests: Vec::new(),
            pending: VecDeque::new(),
        }
    }
}

impl Transport for Mute {
    fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        for &b in bytes {
            let Some(Ok(payload)) = self.decoder.push(b) else {
                continue;
            };
            let request: Request = postcard::from_bytes(payload).expect("a request");
            if let RequestBody::Upload { total, .. } = request.body {
                let ack = Reply {
                    header: Header::new(request.header.id),
                    body: ReplyBody::Uploaded {
                        received: total,
                        total,
                    },
                };
                let mut scratch = [0u8; ENCODE_SCRATCH];
                self.pending.push_back(0);
                encode_frame(&ack, &mut scratch, &mut |b: &[u8]| self.pending.extend(b))
                    .expect("an ack fits");
            }
            self.requests.push(request.body);
        }
        Ok(())
    }

    /// Silence costs no time here: returning nothing is the timeout.
    fn recv(&mut self, buf: &mut [u8], _timeout: Duration) -> io::Result<usize> {
        self.pending.read(buf)
    }
}

#[test]
fn a_quiet_session_gives_up_on_a_silent_plan_without_asking_for_its_status() {
    let paper = needle_scenario::load_scenario(&example("paper")).expect("paper.toml");
    let limit = Duration::from_secs(600);
    let mut quiet = Client::new(Mute::new(), LINK).with_quiet_planning(limit);
    match quiet.plan(&paper, &mut |_| {}) {
        Err(LinkError::NoResult { waited }) => assert_eq!(waited, limit),
        other => panic!("expected NoResult, got {other:?}"),
    }
    let asked = &quiet.link().requests;
    assert!(
        matches!(asked[..], [RequestBody::Upload { .. }, RequestBody::Cancel]),
        "upload, then only the cancel of the abandoned plan: {asked:?}"
    );

    // The same silence makes the usual session ask.
    let mut usual = Client::new(Mute::new(), LINK);
    assert!(usual.plan(&paper, &mut |_| {}).is_err());
    assert!(
        usual
            .link()
            .requests
            .iter()
            .any(|r| matches!(r, RequestBody::Status)),
        "{:?}",
        usual.link().requests
    );
}
