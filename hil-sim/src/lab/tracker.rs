//! The simulated lab's tracker: an OpenIGTLink server as PLUS is. Every client gets each pose
//! the world measures, a `TRANSFORM` named `TargetToReference` (the target as imaging sees it)
//! then one named `NeedleTipToReference` (the tip frame: e2 the bevel, e3 the heading), and,
//! when told, the registration as a `TRANSFORM` of its own name before them.
//!
//! Lock-step by default: a pose goes out when its piece is done, before the robot reports it.
//! With a stream rate the newest pose also goes out again at that rate, free-running, as PLUS
//! streams a tool, optionally in bursts written back to back. The world moves only at piece
//! boundaries, so between two pieces the stream repeats one sample, with its timestamp (the
//! piece's measurement time): a host can tell a new sample from a copy. A group of frames is
//! written whole, under the clients' lock, so the stream and the pieces never interleave their
//! bytes.
//!
//! The world's effects show as a real tracker shows them: a 5-DOF sensor's pose goes out with a
//! roll by a fixed rule (a 5-DOF tool's roll says nothing), a piece without a new image of the
//! target goes out without the target, a dropout as a tip flagged invalid.

use super::Flag;
use anyhow::{anyhow, bail, Result};
use needle_igtl::crc::crc64;
use needle_igtl::{encode_frame, Extended, FrameInfo, Message, Status, StatusCode};
use needle_igtl::{TextEncoding, Timestamp, Transform, HEADER_SIZE};
use needle_lab::wire::{inverse, now, registered_point, registered_pose, tip_transform};
use needle_lab::wire::{TARGET_DEVICE, TIP_DEVICE};
use needle_sim::Measurement;
use planner_core::steer::Pose;
use std::collections::VecDeque;
use std::io::Write;
use std::net::{TcpListener, TcpStream};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};

/// How long the robot waits for a tracker client before its first piece (a pose sent to nobody
/// would be lost to the host).
const TRACKER_WAIT: Duration = Duration::from_secs(10);

/// Every this many stream periods a burst goes out instead of one pose.
const BURST_EVERY: u32 = 50;

/// What the tracker sends besides the poses, and how.
#[derive(Clone, Debug, Default)]
pub struct TrackerConfig {
    /// The registration (tracker to scenario frame): poses go out in the frame it maps from.
    pub registration: Option<Transform>,
    /// Send the registration as a `TRANSFORM` of this name (on connecting, and with each pose).
    pub registration_name: Option<String>,
    /// Test fault: after this many pieces the registration sent is moved 5 mm along x (the
    /// poses stay in the first one's frame).
    pub registration_change_after: Option<u32>,
    /// Test fault: before every this many pieces' pose (sampling free-running: every this many
    /// samples), one bad frame (cycling through a bad CRC, a wrong body size, a 20-byte name
    /// that is not UTF-8, a non-rigid matrix, and a 20-byte name one letter off the tip's).
    pub bad_frames_every: Option<u32>,
    /// Poses go out only as the free-running sampler takes them ([`TrackerClients::sample`]),
    /// not when a piece ends.
    pub sampling: bool,
}

/// The newest pose, as measured, and how it is flagged.
#[derive(Clone, Copy)]
struct Sample {
    m: Measurement,
    flag: Option<Flag>,
    piece: u32,
    stamp: Timestamp,
}

/// The tracker's clients and what it streams; a client whose socket fails is dropped.
#[derive(Clone, Default)]
pub struct TrackerClients {
    clients: Arc<Mutex<Vec<TcpStream>>>,
    latest: Arc<Mutex<Option<Sample>>>,
    config: Arc<TrackerConfig>,
}

fn locked<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    // A thread that panicked left the data as it was; it is still the newest.
    m.lock().unwrap_or_else(|p| p.into_inner())
}

impl TrackerClients {
    /// A tracker sending as `config` says.
    pub fn new(config: TrackerConfig) -> TrackerClients {
        TrackerClients {
            config: Arc::new(config),
            ..TrackerClients::default()
        }
    }

