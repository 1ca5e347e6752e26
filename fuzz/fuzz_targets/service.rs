//! Feeds arbitrary bytes to the frame decoder and the device service, split at arbitrary points.
//!
//! Checks: nothing panics; the service always goes idle within a bounded number of polls; every
//! byte it sends parses back as well-formed frames carrying `Reply` messages; the decoder never
//! yields a payload that fails its own CRC.

#![no_main]

use libfuzzer_sys::fuzz_target;
use planner_core::device::DeviceService;
use planner_core::wire::{FrameDecoder, Reply, MAX_FRAME};

fuzz_target!(|data: &[u8]| {
    // The first byte picks the split size, so chunk boundaries vary too.
    let Some((&split, rest)) = data.split_first() else {
        return;
    };
    let split = usize::from(split % 64) + 1;
    let mut device = Box::new(DeviceService::new());
    let mut out = Vec::new();
    for chunk in rest.chunks(split) {
        device.receive(chunk);
        let mut polls = 0;
        while device.poll(&mut |b: &[u8]| out.extend_from_slice(b)) {
            polls += 1;
            // Each poll handles a frame or plans one form: both run out.
            assert!(polls < 10_000, "service never went idle");
        }
    }
    let mut decoder = FrameDecoder::<MAX_FRAME>::for_replies();
    for &b in &out {
        if let Some(ev) = decoder.push(b) {
            let payload = ev.expect("the device sent a damaged frame");
            postcard::from_bytes::<Reply>(payload).expect("the device sent a non-reply");
        }
    }
});
