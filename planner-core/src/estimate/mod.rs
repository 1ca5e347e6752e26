//! The tip-state estimator: an error-state Kalman filter on the tip frame and the tissue's
//! effective curvature, fed by the robot's own progress (insertion depth and base rotation, which
//! drive the kinematic prediction) and the tracker's noisy poses; and a separate filter for the
//! target as imaging sees it.
//!
//! Error state (7): position (world, mm), a small rotation in the tip's own axes (radians: about
//! e1 and e2 tilts the heading, about e3 rolls the bevel), and the curvature factor (the tissue
//! bends the needle with curvature factor / radius; Moreira & Misra 2015 estimate it online the
//! same way, from the path so far). The prediction's Jacobian is taken by finite differences of
//! the same unicycle step the planner uses, so the filter and the planner share one model.

mod lost;
mod noise;
mod offset;
mod slip;
pub mod target;

use crate::matmul::{mul, sandwich};
use crate::model::form::SegmentKind;
use crate::model::kinematics::{rotate, Frame, V3};
use lost::{Rejected, LOST_CONSISTENCY};
use nalgebra::{Matrix3, SMatrix, SVector};
use offset::TrackerOffset;
use target::{TargetFilter, TargetFix, PUSH_ZONE_MM};

pub use noise::NoiseModel;

/// Size of the error state.
pub const STATES: usize = 7;
type Cov = SMatrix<f32, STATES, STATES>;
type ErrorState = SVector<f32, STATES>;

/// Standard deviations of the tip's position estimate ([`Estimate::margin_sd`]) a continuation
/// keeps clear of every obstacle on top of the scenario's floor: the true tip may be that far
/// from where the estimate has it. A plan steered under a collision bound keeps it too.
pub const STEER_MARGIN_SDS: f32 = 2.0;

/// Smallest and largest curvature factor the estimate may take.
pub const FACTOR_RANGE: (f32, f32) = (0.2, 5.0);

/// Innovations beyond this many standard deviations (squared, summed over the axes) are
/// outliers: about 5 sigma for three axes.
const GATE: f32 = 25.0;

/// How far (mm) the fixes' progress along the heading may fall short of the insertion commanded
/// over the last 3 mm or more ([`slip`]) before a rejected fix counts as a tip held back by
/// a membrane rather than one the estimate has lost ([`Estimate::lost_offset`]). Why: after a
/// stall of 4-6 mm a rejected fix stopped the run near a sphere as tracking lost, though the tip
/// was behind on a path already cleared (space-clinical seeds 11 and 543, paper-clinical 352;
/// docs/execution.md, "A tip held by a membrane"). 1.5, 2 and 2.5 mm gave the same runs on both
/// examples then; 2.5 was kept, until a turn made early at the full curvature had the gate reject
/// a stalled fix 2.2-2.3 mm behind (paper-clinical seeds 575 and 963 stopped 64-83 mm from the
/// target: docs/execution.md, "Part of the turn made early").
const HELD_BACK_MM: f32 = 2.0;

/// The fused fixes' consistency ([`LOST_CONSISTENCY`] and above: a world the model does not
/// describe) up to which a tip held back counts as held rather than lost. A stall's own lag
/// raises it to 2.1-2.3 by the first rejected fix (the runs above); in the world at twice the
/// steering's assumption it sits near 3, and there two stalled runs taken for held touched a
/// sphere (docs/execution.md, "A tip held by a membrane").
const HELD_CONSISTENCY: f32 = 2.5;

/// Heading fixes rejected in a row (with their positions fused) after which the heading is
/// re-anchored to the fix ([`Estimate::fuse_heading`]). Two: a single rejection is an outlier
/// as the gate means it; at three, the world at twice the assumption still had a heading 7
/// degrees off for 3 mm near a sphere, and one collision in 1000 runs of an unseen family.
const HEADINGS_REJECTED_TO_REANCHOR: u8 = 2;

