//! The broad phase: a bounding-volume tree over a scenario's spheres, in fixed storage, that
//! finds every sphere that may come within a given reach of a path.
//!
//! It only ever skips spheres that cannot matter: a query returns a superset of the spheres
//! within reach (each segment of the path is split into pieces no longer than [`PIECE_MM`],
//! and every point of a piece lies within half its arc length of the piece's middle), and the
//! caller measures each returned sphere exactly and visits them in index order. So a plan does
//! not depend on the tree, only the work does.

use crate::model::form::SegmentKind;
use crate::model::kinematics::{Frame, PathGeometry, V3};
use crate::model::scenario::{Obstacle, MAX_OBSTACLES};

/// Spheres in one leaf: a leaf's spheres are tested one by one.
const LEAF: usize = 16;

/// Nodes the tree can need: halving ranges until they hold at most [`LEAF`] spheres leaves
/// fewer than `2 n / LEAF` leaves, and a binary tree has fewer than twice as many nodes.
const MAX_NODES: usize = 4 * MAX_OBSTACLES.div_ceil(LEAF);

/// Depth of the tree's walks: ranges halve at every level.
const MAX_DEPTH: usize = 24;

/// Longest piece of a segment one query covers (mm): shorter pieces make tighter bounding
/// spheres, at one point on the path each.
pub const PIECE_MM: f32 = 10.0;

/// Spheres up to this many are measured without a tree outside the optimiser (the check, the
/// steering's prediction): building one would cost more than it saves.
pub const BROAD_FROM: usize = 32;

/// Whether trees outside the optimiser are built at all: on the host, not on the device. Why not
/// the device: with 256 spheres the check's tree on the stack and the controller's in `Steering`
/// took its RAM from 55.4 to 72.5 KiB (the budget is 60) and a steering reading from 0.90 to 1.08
/// M instructions (the budget is 1 M), building a tree per re-planned continuation.
const TREES_OUTSIDE_THE_OPTIMISER: bool = MAX_OBSTACLES > BROAD_FROM && !cfg!(target_os = "none");

/// Whether `count` spheres are worth a tree outside the optimiser. Never on the device (see
/// [`TREES_OUTSIDE_THE_OPTIMISER`]): no tree is then built or compiled in there.
pub fn worth_a_tree(count: usize) -> bool {
    TREES_OUTSIDE_THE_OPTIMISER && count > BROAD_FROM
}

/// A tree kept beside other state: room for one where [`worth_a_tree`] can hold, none (no
/// bytes) on the device.
pub type KeptTree = heapless::Vec<Broad, { TREES_OUTSIDE_THE_OPTIMISER as usize }>;

/// The tree over `obstacles` to keep, if they are [`worth_a_tree`].
pub fn kept_tree(obstacles: &[Obstacle]) -> KeptTree {
    let mut kept = KeptTree::new();
    if worth_a_tree(obstacles.len()) {
        let _ = kept.push(Broad::new(obstacles));
    }
    kept
}

/// Words of a [`Set`].
const WORDS: usize = MAX_OBSTACLES.div_ceil(32);

/// A set of obstacle indices, visited in increasing order.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Set([u32; WORDS]);

impl Set {
    /// Every index below `count`.
    pub fn all(count: usize) -> Set {
        let mut s = Set::default();
        for o in 0..count.min(MAX_OBSTACLES) {
            s.insert(o);
        }
        s
    }

    /// Adds obstacle `o` (ignored past the capacity).
    pub fn insert(&mut self, o: usize) {
        if let Some(w) = self.0.get_mut(o / 32) {
            *w |= 1 << (o % 32);
        }
    }

    /// Whether obstacle `o` is in the set.
    pub fn contains(&self, o: usize) -> bool {
        self.0.get(o / 32).is_some_and(|w| w & (1 << (o % 32)) != 0)
    }

    /// The indices, smallest first.
    pub fn iter(&self) -> impl Iterator<Item = usize> + '_ {
        self.0.iter().enumerate().flat_map(|(i, &w)| {
            let mut bits = w;
            core::iter::from_fn(move || {
                if bits == 0 {
                    return None;
                }
                let b = bits.trailing_zeros() as usize;
                bits &= bits - 1;
                Some(32 * i + b)
            })
        })
    }
}

/// A node: the box around its spheres; a leaf holds `order[start..start + len]`, an inner node's
/// children are the next node and `right`.
#[derive(Clone, Copy, Debug, Default)]
struct Node {
    lo: [f32; 3],
    hi: [f32; 3],
    start: u16,
    len: u16,
    right: u16,
    leaf: bool,
}

/// The tree over one scenario's spheres (built once per problem; deterministic).
#[derive(Clone, Debug)]
pub struct Broad {
    order: [u16; MAX_OBSTACLES],
    nodes: heapless::Vec<Node, MAX_NODES>,
    /// False when the tree could not be built (it cannot happen within the capacities): every
    /// query then returns every sphere.
    built: bool,
    count: usize,
}

