//! A seeded family of anatomy-like label maps for the cover's tests and benchmark: smooth
//! irregular organs (a sum of random Gaussian bumps, thresholded), a vessel tree of tubes, a
//! thin capsule around one organ, and a lesion target 2–8 mm from the nearest organ voxel; the
//! voxels isotropic (1 mm) or anisotropic (0.7 × 0.7 × 2.5 mm), the files LPS or RAS by seed.
//! The same seed gives the same map, bit for bit.

use crate::label_files::{write_nrrd, Labels, NrrdStyle};
use std::path::{Path, PathBuf};

/// Labels of the family: organs 1–3, the vessel tree 4, the capsule 5.
pub const VESSELS: i16 = 4;
/// The capsule's label.
pub const CAPSULE: i16 = 5;

/// One map of the family and where its lesion is.
pub struct AnatomyCase {
    /// The map.
    pub labels: Labels,
    /// The lesion's centre (RAS, mm): 2–8 mm from the nearest labelled voxel's centre.
    pub target: [f64; 3],
    /// Whether the file is written in LPS (else RAS).
    pub lps: bool,
}

/// splitmix64: a small, fixed generator, so the family does not depend on a crate's version.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }

    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
}

/// An organ: Gaussian bumps (centre mm, width mm) whose sum above 1 is inside.
struct Organ {
    bumps: Vec<([f64; 3], f64)>,
}

impl Organ {
    fn random(rng: &mut Rng, centre: [f64; 3], size: f64) -> Organ {
        let bumps = (0..6)
            .map(|_| {
                let c = centre.map(|x| x + rng.range(-0.5, 0.5) * size);
                (c, size * rng.range(0.35, 0.55))
            })
            .collect();
        Organ { bumps }
    }

    fn field(&self, p: [f64; 3]) -> f64 {
        self.bumps
            .iter()
            .map(|(c, w)| {
                let d2: f64 = (0..3).map(|k| (p[k] - c[k]).powi(2)).sum();
                (-d2 / (w * w)).exp()
            })
            .sum()
    }
}

/// The distance from `p` to the segment `a`–`b`.
fn to_segment(p: [f64; 3], a: [f64; 3], b: [f64; 3]) -> f64 {
    let ab = [0, 1, 2].map(|k| b[k] - a[k]);
    let ap = [0, 1, 2].map(|k| p[k] - a[k]);
    let t = ((0..3).map(|k| ab[k] * ap[k]).sum::<f64>()
        / (0..3).map(|k| ab[k] * ab[k]).sum::<f64>())
    .clamp(0.0, 1.0);
    (0..3)
        .map(|k| (p[k] - a[k] - t * ab[k]).powi(2))
        .sum::<f64>()
        .sqrt()
}

/// Map `seed` of the family, about `scale` times the base size (1: about 80 mm across).
pub fn anatomy_case(seed: u64, scale: f64) -> AnatomyCase {
    let mut rng = Rng(seed.wrapping_mul(0x2545_f491_4f6c_dd1d) ^ 0x5eed);
    let anisotropic = !seed.is_multiple_of(2);
    let spacing = if anisotropic {
        [0.7, 0.7, 2.5]
    } else {
        [1.0, 1.0, 1.0]
    };
    let extent = 80.0 * scale;
    let dims = spacing.map(|s| (extent / s).round() as usize);
    let origin = [-40.0 * scale, -40.0 * scale, 10.0];
    let size = 24.0 * scale;
    let organs: Vec<Organ> = [[-18.0, -12.0, 30.0], [16.0, -10.0, 28.0], [0.0, 18.0, 52.0]]
        .iter()
        .map(|c| {
            let c = [c[0] * scale, c[1] * scale, 10.0 + (c[2] - 10.0) * scale];
            let jitter = c.map(|x| x + rng.range(-3.0, 3.0) * scale);
            Organ::random(&mut rng, jitter, size)
        })
        .collect();
    let trunk = [
        [rng.range(-5.0, 5.0) * scale, -30.0 * scale, 40.0 * scale],
        [rng.range(-5.0, 5.0) * scale, 30.0 * scale, 45.0 * scale],
    ];
    let fork = [0, 1, 2].map(|k| 0.5 * (trunk[0][k] + trunk[1][k]));
    let branches = [
        (trunk[0], trunk[1], 2.5),
        (fork, [30.0 * scale, fork[1] + 5.0, 60.0 * scale], 1.6),
        (fork, [-30.0 * scale, fork[1] - 5.0, 20.0 * scale], 1.6),
    ];
    let a = [
        [spacing[0], 0.0, 0.0, origin[0]],
        [0.0, spacing[1], 0.0, origin[1]],
        [0.0, 0.0, spacing[2], origin[2]],
    ];
    let world = |i: i64, j: i64, k: i64| {
        [0, 1, 2].map(|r| a[r][0] * i as f64 + a[r][1] * j as f64 + a[r][2] * k as f64 + a[r][3])
    };
    let labels = Labels::of(dims, a, |i, j, k| {
        let p = world(i, j, k);
        if branches.iter().any(|(a, b, r)| to_segment(p, *a, *b) <= *r) {
            return VESSELS;
        }
        for (n, o) in organs.iter().enumerate() {
            let f = o.field(p);
            if f >= 1.0 {
                return n as i16 + 1;
            }
            // The capsule: a shell about 1.5 mm thick around the first organ.
            if n == 0 && f >= 0.8 {
                return CAPSULE;
            }
        }
        0
    });
    let target = lesion(&mut rng, &labels, &world);
    AnatomyCase {
        labels,
        target,
        lps: seed.is_multiple_of(3),
    }
}

