//! What 3D Slicer (OpenIGTLinkIF, as a server) is shown while steering: the plan and each new
//! continuation as `POLYDATA` paths (models), the controller's estimated tip as a `TRANSFORM`,
//! the state and any stop reason as `STATUS` and `STRING`. Slicer is a spectator: a send that
//! fails drops the connection and steering goes on. Slicer may be the server (`--slicer`) or
//! connect to this program (`--serve-slicer`, [`Viewers`]).

use super::viewers::Viewers;
use super::wire::{igtl_error, send, tip_transform};
use anyhow::Result;
use needle_igtl::messages::point::MAX_POINTS;
use needle_igtl::messages::polydata::{MAX_POLY_POINTS, MAX_POLY_TRIANGLES};
use needle_igtl::{Message, PointElement, PointList, PolyData, Status, StatusCode, StringMessage};
use planner_core::execute::nominal::{execute_from, sample};
use planner_core::execute::schedule::{Schedule, Step};
use planner_core::model::kinematics::Frame;
use planner_core::Scenario;
use std::time::Duration;

/// Device name of the planned path.
pub const PLAN_DEVICE: &str = "NeedlePlan";
/// Device name of the obstacles (the first 16; then `NeedleObstacles2`, ...).
pub const OBSTACLES_DEVICE: &str = "NeedleObstacles";
/// Device name of the obstacles as a model of spheres (the first 6; then
/// `NeedleObstaclesModel2`, ...).
pub const OBSTACLES_MODEL_DEVICE: &str = "NeedleObstaclesModel";
/// Device name of the newest continuation.
pub const CONTINUATION_DEVICE: &str = "NeedleContinuation";
/// Device name of the estimated tip.
pub const ESTIMATE_DEVICE: &str = "NeedleTipEstimate";
/// Device name of the state (`STATUS` and `STRING`).
pub const STATE_DEVICE: &str = "NeedleSteering";

/// What Slicer is shown, and where.
#[derive(Default)]
pub struct Slicer {
    viewers: Viewers,
    /// Frames sent now belong to the scene a late viewer is sent first.
    scene: bool,
    /// Why the connection was dropped, if it was.
    pub failure: Option<String>,
}

/// A path's points, spaced so that at most [`MAX_POLY_POINTS`] carry it (at least 1 mm apart).
fn spacing(steps: &[Step]) -> f32 {
    let length: f32 = steps.iter().map(|s| s.op.inserted_mm()).sum();
    (length / (MAX_POLY_POINTS - 2) as f32).max(1.0)
}

impl Slicer {
    /// Connects to Slicer at `address` (none: nothing is shown).
    pub fn connect(address: Option<&str>) -> Result<Slicer> {
        let viewers = match address {
            Some(address) => Viewers::connect(address)?,
            None => Viewers::None,
        };
        Ok(Slicer::showing(viewers))
    }

    /// Serves Slicer on `at` (address, port), waiting up to `wait` for the first viewer.
    pub fn serve(at: (std::net::IpAddr, u16), wait: Duration) -> Result<Slicer> {
        Ok(Slicer::showing(Viewers::serve(at, wait)?))
    }

    fn showing(viewers: Viewers) -> Slicer {
        Slicer {
            viewers,
            scene: false,
            failure: None,
        }
    }

    fn send(&mut self, device: &str, message: &Message) {
        if !self.viewers.active() {
            return;
        }
        let mut frame = Vec::new();
        let sent = send(&mut frame, device, message)
            .and_then(|()| self.viewers.deliver(&frame, self.scene));
        if let Err(e) = sent {
            self.failure = Some(e.to_string());
        }
    }

    fn send_text(&mut self, device: &str, text: &str) {
        match StringMessage::ascii(text) {
            Ok(m) => self.send(device, &Message::String(m)),
            Err(e) => self.failure = Some(igtl_error(e).to_string()),
        }
    }

    fn path(&mut self, device: &str, points: &[[f32; 3]]) {
        let keep = &points[..points.len().min(MAX_POLY_POINTS)];
        match PolyData::polyline(keep) {
            Ok(p) => self.send(device, &Message::PolyData(p)),
            Err(e) => self.failure = Some(format!("{device}: {e:?}")),
        }
    }

    /// The plan's path from the entry.
    pub fn plan(&mut self, scenario: &Scenario, schedule: &Schedule) {
        if !self.viewers.active() {
            return;
        }
        let mut points = Vec::new();
        sample(scenario, schedule, spacing(&schedule.steps), |p| {
            points.push([p.x, p.y, p.z]);
        });
        self.scene = true;
        self.path(PLAN_DEVICE, &points);
        self.obstacles(scenario);
        self.obstacles_model(scenario);
        self.scene = false;
    }

