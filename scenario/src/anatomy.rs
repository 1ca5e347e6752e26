//! `[[anatomy]]` entries of a scenario file: each label map's segments covered by spheres
//! (`needle cover`'s cover), added to the obstacles, within one sphere budget for the scenario.

use super::file::{AnatomyFile, ScenarioFile};
use super::shapes::ObstacleShape;
use anyhow::{anyhow, bail, Result};
use needle_anatomy::budget::allocate;
use needle_anatomy::command::selected;
use needle_anatomy::cover::{clear_of, finish, group_ladder, CoverOptions, Ladder, Reach};
use needle_anatomy::label_map::{LabelMap, Segment};
use needle_anatomy::touching::{merged, touching_groups};
use planner_core::model::scenario::{Obstacle, DEFAULT_NEEDLE_LENGTH_MM};
use planner_core::{DEVICE_MAX_OBSTACLES, HOST_MAX_OBSTACLES};

/// The tightness of a scenario's covers when its `[[anatomy]]` entry gives none: tighter than a
/// lone `needle cover`'s ([`needle_anatomy::cover::DEFAULT_TIGHTNESS`]), since the scenario's sphere budget loosens
/// them where that loses the least (docs/anatomy.md, "One sphere budget a scenario").
pub const SCENARIO_TIGHTNESS: f64 = 1.2;

/// Segments of an `[[anatomy]]` entry that touch (one, usually) and the covers tried for them.
struct Covered {
    entry: usize,
    map: std::rc::Rc<LabelMap>,
    segment: Segment,
    options: CoverOptions,
    ladder: Ladder,
}

impl ScenarioFile {
    /// How many spheres the anatomy may take beside `used` obstacle spheres:
    /// `planner.max_anatomy_spheres`, up to what the host holds, else what keeps the scenario
    /// within the device's capacity ([`DEVICE_MAX_OBSTACLES`]; the host's when the obstacles
    /// alone fill it).
    fn anatomy_budget(&self, used: usize) -> Result<usize> {
        let host = HOST_MAX_OBSTACLES.saturating_sub(used);
        match self.planner.as_ref().and_then(|p| p.max_anatomy_spheres) {
            Some(0) => bail!("planner.max_anatomy_spheres is 0: the anatomy needs at least 1"),
            Some(n) if n > host => bail!(
                "planner.max_anatomy_spheres is {n}: at most {host} (the host's \
                 {HOST_MAX_OBSTACLES} obstacles less the {used} of [[obstacles]])"
            ),
            Some(n) => Ok(n),
            None if used < DEVICE_MAX_OBSTACLES => Ok(DEVICE_MAX_OBSTACLES - used),
            None => Ok(host),
        }
    }

    /// The spheres of every `[[anatomy]]` entry, one shape per entry; their indices follow the
    /// `[[obstacles]]`' ones. `used` spheres are the obstacles': the anatomy takes at most its
    /// budget beside them ([`ScenarioFile::anatomy_budget`]), and a cover loosened to fit says
    /// so on stderr.
    pub fn anatomy_shapes(&self, plane: bool, used: usize) -> Result<Vec<ObstacleShape>> {
        if self.anatomy.is_empty() {
            return Ok(Vec::new());
        }
        if plane {
            bail!("anatomy is 3-D: leave planner.plane out");
        }
        let budget = self.anatomy_budget(used)?;
        // Once for every entry: a target given as a label reads its label map.
        let ends = [self.entry_position()?, self.target_position()?];
        let reach = Reach {
            entry: ends[0].map(f64::from),
            target: ends[1].map(f64::from),
            length: f64::from(self.needle.length.unwrap_or(DEFAULT_NEEDLE_LENGTH_MM)),
        };
        let mut covered = Vec::new();
        for (n, a) in self.anatomy.iter().enumerate() {
            self.anatomy_ladders(n, a, &reach, &mut covered)
                .map_err(|e| anyhow!("in anatomy[{n}]: {e:#}"))?;
        }
        let ladders: Vec<&[_]> = covered.iter().map(|c| &c.ladder.candidates[..]).collect();
        let chosen = allocate(&ladders, budget).map_err(|e| anyhow!("in anatomy: {e:#}"))?;
        let mut shapes: Vec<ObstacleShape> = (0..self.anatomy.len())
            .map(|n| ObstacleShape {
                index: self.obstacles.len() + n,
                polygon: None,
                circles: Vec::new(),
            })
            .collect();
        for (c, &i) in covered.iter().zip(&chosen) {
            let candidates = &c.ladder.candidates;
            let cover = finish(&c.map, &c.segment, &c.ladder, &candidates[i], &c.options)
                .map_err(|e| anyhow!("in anatomy[{}]: {e:#}", c.entry))?;
            if i + 1 < candidates.len() {
                let asked = candidates.last().map_or(0, |x| x.spheres.len());
                eprintln!(
                    "note: anatomy[{}]: segment {:?} is covered by {} spheres, looser than \
                     tightness {} asks ({asked} spheres; {:.0} % outside the dilated segment), \
                     so that the scenario holds at most {budget} anatomy spheres \
                     (planner.max_anatomy_spheres)",
                    c.entry,
                    c.segment.name,
                    cover.spheres.len(),
                    c.options.tightness,
                    100.0 * cover.outside_dilated_ratio
                );
            }
            shapes[c.entry]
                .circles
                .extend(cover.spheres.iter().map(|s| Obstacle {
                    center: s.center.map(|v| v as f32),
                    radius: s.radius as f32,
                }));
        }
        Ok(shapes)
    }