fn bounds(obstacles: &[Obstacle], order: &[u16]) -> ([f32; 3], [f32; 3]) {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for &o in order {
        if let Some(ob) = obstacles.get(usize::from(o)) {
            for k in 0..3 {
                lo[k] = lo[k].min(ob.center[k] - ob.radius);
                hi[k] = hi[k].max(ob.center[k] + ob.radius);
            }
        }
    }
    (lo, hi)
}

fn center(obstacles: &[Obstacle], o: u16, axis: usize) -> f32 {
    obstacles
        .get(usize::from(o))
        .map_or(0.0, |ob| ob.center[axis])
}

impl Broad {
    /// The tree over `obstacles` (at most [`MAX_OBSTACLES`] are taken).
    pub fn new(obstacles: &[Obstacle]) -> Broad {
        let count = obstacles.len().min(MAX_OBSTACLES);
        let mut order = [0u16; MAX_OBSTACLES];
        for (i, o) in order.iter_mut().enumerate().take(count) {
            *o = i as u16;
        }
        let mut b = Broad {
            order,
            nodes: heapless::Vec::new(),
            built: false,
            count,
        };
        // The boxes bound spheres of finite centres and radii not below zero; any other sphere
        // (an unvalidated scenario) makes every query return every sphere.
        let sound = obstacles.iter().take(count).all(|o| {
            o.radius >= 0.0 && o.radius.is_finite() && o.center.iter().all(|c| c.is_finite())
        });
        b.built = sound && b.build(obstacles);
        b
    }

