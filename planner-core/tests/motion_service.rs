//! Motion over the link: the device service drives the board's motion core, here against the
//! simulated axes (`needle_motion::plant`) as a board's timer and main loop would.

use needle_motion::plant::{Plant, PlantAxis, PlantConfig};
use needle_motion::{Axis, FaultCause, MotionConfig, MotionError, Rates, SafetyConfig, State};
use planner_core::device::DeviceService;
use planner_core::execute::schedule::schedule;
use planner_core::wire::{
    encode_frame, Fault, FrameDecoder, Header, MotionRequest, MotionStatus, Reply, ReplyBody,
    Request, RequestBody, ENCODE_SCRATCH, MAX_FRAME,
};
use planner_core::{plan, Scenario};

fn ask(dev: &mut DeviceService, id: u16, req: MotionRequest) -> ReplyBody {
    let mut scratch = [0u8; ENCODE_SCRATCH];
    let mut bytes = Vec::new();
    let request = Request {
        header: Header::new(id),
        body: RequestBody::Motion(req),
    };
    encode_frame(&request, &mut scratch, &mut |b: &[u8]| {
        bytes.extend_from_slice(b)
    })
    .unwrap();
    dev.receive(&bytes);
    let mut out = Vec::new();
    while dev.poll(&mut |b: &[u8]| out.extend_from_slice(b)) {}
    let mut d = FrameDecoder::<MAX_FRAME>::for_replies();
    let mut replies: Vec<Reply> = Vec::new();
    for &b in &out {
        if let Some(p) = d.push(b) {
            replies.push(postcard::from_bytes(p.unwrap()).unwrap());
        }
    }
    assert_eq!(replies.len(), 1);
    assert_eq!(replies[0].header.id, id);
    replies[0].body.clone()
}

fn status(body: ReplyBody) -> MotionStatus {
    match body {
        ReplyBody::Motion(s) => s,
        other => panic!("not a status: {other:?}"),
    }
}

/// A board: the service with the bench axes and the simulated ones behind them.
struct Board {
    dev: DeviceService,
    plant: Plant,
}

impl Board {
    fn new() -> Board {
        let rates = Rates {
            insert_mm_s: 2.5,
            rotate_deg_s: 360.0,
            spin_rev_s: 4.0,
        };
        let cfg = MotionConfig::bench(200.0, 360.0, rates);
        let mut dev = DeviceService::new();
        dev.set_motion(cfg, SafetyConfig::BENCH).unwrap();
        let axis = |i: usize| PlantAxis {
            pull_out: 1.2 * cfg.axes[i].max_speed * cfg.axes[i].steps_per_unit,
            torque_accel: 1.2 * cfg.axes[i].max_accel * cfg.axes[i].steps_per_unit,
            full_step: 16.0,
            encoder_steps: Some(4),
        };
        let plant = Plant::new(PlantConfig {
            axes: [axis(0), axis(1)],
            tick_hz: cfg.tick_hz,
            start: [3200, 0],
            end: 201 * 1600,
        });
        Board { dev, plant }
    }

    /// Armed, homed, and 5000 steps into a spun insertion of 20 mm.
    fn spinning() -> Board {
        let mut b = Board::new();
        ask(&mut b.dev, 1, MotionRequest::Arm);
        ask(&mut b.dev, 2, MotionRequest::Home);
        b.run(usize::MAX);
        let steps = [planner_core::execute::schedule::Step {
            op: planner_core::execute::schedule::Op::InsertSpin {
                length_mm: 20.0,
                turns: 16,
            },
            duration_s: 8.0,
        }];
        let job = MotionRequest::Move {
            driver: Scenario::paper().driver,
            needle_mm: 150.0,
            steps: steps.iter().copied().collect(),
        };
        status(ask(&mut b.dev, 3, job));
        b.run(5000);
        b
    }

    /// The timer and the main loop: up to `n` steps, the inputs read after each.
    fn run(&mut self, n: usize) {
        let c = self.dev.motion().unwrap();
        for _ in 0..n {
            let Some(e) = c.next_step() else { return };
            self.plant.apply(&e);
            c.heartbeat();
            c.update(self.plant.now_ms(), &self.plant.inputs());
        }
    }
}

