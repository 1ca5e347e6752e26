//! Conservative sphere covers of a label map's segments that follow their shape.
//!
//! Every voxel of a segment (the whole cube: its eight corners in one sphere) lies inside a
//! sphere of its cover, and every sphere is grown by the margin, so the segment dilated by the
//! margin is covered. The spheres are medial balls (`medial.rs`): placed greedily on the
//! segment's medial axis from an exact Euclidean distance transform, each reaching at most an
//! overshoot `k` beyond the segment. The tightness asked, a ratio of volumes, picks `k`: the
//! cover is the one with the fewest spheres whose volume outside the dilated segment is at most
//! `tightness − 1` times the dilated segment's volume, tried from one sphere around the whole
//! segment, then medial balls from a loose overshoot to a tight one.

use super::block::Block;
use super::label_map::{LabelMap, Segment};
use super::measure::{dilated, tightness, Dilated, Tightness};
use super::medial::{deepest_first, depths, medial_cover, Fit};
pub use super::reach::Reach;
use anyhow::{bail, Result};
use serde::Serialize;

/// The tightness a cover keeps when none is given: its volume at most 1.5 times the dilated
/// segment's (half of it again outside).
pub const DEFAULT_TIGHTNESS: f64 = 1.5;

/// The overshoots tried (in half voxel diagonals), loosest first.
const OVERSHOOTS: [f64; 9] = [8.0, 5.6, 4.0, 2.8, 2.0, 1.4, 1.0, 0.7, 0.5];

/// A sphere of a cover (RAS, mm).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Sphere {
    /// Centre (mm).
    pub center: [f64; 3],
    /// Radius (mm), the margin included.
    pub radius: f64,
}

impl Sphere {
    fn volume(&self) -> f64 {
        4.0 / 3.0 * std::f64::consts::PI * self.radius.powi(3)
    }
}

/// How a cover is made.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CoverOptions {
    /// Every sphere grows by this (mm, 0 to [`MAX_MARGIN_MM`]): the voxels dilated by it are
    /// covered.
    pub margin_mm: f64,
    /// The most spheres one segment's cover may have (at least 1).
    pub max_spheres: usize,
    /// The cover's volume is at most this many times the dilated segment's, where spheres that
    /// hold whole voxels can be that tight.
    pub tightness: f64,
}

/// The largest margin a cover takes (mm): beyond it the dilated segment says little of the
/// organ, and the cover's cost grows with the margin's cube.
pub const MAX_MARGIN_MM: f64 = 100.0;

impl CoverOptions {
    /// `self` when every option is in its range, else an error naming the option.
    pub fn validated(self) -> Result<CoverOptions> {
        let m = self.margin_mm;
        if !m.is_finite() || m < 0.0 {
            bail!(
                "the margin must be 0 to {MAX_MARGIN_MM} mm, not {m}: a cover holds every voxel \
                 of the segment, so a negative margin cannot shrink it (give 0, the default, to \
                 cover the segment itself)"
            );
        }
        if m > MAX_MARGIN_MM {
            bail!("the margin must be 0 to {MAX_MARGIN_MM} mm, not {m}");
        }
        if self.max_spheres == 0 {
            bail!("the most spheres a segment may take must be at least 1, not 0");
        }
        if !(self.tightness > 1.0 && self.tightness.is_finite()) {
            bail!(
                "the tightness must be a number above 1, not {}",
                self.tightness
            );
        }
        Ok(self)
    }
}

/// One segment's cover and how tight it is.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SegmentCover {
    /// The segment's name.
    pub name: String,
    /// Its label value.
    pub label: i64,
    /// Its voxels.
    pub voxels: usize,
    /// Its volume (mm³).
    pub volume_mm3: f64,
    /// The cover.
    pub spheres: Vec<Sphere>,
    /// The cover's volume outside the segment over the segment's volume (sampled at eight points
    /// a voxel).
    pub outside_ratio: f64,
    /// The cover's volume outside the segment dilated by the margin over the dilated segment's
    /// volume (sampled alike; `outside_ratio` without a margin).
    pub outside_dilated_ratio: f64,
    /// The volume of the segment dilated by the margin (mm³, sampled alike).
    pub dilated_volume_mm3: f64,
    /// Whether the cover is as tight as asked; when not, it is the tightest tried (a segment a
    /// voxel or two thin cannot be held whole by spheres that tight).
    pub tight_enough: bool,
    /// The largest distance from a point of the cover to the segment's nearest voxel centre
    /// (mm, sampled at the voxel centres).
    pub farthest_mm: f64,
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// The eight corner offsets of a voxel in the world (mm).
fn corner_offsets(map: &LabelMap) -> [[f64; 3]; 8] {
    let a = &map.ijk_to_ras;
    std::array::from_fn(|n| {
        let d = [0, 1, 2].map(|k| if n >> k & 1 == 1 { 0.5 } else { -0.5 });
        [0, 1, 2].map(|r| a[r][0] * d[0] + a[r][1] * d[1] + a[r][2] * d[2])
    })
}