    /// Accepts tracker clients on `listener` for the life of the process; each is sent the
    /// registration first, if the tracker sends one.
    pub fn accept(&self, listener: TcpListener) {
        let tracker = self.clone();
        std::thread::spawn(move || {
            for mut conn in listener.incoming().flatten() {
                let _ = conn.set_nodelay(true);
                let mut list = locked(&tracker.clients);
                let first = tracker.registration_frame(0).unwrap_or_default();
                if conn.write_all(&first).is_ok() {
                    list.push(conn);
                }
            }
        });
    }

    /// Streams the newest pose `rate_hz` times a second for the life of the process; every
    /// [`BURST_EVERY`] periods `burst` copies go out back to back in one write.
    pub fn stream(&self, rate_hz: f64, burst: u32) {
        let tracker = self.clone();
        let period = Duration::from_secs_f64(1.0 / rate_hz);
        std::thread::spawn(move || {
            let mut next = Instant::now();
            for tick in 1u32.. {
                next += period;
                match next.checked_duration_since(Instant::now()) {
                    Some(wait) => std::thread::sleep(wait),
                    // Late by more than a period (a loaded machine): no catching up in a rush.
                    None => next = Instant::now(),
                }
                let Some(sample) = *locked(&tracker.latest) else {
                    continue;
                };
                let copies = if tick % BURST_EVERY == 0 { burst } else { 1 };
                let _ = tracker.send(&sample, copies.max(1), None);
            }
        });
    }

    /// Drops the clients that hung up, and counts the others: a client of an earlier
    /// insertion must not stand in for the one about to steer.
    fn live(&self) -> usize {
        let mut list = locked(&self.clients);
        list.retain(|c| {
            let mut byte = [0u8; 1];
            let hung_up = c.set_nonblocking(true).is_err()
                || match c.peek(&mut byte) {
                    Ok(0) => true,
                    Ok(_) => false,
                    Err(e) => e.kind() != std::io::ErrorKind::WouldBlock,
                };
            !hung_up && c.set_nonblocking(false).is_ok()
        });
        list.len()
    }

    /// Waits for a client (and forgets the previous insertion's pose: nothing is streamed until
    /// this one's first piece).
    pub(super) fn wait_for_one(&self) -> Result<()> {
        *locked(&self.latest) = None;
        let start = Instant::now();
        while self.live() == 0 {
            if start.elapsed() > TRACKER_WAIT {
                bail!("no tracker client connected");
            }
            std::thread::sleep(Duration::from_millis(5));
        }
        Ok(())
    }

    /// The tracker goes quiet (a test fault): the stream stops too.
    pub(super) fn silence(&self) {
        *locked(&self.latest) = None;
    }

    /// The tip is now as `m` measures it (the piece `piece` ended): gives the time it became
    /// so. Lock-step, its pose goes out now, stamped then, and is the one the stream repeats;
    /// sampling free-running, the stream's next sample sees it.
    pub(super) fn publish(
        &self,
        m: &Measurement,
        flag: Option<Flag>,
        piece: u32,
    ) -> Result<Timestamp> {
        let sample = {
            // Under the lock: a sample stamped from this instant on sees this pose.
            let mut latest = locked(&self.latest);
            let sample = Sample {
                m: *m,
                flag,
                piece,
                stamp: now(),
            };
            *latest = Some(sample);
            sample
        };
        if !self.config.sampling {
            let fault = self.fault_before(piece);
            self.send(&sample, 1, fault)?;
        }
        Ok(sample.stamp)
    }

    /// Samples the tip `rate_hz` times a second, free-running, as a tracker does: each sample is
    /// the tip as it is at that instant, stamped then (between two pieces' ends the tip is
    /// where the last one left it: a piece's pose is seen once it ended); each goes out `lag`
    /// after it was sampled (a tracker and link that deliver late).
    pub fn sample(&self, rate_hz: f64, lag: Duration) {
        let tracker = self.clone();
        let period = Duration::from_secs_f64(1.0 / rate_hz);
        std::thread::spawn(move || {
            let mut waiting: VecDeque<(Instant, Sample)> = VecDeque::new();
            let mut next = Instant::now();
            let mut sent = 0u32;
            loop {
                next += period;
                match next.checked_duration_since(Instant::now()) {
                    Some(wait) => std::thread::sleep(wait),
                    None => next = Instant::now(),
                }
                let sampled = {
                    let latest = locked(&tracker.latest);
                    latest.map(|s| Sample { stamp: now(), ..s })
                };
                if let Some(s) = sampled {
                    waiting.push_back((Instant::now(), s));
                }
                while let Some((at, s)) = waiting.front().copied() {
                    if at.elapsed() < lag {
                        break;
                    }
                    waiting.pop_front();
                    sent = sent.wrapping_add(1);
                    let _ = tracker.send(&s, 1, tracker.fault_before(sent));
                }
            }
        });
    }