/// The variance given to a row a fix does not observe (a 5-DOF fix's roll): it keeps the row
/// out of the update.
const UNOBSERVED_VARIANCE: f32 = 1e12;

/// Weight of a new fix in the running innovation consistency (about the last 20 fixes).
const CONSISTENCY_WEIGHT: f32 = 0.05;

/// The rotation matrix of the rotation vector `w` (Rodrigues).
fn exp_so3(w: V3) -> Matrix3<f32> {
    let angle = crate::fmath::sqrt(w.dot(&w));
    if angle < 1e-9 {
        return Matrix3::identity();
    }
    let axis = w / angle;
    Matrix3::from_columns(&[
        rotate(V3::x(), axis, angle),
        rotate(V3::y(), axis, angle),
        rotate(V3::z(), axis, angle),
    ])
}

/// The small rotation vector taking `a` to `b`, in `a`'s axes.
fn log_small(a: &Matrix3<f32>, b: &Matrix3<f32>) -> V3 {
    let m = a.transpose() * b;
    V3::new(
        m[(2, 1)] - m[(1, 2)],
        m[(0, 2)] - m[(2, 0)],
        m[(1, 0)] - m[(0, 1)],
    ) * 0.5
}

/// Gram–Schmidt on the columns, keeping the heading.
fn orthonormal(r: &Matrix3<f32>) -> Option<Matrix3<f32>> {
    let e3: V3 = r.column(2).into();
    let e3 = e3.try_normalize(1e-6)?;
    let b: V3 = r.column(1).into();
    let e2 = (b - e3 * b.dot(&e3)).try_normalize(1e-6)?;
    Some(Matrix3::from_columns(&[e2.cross(&e3), e2, e3]))
}

/// The estimated tip, curvature and target, with their uncertainty.
#[derive(Clone, Debug)]
pub struct Estimate {
    /// Estimated tip frame.
    pub tip: Frame,
    /// Estimated curvature factor (the tissue bends arcs with radius = nominal / this).
    pub factor: f32,
    /// Estimated target.
    pub target: V3,
    cov: Cov,
    target_filter: TargetFilter,
    noise: NoiseModel,
    /// The position fixes' squared innovations against what the model expects (per axis,
    /// averaged over the last tens of fixes): about 1 in a world as the model says, more in a
    /// noisier one.
    consistency: f32,
    /// The sensor gives no roll (a 5-DOF sensor, as its last fix said): only then does a turn
    /// of the base bring the roll estimate back to the commanded one ([`Estimate::rotated`]).
    roll_unmeasured: bool,
    /// How far the fixes without a roll have moved the roll since it was last brought back to
    /// the commanded one (radians about the heading).
    roll_offset: f32,
    /// The position fixes rejected in a row ([`Estimate::lost_offset`]).
    rejected: Rejected,
    /// Heading fixes rejected in a row while the positions were fused.
    headings_rejected: u8,
    /// The fused fixes' progress against the commanded insertion.
    slip: slip::Slip,
    /// The tracker's offset from the imaging frame, read near the entry.
    offset: TrackerOffset,
}

impl Estimate {
    /// The prior at the start of an insertion: the planned posture with the model's spreads.
    pub fn new(tip: Frame, target: V3, noise: &NoiseModel) -> Estimate {
        let mut cov = Cov::zeros();
        let dir = noise.entry_direction_deg.to_radians();
        for k in 0..3 {
            cov[(k, k)] = noise.entry_position_mm * noise.entry_position_mm;
        }
        cov[(3, 3)] = dir * dir;
        cov[(4, 4)] = dir * dir;
        cov[(5, 5)] = 1e-6;
        cov[(6, 6)] = noise.curvature_spread * noise.curvature_spread;
        Estimate {
            tip,
            factor: 1.0,
            target,
            cov,
            target_filter: TargetFilter::new(
                noise.target_mm,
                noise.target_walk_mm,
                noise.target_speed_walk,
            ),
            noise: *noise,
            consistency: 1.0,
            roll_unmeasured: false,
            roll_offset: 0.0,
            rejected: Rejected::NONE,
            headings_rejected: 0,
            slip: slip::Slip::NONE,
            offset: TrackerOffset::new(tip.p, noise),
        }
    }

