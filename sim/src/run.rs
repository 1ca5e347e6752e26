//! One open-loop run: every step of the schedule executed in a perturbed [`World`], and how far
//! the true path lands from the target and strays from the plan.

use crate::drawn::Drawn;
use crate::world::{World, WorldError};
use crate::{PerturbError, Perturbation, WorldEffects};
use planner_core::check::rebuild;
use planner_core::execute::schedule::{Op, Schedule, Step};
use planner_core::model::clearance::closest;
use planner_core::model::kinematics::{PathGeometry, V3};
use planner_core::model::scenario::Workspace;
use planner_core::{FormOutcome, Scenario};
use std::ops::ControlFlow;

/// What one simulated insertion gave (serialised without `steps`, whose JSON form is the
/// reader's choice).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct Run {
    /// The run's seed.
    pub seed: u64,
    /// The values drawn.
    pub drawn: Drawn,
    /// Distance from the true end to the true (displaced) target (mm).
    pub target_error: f32,
    /// RMS over the run's points of their distance to the planned path (mm).
    pub path_rms: f32,
    /// Largest distance of a point to the planned path (mm).
    pub path_max: f32,
    /// For a plane scenario, [`Run::path_rms`] in the plan's plane: each point projected onto
    /// the plane before its distance to the (planar) plan is taken, what a camera over a planar
    /// phantom sees; `None` in 3-D.
    pub path_rms_in_plane: Option<f32>,
    /// For a plane scenario, the largest in-plane deviation; `None` in 3-D.
    pub path_max_in_plane: Option<f32>,
    /// The tissue's reach: the nearest a turn at the world's full curvature, from the true entry
    /// towards where the target ended, comes to it (mm;
    /// [`World::nearest_reach`](crate::World::nearest_reach)).
    pub nearest_reach_mm: f32,
    /// The true path entered an obstacle (a sphere, or a voxel of an organ: see
    /// `entered_voxels`).
    pub collided: bool,
    /// Smallest clearance of the true path to the spheres (mm).
    pub min_clearance: f32,
    /// Whether the true path entered a voxel of the segments the spheres cover, as the caller
    /// judged it against the label map (`None`: no label map; the world knows only spheres).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub entered_voxels: Option<bool>,
    /// The bevel rotations the driver executed.
    pub rotations: Rotations,
    /// The true tip path, at most 1 mm apart.
    pub points: Vec<[f32; 3]>,
    /// What the driver executed.
    #[serde(skip)]
    pub steps: Vec<Step>,
}

/// The bevel rotations of an insertion: how many, how far in all, the smallest.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Rotations {
    /// Rotations executed (turns of no angle are not counted).
    pub count: u32,
    /// Their sizes summed (degrees).
    pub total_deg: f32,
    /// The smallest (degrees; null without any).
    pub smallest_deg: Option<f32>,
}

impl Rotations {
    /// The rotations among `steps`.
    ///
    /// ```
    /// use needle_sim::Rotations;
    /// use planner_core::execute::schedule::{Op, Step};
    ///
    /// let step = |op| Step { op, duration_s: 1.0 };
    /// let steps = [
    ///     step(Op::Rotate { angle_deg: -30.0 }),
    ///     step(Op::Insert { length_mm: 5.0 }),
    ///     step(Op::Rotate { angle_deg: 2.5 }),
    ///     step(Op::Rotate { angle_deg: 0.0 }),
    /// ];
    /// let r = Rotations::of(&steps);
    /// assert_eq!((r.count, r.total_deg, r.smallest_deg), (2, 32.5, Some(2.5)));
    /// ```
    pub fn of(steps: &[Step]) -> Rotations {
        let mut r = Rotations::default();
        for step in steps {
            if let Op::Rotate { angle_deg } = step.op {
                let size = angle_deg.abs();
                if size > 0.0 {
                    r.count += 1;
                    r.total_deg += size;
                    r.smallest_deg = Some(r.smallest_deg.map_or(size, |s| s.min(size)));
                }
            }
        }
        r
    }
}