    /// Which bad frame, if any, goes before the `count`th pose (pieces lock-step, samples
    /// free-running): one every `bad_frames_every`, the kinds in turn.
    fn fault_before(&self, count: u32) -> Option<u32> {
        let n = self.config.bad_frames_every.filter(|&n| n > 0)?;
        count.is_multiple_of(n).then_some(count / n)
    }

    /// Writes `copies` groups of `sample`'s frames to every client, in one write each, after
    /// the bad frame `fault` if one is due.
    fn send(&self, sample: &Sample, copies: u32, fault: Option<u32>) -> Result<()> {
        let mut bytes = Vec::new();
        if let Some(k) = fault {
            bytes.extend(bad_frame(k)?);
        }
        let group = self.group(sample)?;
        for _ in 0..copies {
            bytes.extend_from_slice(&group);
        }
        let mut list = locked(&self.clients);
        list.retain_mut(|c| c.write_all(&bytes).and_then(|()| c.flush()).is_ok());
        Ok(())
    }

    /// The registration's frame as sent after `piece` pieces (empty when none is sent).
    fn registration_frame(&self, piece: u32) -> Result<Vec<u8>> {
        let (Some(name), Some(reg)) = (&self.config.registration_name, self.config.registration)
        else {
            return Ok(Vec::new());
        };
        let moved = self
            .config
            .registration_change_after
            .is_some_and(|n| piece > n);
        let mut t = reg.translation();
        if moved {
            t[0] += 5.0;
        }
        let sent = Transform::new(reg.rotation(), t).map_err(|e| anyhow!("{e:?}"))?;
        frame(&info(name)?, &Message::Transform(sent))
    }

    /// The frames of one pose: the registration (if sent), the target, then the tip, flagged
    /// invalid by `flag`.
    fn group(&self, sample: &Sample) -> Result<Vec<u8>> {
        let m = &match &self.config.registration {
            Some(reg) => in_frame(&inverse(reg).map_err(|e| anyhow!("{e:?}"))?, &sample.m),
            None => sample.m,
        };
        // A 5-DOF coil measures no roll: its pose carries one of no meaning, as a 5-DOF tool's
        // does (`needle steer --tracker-dof 5` leaves it out).
        let bevel = if m.roll_seen {
            m.bevel
        } else {
            across(m.heading)
        };
        let tip = tip_transform(m.position, m.heading, bevel)
            .map_err(|e| anyhow!("the simulated tip is no pose: {e:?}"))?;
        let target = Transform::new(Transform::IDENTITY.rotation(), m.target)
            .map_err(|e| anyhow!("the simulated target is no position: {e:?}"))?;
        let stamped = |name| -> Result<FrameInfo> {
            let mut i = info(name)?;
            i.timestamp = sample.stamp;
            Ok(i)
        };
        let mut tip_info = stamped(TIP_DEVICE)?;
        if sample.flag == Some(Flag::Metadata) {
            let mut ext = Extended::default();
            ext.metadata
                .insert("TransformStatus", TextEncoding::UsAscii, "INVALID")
                .map_err(|e| anyhow!("{e:?}"))?;
            tip_info.extended = Some(ext);
        }
        let status = |code| Message::Status(Status::new(code));
        let by_status = sample.flag == Some(Flag::Status);
        let mut out = self.registration_frame(sample.piece)?;
        // No new image of the target since the last piece: no target (imaging at its own rate).
        if m.target_seen {
            out.extend(frame(
                &stamped(TARGET_DEVICE)?,
                &Message::Transform(target),
            )?);
        }
        if by_status {
            out.extend(frame(
                &stamped(TIP_DEVICE)?,
                &status(StatusCode::NOT_READY),
            )?);
        }
        out.extend(frame(&tip_info, &Message::Transform(tip))?);
        if by_status {
            out.extend(frame(&stamped(TIP_DEVICE)?, &status(StatusCode::OK))?);
        }
        Ok(out)
    }
}

