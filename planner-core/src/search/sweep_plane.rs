//! The plane a group's seeds are swept in ([`SweepPlane`]): its frame (chord, in-plane normal,
//! plane normal), the obstacles in its coordinates, the form's segments as the pieces swept in it,
//! and what a planar path there scores and which problem variables it makes.

use crate::model::form::SegmentKind;
use crate::model::kinematics::{insertion_frame, V3};
use crate::model::scenario::MAX_OBSTACLES;
use crate::optim::problem::{Problem, Vars, MAX_VARS};
use crate::search::in_plane_geometry::{Drawn, Pose};
use crate::MAX_CONTROL_DEGREE;

/// A planar path: heading (radians from the chord, towards `m`), then segments.
#[derive(Clone, Copy, Debug)]
pub(super) struct PlanarPath {
    pub(super) heading: f32,
    pub(super) lengths: [f32; MAX_CONTROL_DEGREE],
}

/// Side (+1 right, -1 left) of each segment for arc-side bits `sides` (bit set: left).
pub(super) fn segment_sides(p: &Problem, sides: u8) -> [f32; MAX_CONTROL_DEGREE] {
    let mut out = [1.0; MAX_CONTROL_DEGREE];
    let mut arc = 0;
    for (i, o) in out.iter_mut().enumerate().take(p.form.len()) {
        if p.form.kind(i) == SegmentKind::Arc {
            if sides & (1 << arc) != 0 {
                *o = -1.0;
            }
            arc += 1;
        }
    }
    out
}

/// A run of segments swept as one: consecutive arcs bending to the same side lie on one circle,
/// so they are swept as a single arc of up to `count` times the longest arc and written out as
/// `count` equal pieces. Without this, paths whose turn exceeds one arc's bound (the long loops
/// around obstacles that block every short path) would have no seeds at all.
#[derive(Clone, Copy, Debug)]
pub(super) struct Piece {
    pub(super) kind: SegmentKind,
    pub(super) side: f32,
    /// The segments it covers (bit i: segment i).
    pub(super) segments: u8,
    pub(super) count: u8,
}

pub(super) type Pieces = heapless::Vec<Piece, MAX_CONTROL_DEGREE>;

/// The form of `p` with sides `side`, without the segments in `skipped` (they get length zero),
/// runs of same-side arcs merged.
pub(super) fn pieces(p: &Problem, side: &[f32; MAX_CONTROL_DEGREE], skipped: u8) -> Pieces {
    let mut out = Pieces::new();
    for i in (0..p.form.len()).filter(|i| skipped & (1 << i) == 0) {
        let kind = p.form.kind(i);
        if let Some(last) = out.last_mut() {
            if kind == SegmentKind::Arc && last.kind == SegmentKind::Arc && last.side == side[i] {
                last.segments |= 1 << i;
                last.count += 1;
                continue;
            }
        }
        // At most one piece per segment.
        let _ = out.push(Piece {
            kind,
            side: side[i],
            segments: 1 << i,
            count: 1,
        });
    }
    out
}

/// Clearance shortfall (mm) under which a probe's cell is searched again more finely, and a seed
/// counts as a near miss.
pub const NEAR_MISS: f32 = 4.0;

/// The plane of a sweep and the arcs' sides.
pub(super) struct SweepPlane {
    /// Unit vector from the entry to the target.
    pub(super) chord: V3,
    /// In-plane unit normal to the chord (positive headings turn towards it).
    pub(super) m: V3,
    pub(super) normal: V3,
    /// Entry to target (mm).
    pub(super) dist: f32,
    pub(super) sides: [f32; MAX_CONTROL_DEGREE],
    /// The in-plane headings on the tilt bound (just inside), if the plane crosses it.
    pub(super) tilt_bound_headings: Option<[f32; 2]>,
    /// Components of the nominal insertion axis along the chord and `m`.
    pub(super) axis: (f32, f32),
    /// Each obstacle's centre in plane coordinates and its squared height over the plane.
    pub(super) obstacles: [(f32, f32, f32); MAX_OBSTACLES],
}

impl SweepPlane {
    /// The plane through the entry and the target turned by `psi` about the chord.
    pub(super) fn new(p: &Problem, psi: f32, sides: u8) -> Self {
        let e = p.scenario.entry.position;
        let t = p.scenario.target.position;
        let d = V3::new(t[0] - e[0], t[1] - e[1], t[2] - e[2]);
        let dist = crate::fmath::sqrt(d.dot(&d));
        let chord = d / dist;
        let b1: V3 = p.basis.column(0).into();
        let b2: V3 = p.basis.column(1).into();
        let b3: V3 = p.basis.column(2).into();
        let pick = if libm::fabsf(chord.dot(&b1)) < 0.9 {
            b1
        } else {
            b2
        };
        let a = pick - chord * pick.dot(&chord);
        let a = a / crate::fmath::sqrt(a.dot(&a));
        let (sn, cs) = crate::fmath::sincos(psi);
        let normal = a * cs + chord.cross(&a) * sn;
        let m = normal.cross(&chord);
        // heading . b3 = A cos h + B sin h = R cos(h - phi) meets cos(max tilt) at phi +- w.
        let (ca, cb) = (chord.dot(&b3), m.dot(&b3));
        let reach = crate::fmath::sqrt(ca * ca + cb * cb);
        let tilt_bound_headings = (reach > p.cos_max_tilt).then(|| {
            let phi = crate::fmath::atan2(cb, ca);
            let w = crate::fmath::acos(p.cos_max_tilt / reach) * (1.0 - 1e-4);
            [phi - w, phi + w]
        });
        let mut obstacles = [(0.0, 0.0, 0.0); MAX_OBSTACLES];
        for (o, ob) in obstacles.iter_mut().zip(&p.scenario.obstacles) {
            let c = V3::new(
                ob.center[0] - e[0],
                ob.center[1] - e[1],
                ob.center[2] - e[2],
            );
            let h = c.dot(&normal);
            *o = (c.dot(&chord), c.dot(&m), h * h);
        }
        SweepPlane {
            chord,
            m,
            normal,
            dist,
            sides: segment_sides(p, sides),
            tilt_bound_headings,
            axis: (ca, cb),
            obstacles,
        }
    }