    /// Splits ranges at the median of the longest axis of their box, depth first (so an inner
    /// node's left child is the next node). False when a capacity ran out.
    fn build(&mut self, obstacles: &[Obstacle]) -> bool {
        // (parent whose `right` is this node, start, end); the root has no parent.
        let mut stack = [(usize::MAX, 0usize, 0usize); MAX_DEPTH];
        stack[0] = (usize::MAX, 0, self.count);
        let mut depth = 1;
        while depth > 0 {
            depth -= 1;
            let (parent, start, end) = stack[depth];
            let Some(range) = self.order.get_mut(start..end) else {
                return false;
            };
            let (lo, hi) = bounds(obstacles, range);
            let me = self.nodes.len();
            if let Some(p) = self.nodes.get_mut(parent) {
                p.right = me as u16;
            }
            let leaf = end - start <= LEAF;
            let node = Node {
                lo,
                hi,
                start: start as u16,
                len: (end - start) as u16,
                right: 0,
                leaf,
            };
            if self.nodes.push(node).is_err() {
                return false;
            }
            if leaf {
                continue;
            }
            let axis = (0..3)
                .max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b])))
                .unwrap_or(0);
            let mid = (end - start) / 2;
            range.select_nth_unstable_by(mid, |&a, &b| {
                center(obstacles, a, axis)
                    .total_cmp(&center(obstacles, b, axis))
                    .then(a.cmp(&b))
            });
            if depth + 2 > MAX_DEPTH {
                return false;
            }
            // The right half waits below the left one: the left child is the next node.
            stack[depth] = (me, start + mid, end);
            stack[depth + 1] = (usize::MAX, start, start + mid);
            depth += 2;
        }
        true
    }

    /// Adds to `out` every sphere of `obstacles` (the list the tree was built on) whose surface
    /// comes within `reach` of the ball of radius `r` around `q`.
    pub fn query(&self, obstacles: &[Obstacle], q: &V3, r: f32, reach: f32, out: &mut Set) {
        if !self.built {
            *out = Set::all(self.count);
            return;
        }
        let h = r + reach;
        // A point or reach the comparisons below cannot order (NaN, infinite) would skip
        // spheres an exhaustive measure counts: every sphere is a candidate then.
        if !(h.is_finite() && q.iter().all(|x| x.is_finite())) {
            *out = Set::all(self.count);
            return;
        }
        let mut stack = [0u16; MAX_DEPTH];
        let mut depth = 1;
        while depth > 0 {
            depth -= 1;
            let Some(node) = self.nodes.get(usize::from(stack[depth])) else {
                continue;
            };
            let mut gap2 = 0.0f32;
            for k in 0..3 {
                let g = (node.lo[k] - q[k]).max(q[k] - node.hi[k]).max(0.0);
                gap2 += g * g;
            }
            if !(gap2 <= h * h) {
                continue;
            }
            if node.leaf {
                let range = usize::from(node.start)..usize::from(node.start + node.len);
                for &o in self.order.get(range).unwrap_or(&[]) {
                    let Some(ob) = obstacles.get(usize::from(o)) else {
                        continue;
                    };
                    let c = V3::new(ob.center[0], ob.center[1], ob.center[2]);
                    let within = h + ob.radius;
                    if (c - q).norm_squared() <= within * within {
                        out.insert(usize::from(o));
                    }
                }
            } else if depth + 2 <= MAX_DEPTH {
                let left = stack[depth] + 1;
                stack[depth] = node.right;
                stack[depth + 1] = left;
                depth += 2;
            } else {
                *out = Set::all(self.count);
                return;
            }
        }
    }

    /// The spheres whose surface may come within `reach` of the path `geo` (a superset of those
    /// that do, with a margin for rounding).
    pub fn near_path(&self, obstacles: &[Obstacle], geo: &PathGeometry, reach: f32) -> Set {
        let mut out = Set::default();
        for i in 0..geo.form.len() {
            let kind = geo.form.kind(i);
            self.near_segment(
                obstacles,
                &geo.starts[i],
                kind,
                geo.lengths[i],
                geo.radius,
                reach,
                &mut out,
            );
        }
        out
    }

    /// Adds to `out` the spheres whose surface may come within `reach` of the segment of `kind`
    /// and `length` from `start` (arcs of `radius`), with a margin for rounding.
    #[allow(clippy::too_many_arguments)]
    pub fn near_segment(
        &self,
        obstacles: &[Obstacle],
        start: &Frame,
        kind: SegmentKind,
        len: f32,
        radius: f32,
        reach: f32,
        out: &mut Set,
    ) {
        // A length the pieces below cannot cover is measured against every sphere.
        if !(len >= 0.0 && len.is_finite()) {
            *out = Set::all(self.count);
            return;
        }
        let pieces = libm::ceilf(len / PIECE_MM).clamp(1.0, 1e4) as u32;
        let piece = len / pieces as f32;
        for k in 0..pieces {
            let t = piece * (k as f32 + 0.5);
            let q = start.point_at(kind, t, radius);
            // The rounding of the point and of the exact distances later compared with
            // `reach` (f32 at coordinates up to 1000 mm).
            let slack = 1e-3 + 1e-5 * (reach + piece);
            self.query(obstacles, &q, 0.5 * piece + slack, reach, out);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::clearance::closest;
    use crate::model::form::Form;
    use crate::model::kinematics::{entry_basis, insertion_frame};

    /// A deterministic scatter of spheres (a linear congruential generator).
    fn scatter(n: usize, seed: u32) -> heapless::Vec<Obstacle, MAX_OBSTACLES> {
        let mut state = seed;
        let mut next = || {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (state >> 8) as f32 / (1u32 << 24) as f32
        };
        let mut v = heapless::Vec::new();
        for _ in 0..n {
            let center = [
                200.0 * next() - 100.0,
                200.0 * next() - 100.0,
                200.0 * next() - 50.0,
            ];
            let _ = v.push(Obstacle {
                center,
                radius: 1.0 + 6.0 * next(),
            });
        }
        v
    }

    #[test]
    fn a_query_returns_every_sphere_within_reach_and_skips_many_others() {
        let obstacles = scatter(MAX_OBSTACLES, 7);
        let broad = Broad::new(&obstacles);
        assert!(broad.built);
        let basis = entry_basis([0.0, 0.0, 1.0]);
        let mut skipped = 0;
        for (word, theta) in [("RL", 0.3f32), ("LRL", -0.2), ("RRR", 0.5), ("L", 0.0)] {
            let form = Form::parse(word).unwrap();
            let start = insertion_frame(V3::zeros(), &basis, theta, 0.1);
            let lengths = [40.0, 25.0, 30.0, 0.0];
            let bevels = [0.0, 1.0, -2.0, 0.0];
            let geo = PathGeometry::build(form, start, &lengths, &bevels, 60.0);
            for reach in [0.5f32, 5.0, 20.0] {
                let set = broad.near_path(&obstacles, &geo, reach);
                for (o, ob) in obstacles.iter().enumerate() {
                    let c = V3::new(ob.center[0], ob.center[1], ob.center[2]);
                    let d = (0..form.len())
                        .map(|i| {
                            closest(&geo.starts[i], form.kind(i), geo.lengths[i], 60.0, &c).distance
                        })
                        .fold(f32::INFINITY, f32::min)
                        - ob.radius;
                    if d < reach {
                        assert!(set.contains(o), "{word} reach {reach}: sphere {o} at {d}");
                    } else if !set.contains(o) {
                        skipped += 1;
                    }
                }
            }
        }
        assert!(skipped > 4 * MAX_OBSTACLES, "skipped {skipped}");
    }

    #[test]
    fn sets_visit_in_index_order() {
        let mut s = Set::default();
        for o in [300, 5, 64, 31, 32] {
            s.insert(o % MAX_OBSTACLES);
        }
        let got: heapless::Vec<usize, 8> = s.iter().collect();
        let mut want = [300 % MAX_OBSTACLES, 5, 64, 31, 32];
        want.sort();
        assert_eq!(&got[..], &want[..]);
        assert!(Set::all(3).contains(2) && !Set::all(3).contains(3));
    }
}
