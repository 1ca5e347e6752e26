//! OpenIGTLink over TCP for the lab: frames written whole (a client such as pyigtl loses a
//! header that arrives in pieces), one reader thread per connection, and the tip pose as a
//! `TRANSFORM` as PLUS sends it.

use needle_igtl::{
    encode_frame, Error, Frame, FrameDecoder, FrameInfo, Message, StringMessage, Timestamp,
    Transform,
};
use planner_core::steer::Pose;
use std::io::{Read, Write};
use std::net::TcpStream;
use std::time::{Instant, SystemTime, UNIX_EPOCH};

/// Device name of the tracked needle tip (PLUS's `NeedleTip` tool to the `Reference` tool).
pub const TIP_DEVICE: &str = "NeedleTipToReference";
/// Device name of the target as imaging sees it, in the reference frame.
pub const TARGET_DEVICE: &str = "TargetToReference";
/// Largest body read whole: the robot's text and the tracker's poses are far smaller, a
/// `POLYDATA` of 256 points fits; anything larger is skipped by its size.
pub const MAX_BODY: usize = 8192;

/// When a frame is sent (the wall clock, as PLUS stamps its poses).
pub fn now() -> Timestamp {
    let t = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .unwrap_or_default();
    let seconds = u32::try_from(t.as_secs()).unwrap_or(u32::MAX);
    Timestamp::from_secs_nanos(seconds, t.subsec_nanos())
}

/// Writes one frame, whole, to `w`.
pub fn send(w: &mut impl Write, device: &str, message: &Message) -> std::io::Result<()> {
    let mut info = FrameInfo::new(device).map_err(igtl_error)?;
    info.timestamp = now();
    send_with(w, &info, message)
}

/// Writes one frame with the given info.
pub fn send_with(w: &mut impl Write, info: &FrameInfo, message: &Message) -> std::io::Result<()> {
    let mut buf = vec![0u8; MAX_BODY + 1024];
    let n = encode_frame(info, message, &mut buf).map_err(igtl_error)?;
    w.write_all(&buf[..n])?;
    w.flush()
}

/// Writes one US-ASCII `STRING`.
pub fn send_text(w: &mut impl Write, device: &str, text: &str) -> std::io::Result<()> {
    let message = Message::String(StringMessage::ascii(text).map_err(igtl_error)?);
    send(w, device, &message)
}

/// A codec error as an I/O error (what cannot be encoded is invalid data).
pub fn igtl_error(e: Error) -> std::io::Error {
    std::io::Error::new(std::io::ErrorKind::InvalidData, format!("{e:?}"))
}

fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// The tip frame as a `TRANSFORM`: columns e1 = e2 × e3, e2 the bevel, e3 the heading (the
/// needle's axis), translation the tip. The bevel and heading cross unchanged.
pub fn tip_transform(
    position: [f32; 3],
    heading: [f32; 3],
    bevel: [f32; 3],
) -> Result<Transform, Error> {
    let e1 = cross(bevel, heading);
    let mut rotation = [[0.0; 3]; 3];
    for row in 0..3 {
        rotation[row] = [e1[row], bevel[row], heading[row]];
    }
    Transform::new(rotation, position)
}

/// The pose a tip `TRANSFORM` carries (see [`tip_transform`]).
pub fn tip_pose(t: &Transform) -> Pose {
    let r = t.rotation();
    Pose {
        position: t.translation(),
        heading: [r[0][2], r[1][2], r[2][2]],
        bevel: Some([r[0][1], r[1][1], r[2][1]]),
    }
}

/// A frame off a connection and when it arrived.
pub type Arrival = (Result<Frame, Error>, Instant);

/// Reads frames off `stream` on a thread of its own: each decoded frame or rejection goes to
/// `on_frame` with its arrival time until `on_frame` says `false` or the stream ends; then
/// `on_end` runs.
pub fn read_frames(
    mut stream: TcpStream,
    mut on_frame: impl FnMut(Arrival) -> bool + Send + 'static,
    on_end: impl FnOnce() + Send + 'static,
) -> std::thread::JoinHandle<()> {
    std::thread::spawn(move || {
        let mut decoder: Box<FrameDecoder<MAX_BODY>> = Box::default();
        let mut buf = [0u8; 4096];
        'reading: loop {
            let n = match stream.read(&mut buf) {
                Ok(0) | Err(_) => break,
                Ok(n) => n,
            };
            let at = Instant::now();
            let mut input = &buf[..n];
            while let Some(result) = decoder.feed(&mut input) {
                if !on_frame((result, at)) {
                    break 'reading;
                }
            }
        }
        on_end();
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_tip_pose_crosses_as_a_transform_bit_for_bit() {
        let heading = [0.6, 0.0, 0.8];
        let bevel = [0.0, 1.0, 0.0];
        let (c, s) = (0.3_f32.cos(), 0.3_f32.sin());
        let tilted = [c * 0.6, s, c * 0.8];
        let n = tilted.iter().map(|v| v * v).sum::<f32>().sqrt();
        let tilted = tilted.map(|v| v / n);
        for (h, b) in [(heading, bevel), ([0.0, 0.0, 1.0], [1.0, 0.0, 0.0])] {
            let t = tip_transform([1.5, -2.25, 80.125], h, b).unwrap();
            let pose = tip_pose(&t);
            assert_eq!(pose.position, [1.5, -2.25, 80.125]);
            assert_eq!(pose.heading, h);
            assert_eq!(pose.bevel, Some(b));
        }
        // Not a pose: a bevel along the heading.
        assert_eq!(
            tip_transform([0.0; 3], heading, heading),
            Err(Error::NotRigid)
        );
        assert!(tip_transform([0.0; 3], tilted, bevel).is_err());
    }
}