/// A point 2–8 mm from the nearest labelled voxel centre, found by random draws.
fn lesion(rng: &mut Rng, m: &Labels, world: &dyn Fn(i64, i64, i64) -> [f64; 3]) -> [f64; 3] {
    let mut centres = Vec::new();
    for k in 0..m.dims[2] as i64 {
        for j in 0..m.dims[1] as i64 {
            for i in 0..m.dims[0] as i64 {
                let n = (i + m.dims[0] as i64 * (j + m.dims[1] as i64 * k)) as usize;
                if m.labels[n] != 0 {
                    centres.push(world(i, j, k));
                }
            }
        }
    }
    let lo = world(0, 0, 0);
    let hi = world(
        m.dims[0] as i64 - 1,
        m.dims[1] as i64 - 1,
        m.dims[2] as i64 - 1,
    );
    loop {
        let p = [0, 1, 2].map(|k| rng.range(lo[k] + 5.0, hi[k] - 5.0));
        let d = centres
            .iter()
            .map(|c| (0..3).map(|k| (p[k] - c[k]).powi(2)).sum::<f64>())
            .fold(f64::INFINITY, f64::min)
            .sqrt();
        if (2.0..=8.0).contains(&d) {
            return p;
        }
    }
}

impl AnatomyCase {
    /// Writes the map to `path` as gzipped NRRD, in the space the case says (LPS or RAS).
    pub fn write_map(&self, path: &Path) {
        let space = if self.lps {
            "left-posterior-superior"
        } else {
            "right-anterior-superior"
        };
        let style = NrrdStyle {
            space,
            gzip: true,
            pairs: &[],
        };
        write_nrrd(path, &self.labels, &style);
    }
}

/// Writes map `seed` of the family (scale 0.6) to `dir/caseSEED.nrrd` and a scenario that plans
/// from above it to its lesion, every segment covered with a 1 mm margin, `extra` appended (a
/// table of keys; the file is then `caseSEED-x.toml`); the case and the scenario's path.
pub fn write_scenario(dir: &Path, seed: u64, extra: &str) -> (AnatomyCase, PathBuf) {
    let case = anatomy_case(seed, 0.6);
    case.write_map(&dir.join(format!("case{seed}.nrrd")));
    let (d, a) = (case.labels.dims, case.labels.ijk_to_ras);
    let g = [0.5 * d[0] as f64, 0.5 * d[1] as f64, d[2] as f64 + 4.0];
    let top = [0, 1, 2].map(|r| a[r][0] * g[0] + a[r][1] * g[1] + a[r][2] * g[2] + a[r][3]);
    let t = case.target;
    let to: Vec<f64> = (0..3).map(|k| t[k] - top[k]).collect();
    let text = format!(
        "[needle]\ncurvature_radius = 60.0\n\n[entry]\nposition = {top:?}\ndirection = {to:?}\n\n\
         [target]\nposition = {t:?}\n\n[[anatomy]]\nfile = \"case{seed}.nrrd\"\nmargin_mm = 1.0\n{extra}"
    );
    let name = if extra.is_empty() { "" } else { "-x" };
    let path = dir.join(format!("case{seed}{name}.toml"));
    std::fs::write(&path, text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    (case, path)
}
