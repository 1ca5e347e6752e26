//! The planning problem as the user states it: needle, entry, target, obstacles, weights, options.
//! Lengths in millimetres, angles in degrees, as in the scenario files.

use crate::error::{Field, PlanError};
use crate::model::form::{FormSet, MAX_CONTROL_DEGREE};
use crate::model::kinematics::V3;
use serde::{Deserialize, Serialize};

/// Largest coordinate, arc radius or obstacle radius a scenario may use (mm): a needle's workspace
/// is tens of centimetres, and beyond this the path's sampled outputs would grow without bound.
pub const MAX_EXTENT_MM: f32 = 1000.0;

/// The arc radii a bevel-tip needle bends with in tissue (mm). Measured radii are tens to
/// hundreds of millimetres: about 61.5 mm for a nitinol needle in a gel phantom (Webster et al.,
/// "Nonholonomic modeling of needle steering", IJRR 25(5-6), 2006) and 50 mm to over 1000 mm across
/// needles and tissues (Majewicz et al., "Behavior of tip-steerable needles in ex vivo and in vivo
/// tissue", IEEE TBME 59(10), 2012). A radius outside this range is almost certainly a unit
/// mistake (0.0637, the paper's radius typed in metres, would plan a 0.02 mm "arc"), so it is
/// refused rather than planned.
pub const CURVATURE_RADIUS_RANGE_MM: (f32, f32) = (5.0, MAX_EXTENT_MM);

/// Obstacles a scenario can hold on the host: the sphere cover of an organ and its neighbours.
pub const HOST_MAX_OBSTACLES: usize = 512;

/// Obstacles a scenario can hold on the device, the wire's device-side bound (a plan request with
/// more is answered [`PlanError::TooManyObstacles`], on the board and in hil-sim alike). The
/// firmware holds them once, in place, within 64 KiB of RAM (docs/firmware.md).
pub const DEVICE_MAX_OBSTACLES: usize = 256;

/// Obstacles a scenario can hold on this build ([`DEVICE_MAX_OBSTACLES`] on a bare-metal
/// target, [`HOST_MAX_OBSTACLES`] elsewhere).
pub const MAX_OBSTACLES: usize = if cfg!(target_os = "none") {
    DEVICE_MAX_OBSTACLES
} else {
    HOST_MAX_OBSTACLES
};

/// Fixed-capacity obstacle list.
pub type Obstacles = heapless::Vec<Obstacle, MAX_OBSTACLES>;

/// How far `planner.risk_within_mm` must lie beyond `planner.min_clearance` (mm).
pub const MIN_RISK_REACH_MM: f32 = 0.01;

/// The needle's mechanics.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Needle {
    /// Radius of an R segment (mm).
    pub curvature_radius: f32,
    /// Longest single R segment as a turning angle (degrees).
    pub max_arc_deg: f32,
    /// Longest single L segment (mm); 0 means "twice the entry-target distance plus a half turn".
    pub max_line_length: f32,
    /// Insertable length (mm): no plan or continuation inserts more in all.
    ///
    /// Default [`DEFAULT_NEEDLE_LENGTH_MM`].
    pub length: f32,
}

/// The insertable length of a needle when the scenario does not give one (mm): the
/// 20 cm of a long biopsy or brachytherapy needle.
pub const DEFAULT_NEEDLE_LENGTH_MM: f32 = 200.0;

/// The longest insertable length a scenario may give (mm).
pub const MAX_NEEDLE_LENGTH_MM: f32 = 5000.0;

/// The largest curvature reserve a scenario may ask for: at half its curvature a needle still
/// bends, duty-cycled, as an arc rather than a drifting line.
pub const MAX_CURVATURE_RESERVE: f32 = 0.5;

/// Where and how the needle enters.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Entry {
    /// Entry point (mm).
    pub position: [f32; 3],
    /// Nominal insertion axis (any length but zero).
    pub direction: [f32; 3],
    /// Largest tilt of the insertion posture away from the nominal axis (degrees).
    pub max_tilt_deg: f32,
}

/// Where the tip must end.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Target {
    /// Target point (mm).
    pub position: [f32; 3],
    /// Largest allowed distance between the path's end and the target (mm).
    pub tolerance: f32,
}

/// A spherical obstacle (a circle in plane mode).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Obstacle {
    /// Centre (mm).
    pub center: [f32; 3],
    /// Radius (mm).
    pub radius: f32,
}

/// The weights a1..a4 of F = a1 L + a2 D + a3 H + a4 N.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Weights {
    /// a1, on the path length L (mm).
    pub length: f32,
    /// a2, on the risk degree D.
    pub risk: f32,
    /// a3, on the penalty H for entering an obstacle.
    pub penalty: f32,
    /// a4, on the control degree N.
    pub control: f32,
}