    /// The frame `f` and factor `k` moved by the error state `d`.
    fn plus(f: &Frame, k: f32, d: &ErrorState) -> (Frame, f32) {
        let frame = Frame {
            p: f.p + V3::new(d[0], d[1], d[2]),
            r: f.r * exp_so3(V3::new(d[3], d[4], d[5])),
        };
        (frame, k + d[6])
    }

    /// The error state taking (`a`, `ka`) to (`b`, `kb`).
    fn minus(a: &Frame, ka: f32, b: &Frame, kb: f32) -> ErrorState {
        let dp = b.p - a.p;
        let dw = log_small(&a.r, &b.r);
        ErrorState::from_column_slice(&[dp.x, dp.y, dp.z, dw.x, dw.y, dw.z, kb - ka])
    }

    /// The base turned the shaft by `angle_deg` at inserted depth `depth_mm`: the tip is rolled
    /// by as much, give or take the torsional play.
    ///
    /// With a sensor that gives no roll (5-DOF) a turn of at least twice the play brings the
    /// roll back to the commanded one ([`Estimate::roll_to_base`]); otherwise the play's variance
    /// adds to the roll's, as it always does with a 6-DOF sensor (whose next fix measures it).
    pub fn rotated(&mut self, angle_deg: f32, depth_mm: f32) {
        self.tip = self.tip.rolled(angle_deg.to_radians());
        let play = (self.noise.torsion_lag_deg_per_mm * depth_mm).to_radians();
        if self.roll_unmeasured && libm::fabsf(angle_deg.to_radians()) >= 2.0 * play {
            self.roll_to_base(play);
        } else {
            self.cov[(5, 5)] += play * play;
        }
    }

    /// After a turn of the base by at least twice the shaft's play (`play`, radians) the tip's
    /// roll rests within the play of the base's, whatever it was before (the play is a
    /// backlash: the base drags the tip once it has taken up the play on either side). So with
    /// no sensor of the roll the estimate takes the commanded roll back, with the play's
    /// variance and no correlation with the rest of the state: the roll's error is then at most
    /// the play, dead reckoning's.
    ///
    /// Why: the roll is read only from the side to which arcs bend; before this rule a 5-DOF
    /// filter's roll variance summed the play of every turn (37 turns per insertion on the
    /// paper's, 10° of play at 50 mm: a standard deviation of tens of degrees), so the short
    /// corrective arcs after a spun line (0.3–0.5 mm, turning the heading by 0.3–0.45° against
    /// 0.5° of heading noise) moved the roll by tens of degrees on noise, and it did worse than
    /// dead reckoning (roll RMS 20.7° from the first spun line on, over 100 paper runs; 11.8°
    /// with the rule; docs/execution.md, "The roll from a 5-DOF sensor"). Between such turns
    /// the arcs still correct the roll as before.
    fn roll_to_base(&mut self, play: f32) {
        self.tip = self.tip.rolled(-self.roll_offset);
        self.roll_offset = 0.0;
        for k in 0..STATES {
            self.cov[(5, k)] = 0.0;
            self.cov[(k, 5)] = 0.0;
        }
        self.cov[(5, 5)] = play * play;
    }

    /// A spun line settles the tip's roll anywhere within the play of the base.
    pub fn spun(&mut self, depth_mm: f32) {
        let play = (self.noise.torsion_lag_deg_per_mm * depth_mm).to_radians();
        self.cov[(5, 5)] += play * play;
    }

