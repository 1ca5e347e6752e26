//! Segments that touch, covered as one.
//!
//! No path passes between two segments whose voxels meet (face, edge or corner: their
//! dilations by any margin overlap), so the surface they share needs no spheres of its own. A
//! capsule wrapped round its organ, covered alone, is a shell a voxel or two thick that takes
//! hundreds of small spheres and still overshoots it on both faces; covered with its organ it is
//! the outer face of one solid. The cover of the union holds every voxel of each segment, as
//! each segment's own cover would.

use super::label_map::{LabelMap, Segment};

/// The segments of `segments` (indices) in groups that touch, each group in the order given and
/// the groups in the order of their first segment.
pub fn touching_groups(map: &LabelMap, segments: &[Segment]) -> Vec<Vec<usize>> {
    let mut parent: Vec<usize> = (0..segments.len()).collect();
    let mut by_label: Vec<(i64, usize)> = segments
        .iter()
        .enumerate()
        .map(|(n, s)| (s.label, n))
        .collect();
    by_label.sort_unstable();
    let lookup = |label: i64| {
        by_label
            .binary_search_by_key(&label, |&(l, _)| l)
            .ok()
            .map(|at| by_label[at].1)
    };
    let [ni, nj, nk] = map.dims;
    // Half of the 26 neighbours: each pair of voxels is looked at once.
    let forward: Vec<[i64; 3]> = (-1..=1)
        .flat_map(|z| (-1..=1).flat_map(move |y| (-1..=1).map(move |x| [x, y, z])))
        .filter(|d| (d[2], d[1], d[0]) > (0, 0, 0))
        .collect();
    for k in 0..nk {
        for j in 0..nj {
            for i in 0..ni {
                let here = map.labels[i + ni * (j + nj * k)];
                let Some(a) = lookup(here) else { continue };
                for d in &forward {
                    let (x, y, z) = (i as i64 + d[0], j as i64 + d[1], k as i64 + d[2]);
                    if x < 0 || y < 0 || x >= ni as i64 || y >= nj as i64 || z >= nk as i64 {
                        continue;
                    }
                    let there = map.labels[x as usize + ni * (y as usize + nj * z as usize)];
                    if there == here {
                        continue;
                    }
                    if let Some(b) = lookup(there) {
                        union(&mut parent, a, b);
                    }
                }
            }
        }
    }
    let mut groups: Vec<Vec<usize>> = Vec::new();
    let mut group_of_root: Vec<Option<usize>> = vec![None; segments.len()];
    for s in 0..segments.len() {
        let r = root(&mut parent, s);
        match group_of_root[r] {
            Some(g) => groups[g].push(s),
            None => {
                group_of_root[r] = Some(groups.len());
                groups.push(vec![s]);
            }
        }
    }
    groups
}

/// One segment standing for a group in messages: the names joined, the first one's label.
pub fn merged(segments: &[&Segment]) -> Segment {
    let names: Vec<&str> = segments.iter().map(|s| s.name.as_str()).collect();
    Segment {
        name: names.join(" + "),
        label: segments.first().map_or(0, |s| s.label),
    }
}

fn root(parent: &mut [usize], mut s: usize) -> usize {
    while parent[s] != s {
        parent[s] = parent[parent[s]];
        s = parent[s];
    }
    s
}

fn union(parent: &mut [usize], a: usize, b: usize) {
    let (ra, rb) = (root(parent, a), root(parent, b));
    if ra != rb {
        parent[ra.max(rb)] = ra.min(rb);
    }
}