impl Default for Weights {
    fn default() -> Self {
        Weights {
            length: 1.0,
            risk: 1.0,
            penalty: 1000.0,
            control: 2.0,
        }
    }
}

/// How the risk degree D combines the obstacles' clearances d_i.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RiskMeasure {
    /// D = mean over obstacles of 1/d_i (reproduces the paper's figures).
    #[default]
    Mean,
    /// D = sum over obstacles of 1/d_i.
    Sum,
}

/// Where paths may go.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Workspace {
    /// Full 3-D: bevel rotations are continuous.
    #[default]
    Space,
    /// The y-z plane through the entry (as the paper): each arc turns to one side or the other.
    PlaneYz,
}

/// What to plan and how hard to try.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PlannerOptions {
    /// Largest control degree N tried.
    pub max_control_degree: u8,
    /// Forms to try; empty means every form up to `max_control_degree`.
    pub forms: FormSet,
    /// Plane or space.
    pub workspace: Workspace,
    /// Definition of D.
    pub risk: RiskMeasure,
    /// Smallest clearance a plan may keep to any obstacle (mm, >= 0).
    pub min_clearance: f32,
    /// Share of the needle's curvature the plan leaves unused, in [0, 0.5]: arcs are planned
    /// at the radius `curvature_radius / (1 − reserve)` and pushed duty-cycled at
    /// `1 − reserve`, so a steering controller can bend harder than the plan in any direction
    /// (a plan at the needle's full curvature has a target the controller cannot reach when the
    /// tissue bends a little less). 0, the default, plans at the full curvature.
    pub curvature_reserve: f32,
    /// Reach of the risk term (mm): an obstacle adds 1/d − 1/r to D while its clearance d is
    /// under r and nothing beyond (continuous at r), and only such obstacles take clearance rows.
    /// `None`, the default, weighs every obstacle by 1/d wherever it is.
    pub risk_within_mm: Option<f32>,
}

impl Default for PlannerOptions {
    fn default() -> Self {
        PlannerOptions {
            max_control_degree: 3,
            forms: FormSet::default(),
            workspace: Workspace::Space,
            risk: RiskMeasure::Mean,
            min_clearance: 0.0,
            curvature_reserve: 0.0,
            risk_within_mm: None,
        }
    }
}

impl PlannerOptions {
    /// Checks the options' numbers and relations (part of [`Scenario::validate`]).
    pub fn validate(&self) -> Result<(), PlanError> {
        finite(Field::MinClearance, &[self.min_clearance])?;
        if self.min_clearance < 0.0 {
            return Err(PlanError::OutOfRange(Field::MinClearance));
        }
        finite(Field::CurvatureReserve, &[self.curvature_reserve])?;
        if !(0.0..=MAX_CURVATURE_RESERVE).contains(&self.curvature_reserve) {
            return Err(PlanError::OutOfRange(Field::CurvatureReserve));
        }
        if let Some(r) = self.risk_within_mm {
            finite(Field::RiskWithin, &[r])?;
            // Clear of the optimiser's clearance floor (the minimum plus at most 1e-3 mm of
            // rounding margin): an obstacle the path touches must always be measured.
            if !(r >= self.min_clearance + MIN_RISK_REACH_MM && r <= MAX_EXTENT_MM) {
                return Err(PlanError::OutOfRange(Field::RiskWithin));
            }
        }
        if self.max_control_degree == 0 || usize::from(self.max_control_degree) > MAX_CONTROL_DEGREE
        {
            return Err(PlanError::ControlDegreeOutOfRange {
                requested: self.max_control_degree,
                max: MAX_CONTROL_DEGREE as u8,
            });
        }
        if self.selected_forms().is_empty() {
            return Err(PlanError::NoForms);
        }
        Ok(())
    }

    /// The forms this request tries: the explicit list cut to the degree limit, or all up to it.
    pub fn selected_forms(&self) -> FormSet {
        let by_degree = FormSet::up_to_degree(usize::from(self.max_control_degree));
        if self.forms.is_empty() {
            by_degree
        } else {
            FormSet(self.forms.0 & by_degree.0)
        }
    }
}

/// The needle driver's two stages (insertion u1, rotation u2), as the motor schedule uses them.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Driver {
    /// Insertion speed (mm/s).
    pub insert_speed: f32,
    /// Rotation speed of a bevel turn (deg/s).
    pub rotate_speed: f32,
    /// Spin rate while inserting a line (rev/s).
    pub spin_rate: f32,
    /// Largest accumulated shaft twist the schedule may reach (degrees, at least one turn).
    pub max_twist_deg: f32,
}