#[test]
fn the_host_arms_homes_and_moves_the_papers_schedule() {
    let mut b = Board::new();
    let s = status(ask(&mut b.dev, 1, MotionRequest::Status));
    assert_eq!(
        (s.state, s.homed, s.last_fault),
        (State::Disarmed, false, None)
    );
    let scenario = Scenario::paper();
    let report = plan(&scenario).unwrap();
    let sched = schedule(&scenario, report.best().unwrap()).unwrap();
    let job = MotionRequest::Move {
        driver: scenario.driver,
        needle_mm: scenario.needle.length,
        steps: sched.steps.clone(),
    };
    let refused = ReplyBody::Fault(Fault::Motion(MotionError::NotAllowed(State::Disarmed)));
    assert_eq!(ask(&mut b.dev, 2, job.clone()), refused);
    assert_eq!(
        status(ask(&mut b.dev, 3, MotionRequest::Arm)).state,
        State::Armed
    );
    let unhomed = ReplyBody::Fault(Fault::Motion(MotionError::NotHomed));
    assert_eq!(ask(&mut b.dev, 4, job.clone()), unhomed);
    assert_eq!(
        status(ask(&mut b.dev, 5, MotionRequest::Home)).state,
        State::Homing
    );
    b.run(usize::MAX);
    let s = status(ask(&mut b.dev, 6, MotionRequest::Status));
    assert_eq!(
        (s.state, s.homed, s.position),
        (State::Armed, true, [0.0, 0.0])
    );
    assert_eq!(status(ask(&mut b.dev, 7, job)).state, State::Moving);
    b.run(usize::MAX);
    let s = status(ask(&mut b.dev, 8, MotionRequest::Status));
    let inserted: f32 = sched.steps.iter().map(|st| st.op.inserted_mm()).sum();
    assert_eq!(s.state, State::Armed);
    assert!(
        (s.position[0] - inserted).abs() <= 1.0 / 1600.0,
        "{s:?} {inserted}"
    );
    assert_eq!(b.plant.missed(), [0, 0]);
}

#[test]
fn an_estop_mid_insertion_is_reported_with_both_positions_and_survives_a_reset() {
    let mut b = Board::spinning();
    let moving = status(ask(&mut b.dev, 4, MotionRequest::Status));
    assert_eq!(moving.state, State::Moving);
    b.plant.estop = true;
    b.run(1);
    let s = status(ask(&mut b.dev, 5, MotionRequest::Status));
    let f = s.last_fault.unwrap();
    assert_eq!((s.state, f.cause), (State::Faulted, FaultCause::EStop));
    assert_eq!(f.position, s.position);
    assert!(f.position[0] > 0.0 && f.position[1] != 0.0, "{f:?}");
    let latched = ReplyBody::Fault(Fault::Motion(MotionError::Faulted(FaultCause::EStop)));
    assert_eq!(ask(&mut b.dev, 6, MotionRequest::Reset), latched);
    assert_eq!(ask(&mut b.dev, 7, MotionRequest::Arm), latched);
    let active = ReplyBody::Fault(Fault::Motion(MotionError::CauseActive(FaultCause::EStop)));
    assert_eq!(ask(&mut b.dev, 8, MotionRequest::ClearFault), active);
    b.plant.estop = false;
    let c = b.dev.motion().unwrap();
    c.update(b.plant.now_ms(), &b.plant.inputs());
    let s = status(ask(&mut b.dev, 9, MotionRequest::ClearFault));
    assert_eq!((s.state, s.homed), (State::Disarmed, false));
    assert_eq!(s.last_fault.unwrap().cause, FaultCause::EStop);
}

#[test]
fn an_estop_over_the_link_stops_both_axes_at_once_and_latches_until_cleared() {
    let mut b = Board::spinning();
    let s = status(ask(&mut b.dev, 4, MotionRequest::EStop));
    let f = s.last_fault.unwrap();
    assert_eq!((s.state, f.cause), (State::Faulted, FaultCause::EStop));
    assert!(f.position[0] > 0.0 && f.position[1] != 0.0, "{f:?}");
    // Not one more step on either axis.
    assert!(b.dev.motion().unwrap().next_step().is_none());
    // A second e-stop changes nothing; a reset or an arm does not end it.
    let again = status(ask(&mut b.dev, 5, MotionRequest::EStop));
    assert_eq!(again.last_fault, Some(f));
    let latched = ReplyBody::Fault(Fault::Motion(MotionError::Faulted(FaultCause::EStop)));
    assert_eq!(ask(&mut b.dev, 6, MotionRequest::Reset), latched);
    assert_eq!(ask(&mut b.dev, 7, MotionRequest::Arm), latched);
    // Nothing holds the e-stop input: clearing ends it, disarmed and unhomed.
    let s = status(ask(&mut b.dev, 8, MotionRequest::ClearFault));
    assert_eq!((s.state, s.homed), (State::Disarmed, false));
}