    /// The shaft spins while it is pushed (a spun line, a duty-cycled push): the tip's roll is
    /// known no better than the play of the base at this depth, which grows as it goes in.
    pub fn spinning(&mut self, depth_mm: f32) {
        let play = (self.noise.torsion_lag_deg_per_mm * depth_mm).to_radians();
        self.cov[(5, 5)] = self.cov[(5, 5)].max(play * play);
    }

    /// A new arc begins: its curvature may differ from the last one's.
    pub fn new_arc(&mut self) {
        let s = self.noise.segment_curvature_spread;
        self.cov[(6, 6)] += s * s;
    }

    /// The robot pushed `length` mm along a segment of `kind` (arcs of nominal radius `radius`).
    pub fn advanced(&mut self, kind: SegmentKind, length: f32, radius: f32) {
        if !(length > 0.0) {
            return;
        }
        let step = |f: &Frame, k: f32| {
            let k = crate::fmath::clamp(k, FACTOR_RANGE.0, FACTOR_RANGE.1);
            f.advanced(kind, length, radius / k)
        };
        let next = step(&self.tip, self.factor);
        // The Jacobian by central differences of the same step.
        let mut phi = Cov::zeros();
        for j in 0..STATES {
            let h = if j < 3 { 1e-2 } else { 1e-3 };
            let mut d = ErrorState::zeros();
            d[j] = h;
            let (fp, kp) = Estimate::plus(&self.tip, self.factor, &d);
            d[j] = -h;
            let (fm, km) = Estimate::plus(&self.tip, self.factor, &d);
            let up = Estimate::minus(&next, self.factor, &step(&fp, kp), kp);
            let down = Estimate::minus(&next, self.factor, &step(&fm, km), km);
            phi.set_column(j, &((up - down) / (2.0 * h)));
        }
        self.cov = sandwich(&phi, &self.cov);
        // Process noise: the advance along the heading, the heading's walk on lines.
        let along = next.e3();
        let q_len = self.noise.insertion_error_mm * self.noise.insertion_error_mm / 100.0 * length;
        for a in 0..3 {
            for b in 0..3 {
                self.cov[(a, b)] += q_len * along[a] * along[b];
            }
        }
        let walk = self.noise.curvature_walk;
        self.cov[(6, 6)] += walk * walk * length;
        if kind == SegmentKind::Line {
            let walk = self.noise.line_walk_deg.to_radians();
            self.cov[(3, 3)] += walk * walk * length;
            self.cov[(4, 4)] += walk * walk * length;
        }
        self.slip.advanced(length);
        self.offset.advanced(next.p - self.tip.p, length);
        self.tip = next;
        let near = (self.target - self.tip.p).norm() < PUSH_ZONE_MM;
        let heading = near.then(|| self.tip.e3());
        self.target_filter
            .advanced(&mut self.target, length, heading);
    }

    /// Says whether the sensor's fixes carry the roll (a 6-DOF sensor's, the default, even
    /// while a spinning shaft leaves its bevel unused) or not (a 5-DOF sensor's): only without
    /// it does a turn bring the roll back to the commanded one ([`Estimate::rotated`]).
    pub fn sensor_measures_roll(&mut self, measured: bool) {
        self.roll_unmeasured = !measured;
    }

    /// Fuses a measured tip position; `false` (and no change) for an outlier.
    pub fn fuse_position(&mut self, z: V3) -> bool {
        let (z, read) = self.offset.corrected(z, self.tip.e3());
        if let Some(offset) = read {
            // The estimate followed the fixes: it moves with them into the imaging frame.
            self.tip.p -= offset;
            self.slip.moved(-offset);
        }
        let r = self.noise.position_mm * self.noise.position_mm;
        let y = z - self.tip.p;
        let mut h = SMatrix::<f32, 3, STATES>::zeros();
        for k in 0..3 {
            h[(k, k)] = 1.0;
        }
        let Some(d2) = self.fuse_rows(&h, y, [r; 3]) else {
            // A tip a membrane holds back is behind on the path it travelled, not lost.
            let held = self.slip.slip(z, self.tip.e3()) < -HELD_BACK_MM
                && self.consistency < HELD_CONSISTENCY;
            if !held {
                self.rejected.rejected(lost::off_the_path(y, self.tip.e3()));
            }
            return false;
        };
        self.rejected = Rejected::NONE;
        self.slip.fused(z);
        self.consistency += CONSISTENCY_WEIGHT * (d2 / 3.0 - self.consistency);
        true
    }