impl Driver {
    /// The defaults of the `[driver]` table: 2.5 mm/s, 360 deg/s, 4 rev/s, 360 degrees.
    pub const DEFAULT: Driver = Driver {
        insert_speed: 2.5,
        rotate_speed: 360.0,
        spin_rate: 4.0,
        max_twist_deg: 360.0,
    };
}

impl Driver {
    /// Positive, finite speeds and a twist limit of at least one turn.
    pub fn validate(&self) -> Result<(), PlanError> {
        positive(Field::InsertSpeed, self.insert_speed)?;
        positive(Field::RotateSpeed, self.rotate_speed)?;
        positive(Field::SpinRate, self.spin_rate)?;
        // Physical ranges of a needle driver's stages; they also bound a line's spin turns
        // (at most 1e3 rev/s for 1000 mm at 1e-3 mm/s: 1e9, well within the step's u32).
        for (field, v, lo, hi) in [
            (Field::InsertSpeed, self.insert_speed, 1e-3, 1e3),
            (Field::RotateSpeed, self.rotate_speed, 1e-2, 1e5),
            (Field::SpinRate, self.spin_rate, 1e-2, 1e3),
        ] {
            if !(lo..=hi).contains(&v) {
                return Err(PlanError::OutOfRange(field));
            }
        }
        finite(Field::MaxTwist, &[self.max_twist_deg])?;
        // A line's spin turns the shaft by whole revolutions, so one turn of room is the least.
        if self.max_twist_deg < 360.0 {
            return Err(PlanError::OutOfRange(Field::MaxTwist));
        }
        Ok(())
    }
}

impl Default for Driver {
    fn default() -> Self {
        Driver::DEFAULT
    }
}

/// A whole planning problem.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Scenario {
    /// Needle mechanics.
    pub needle: Needle,
    /// Entry point and posture bounds.
    pub entry: Entry,
    /// Target and tolerance.
    pub target: Target,
    /// Obstacles (at most [`MAX_OBSTACLES`]).
    pub obstacles: Obstacles,
    /// Objective weights.
    pub weights: Weights,
    /// Planner options.
    pub options: PlannerOptions,
    /// The driver that executes the plan.
    pub driver: Driver,
}

fn finite(field: Field, values: &[f32]) -> Result<(), PlanError> {
    if values.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(PlanError::NotFinite(field))
    }
}

fn positive(field: Field, v: f32) -> Result<(), PlanError> {
    finite(field, &[v])?;
    if v > 0.0 {
        Ok(())
    } else {
        Err(PlanError::NotPositive(field))
    }
}

/// Finite coordinates within [`MAX_EXTENT_MM`] of the origin.
fn within_extent(field: Field, p: &[f32; 3]) -> Result<(), PlanError> {
    finite(field, p)?;
    if p.iter().all(|c| libm::fabsf(*c) <= MAX_EXTENT_MM) {
        Ok(())
    } else {
        Err(PlanError::OutOfRange(field))
    }
}

fn dist(a: [f32; 3], b: [f32; 3]) -> f32 {
    let d = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    crate::fmath::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
}

impl Scenario {
    /// The radius the plan's arcs have (mm): the needle's, widened by the curvature reserve.
    pub fn planned_radius(&self) -> f32 {
        self.needle.curvature_radius / self.arc_duty()
    }

    /// The share of each planned arc's push with the bevel held (1 without a curvature reserve:
    /// a plain push).
    pub fn arc_duty(&self) -> f32 {
        1.0 - crate::fmath::clamp(self.options.curvature_reserve, 0.0, MAX_CURVATURE_RESERVE)
    }

    /// Longest line segment allowed (mm): the needle's setting, or by default twice the
    /// entry-target distance plus half a turn of arc.
    pub fn max_line_length(&self) -> f32 {
        let n = &self.needle;
        if n.max_line_length > 0.0 {
            return n.max_line_length;
        }
        let (a, b) = (self.entry.position, self.target.position);
        let d = V3::new(b[0] - a[0], b[1] - a[1], b[2] - a[2]);
        2.0 * crate::fmath::sqrt(d.dot(&d)) + core::f32::consts::PI * self.planned_radius()
    }

    /// How finely f32 arithmetic resolves positions at this scenario's coordinates (mm): four
    /// units in the last place of its largest entry or target coordinate (at least 1 mm).
    pub fn resolution(&self) -> f32 {
        let scale = self
            .entry
            .position
            .iter()
            .chain(self.target.position.iter())
            .fold(1.0f32, |m, c| m.max(libm::fabsf(*c)));
        4.0 * f32::EPSILON * scale
    }

