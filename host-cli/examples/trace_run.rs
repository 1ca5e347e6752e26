//! Diagnostic: one closed-loop run of FILE traced reading by reading (true tip, estimate,
//! curvature factor, what the tip is pushed with).
use needle_cli::simulate::closed_loop_setup;
use needle_sim::{closed_loop_observed, in_process, Conditions};
use planner_core::execute::schedule::Op;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let file = std::path::PathBuf::from(&args[1]);
    let seed: u64 = args[2].parse()?;
    let setup = closed_loop_setup(&file, seed, &args[3..])?;
    let world = Conditions {
        perturbation: &setup.perturbation,
        effects: &setup.effects,
        faults: &setup.faults,
    };
    let mut ctl = in_process(&setup.scenario, &setup.prepared.schedule, &setup.config)
        .map_err(|e| format!("{e:?}"))?;
    let target = setup.scenario.target;
    let mut last = -10.0f32;
    let run = closed_loop_observed(
        &setup.scenario,
        &setup.planned,
        &setup.prepared.schedule,
        &world,
        &mut ctl,
        seed,
        |s| {
            let clear = setup
                .scenario
                .obstacles
                .iter()
                .map(|o| {
                    let c = planner_core::model::kinematics::V3::new(
                        o.center[0],
                        o.center[1],
                        o.center[2],
                    );
                    (s.tip.p - c).norm() - o.radius
                })
                .fold(f32::INFINITY, f32::min);
            if s.reading.depth_mm - last < 2.0 && clear > 1.0 {
                return;
            }
            last = s.reading.depth_mm;
            let e = s.controller.estimate();
            let t = s.tip;
            let to = e.target - t.p;
            let ahead = to.dot(&t.e3());
            let side = (to - t.e3() * ahead).norm();
            let op = match s.step.op {
                Op::Insert { .. } => "arc".to_string(),
                Op::InsertSpin { .. } => "line".to_string(),
                Op::InsertDuty { duty, .. } => format!("duty {duty:.2}"),
                Op::Rotate { .. } => "rot".to_string(),
            };
            println!(
                "clr {clear:5.2} hd {:5.2} roll {:6.1} d {:6.1} est-err {:5.2} factor {:4.2} ahead {:6.2} side {:5.2} bevel.to {:5.2} {}",
                e.tip.e3().angle(&t.e3()).to_degrees(),
                {
                    let b = e.tip.e2() - t.e3() * e.tip.e2().dot(&t.e3());
                    let ang = libm::atan2f(b.dot(&t.e1()), b.dot(&t.e2()));
                    ang.to_degrees()
                },
                s.reading.depth_mm,
                (e.tip.p - t.p).norm(),
                e.factor,
                ahead,
                side,
                t.e2().dot(&(to - t.e3() * ahead).normalize()),
                op
            );
        },
    )?;
    let _ = target;
    println!(
        "stop {:?} error {:.2} predicted {:?}",
        run.stop_reason, run.run.target_error, run.predicted_miss_mm
    );
    Ok(())
}