    /// How far the tip may be from the estimate's path when the tracker keeps disagreeing with it
    /// (mm; 0 while fixes are fused, or while the fused ones agree with the model): see
    /// [`Rejected::offset`].
    pub fn lost_offset(&self) -> f32 {
        if self.consistency > LOST_CONSISTENCY {
            self.rejected.offset()
        } else {
            0.0
        }
    }

    /// Fuses a measured heading and (when the sensor gives it) bevel direction; `false` (and no
    /// change) for an outlier or a degenerate measurement.
    pub fn fuse_orientation(&mut self, heading: V3, bevel: Option<V3>) -> bool {
        let r = self.noise.orientation_deg.to_radians();
        let r = r * r;
        match bevel {
            Some(b) => {
                let Some(m) = orthonormal(&Matrix3::from_columns(&[V3::zeros(), b, heading]))
                else {
                    return false;
                };
                let y = log_small(&self.tip.r, &m);
                let mut h = SMatrix::<f32, 3, STATES>::zeros();
                for k in 0..3 {
                    h[(k, 3 + k)] = 1.0;
                }
                self.fuse_heading(&h, y, [r; 3])
            }
            None => {
                let Some(hd) = heading.try_normalize(1e-6) else {
                    return false;
                };
                // In the tip's axes the heading tilts by (w2, -w1, 1).
                let local = self.tip.r.transpose() * hd;
                let y = V3::new(-local.y, local.x, 0.0);
                let mut h = SMatrix::<f32, 3, STATES>::zeros();
                h[(0, 3)] = 1.0;
                h[(1, 4)] = 1.0;
                // The third row observes nothing: a huge variance keeps it out.
                self.fuse_heading(&h, y, [r, r, UNOBSERVED_VARIANCE])
            }
        }
    }

    /// [`Estimate::fuse_rows`] for a heading (and bevel) fix, re-anchored when the fixes keep
    /// rejecting it: after [`HEADINGS_REJECTED_TO_REANCHOR`] in a row (their positions fused),
    /// the heading's variance grows by the innovation's square and the fix is fused again.
    ///
    /// Why: a heading that has drifted past the gate stays there. Every later heading fix is an
    /// outlier, so nothing teaches the heading or the curvature, and the drift grows with each
    /// arc. In the world at twice the controller's assumption (a layer bending at 1.6 times
    /// the nominal curvature, a 5 mm stall at its boundary) the estimate's heading drifted from
    /// 1 to 15 degrees over 20 mm, its factor stuck at 0.93, and the needle met a sphere it
    /// believed 3.5 mm away (docs/execution.md, "A heading the fixes keep rejecting").
    fn fuse_heading(&mut self, h: &SMatrix<f32, 3, STATES>, y: V3, r: [f32; 3]) -> bool {
        if self.fuse_rows(h, y, r).is_some() {
            self.headings_rejected = 0;
            return true;
        }
        self.headings_rejected = self.headings_rejected.saturating_add(1);
        if self.headings_rejected < HEADINGS_REJECTED_TO_REANCHOR {
            return false;
        }
        for k in 0..3 {
            // Only the rows the fix observes (a 5-DOF fix leaves the roll's out).
            if r[k] < UNOBSERVED_VARIANCE {
                self.cov[(3 + k, 3 + k)] += y[k] * y[k];
            }
        }
        let fused = self.fuse_rows(h, y, r).is_some();
        if fused {
            self.headings_rejected = 0;
        }
        fused
    }