    /// Checks every number and relation the planner relies on; the first problem found is returned.
    pub fn validate(&self) -> Result<(), PlanError> {
        let n = &self.needle;
        positive(Field::CurvatureRadius, n.curvature_radius)?;
        let (least, most) = CURVATURE_RADIUS_RANGE_MM;
        if !(least..=most).contains(&n.curvature_radius) {
            return Err(PlanError::OutOfRange(Field::CurvatureRadius));
        }
        positive(Field::MaxArc, n.max_arc_deg)?;
        if n.max_arc_deg > 360.0 {
            return Err(PlanError::OutOfRange(Field::MaxArc));
        }
        finite(Field::MaxLineLength, &[n.max_line_length])?;
        if n.max_line_length < 0.0 {
            return Err(PlanError::OutOfRange(Field::MaxLineLength));
        }
        let e = &self.entry;
        within_extent(Field::EntryPosition, &e.position)?;
        finite(Field::EntryDirection, &e.direction)?;
        let dir_len = dist(e.direction, [0.0; 3]);
        if !(dir_len > 0.0) || !dir_len.is_finite() {
            return Err(PlanError::ZeroDirection);
        }
        finite(Field::MaxTilt, &[e.max_tilt_deg])?;
        if !(0.0..=89.0).contains(&e.max_tilt_deg) {
            return Err(PlanError::OutOfRange(Field::MaxTilt));
        }
        let t = &self.target;
        within_extent(Field::TargetPosition, &t.position)?;
        positive(Field::TargetTolerance, t.tolerance)?;
        let least = 4.0 * self.resolution();
        if t.tolerance < least {
            let least_nm = libm::ceilf(least * 1e6) as u32;
            return Err(PlanError::ToleranceTooFine { least_nm });
        }
        if dist(e.position, t.position) <= t.tolerance {
            return Err(PlanError::TargetAtEntry);
        }
        positive(Field::NeedleLength, n.length)?;
        let shortest = dist(e.position, t.position) - t.tolerance;
        if !(shortest..=MAX_NEEDLE_LENGTH_MM).contains(&n.length) {
            return Err(PlanError::OutOfRange(Field::NeedleLength));
        }
        let w = &self.weights;
        for (field, v) in [
            (Field::WeightLength, w.length),
            (Field::WeightRisk, w.risk),
            (Field::WeightPenalty, w.penalty),
            (Field::WeightControl, w.control),
        ] {
            finite(field, &[v])?;
            if v < 0.0 {
                return Err(PlanError::OutOfRange(field));
            }
        }
        let o = &self.options;
        o.validate()?;
        if o.workspace == Workspace::PlaneYz {
            if e.direction[0] != 0.0 {
                return Err(PlanError::NotInPlane(Field::EntryDirection));
            }
            if t.position[0] != e.position[0] {
                return Err(PlanError::NotInPlane(Field::TargetPosition));
            }
        }
        self.driver.validate()?;
        for (i, ob) in self.obstacles.iter().enumerate() {
            let i = i as u16;
            within_extent(Field::ObstacleCenter(i), &ob.center)?;
            positive(Field::ObstacleRadius(i), ob.radius)?;
            if ob.radius > MAX_EXTENT_MM {
                return Err(PlanError::OutOfRange(Field::ObstacleRadius(i)));
            }
            if dist(ob.center, e.position) <= ob.radius {
                return Err(PlanError::EntryInsideObstacle(i));
            }
            if dist(ob.center, t.position) <= ob.radius {
                return Err(PlanError::TargetInsideObstacle(i));
            }
        }
        Ok(())
    }

    /// The paper's simulation scenario (as `examples/paper.toml`).
    pub fn paper() -> Scenario {
        let mut obstacles = Obstacles::new();
        for (c, r) in [
            ([0.0, 30.0, 50.0], 10.0),
            ([0.0, -5.0, 40.0], 11.0),
            ([0.0, -40.0, 30.0], 13.0),
        ] {
            // Three obstacles always fit in the capacity.
            let _ = obstacles.push(Obstacle {
                center: c,
                radius: r,
            });
        }
        Scenario {
            needle: Needle {
                curvature_radius: 63.7,
                max_arc_deg: 180.0,
                max_line_length: 0.0,
                length: DEFAULT_NEEDLE_LENGTH_MM,
            },
            entry: Entry {
                position: [0.0; 3],
                direction: [0.0, 0.0, 1.0],
                max_tilt_deg: 60.0,
            },
            target: Target {
                position: [0.0, 0.0, 90.0],
                tolerance: 0.1,
            },
            obstacles,
            weights: Weights::default(),
            options: PlannerOptions {
                max_control_degree: 3,
                workspace: Workspace::PlaneYz,
                ..PlannerOptions::default()
            },
            driver: Driver::DEFAULT,
        }
    }
}
