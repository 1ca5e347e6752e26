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
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
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

/// The registration file: the rigid transform taking a point in the tracker's reference frame
/// to the scenario's frame, `p_scenario = rotation · p_tracker + translation_mm`.
#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct RegistrationFile {
    /// Row-major rotation.
    rotation: [[f32; 3]; 3],
    /// Translation (mm).
    translation_mm: [f32; 3],
}

/// Reads a registration file (JSON: `rotation`, row-major, and `translation_mm`); a rotation
/// that is not rigid is refused.
pub fn load_registration(path: &std::path::Path) -> anyhow::Result<Transform> {
    use anyhow::Context;
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read the registration {}", path.display()))?;
    let r: RegistrationFile =
        serde_json::from_str(&text).with_context(|| format!("registration {}", path.display()))?;
    Transform::new(r.rotation, r.translation_mm)
        .map_err(|e| anyhow::anyhow!("registration {}: {e:?}", path.display()))
}

fn rotated(r: &[[f32; 3]; 3], v: [f32; 3]) -> [f32; 3] {
    [0, 1, 2].map(|i| r[i][0] * v[0] + r[i][1] * v[1] + r[i][2] * v[2])
}

/// `reg` applied to a point.
pub fn registered_point(reg: &Transform, p: [f32; 3]) -> [f32; 3] {
    let (r, t) = (reg.rotation(), reg.translation());
    let q = rotated(&r, p);
    [q[0] + t[0], q[1] + t[1], q[2] + t[2]]
}

/// `reg` applied to a pose (its position moved, its heading and bevel turned).
pub fn registered_pose(reg: &Transform, pose: Pose) -> Pose {
    let r = reg.rotation();
    Pose {
        position: registered_point(reg, pose.position),
        heading: rotated(&r, pose.heading),
        bevel: pose.bevel.map(|b| rotated(&r, b)),
    }
}

/// The inverse of a rigid `reg` (the scenario's frame to the tracker's).
pub fn inverse(reg: &Transform) -> Result<Transform, Error> {
    let r = reg.rotation();
    let rt = [0, 1, 2].map(|i| [r[0][i], r[1][i], r[2][i]]);
    let t = rotated(&rt, reg.translation()).map(|v| -v);
    Transform::new(rt, t)
}

/// A frame off a connection and when it arrived.
pub type Arrival = (Result<Frame, Error>, Instant);

/// Reads frames off `stream` on a thread of its own: each decoded frame or rejection goes to
/// `on_frame` with its arrival time until `on_frame` says `false` or the stream ends; then
/// `on_end` runs.
pub fn read_frames(
    stream: TcpStream,
    on_frame: impl FnMut(Arrival) -> bool + Send + 'static,
    on_end: impl FnOnce() + Send + 'static,
) -> std::thread::JoinHandle<()> {
    read_frames_counting(stream, Arc::default(), on_frame, on_end)
}

/// [`read_frames`], adding the bytes read to `received` as they arrive: bytes that came without
/// a single frame are a peer that does not speak OpenIGTLink.
pub fn read_frames_counting(
    mut stream: TcpStream,
    received: Arc<AtomicU64>,
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
            received.fetch_add(n as u64, Ordering::Relaxed);
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
    fn a_registration_and_its_inverse_undo_each_other() {
        let (c, s) = (0.6_f32, 0.8_f32);
        let reg = Transform::new(
            [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]],
            [100.0, -50.0, 25.0],
        )
        .unwrap();
        let back = inverse(&reg).unwrap();
        let p = [1.5, -2.0, 80.0];
        let there = registered_point(&reg, p);
        assert_eq!(
            there,
            [100.0 + c * 1.5 + s * 2.0, -50.0 + s * 1.5 - c * 2.0, 105.0]
        );
        let again = registered_point(&back, there);
        for (a, b) in again.iter().zip(p) {
            assert!((a - b).abs() < 1e-4, "{again:?}");
        }
        let pose = Pose {
            position: p,
            heading: [0.0, 0.0, 1.0],
            bevel: Some([1.0, 0.0, 0.0]),
        };
        let turned = registered_pose(&reg, pose);
        assert_eq!(turned.heading, [0.0, 0.0, 1.0]);
        assert_eq!(turned.bevel, Some([c, s, 0.0]));
    }

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