    /// The covers tried for each segment of entry `a`, without those that hold the entry or
    /// the target (an error when the cover asked for does).
    fn anatomy_ladders(
        &self,
        n: usize,
        a: &AnatomyFile,
        reach: &Reach,
        out: &mut Vec<Covered>,
    ) -> Result<()> {
        let path = self.relative(&a.file);
        let options = CoverOptions {
            margin_mm: a.margin_mm.unwrap_or(0.0),
            max_spheres: a.max_spheres.unwrap_or(HOST_MAX_OBSTACLES),
            tightness: a.tightness.unwrap_or(SCENARIO_TIGHTNESS),
        }
        .validated()?;
        let voxel = a.voxel_mm.unwrap_or(needle_anatomy::mesh::DEFAULT_VOXEL_MM);
        let map = std::rc::Rc::new(LabelMap::read_with(&path, voxel, a.unit.as_deref())?);
        let at = |e: anyhow::Error| anyhow!("{}: {e:#}", path.display());
        let chosen = selected(&map, a.labels.as_deref(), a.segments.as_deref()).map_err(at)?;
        let mut progress =
            needle_anatomy::progress::Progress::new(format!("covering {}", path.display()));
        // Segments that touch are covered as one (a capsule with its organ).
        let groups = touching_groups(&map, &chosen);
        let total = groups.len();
        for (done, group) in groups.iter().enumerate() {
            let members: Vec<&Segment> = group.iter().map(|&g| &chosen[g]).collect();
            let segment = merged(&members);
            progress.step(done, total, &format!("segment {:?}", segment.name));
            // A point no cover can keep out is an error before the cover is tried.
            for member in &members {
                let voxels = map.voxels_of(member.label);
                for (what, p) in [("entry", reach.entry), ("target", reach.target)] {
                    let (hd, nearest) = clear_of(&map, &voxels, p);
                    if nearest - hd - 1e-3 < options.margin_mm {
                        let name = format!("segment {:?} of {}", member.name, path.display());
                        bail!(
                            "{}",
                            kept_out_error(what, &name, options.margin_mm, hd, nearest)
                        );
                    }
                }
            }
            let group_segments: Vec<Segment> = members.iter().map(|&m| m.clone()).collect();
            let mut ladder =
                group_ladder(&map, &group_segments, &options, Some(reach)).map_err(at)?;
            let holds = |spheres: &[needle_anatomy::cover::Sphere], p: [f64; 3]| {
                spheres.iter().any(|s| {
                    let d: f64 = (0..3).map(|k| (p[k] - s.center[k]).powi(2)).sum();
                    d.sqrt() <= s.radius
                })
            };
            let asked = ladder.candidates.last().expect("a ladder is never empty");
            for (what, p) in [("entry", reach.entry), ("target", reach.target)] {
                if holds(&asked.spheres, p) {
                    let (hd, nearest) = clear_of(&map, &ladder.voxels, p);
                    let name = format!("segment {:?} of {}", segment.name, path.display());
                    bail!(
                        "{}",
                        kept_out_error(what, &name, options.margin_mm, hd, nearest)
                    );
                }
            }
            ladder
                .candidates
                .retain(|c| !holds(&c.spheres, reach.entry) && !holds(&c.spheres, reach.target));
            out.push(Covered {
                entry: n,
                map: map.clone(),
                segment,
                options,
                ladder,
            });
        }
        Ok(())
    }
}

/// Why the entry or target (`what`), `nearest` mm from the nearest voxel centre of a segment
/// (`name`) whose voxels' half diagonal is `hd`, lies inside its cover with `margin`.
fn kept_out_error(what: &str, name: &str, margin: f64, hd: f64, nearest: f64) -> String {
    // A sphere about a voxel's own centre reaches the half diagonal and the margin; a hair less
    // keeps the point out whatever the float rounding.
    let largest = ((nearest - hd - 1e-3) * 100.0).floor() / 100.0;
    if largest < 0.0 {
        return format!(
            "the {what} lies inside the cover of {name} ({nearest:.2} mm from a voxel's centre, \
             within its half diagonal of {hd:.2} mm, so no margin keeps it out): select the \
             structures to avoid (labels, segments), not the one that holds the {what}"
        );
    }
    format!(
        "the {what} lies inside the cover of {name}: it is {nearest:.2} mm from the nearest \
         voxel's centre, and the cover with margin_mm = {margin} reaches up to {:.2} mm from it \
         (the margin and half the voxel's diagonal, {hd:.2} mm), {:.2} mm too far; a margin of \
         at most {largest:.2} mm keeps the {what} outside",
        margin + hd,
        margin + hd - nearest
    )
}