fn centre_of(map: &LabelMap, v: &[i64; 3]) -> [f64; 3] {
    map.world(v.map(|x| x as f64))
}

/// The sphere around the corners of `voxels` (no margin), centred on their bounding box.
fn enclosing(map: &LabelMap, voxels: &[[i64; 3]]) -> Sphere {
    let corners = corner_offsets(map);
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for v in voxels {
        let c = centre_of(map, v);
        for off in &corners {
            for k in 0..3 {
                lo[k] = lo[k].min(c[k] + off[k]);
                hi[k] = hi[k].max(c[k] + off[k]);
            }
        }
    }
    let center = [0, 1, 2].map(|k| 0.5 * (lo[k] + hi[k]));
    let mut radius = 0.0f64;
    for v in voxels {
        let c = centre_of(map, v);
        for off in &corners {
            radius = radius.max(dist(center, [c[0] + off[0], c[1] + off[1], c[2] + off[2]]));
        }
    }
    Sphere { center, radius }
}

/// A radius computed on the rounded grid (`block.rs`) made safe for the file's own affine, which
/// may differ from it by float32's rounding.
fn safe(radius: f64) -> f64 {
    radius * (1.0 + 1e-7) + 1e-6
}

/// The box of `voxels` grown to hold balls reaching `reach` mm beyond the segment.
fn block_for(map: &LabelMap, voxels: &[[i64; 3]], reach: f64) -> Block {
    let probe = Block::around(map, voxels, [1, 1, 1]);
    let cells = probe.reach(reach + 2.0 * probe.half_diagonal());
    Block::around(map, voxels, cells.map(|c| c as i64 + 1))
}

/// The tightness of `spheres` about the segment, on `b` (which must hold them).
fn measured(
    map: &LabelMap,
    b: &Block,
    d: &Dilated,
    spheres: &[Sphere],
    reach: Option<&Reach>,
) -> Tightness {
    let balls: Vec<([f64; 3], f64)> = spheres
        .iter()
        .map(|s| {
            let g = map.grid(s.center);
            ([0, 1, 2].map(|k| g[k] - b.lo[k] as f64), s.radius)
        })
        .collect();
    let in_reach = |c: usize| {
        let g = b.cell(c);
        reach.is_none_or(|r| r.holds(map.world([0, 1, 2].map(|k| (g[k] as i64 + b.lo[k]) as f64))))
    };
    tightness(b, d, &balls, Some(&in_reach))
}

/// A cover of a segment that its choice tried.
#[derive(Clone, Debug)]
pub struct Candidate {
    /// The spheres (the margin included).
    pub spheres: Vec<Sphere>,
    /// How tight they are; `None` for one sphere around the whole segment when a looser cover
    /// was taken (measured when chosen).
    pub tightness: Option<Tightness>,
    /// Their volume outside the dilated segment where a needle can reach (mm³).
    pub outside_in_reach_mm3: f64,
    /// Whether they are as tight as asked (within the reach, when one is given).
    pub tight_enough: bool,
}

/// A segment's voxels and the covers tried, loosest first: the last is the one the options ask
/// for (the fewest spheres as tight as asked, else the tightest tried).
pub struct Ladder {
    /// The segment's voxels.
    pub voxels: Vec<[i64; 3]>,
    /// The covers tried.
    pub candidates: Vec<Candidate>,
}