#[test]
fn hold_resume_stop_and_a_soft_limit_over_the_link() {
    let mut b = Board::new();
    ask(&mut b.dev, 1, MotionRequest::Arm);
    ask(&mut b.dev, 2, MotionRequest::Home);
    b.run(usize::MAX);
    let mut driver = Scenario::paper().driver;
    let insert = |len| planner_core::execute::schedule::Step {
        op: planner_core::execute::schedule::Op::Insert { length_mm: len },
        duration_s: 1.0,
    };
    let too_far = MotionRequest::Move {
        driver,
        needle_mm: 10.0,
        steps: [insert(6.0), insert(6.0)].into_iter().collect(),
    };
    let past = ReplyBody::Fault(Fault::Motion(MotionError::SoftLimit(Axis::Insertion)));
    assert_eq!(ask(&mut b.dev, 3, too_far), past);
    driver.insert_speed = 5.0;
    let job = MotionRequest::Move {
        driver,
        needle_mm: 10.0,
        steps: [insert(6.0)].into_iter().collect(),
    };
    status(ask(&mut b.dev, 4, job));
    b.run(2000);
    assert_eq!(
        status(ask(&mut b.dev, 5, MotionRequest::Hold)).state,
        State::Holding
    );
    b.run(usize::MAX);
    let held = status(ask(&mut b.dev, 6, MotionRequest::Status));
    assert_eq!((held.state, held.speed), (State::Holding, [0.0, 0.0]));
    assert!(held.position[0] > 0.0 && held.position[0] < 6.0);
    status(ask(&mut b.dev, 7, MotionRequest::Resume));
    b.run(100);
    assert_eq!(
        status(ask(&mut b.dev, 8, MotionRequest::Stop)).state,
        State::Moving
    );
    b.run(usize::MAX);
    let s = status(ask(&mut b.dev, 9, MotionRequest::Status));
    assert_eq!((s.state, s.moves_left), (State::Armed, 0));
    assert!(s.position[0] < 6.0);
}

#[test]
fn a_device_without_axes_says_so() {
    let mut dev = DeviceService::new();
    assert_eq!(
        ask(&mut dev, 1, MotionRequest::Arm),
        ReplyBody::Fault(Fault::NoMotion)
    );
}

/// A board that keeps the core where its interrupts reach it, and lends it per request.
struct KeptCore(std::sync::Mutex<Option<needle_motion::Controller>>);

impl planner_core::device::MotionPort for KeptCore {
    fn with_motion(&self, f: &mut dyn FnMut(&mut needle_motion::Controller)) {
        if let Some(c) = self.0.lock().unwrap().as_mut() {
            f(c);
        }
    }
}

#[test]
fn a_core_the_board_keeps_answers_through_its_port() {
    let cfg = needle_motion::bench::bench_config();
    let core = needle_motion::Controller::new(cfg, SafetyConfig::BENCH).unwrap();
    let kept: &'static KeptCore = Box::leak(Box::new(KeptCore(Some(core).into())));
    let mut dev = DeviceService::new();
    dev.set_motion_port(kept);
    assert!(dev.motion().is_none());
    assert_eq!(
        status(ask(&mut dev, 1, MotionRequest::Arm)).state,
        State::Armed
    );
    assert_eq!(
        status(ask(&mut dev, 2, MotionRequest::Home)).state,
        State::Homing
    );
    // The board's timer steps the core between requests; the service sees where it got.
    let stepped = {
        let mut guard = kept.0.lock().unwrap();
        let c = guard.as_mut().unwrap();
        (0..100).filter_map(|_| c.next_step()).count()
    };
    assert_eq!(stepped, 100);
    let s = status(ask(&mut dev, 3, MotionRequest::EStop));
    // 100 steps of homing back, at 1600 steps a millimetre.
    let f = s.last_fault.unwrap();
    assert_eq!(
        (s.state, f.position),
        (State::Faulted, [-100.0 / 1600.0, 0.0])
    );
    assert!(kept
        .0
        .lock()
        .unwrap()
        .as_mut()
        .unwrap()
        .next_step()
        .is_none());
    // A board that cannot lend its core (its set-up failed) answers as one without axes.
    *kept.0.lock().unwrap() = None;
    assert_eq!(
        ask(&mut dev, 4, MotionRequest::Status),
        ReplyBody::Fault(Fault::NoMotion)
    );
}