    /// The obstacles as a model: each a sphere of its radius (a twice-split icosahedron's 42
    /// points on it, 80 triangles), as many a `POLYDATA` as its bounds hold:
    /// `NeedleObstaclesModel`, then `NeedleObstaclesModel2`, ...
    fn obstacles_model(&mut self, scenario: &Scenario) {
        let (unit, faces) = super::sphere::unit_sphere();
        let per_message = (MAX_POLY_POINTS / unit.len()).min(MAX_POLY_TRIANGLES / faces.len());
        for (k, chunk) in scenario.obstacles.chunks(per_message).enumerate() {
            let mut points = Vec::new();
            let mut triangles = Vec::new();
            for ob in chunk {
                let base = points.len() as u32;
                points.extend(
                    unit.iter()
                        .map(|u| [0, 1, 2].map(|i| ob.center[i] + ob.radius * u[i])),
                );
                triangles.extend(faces.iter().map(|f| f.map(|i| base + i)));
            }
            let device = match k {
                0 => OBSTACLES_MODEL_DEVICE.to_string(),
                _ => format!("{OBSTACLES_MODEL_DEVICE}{}", k + 1),
            };
            match PolyData::mesh(&points, &triangles) {
                Ok(m) => self.send(&device, &Message::PolyData(m)),
                Err(e) => self.failure = Some(format!("{device}: {e:?}")),
            }
        }
    }

    /// The obstacles as fiducials of their diameter, [`MAX_POINTS`] a message: `NeedleObstacles`,
    /// then `NeedleObstacles2`, ... (a plane scenario's circles drawn as spheres).
    fn obstacles(&mut self, scenario: &Scenario) {
        for (k, chunk) in scenario.obstacles.chunks(MAX_POINTS).enumerate() {
            let mut list = PointList::default();
            for (i, ob) in chunk.iter().enumerate() {
                let name = format!("obstacle {}", k * MAX_POINTS + i + 1);
                let Ok(mut point) = PointElement::at(&name, ob.center) else {
                    continue;
                };
                point.diameter = 2.0 * ob.radius;
                point.rgba = [230, 80, 60, 160];
                let _ = point.group.push_str("Obstacle");
                let _ = list.points.push(point);
            }
            let device = match k {
                0 => OBSTACLES_DEVICE.to_string(),
                _ => format!("{OBSTACLES_DEVICE}{}", k + 1),
            };
            self.send(&device, &Message::Point(list));
        }
    }

    /// Whether anything drawn may reach a viewer (else the drawing need not be computed).
    pub fn shown(&self) -> bool {
        self.viewers.active()
    }

    /// The estimated tip, and the new continuation from it when the controller replaced the
    /// steps (drawn on the nominal needle of arc radius `radius`).
    pub fn reading(&mut self, tip: &Frame, replaced: Option<&[Step]>, radius: f32) {
        if !self.viewers.active() {
            return;
        }
        let v = |v: planner_core::model::kinematics::V3| [v.x, v.y, v.z];
        if let Ok(t) = tip_transform(v(tip.p), v(tip.e3()), v(tip.e2())) {
            self.send(ESTIMATE_DEVICE, &Message::Transform(t));
        }
        let Some(steps) = replaced else {
            return;
        };
        let step = spacing(steps);
        let mut points = vec![v(tip.p)];
        execute_from(*tip, steps, radius, |start, kind, length, r| {
            let pieces = libm::ceilf(length / step).max(1.0) as u32;
            for k in 1..=pieces {
                points.push(v(start.point_at(
                    kind,
                    length * k as f32 / pieces as f32,
                    r,
                )));
            }
        });
        self.path(CONTINUATION_DEVICE, &points);
    }

    /// The state: `steering`, `reached` or `stopped: REASON`; a `STATUS` OK while steering or
    /// on reaching the target, otherwise one that names the reason.
    pub fn state(&mut self, stop_reason: Option<&str>, over: bool) {
        if !self.viewers.active() {
            return;
        }
        let (text, code) = match (over, stop_reason) {
            (false, _) => ("steering".to_string(), StatusCode::OK),
            (true, None) => ("reached".to_string(), StatusCode::OK),
            (true, Some(r)) => (format!("stopped: {r}"), StatusCode::DISABLED),
        };
        let mut status = Status::new(code);
        let _ = status.message.push_str(&text);
        // A viewer joining mid-insertion learns the state from the scene too.
        self.scene = true;
        self.send(STATE_DEVICE, &Message::Status(status));
        self.send_text(STATE_DEVICE, &text);
        self.scene = false;
    }

    /// Viewers connected now.
    pub fn viewers(&self) -> usize {
        self.viewers.count()
    }
}