/// The covers of `voxels` tried for the options, loosest first; with a `reach`, spheres beyond
/// it take the loosest overshoot, and tightness counts only the volume within it.
fn choose(
    map: &LabelMap,
    voxels: &[[i64; 3]],
    o: &CoverOptions,
    name: &str,
    reach: Option<&Reach>,
) -> Result<Vec<Candidate>> {
    let m = o.margin_mm;
    let probe = Block::around(map, voxels, [1, 1, 1]);
    let hd = probe.half_diagonal();
    let b = block_for(map, voxels, OVERSHOOTS[0] * hd + m);
    let d = dilated(&b, m);
    let goal = o.tightness - 1.0;
    // One sphere around everything: its volume outside the dilated segment, which it holds whole,
    // is its volume less the dilated segment's.
    let mut one = enclosing(map, voxels);
    one.radius += m;
    let dilated_volume =
        d.bits.iter().map(|x| x.count_ones()).sum::<u32>() as f64 / 8.0 * map.voxel_volume();
    let one_outside = if reach.is_some_and(|r| r.misses(one.center, one.radius)) {
        0.0
    } else {
        (one.volume() - dilated_volume).max(0.0)
    };
    let one_clear = reach.is_none_or(|x| {
        [x.entry, x.target]
            .iter()
            .all(|&p| dist(one.center, p) > one.radius)
    });
    let mut tried = vec![Candidate {
        spheres: vec![one],
        tightness: None,
        outside_in_reach_mm3: one_outside,
        tight_enough: one_clear && one_outside <= goal * dilated_volume * (1.0 + 1e-9),
    }];
    if tried[0].tight_enough {
        return Ok(tried);
    }
    if o.max_spheres == 1 {
        bail!(
            "covering {name} within a tightness of {} needs more than 1 spheres \
             (--max-spheres): raise it, or loosen --tightness",
            o.tightness
        );
    }
    let depth = depths(&b);
    let order = deepest_first(&b, &depth);
    let to_world = |g: [usize; 3]| map.world([0, 1, 2].map(|a| (g[a] as i64 + b.lo[a]) as f64));
    let beyond_reach =
        |g: [usize; 3], r: f64| reach.is_some_and(|x| x.misses(to_world(g), safe(r) + m));
    let holds_kept_out = |g: [usize; 3], r: f64| {
        let c = to_world(g);
        reach.is_some_and(|x| {
            [x.entry, x.target]
                .iter()
                .any(|&p| dist(c, p) <= safe(r) + m)
        })
    };
    let fit = Fit {
        beyond_reach: &beyond_reach,
        coarse_k: OVERSHOOTS[0] * hd,
        holds_kept_out: &holds_kept_out,
    };
    for k in OVERSHOOTS.map(|x| x * hd) {
        // Over the budget: the tightest cover within it, if a looser overshoot gave one.
        let fit = reach.map(|_| &fit);
        let Some(balls) = medial_cover(&b, &depth, &order, k, o.max_spheres, fit) else {
            break;
        };
        let spheres: Vec<Sphere> = balls
            .iter()
            .map(|ball| Sphere {
                center: to_world(ball.cell),
                radius: safe(ball.radius) + m,
            })
            .collect();
        let t = measured(map, &b, &d, &spheres, reach);
        let tight_enough = t.outside_in_reach <= goal;
        tried.push(Candidate {
            spheres,
            tightness: Some(t),
            outside_in_reach_mm3: t.outside_in_reach * dilated_volume,
            tight_enough,
        });
        if tight_enough {
            break;
        }
    }
    if tried.len() == 1 {
        bail!(
            "covering {name} within a tightness of {} needs more than {} spheres \
             (--max-spheres): raise it, or loosen --tightness",
            o.tightness,
            o.max_spheres
        );
    }
    Ok(tried)
}

/// The covers of `segment` tried for the options, loosest first (see [`Ladder`]).
pub fn ladder(
    map: &LabelMap,
    segment: &Segment,
    o: &CoverOptions,
    reach: Option<&Reach>,
) -> Result<Ladder> {
    group_ladder(map, std::slice::from_ref(segment), o, reach)
}

/// The covers tried for the union of `segments` (segments that touch, covered as one:
/// [`crate::touching`]), loosest first.
pub fn group_ladder(
    map: &LabelMap,
    segments: &[Segment],
    o: &CoverOptions,
    reach: Option<&Reach>,
) -> Result<Ladder> {
    let o = &o.validated()?;
    let mut voxels = Vec::new();
    for segment in segments {
        let of_segment = map.voxels_of(segment.label);
        if of_segment.is_empty() {
            bail!(
                "segment {:?} (label {}) has no voxels",
                segment.name,
                segment.label
            );
        }
        voxels.extend(of_segment);
    }
    let name: Vec<String> = segments.iter().map(name_of).collect();
    let candidates = choose(map, &voxels, o, &name.join(" with "), reach)?;
    Ok(Ladder { voxels, candidates })
}

fn name_of(segment: &Segment) -> String {
    format!("{:?} (label {})", segment.name, segment.label)
}

/// `segment`'s cover `c` of its ladder, checked voxel by voxel on the map's own affine.
pub fn finish(
    map: &LabelMap,
    segment: &Segment,
    ladder: &Ladder,
    c: &Candidate,
    o: &CoverOptions,
) -> Result<SegmentCover> {
    let m = o.margin_mm;
    let voxels = &ladder.voxels;
    let t = c.tightness.unwrap_or_else(|| {
        let big = block_for(map, voxels, c.spheres[0].radius);
        measured(map, &big, &dilated(&big, m), &c.spheres, None)
    });
    let uncovered = uncovered_voxels(map, voxels, &c.spheres, m);
    if uncovered > 0 {
        bail!(
            "internal error: the cover of {} leaves {uncovered} voxels out",
            name_of(segment)
        );
    }
    let volume = voxels.len() as f64 * map.voxel_volume();
    Ok(SegmentCover {
        name: segment.name.clone(),
        label: segment.label,
        voxels: voxels.len(),
        volume_mm3: volume,
        spheres: c.spheres.clone(),
        outside_ratio: t.outside,
        outside_dilated_ratio: t.outside_dilated,
        dilated_volume_mm3: t.dilated_over_segment * volume,
        tight_enough: c.tight_enough,
        farthest_mm: t.farthest,
    })
}

