//! A form reduced for the search: consecutive arcs that share a plane and a side merge into one
//! (longer) arc, and the free parameters that remain once the last two segments are solved in
//! closed form.

use super::complete::{arc_arc, arc_line, line_arc, single_arc, single_line};
use super::problem::{Cand, Problem, Seg};
use core::f64::consts::PI;
use planner_core::SegmentKind::{self, Arc, Line};

/// What one free parameter is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Var {
    /// Insertion angle about b1, within the tilt bound.
    Theta1,
    /// Insertion angle about b2 (3-D only), within the tilt cone with `Theta1`.
    Theta2,
    /// A roll (periodic).
    Roll,
    /// A segment length in `[0, max]`.
    Length(f64),
}

/// A reduced form and, in plane mode, the fixed bevels (0 or pi) of its free arcs.
#[derive(Clone, Debug, PartialEq)]
pub struct Variant {
    /// Reduced segments: kind and how many form segments each stands for.
    pub segs: Vec<(SegmentKind, u8)>,
    /// N of the original form.
    pub control: usize,
    /// Plane mode: the roll of each arc whose roll is not solved in closed form, in order.
    pub plane_rolls: Vec<f64>,
}

impl Variant {
    /// The free parameters, in the order `candidates` reads them.
    pub fn vars(&self, pb: &Problem) -> Vec<Var> {
        let m = self.segs.len();
        let mut v = Vec::new();
        if m == 1 {
            if self.segs[0].0 == Arc && !pb.plane {
                v.push(Var::Roll); // the heading's angle around the chord
            }
            return v;
        }
        v.push(Var::Theta1);
        if !pb.plane {
            v.push(Var::Theta2);
        }
        for &(kind, pieces) in &self.segs[..m - 2] {
            if kind == Arc && !pb.plane {
                v.push(Var::Roll);
            }
            v.push(Var::Length(pb.bound(kind, pieces)));
        }
        if self.segs[m - 2].0 == Arc && self.segs[m - 1].0 == Arc && !pb.plane {
            v.push(Var::Roll);
        }
        v
    }

    /// Every path of this variant with free parameters `x` that ends exactly on the target.
    pub fn candidates(&self, pb: &Problem, x: &[f64], out: &mut Vec<Cand>) {
        out.clear();
        let m = self.segs.len();
        let mut rolls = self.plane_rolls.iter().copied();
        if m == 1 {
            match self.segs[0] {
                (Line, _) => single_line(pb, out),
                (Arc, pieces) => {
                    let omega = if pb.plane {
                        rolls.next().unwrap_or(0.0)
                    } else {
                        x[0]
                    };
                    single_arc(pb, omega, pieces, out);
                }
            }
            return;
        }
        let mut xs = x.iter().copied();
        let mut next = || xs.next().unwrap_or(0.0);
        let theta1 = next();
        let theta2 = if pb.plane { 0.0 } else { next() };
        let mut cand = Cand::new(theta1, theta2);
        let mut f = pb.first_frame(theta1, theta2);
        for &(kind, pieces) in &self.segs[..m - 2] {
            let roll = match kind {
                Arc if pb.plane => rolls.next().unwrap_or(0.0),
                Arc => next(),
                Line => 0.0,
            };
            let length = next();
            f = f.roll(roll);
            f = match kind {
                Arc => f.arc(length, pb.rho),
                Line => f.line(length),
            };
            cand.push(Seg {
                kind,
                length,
                roll,
                pieces,
            });
        }
        let (k1, p1) = self.segs[m - 2];
        let (k2, p2) = self.segs[m - 1];
        match (k1, k2) {
            (Arc, Line) => arc_line(pb, &f, &cand, p1, out),
            (Line, Arc) => line_arc(pb, &f, &cand, p2, out),
            (Arc, Arc) => {
                let roll = if pb.plane {
                    rolls.next().unwrap_or(0.0)
                } else {
                    next()
                };
                arc_arc(pb, &f, roll, &cand, (p1, p2), out);
            }
            (Line, Line) => {}
        }
    }
}

/// Ways to cut `k` consecutive arcs into groups (compositions of k), e.g. 3 -> [3], [2,1], [1,2],
/// [1,1,1].
fn compositions(k: usize) -> Vec<Vec<u8>> {
    if k == 0 {
        return vec![vec![]];
    }
    let mut out = Vec::new();
    for first in 1..=k {
        for rest in compositions(k - first) {
            let mut v = vec![first as u8];
            v.extend(rest);
            out.push(v);
        }
    }
    out
}

/// The reduced variants to search for a form (`kinds`).
///
/// A closed-form completion cannot represent two final arcs on one circle, so the last run of
/// arcs is also searched merged. In plane mode every run is cut every way, and two neighbouring
/// reduced arcs always turn to opposite sides (same-side neighbours are a coarser cut), so each
/// side assignment is searched exactly once.
pub fn variants(pb: &Problem, kinds: &[SegmentKind]) -> Vec<Variant> {
    // Runs: (kind, count) with arcs grouped.
    let mut runs: Vec<(SegmentKind, usize)> = Vec::new();
    for &k in kinds {
        match runs.last_mut() {
            Some((Arc, n)) if k == Arc => *n += 1,
            _ => runs.push((k, 1)),
        }
    }
    let last_arc_run = runs.iter().rposition(|r| r.0 == Arc);
    let mut reduced: Vec<Vec<(SegmentKind, u8)>> = vec![vec![]];
    for (i, &(kind, count)) in runs.iter().enumerate() {
        let cuts = if kind == Line {
            vec![vec![1u8]]
        } else if pb.plane || Some(i) == last_arc_run {
            compositions(count)
        } else {
            vec![vec![1u8; count]]
        };
        let mut next = Vec::new();
        for r in &reduced {
            for cut in &cuts {
                let mut v = r.clone();
                v.extend(cut.iter().map(|&p| (kind, p)));
                next.push(v);
            }
        }
        reduced = next;
    }
    let mut out = Vec::new();
    for segs in reduced {
        let base = Variant {
            segs,
            control: kinds.len(),
            plane_rolls: Vec::new(),
        };
        if !pb.plane {
            out.push(base);
            continue;
        }
        // Free arcs in plane mode: those before the last two, the first of a final RR pair, a
        // lone arc. Each gets 0 or pi, but pi only after an arc (0 would merge them).
        let m = base.segs.len();
        let mut choices: Vec<Vec<f64>> = Vec::new();
        for i in 0..m {
            let free = base.segs[i].0 == Arc
                && (m == 1 || i + 2 < m || (i + 2 == m && base.segs[m - 1].0 == Arc));
            if free {
                let after_arc = i > 0 && base.segs[i - 1].0 == Arc;
                choices.push(if after_arc { vec![PI] } else { vec![0.0, PI] });
            }
        }
        let mut sets: Vec<Vec<f64>> = vec![vec![]];
        for c in choices {
            sets = sets
                .into_iter()
                .flat_map(|s| {
                    c.iter().map(move |&r| {
                        let mut t = s.clone();
                        t.push(r);
                        t
                    })
                })
                .collect();
        }
        for rolls in sets {
            out.push(Variant {
                plane_rolls: rolls,
                ..base.clone()
            });
        }
    }
    out
}