    /// Whether the in-plane `heading` lies inside the tilt cone.
    pub(super) fn within_tilt(&self, p: &Problem, (sn, cs): (f32, f32)) -> bool {
        self.axis.0 * cs + self.axis.1 * sn >= p.cos_max_tilt
    }

    /// D and the smallest clearance of the planar path (as [`Problem::score`]: D is infinite once
    /// an obstacle is within the clearance floor, and the scan stops at the first obstacle cut
    /// deeper than a near miss).
    pub(super) fn clearances(
        &self,
        p: &Problem,
        heading: f32,
        heading_sc: (f32, f32),
        pieces: &Pieces,
        lengths: &[f32; MAX_CONTROL_DEGREE],
    ) -> (f32, f32) {
        let mut drawn: heapless::Vec<Drawn, MAX_CONTROL_DEGREE> = heapless::Vec::new();
        let mut at = Pose {
            x: 0.0,
            y: 0.0,
            psi: heading,
        };
        let mut sc = heading_sc;
        for (piece, &len) in pieces.iter().zip(lengths) {
            let d = Drawn::new_from(at, sc, piece.kind, len, piece.side, p.radius);
            at = d.end;
            sc = d.end_sc;
            // As many as there are pieces.
            let _ = drawn.push(d);
        }
        let mut min_clearance = f32::INFINITY;
        let mut inv_sum = 0.0f32;
        let mut blocked = false;
        for (&(x, y, h2), ob) in self.obstacles.iter().zip(&p.scenario.obstacles) {
            let nearest = drawn.iter().fold(f32::INFINITY, |m, d| {
                crate::fmath::min(m, d.distance_squared((x, y)))
            });
            let d = crate::fmath::sqrt(nearest + h2) - ob.radius;
            min_clearance = crate::fmath::min(min_clearance, d);
            if d > p.min_clearance {
                inv_sum += 1.0 / d;
            } else if d > p.min_clearance - NEAR_MISS {
                blocked = true;
            } else {
                return (f32::INFINITY, min_clearance);
            }
        }
        if blocked {
            return (f32::INFINITY, min_clearance);
        }
        (inv_sum * p.risk_scale(), min_clearance)
    }

    /// Problem variables of a planar path; `None` when it leaves the tilt cone or a bound.
    pub(super) fn variables(&self, p: &Problem, path: &PlanarPath) -> Option<Vars> {
        let (sn, cs) = crate::fmath::sincos(path.heading);
        let heading = self.chord * cs + self.m * sn;
        let basis = &p.basis;
        let b1: V3 = basis.column(0).into();
        let b2: V3 = basis.column(1).into();
        let b3: V3 = basis.column(2).into();
        if heading.dot(&b3) < p.cos_max_tilt {
            return None;
        }
        let mut x = [0.0f32; MAX_VARS];
        let theta2 = crate::fmath::asin(crate::fmath::clamp(heading.dot(&b1), -1.0, 1.0));
        let theta1 = crate::fmath::atan2(-heading.dot(&b2), heading.dot(&b3));
        x[0] = theta1;
        if !p.plane {
            x[1] = theta2;
        }
        for i in 0..p.form.len() {
            let k = p.length_var(i);
            let u = path.lengths[i] / p.radius;
            if !(u >= 0.0 && u <= p.upper[k]) {
                return None;
            }
            x[k] = u;
        }
        if !p.plane {
            // Roll the bevel so that e1 is the plane normal (the bevel faces the right of the
            // heading), then flip by pi whenever the next arc bends to the other side.
            let f0 = insertion_frame(V3::zeros(), basis, theta1, theta2);
            let base = crate::fmath::atan2(self.normal.dot(&f0.e2()), self.normal.dot(&f0.e1()));
            let mut facing_left = false;
            let mut first = true;
            for i in 0..p.form.len() {
                if p.form.kind(i) != SegmentKind::Arc {
                    continue;
                }
                let left = self.sides[i] < 0.0;
                let mut roll = if first { base } else { 0.0 };
                if left != facing_left {
                    roll += core::f32::consts::PI;
                    facing_left = left;
                }
                first = false;
                if let Some(k) = p.bevel_var(i) {
                    x[k] = roll;
                }
            }
        }
        Some(x)
    }
}
