use hil_sim::insertion::*;
use planner_core::execute::schedule::schedule;
use planner_core::plan;
use planner_core::steer::*;

struct Dbg(Steering, World2);
struct World2;
impl Controller for Dbg {
    type Error = std::convert::Infallible;
    fn update(&mut self, m: &TipMeasurement) -> Result<SteerReply, Self::Error> {
        let r = self.0.update(m);
        let e = self.0.estimate();
        let rollerr = m
            .pose
            .and_then(|p| p.bevel)
            .map(|b| {
                let b = planner_core::model::kinematics::V3::new(b[0], b[1], b[2]);
                e.tip.e2().dot(&b).clamp(-1.0, 1.0).acos().to_degrees()
            })
            .unwrap_or(f32::NAN);
        println!("roll {rollerr:.2} seq {} depth {:.2} base {:.1} | est p {:.2?} f {:.3} | {:?} repl {} err {:.3} clr {:.2} cmd {:?}",
            m.seq, m.depth_mm, m.base_deg, [e.tip.p.x, e.tip.p.y, e.tip.p.z], e.factor, r.reading, r.replanned, r.predicted_error_mm, r.predicted_clearance_mm,
            match &r.command { Command::Replace(s) => format!("replace {:?}", s.iter().map(|x| x.op).collect::<Vec<_>>()), c => format!("{c:?}") });
        let _ = &self.1;
        Ok(r)
    }
    fn stats(&mut self) -> Result<SteerStats, Self::Error> {
        Ok(self.0.stats())
    }
}

fn main() {
    let seed: u64 = std::env::args()
        .nth(1)
        .map(|s| s.parse().unwrap())
        .unwrap_or(1);
    let file = std::env::args()
        .nth(2)
        .unwrap_or("examples/paper.toml".into());
    let (scenario, _) =
        needle_cli::scenario::load_scenario_shapes(std::path::Path::new(&file), None).unwrap();
    let best = plan(&scenario).unwrap().best().unwrap().clone();
    let s = schedule(&scenario, &best).unwrap();
    println!("{:?}", s.steps);
    let planned = Planned::of(&scenario, &best);
    let ctl = Steering::start(&scenario, &s, &SteerConfig::DEFAULT).unwrap();
    let mut d = Dbg(ctl, World2);
    let r = closed_loop(
        &scenario,
        &planned,
        &s,
        &Perturbation::default(),
        &TrackerFaults::default(),
        &mut d,
        seed,
    )
    .unwrap();
    println!(
        "target error {} stop {:?} stats {:?}",
        r.run.target_error, r.stop_reason, r.stats
    );
}
