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

/// How far (1 - cos) a seed's heading may stray from the axis when the heading is fixed: seeds
/// are rounded onto the target by the solver, and the fixed posture is exact there.
pub(super) const AXIS_SLACK: f32 = 1e-6;

/// sin of the largest angle between the chord and a fixed axis at which every seed plane is taken
/// to hold the axis (the angle [`AXIS_SLACK`] allows a seed's heading).
const AXIS_OFF_CHORD: f32 = 1.4e-3;

/// The largest versine of the tilt (1 - cos) a seed's heading may have. Tilts are compared as
/// versines: near the axis, cos rounds away the fraction of a degree that matters.
fn vers_tilt_allowed(p: &Problem) -> f32 {
    if p.heading_fixed() {
        AXIS_SLACK
    } else {
        p.vers_max_tilt
    }
}

/// 1 - cos of the angle between unit vectors whose difference is `d`: |d|² / 2.
fn versine_between(d: (f32, f32, f32)) -> f32 {
    0.5 * (d.0 * d.0 + d.1 * d.1 + d.2 * d.2)
}

/// The entry-target line and the direction the seed planes are turned from.
struct ChordFrame {
    /// Unit vector from the entry to the target.
    chord: V3,
    /// A unit vector across the chord: the normal of the plane at turn 0.
    a: V3,
    /// Entry to target (mm).
    dist: f32,
}

impl ChordFrame {
    fn of(p: &Problem) -> Self {
        let e = p.scenario.entry.position;
        let t = p.scenario.target.position;
        let d = V3::new(t[0] - e[0], t[1] - e[1], t[2] - e[2]);
        let dist = crate::fmath::sqrt(d.dot(&d));
        let chord = d / dist;
        let b1: V3 = p.basis.column(0).into();
        let b2: V3 = p.basis.column(1).into();
        let pick = if libm::fabsf(chord.dot(&b1)) < 0.9 {
            b1
        } else {
            b2
        };
        let a = pick - chord * pick.dot(&chord);
        let a = a / crate::fmath::sqrt(a.dot(&a));
        ChordFrame { chord, a, dist }
    }
}

/// The turns about the chord of the planes a 3-D form's seeds are swept in: `count` planes
/// evenly over half a turn, unless the tilt cone is narrower than the chord's angle from the
/// axis; then only the planes within the band that crosses the cone are of use, and the `count`
/// planes are spread over that band (one plane, the one holding the axis, when the heading is
/// fixed).
///
/// Returns how many turns were written, and whether they are spread over a band (the cone is
/// narrow or the heading fixed, off the chord).
pub(super) fn seed_plane_turns(p: &Problem, count: usize, out: &mut [f32]) -> (usize, bool) {
    let ChordFrame { chord, a, .. } = ChordFrame::of(p);
    let b3: V3 = p.basis.column(2).into();
    // The plane at turn psi has normal n = a cos psi + (chord x a) sin psi, and crosses the cone
    // when |n . b3| <= sin(max tilt): n . b3 = R cos(psi - psi0).
    let (u, v) = (a.dot(&b3), chord.cross(&a).dot(&b3));
    let off_axis = crate::fmath::sqrt(u * u + v * v);
    let sin_tilt = crate::fmath::sqrt(crate::fmath::max(
        1.0 - p.cos_max_tilt * p.cos_max_tilt,
        0.0,
    ));
    let count = count.min(out.len());
    let every_plane_crosses = if p.heading_fixed() {
        off_axis <= AXIS_OFF_CHORD
    } else {
        sin_tilt >= off_axis
    };
    if every_plane_crosses {
        for (k, o) in out.iter_mut().enumerate().take(count) {
            *o = core::f32::consts::PI * k as f32 / count as f32;
        }
        return (count, false);
    }
    let holds_axis = crate::fmath::atan2(v, u) + core::f32::consts::FRAC_PI_2;
    if p.heading_fixed() || count < 2 {
        if let Some(o) = out.first_mut() {
            *o = holds_axis;
        }
        return (out.len().min(1), true);
    }
    let band = crate::fmath::asin(crate::fmath::clamp(sin_tilt / off_axis, 0.0, 1.0));
    for (k, o) in out.iter_mut().enumerate().take(count) {
        *o = holds_axis + band * (2.0 * k as f32 / (count - 1) as f32 - 1.0);
    }
    (count, true)
}

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
    /// The in-plane headings on the tilt bound (just inside), if the plane crosses it; with the
    /// heading fixed, the axis alone, if the plane holds it.
    pub(super) tilt_bound_headings: heapless::Vec<f32, 2>,
    /// Components of the nominal insertion axis along the chord, `m` and the normal.
    pub(super) axis: (f32, f32, f32),
    /// Each obstacle's centre in plane coordinates, its squared height over the plane and its
    /// radius, in index order; with a reach (`planner.risk_within_mm`), only the obstacles
    /// within it of the plane: any other is farther than the reach from every path in the plane,
    /// adds nothing to D and touches none (the plane's broad phase).
    pub(super) obstacles: heapless::Vec<[f32; 4], MAX_OBSTACLES>,
}

