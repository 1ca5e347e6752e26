//! The simulated lab with a driver board instead of a robot: the simulated device (the very
//! `DeviceService` of the firmware) with the bench's simulated stages, stepped in real time,
//! serves `needle`'s protocol on a TCP port, one connection at a time; the host arms and homes
//! it (`needle motion`), plans on it, starts steering and has it move the insertion itself
//! (`SteerDrive`). Whenever the stages have finished a piece
//! the board queued, the world takes that piece (the tissue bends the needle as the piece was
//! cut) and the tracker shows the tip; the board's next piece waits for the host's reading.
//! The needle is set at the plan's posture (the guide's tilt set by hand, the roll the host's
//! turn before steering).

use super::{End, Lab, LabRun};
use crate::axes::SimulatedAxes;
use anyhow::{anyhow, Result};
use needle_motion::State;
use needle_sim::{finish, Tracker, World};
use planner_core::device::DeviceService;
use std::io::{ErrorKind, Read, Write};
use std::net::{TcpListener, TcpStream};
use std::ops::ControlFlow;
use std::time::{Duration, Instant};

/// Simulated time runs in steps of at most this long (ms), checked against the wall's.
const TICK_MS: u32 = 1;

/// One board for the life of the process: its device and stages, the insertion its drive is
/// moving and the world that insertion runs in.
struct Board {
    device: Box<DeviceService>,
    axes: SimulatedAxes,
    start: Instant,
    simulated_ms: u32,
    /// The insertion being driven: its world, the fault stream, the pieces the world took.
    insertion: Option<Insertion>,
    /// Insertions begun.
    begun: u64,
}

struct Insertion {
    seed: u64,
    world: World,
    faults: Tracker,
    taken: u32,
}

impl Lab {
    /// Serves the board on `listener` for ever, one connection at a time (`needle motion`'s
    /// arming and homing, then `needle steer`'s insertion); each insertion (one `SteerDrive`,
    /// the k-th in the world of seed + k) ends with its figures to `on_run`.
    pub fn serve_board(
        &self,
        listener: TcpListener,
        mut on_run: impl FnMut(&LabRun),
    ) -> Result<()> {
        let mut device = Box::new(DeviceService::with_identity(crate::IDENTITY));
        let axes = SimulatedAxes::attach(&mut device).map_err(|e| anyhow!("{e}"))?;
        let mut board = Board {
            device,
            axes,
            start: Instant::now(),
            simulated_ms: 0,
            insertion: None,
            begun: 0,
        };
        listener.set_nonblocking(true)?;
        loop {
            match listener.accept() {
                Ok((conn, _)) => {
                    if let Err(e) = self.serve_connection(&mut board, conn, &mut on_run) {
                        eprintln!("hil-sim lab: board connection: {e:#}");
                    }
                }
                Err(e) if e.kind() == ErrorKind::WouldBlock => {
                    self.tick(&mut board, &mut on_run)?;
                    std::thread::sleep(Duration::from_millis(1));
                }
                Err(e) => return Err(e.into()),
            }
        }
    }

    /// Serves `conn` until it hangs up, time running for the stages and the world.
    fn serve_connection(
        &self,
        board: &mut Board,
        mut conn: TcpStream,
        on_run: &mut impl FnMut(&LabRun),
    ) -> Result<()> {
        conn.set_nodelay(true)?;
        conn.set_nonblocking(true)?;
        let mut buf = [0u8; 512];
        let mut out = Vec::new();
        loop {
            match conn.read(&mut buf) {
                Ok(0) => return Ok(()),
                Ok(n) => board.device.receive(&buf[..n]),
                Err(e) if e.kind() == ErrorKind::WouldBlock => {}
                Err(e) => return Err(e.into()),
            }
            while board.device.poll(&mut |b: &[u8]| out.extend_from_slice(b)) {}
            if !out.is_empty() {
                write_all(&mut conn, &out)?;
                out.clear();
            }
            self.tick(board, on_run)?;
            std::thread::sleep(Duration::from_micros(500));
        }
    }

    /// Simulated time catches up with the wall's; a piece the stages have finished is taken by
    /// the world and shown by the tracker; an insertion begins with a drive and ends with it.
    fn tick(&self, board: &mut Board, on_run: &mut impl FnMut(&LabRun)) -> Result<()> {
        let due = u32::try_from(board.start.elapsed().as_millis()).unwrap_or(u32::MAX);
        while board.simulated_ms < due {
            board.axes.advance(&mut board.device, TICK_MS);
            board.simulated_ms += TICK_MS;
        }
        let driven = board.device.driven_piece();
        if driven.is_some() && board.insertion.is_none() {
            let seed = self.config.seed.wrapping_add(board.begun);
            board.begun += 1;
            board.insertion = Some(self.begin(seed)?);
        }
        let Some(ins) = board.insertion.as_mut() else {
            return Ok(());
        };
        let Some((k, piece)) = driven else {
            // The drive ended (the controller's stop, the steps ran out, a fault).
            let run = finish(&ins.world, &self.setup.planned, ins.seed);
            on_run(&LabRun::of(ins.seed, End::Stopped, ins.taken, &run));
            board.insertion = None;
            return Ok(());
        };
        let at_rest = board
            .device
            .motion()
            .map(|c| c.status())
            .is_some_and(|s| s.state == State::Armed && s.moves_left == 0);
        if k > ins.taken && at_rest {
            ins.taken = k;
            let mut last = None;
            ins.world.execute(&piece, |m| {
                last = Some(*m);
                ControlFlow::Continue(())
            });
            if let Some(m) = last {
                self.show(&mut ins.faults, &m, k)?;
            }
        }
        Ok(())
    }

    /// The world of an insertion in the world of `seed`, the needle set at the plan's posture.
    fn begin(&self, seed: u64) -> Result<Insertion> {
        // The previous insertion's pose is not this one's.
        self.tracker.wait_for_one()?;
        let s = &self.setup;
        let world = World::with_effects(
            &s.scenario,
            &s.prepared.schedule,
            &s.perturbation,
            &s.effects,
            seed,
        )
        .map_err(|e| anyhow!("{e}"))?;
        Ok(Insertion {
            seed,
            world,
            faults: Tracker::new(&s.faults, seed),
            taken: 0,
        })
    }
}

/// Writes all of `bytes` to a non-blocking socket.
fn write_all(conn: &mut TcpStream, mut bytes: &[u8]) -> Result<()> {
    while !bytes.is_empty() {
        match conn.write(bytes) {
            Ok(0) => return Err(anyhow!("the host hung up")),
            Ok(n) => bytes = &bytes[n..],
            Err(e) if e.kind() == ErrorKind::WouldBlock => {
                std::thread::sleep(Duration::from_micros(200))
            }
            Err(e) => return Err(e.into()),
        }
    }
    Ok(())
}
