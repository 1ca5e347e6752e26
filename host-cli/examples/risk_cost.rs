//! The collision-risk spread of every feasible form of `needle bench --near-and-far`'s plan, once,
//! measured as asked: `risk_cost TOTAL NEAR none|walked|kept|near|walk` (`none`: every sphere at
//! every point; `walked`: culled as the device does; `kept`: as the host does; `near`: the near
//! spheres alone, as the host does; `walk`: the walk alone, no spheres). Run under
//! `valgrind --tool=callgrind` to count instructions where the machine is too loaded to time.

use needle_analysis::scale::near_and_far;
use planner_core::execute::perturbation::Perturbation;
use planner_core::execute::risk::{risk_culled, Culling, Execution, ObstacleRisk};
use planner_core::execute::schedule::schedule;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let total: usize = args.get(1).map_or(Ok(256), |a| a.parse())?;
    let near: usize = args.get(2).map_or(Ok(32), |a| a.parse())?;
    let mode = args.get(3).map_or("kept", String::as_str);
    let both = near_and_far(1, total, near);
    let mut s = both.all;
    let report = planner_core::plan(&s)?;
    let how = match mode {
        "none" => Culling::None,
        "walked" => Culling::AsWalked,
        _ => Culling::Kept,
    };
    let schedules: Vec<_> = report
        .forms
        .iter()
        .filter(|o| o.feasible)
        .map(|o| schedule(&s, o))
        .collect::<Result<_, _>>()?;
    if mode == "walk" {
        s.obstacles.clear();
    }
    if mode == "near" {
        s = both.near_alone;
    }
    let mut by = [ObstacleRisk::default(); planner_core::MAX_OBSTACLES];
    let p = Perturbation::default();
    let mut sum = 0.0;
    for sch in &schedules {
        sum += risk_culled(&s, sch, &p, Execution::OpenLoop, &mut by, how).collision_probability;
    }
    println!(
        "{} forms, summed collision probability {sum}",
        schedules.len()
    );
    Ok(())
}