/// A unit vector across the unit `heading`, by a fixed rule (the axis least along it, its part
/// across): the roll a 5-DOF sensor's pose is given, which says nothing of the bevel.
fn across(heading: [f32; 3]) -> [f32; 3] {
    let mut axis = [0.0f32; 3];
    let least = (0..3)
        .min_by(|&i, &j| heading[i].abs().total_cmp(&heading[j].abs()))
        .unwrap_or(0);
    axis[least] = 1.0;
    let along = heading[least];
    super::unit([0, 1, 2].map(|i| axis[i] - along * heading[i]))
}

fn info(name: &str) -> Result<FrameInfo> {
    let mut info = FrameInfo::new(name).map_err(|e| anyhow!("{name}: {e:?}"))?;
    info.timestamp = now();
    Ok(info)
}

fn frame(info: &FrameInfo, message: &Message) -> Result<Vec<u8>> {
    let mut buf = vec![0u8; 1024];
    let n = encode_frame(info, message, &mut buf).map_err(|e| anyhow!("{e:?}"))?;
    buf.truncate(n);
    Ok(buf)
}

/// The `k`-th bad frame (from 1): each kind in turn, each one a frame `needle steer` must count
/// and read past. Built from a good tip frame and altered where the codec must catch it.
fn bad_frame(k: u32) -> Result<Vec<u8>> {
    let t = tip_transform([1.0, 2.0, 3.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0])
        .map_err(|e| anyhow!("{e:?}"))?;
    let mut f = frame(&info(TIP_DEVICE)?, &Message::Transform(t))?;
    let reseal = |f: &mut Vec<u8>| {
        let crc = crc64(&f[HEADER_SIZE..]);
        let size = (f.len() - HEADER_SIZE) as u64;
        f[42..50].copy_from_slice(&size.to_be_bytes());
        f[50..58].copy_from_slice(&crc.to_be_bytes());
    };
    match (k - 1) % 5 {
        // A body byte changed after the CRC was computed.
        0 => f[HEADER_SIZE + 5] ^= 0x40,
        // 47 bytes for a 48-byte TRANSFORM, with a CRC that matches them.
        1 => {
            f.pop();
            reseal(&mut f);
        }
        // All 20 bytes of the name used (no NUL), the last one not UTF-8.
        2 => f[14..34].copy_from_slice(b"NeedleTipToReferenc\xFF"),
        // The rotation scaled by 1.1: not rigid, CRC matching.
        3 => {
            for i in 0..9 {
                let at = HEADER_SIZE + 4 * i;
                let v = f32::from_be_bytes([f[at], f[at + 1], f[at + 2], f[at + 3]]) * 1.1;
                f[at..at + 4].copy_from_slice(&v.to_be_bytes());
            }
            reseal(&mut f);
        }
        // A good frame whose 20-byte name (no NUL) is one letter off the tip's: not the tip.
        _ => f[14..34].copy_from_slice(b"NeedleTipToReferencf"),
    }
    Ok(f)
}

/// A measurement in the frame `t` maps the scenario's frame to.
fn in_frame(t: &Transform, m: &Measurement) -> Measurement {
    let pose = registered_pose(
        t,
        Pose {
            position: m.position,
            heading: m.heading,
            bevel: Some(m.bevel),
        },
    );
    Measurement {
        position: pose.position,
        heading: pose.heading,
        bevel: pose.bevel.unwrap_or(m.bevel),
        target: registered_point(t, m.target),
        ..*m
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 5-DOF roll is a unit vector across the heading, and a tip frame of it is rigid.
    #[test]
    fn the_roll_of_a_5_dof_pose_is_across_the_heading() {
        let s = 0.5f32.sqrt();
        for h in [
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 0.0],
            [0.0, -1.0, 0.0],
            [s, s, 0.0],
            [0.6, 0.0, -0.8],
            [0.48, 0.6, 0.64],
        ] {
            let b = across(h);
            let dot: f32 = (0..3).map(|i| b[i] * h[i]).sum();
            let norm: f32 = b.iter().map(|x| x * x).sum();
            assert!(
                dot.abs() < 1e-6 && (norm - 1.0).abs() < 1e-6,
                "{h:?}: {b:?}"
            );
            assert!(tip_transform([1.0, 2.0, 3.0], h, b).is_ok(), "{h:?}");
        }
    }
}