impl SweepPlane {
    /// The plane through the entry and the target turned by `psi` about the chord.
    pub(super) fn new(p: &Problem, psi: f32, sides: u8) -> Self {
        let e = p.scenario.entry.position;
        let ChordFrame { chord, a, dist } = ChordFrame::of(p);
        let b3: V3 = p.basis.column(2).into();
        let (sn, cs) = crate::fmath::sincos(psi);
        let normal = a * cs + chord.cross(&a) * sn;
        let m = normal.cross(&chord);
        // heading . b3 = A cos h + B sin h = R cos(h - phi) meets cos(max tilt) at phi +- w.
        let (ca, cb, cn) = (chord.dot(&b3), m.dot(&b3), normal.dot(&b3));
        let reach = crate::fmath::sqrt(ca * ca + cb * cb);
        let mut tilt_bound_headings = heapless::Vec::new();
        let phi = crate::fmath::atan2(cb, ca);
        if p.heading_fixed() {
            if reach >= 1.0 - AXIS_SLACK {
                // Capacity 2.
                let _ = tilt_bound_headings.push(phi);
            }
        } else {
            // reach cos w = cos(max tilt), in versines: vers w = (vers max - (1 - reach)) / reach,
            // with 1 - reach = cn² / (1 + reach).
            let vers_w = (p.vers_max_tilt - cn * cn / (1.0 + reach)) / reach;
            if vers_w > 0.0 {
                let w = 2.0 * crate::fmath::asin(crate::fmath::sqrt(0.5 * vers_w)) * (1.0 - 1e-4);
                let _ = tilt_bound_headings.extend_from_slice(&[phi - w, phi + w]);
            }
        }
        let mut obstacles = heapless::Vec::new();
        for ob in &p.scenario.obstacles {
            let c = V3::new(
                ob.center[0] - e[0],
                ob.center[1] - e[1],
                ob.center[2] - e[2],
            );
            let h = c.dot(&normal);
            let h2 = h * h;
            // The clearance of a path in the plane is sqrt(in-plane² + h2) − radius, never less
            // than this (f32's sqrt and subtraction are monotonic).
            let least = crate::fmath::sqrt(h2) - ob.radius;
            if p.reach.as_ref().is_some_and(|r| least >= r.within) {
                continue;
            }
            // As many as the scenario's obstacles.
            let _ = obstacles.push([c.dot(&chord), c.dot(&m), h2, ob.radius]);
        }
        SweepPlane {
            chord,
            m,
            normal,
            dist,
            sides: segment_sides(p, sides),
            tilt_bound_headings,
            axis: (ca, cb, cn),
            obstacles,
        }
    }