/// The planned path of `outcome`, to measure deviations from.
pub struct Planned {
    geo: PathGeometry,
    /// The plan lies in the plane x = this (plane scenarios).
    plane_x: Option<f32>,
}

impl Planned {
    /// The path `outcome` describes in `scenario`.
    pub fn of(scenario: &Scenario, outcome: &FormOutcome) -> Planned {
        let geo = rebuild(
            scenario,
            outcome.form,
            &outcome.insertion,
            &outcome.segments,
        );
        let plane_x =
            (scenario.options.workspace == Workspace::PlaneYz).then_some(geo.starts[0].p.x);
        Planned { geo, plane_x }
    }

    /// For a plane scenario, the distance from `p` projected onto the plan's plane to the plan
    /// (the deviation a view across the plane sees); `None` in 3-D.
    pub fn distance_in_plane(&self, p: [f32; 3]) -> Option<f32> {
        self.plane_x.map(|x| self.distance([x, p[1], p[2]]))
    }

    /// Exact distance from `p` to the planned path (nearest point over its segments).
    pub fn distance(&self, p: [f32; 3]) -> f32 {
        let q = V3::new(p[0], p[1], p[2]);
        let g = &self.geo;
        (0..g.form.len())
            .map(|i| closest(&g.starts[i], g.form.kind(i), g.lengths[i], g.radius, &q).distance)
            .fold(f32::INFINITY, f32::min)
    }
}

/// Executes all of `schedule` open loop in the world of `seed`.
pub fn open_loop(
    scenario: &Scenario,
    planned: &Planned,
    schedule: &Schedule,
    p: &Perturbation,
    seed: u64,
) -> Result<Run, PerturbError> {
    let mut world = World::new(scenario, &schedule.posture, p, seed)?;
    for step in &schedule.steps {
        world.execute(step, |_| ControlFlow::Continue(()));
    }
    Ok(finish(&world, planned, seed))
}

/// [`open_loop`] in a world with `effects` (the tracker's effects change nothing open loop;
/// the layers and the pushed target do).
pub fn open_loop_in(
    scenario: &Scenario,
    planned: &Planned,
    schedule: &Schedule,
    p: &Perturbation,
    effects: &WorldEffects,
    seed: u64,
) -> Result<Run, WorldError> {
    let mut world = World::with_effects(scenario, schedule, p, effects, seed)?;
    for step in &schedule.steps {
        world.execute(step, |_| ControlFlow::Continue(()));
    }
    Ok(finish(&world, planned, seed))
}

/// The figures of a finished world (open or closed loop).
pub fn finish(world: &World, planned: &Planned, seed: u64) -> Run {
    let points = world.points().to_vec();
    let (mut sum, mut max) = (0.0f64, 0.0f32);
    let (mut sum_in, mut max_in) = (0.0f64, 0.0f32);
    for p in &points {
        let d = planned.distance(*p);
        sum += f64::from(d) * f64::from(d);
        max = max.max(d);
        if let Some(d) = planned.distance_in_plane(*p) {
            sum_in += f64::from(d) * f64::from(d);
            max_in = max_in.max(d);
        }
    }
    let n = points.len().max(1) as f64;
    let path_rms = (sum / n).sqrt() as f32;
    let in_plane = planned.plane_x.is_some();
    let miss = world.tip().p - world.true_target();
    Run {
        seed,
        drawn: world.drawn().clone(),
        target_error: miss.norm(),
        path_rms,
        path_max: max,
        path_rms_in_plane: in_plane.then(|| (sum_in / n).sqrt() as f32),
        path_max_in_plane: in_plane.then_some(max_in),
        nearest_reach_mm: world.nearest_reach(),
        collided: world.min_clearance() < 0.0,
        min_clearance: world.min_clearance(),
        entered_voxels: None,
        rotations: Rotations::of(world.executed()),
        points,
        steps: world.executed().to_vec(),
    }
}