/// The cover of `segment` in `map`.
pub fn cover_segment(map: &LabelMap, segment: &Segment, o: &CoverOptions) -> Result<SegmentCover> {
    let l = ladder(map, segment, o, None)?;
    let last = l.candidates.last().expect("a ladder is never empty");
    finish(map, segment, &l, last, o)
}

/// The voxels of `voxels` that no sphere of `spheres`, shrunk by `margin`, holds whole (all eight
/// corners in that one sphere), on the map's own affine: a voxel held whole with the margin to
/// spare has its dilation by the margin inside the sphere.
pub fn uncovered_voxels(
    map: &LabelMap,
    voxels: &[[i64; 3]],
    spheres: &[Sphere],
    margin: f64,
) -> usize {
    let lo = [0, 1, 2].map(|k| voxels.iter().map(|v| v[k]).min().unwrap_or(0));
    let hi = [0, 1, 2].map(|k| voxels.iter().map(|v| v[k]).max().unwrap_or(0));
    let n = [0, 1, 2].map(|k| (hi[k] - lo[k] + 1) as usize);
    let index = |v: [i64; 3]| {
        let g = [0, 1, 2].map(|k| (v[k] - lo[k]) as usize);
        g[0] + n[0] * (g[1] + n[1] * g[2])
    };
    // 0: not in the segment, 1: not held yet, 2: held.
    let mut state = vec![0u8; n[0] * n[1] * n[2]];
    for v in voxels {
        state[index(*v)] = 1;
    }
    let corners = corner_offsets(map);
    for s in spheres {
        let r = s.radius - margin;
        let (mut a, mut b) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for m in 0..8 {
            let p = [0, 1, 2].map(|k| s.center[k] + if m >> k & 1 == 1 { r } else { -r });
            let g = map.grid(p);
            for k in 0..3 {
                a[k] = a[k].min(g[k].floor());
                b[k] = b[k].max(g[k].ceil());
            }
        }
        let a = [0, 1, 2].map(|k| (a[k] as i64).max(lo[k]));
        let b = [0, 1, 2].map(|k| (b[k] as i64).min(hi[k]));
        for z in a[2]..=b[2] {
            for y in a[1]..=b[1] {
                for x in a[0]..=b[0] {
                    let at = index([x, y, z]);
                    if state[at] != 1 {
                        continue;
                    }
                    let c = centre_of(map, &[x, y, z]);
                    let whole = corners
                        .iter()
                        .all(|o| dist(s.center, [c[0] + o[0], c[1] + o[1], c[2] + o[2]]) <= r);
                    if whole {
                        state[at] = 2;
                    }
                }
            }
        }
    }
    state.iter().filter(|&&s| s == 1).count()
}

/// The voxel corners of `voxels` inside no sphere of `spheres` (checked one by one).
pub fn uncovered_corners(map: &LabelMap, voxels: &[[i64; 3]], spheres: &[Sphere]) -> usize {
    let corners = corner_offsets(map);
    voxels
        .iter()
        .flat_map(|v| {
            let c = centre_of(map, v);
            corners.map(|off| [c[0] + off[0], c[1] + off[1], c[2] + off[2]])
        })
        .filter(|&p| !spheres.iter().any(|s| dist(s.center, p) <= s.radius))
        .count()
}

/// The half diagonal of `map`'s voxels (mm) and the distance (mm) from `p` to the nearest
/// centre of `voxels`: a margin below their difference keeps `p` outside every cover of
/// `voxels` a scenario makes (each voxel can be held by a sphere about its own centre).
pub fn clear_of(map: &LabelMap, voxels: &[[i64; 3]], p: [f64; 3]) -> (f64, f64) {
    let half_diagonal = corner_offsets(map)
        .iter()
        .map(|o| (o[0] * o[0] + o[1] * o[1] + o[2] * o[2]).sqrt())
        .fold(0.0, f64::max);
    let nearest = voxels
        .iter()
        .map(|v| dist(centre_of(map, v), p))
        .fold(f64::INFINITY, f64::min);
    (half_diagonal, nearest)
}