    /// Whether the in-plane `heading` lies inside the tilt cone (with the heading fixed: on the
    /// axis, to within [`AXIS_SLACK`]).
    pub(super) fn within_tilt(&self, p: &Problem, (sn, cs): (f32, f32)) -> bool {
        let (ca, cb, cn) = self.axis;
        versine_between((ca - cs, cb - sn, cn)) <= vers_tilt_allowed(p)
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
        let far = self.beyond_reach(p, lengths);
        for &[x, y, h2, radius] in &self.obstacles {
            if far.is_some_and(|f| f.holds(x, y, h2, radius)) {
                continue;
            }
            let nearest = drawn.iter().fold(f32::INFINITY, |m, d| {
                crate::fmath::min(m, d.distance_squared((x, y)))
            });
            let d = crate::fmath::sqrt(nearest + h2) - radius;
            min_clearance = crate::fmath::min(min_clearance, d);
            if d > p.min_clearance {
                inv_sum += match &p.reach {
                    None => 1.0 / d,
                    Some(r) if d < r.within => 1.0 / d - r.inverse,
                    Some(_) => 0.0,
                };
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

    /// With a reach, the test that an obstacle lies beyond it from every path of total length
    /// `lengths` from the entry to the target: such a path lies in the ellipse with those foci
    /// (the sum of its distances to them is at most its length), so in the ellipse's box.
    fn beyond_reach(&self, p: &Problem, lengths: &[f32; MAX_CONTROL_DEGREE]) -> Option<Far> {
        let r = p.reach.as_ref()?;
        let total: f32 = lengths.iter().sum();
        let half = 0.5 * total;
        let (dist, half_dist) = (self.dist, 0.5 * self.dist);
        // Well above the rounding of the drawn path and of the clearances (f32, coordinates up
        // to 1000 mm): what is skipped would have measured beyond the reach.
        let slack = 1e-2 + 1e-4 * total;
        Some(Far {
            centre: half_dist,
            half_length: half,
            half_width: 0.5 * crate::fmath::sqrt((total * total - dist * dist).max(0.0)),
            reach: r.within + slack,
        })
    }

    /// Problem variables of a planar path; `None` when it leaves the tilt cone or a bound.
    pub(super) fn variables(&self, p: &Problem, path: &PlanarPath) -> Option<Vars> {
        let (sn, cs) = crate::fmath::sincos(path.heading);
        let heading = self.chord * cs + self.m * sn;
        let basis = &p.basis;
        let b1: V3 = basis.column(0).into();
        let b2: V3 = basis.column(1).into();
        let b3: V3 = basis.column(2).into();
        let off = heading - b3;
        if versine_between((off.x, off.y, off.z)) > vers_tilt_allowed(p) {
            return None;
        }
        let mut x = [0.0f32; MAX_VARS];
        let theta2 = crate::fmath::asin(crate::fmath::clamp(heading.dot(&b1), -1.0, 1.0));
        let theta1 = crate::fmath::atan2(-heading.dot(&b2), heading.dot(&b3));
        p.set_angles(&mut x, theta1, theta2);
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
            let f0 = match p.start {
                Some(fixed) => fixed,
                None => insertion_frame(V3::zeros(), basis, theta1, theta2),
            };
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

/// The box (in plane coordinates) that holds every path of one length from the entry to the
/// target, widened by the reach.
#[derive(Clone, Copy)]
struct Far {
    centre: f32,
    half_length: f32,
    half_width: f32,
    reach: f32,
}

impl Far {
    /// Whether the obstacle at (x, y), its squared height `h2` over the plane and of radius
    /// `radius`, lies beyond the reach from all of the box.
    fn holds(&self, x: f32, y: f32, h2: f32, radius: f32) -> bool {
        let gx = (libm::fabsf(x - self.centre) - self.half_length).max(0.0);
        let gy = (libm::fabsf(y) - self.half_width).max(0.0);
        let within = radius + self.reach;
        gx * gx + gy * gy + h2 >= within * within
    }
}