    /// The Kalman update of three rows `h` with innovation `y` and noise variances `r`: the
    /// innovation's squared Mahalanobis length, or `None` (and no change) for an outlier or a
    /// degenerate update.
    fn fuse_rows(&mut self, h: &SMatrix<f32, 3, STATES>, y: V3, r: [f32; 3]) -> Option<f32> {
        let mut s = sandwich(h, &self.cov);
        for k in 0..3 {
            s[(k, k)] += r[k];
        }
        let s_inv = s.try_inverse()?;
        let d2 = (y.transpose() * s_inv * y)[(0, 0)];
        if !d2.is_finite() || d2 > GATE {
            return None;
        }
        let k = mul(&mul(&self.cov, &h.transpose()), &s_inv);
        let d = mul(&k, &SMatrix::<f32, 3, 1>::from(y));
        if self.roll_unmeasured {
            self.roll_offset += d[5];
        }
        let (tip, factor) = Estimate::plus(&self.tip, self.factor, &d);
        let rotation = orthonormal(&tip.r)?;
        self.tip = Frame {
            p: tip.p,
            r: rotation,
        };
        self.factor = crate::fmath::clamp(factor, FACTOR_RANGE.0, FACTOR_RANGE.1);
        let ikh = Cov::identity() - mul(&k, h);
        // Joseph form keeps the covariance symmetric and positive in f32.
        let mut rk = SMatrix::<f32, 3, 3>::zeros();
        for i in 0..3 {
            rk[(i, i)] = r[i];
        }
        let cov = sandwich(&ikh, &self.cov) + sandwich(&k, &rk);
        self.cov = (cov + cov.transpose()) * 0.5;
        Some(d2)
    }

    /// Fuses a measured target position: fused, an outlier, or (after agreeing outliers) the
    /// target moved and the estimate followed it.
    pub fn fuse_target(&mut self, z: V3) -> TargetFix {
        let r = self.noise.position_mm * self.noise.position_mm;
        self.target_filter.fuse(&mut self.target, z, r)
    }

    /// Standard deviation of the position estimate (mm, the largest axis).
    pub fn position_sd(&self) -> f32 {
        let v = self.cov[(0, 0)].max(self.cov[(1, 1)]).max(self.cov[(2, 2)]);
        crate::fmath::sqrt(v)
    }

    /// The standard deviation the steering keeps clear of the obstacles (mm): the position
    /// estimate's, widened where the fixes' innovations say the world is noisier than the model
    /// (never narrowed). Widened by their variance ratio, not its square root: a filter tuned
    /// for a quieter world also estimates worse than its own covariance says (measured in a
    /// world with every perturbation doubled, docs/execution.md). The tracker's hidden error
    /// (`registration_mm`) adds in quadrature: no fix shows it, so nothing narrows it.
    pub fn margin_sd(&self) -> f32 {
        let own = self.position_sd() * self.consistency.max(1.0);
        let hidden = self.noise.registration_mm;
        if hidden > 0.0 {
            crate::fmath::sqrt(own * own + hidden * hidden)
        } else {
            own
        }
    }

    /// Covariance of the position estimate (mm²).
    pub fn position_covariance(&self) -> Matrix3<f32> {
        self.cov.fixed_view::<3, 3>(0, 0).into_owned()
    }

    /// The tracker's offset from the imaging frame taken off the fixes (zero until read near
    /// the entry, and always without a hidden error told).
    pub fn tracker_offset(&self) -> V3 {
        self.offset.offset()
    }

    /// Standard deviation of the target estimate, per axis (mm).
    pub fn target_sd(&self) -> f32 {
        crate::fmath::sqrt(self.target_filter.var())
    }
}

#[cfg(test)]
mod tests;
