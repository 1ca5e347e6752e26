//! The cover on the seeded family of anatomy-like maps (`needle_e2e::anatomy_family`): every
//! voxel of every segment whole inside one sphere with the margin to spare, checked here apart
//! from the command and the planner. The spheres a map takes and the cover's volume outside the
//! dilated segments (measured here at the voxel centres) are printed: `needle cover` alone, a
//! segment's cover as tight as asked, takes more than 256 spheres a map; a scenario keeps to
//! the device's 256.

use needle_e2e::anatomy_family::{anatomy_case, write_scenario};
use needle_e2e::label_files::{cover_spheres, write_nrrd, Labels, NrrdStyle};
use needle_e2e::needle_json;

const MARGIN: f64 = 1.0;

fn world(m: &Labels, g: [f64; 3]) -> [f64; 3] {
    let a = &m.ijk_to_ras;
    [0, 1, 2].map(|r| a[r][0] * g[0] + a[r][1] * g[1] + a[r][2] * g[2] + a[r][3])
}

fn label_at(m: &Labels, g: [i64; 3]) -> i16 {
    if (0..3).any(|k| g[k] < 0 || g[k] >= m.dims[k] as i64) {
        return 0;
    }
    m.labels[(g[0] + m.dims[0] as i64 * (g[1] + m.dims[1] as i64 * g[2])) as usize]
}

/// The voxels of `label` (every label but 0 when 0) no sphere, shrunk by the margin, holds whole.
fn unheld(m: &Labels, label: i16, spheres: &[([f64; 3], f64)]) -> usize {
    let mut count = 0;
    for k in 0..m.dims[2] as i64 {
        for j in 0..m.dims[1] as i64 {
            for i in 0..m.dims[0] as i64 {
                if !of(label, label_at(m, [i, j, k])) {
                    continue;
                }
                let corners: Vec<[f64; 3]> = (0..8)
                    .map(|n| {
                        let d = [0, 1, 2].map(|b| if n >> b & 1 == 1 { 0.5 } else { -0.5 });
                        world(m, [i as f64 + d[0], j as f64 + d[1], k as f64 + d[2]])
                    })
                    .collect();
                let held = spheres.iter().any(|(c, r)| {
                    corners.iter().all(|p| {
                        (0..3).map(|a| (p[a] - c[a]).powi(2)).sum::<f64>().sqrt() <= r - MARGIN
                    })
                });
                count += usize::from(!held);
            }
        }
    }
    count
}

/// Whether a voxel of value `v` belongs to `label` (any label but 0 when `label` is 0).
fn of(label: i16, v: i16) -> bool {
    v != 0 && (label == 0 || v == label)
}

/// The cover's voxel centres outside the segment (every label when 0) dilated by the margin,
/// over the dilated segment's voxel centres (a centre is in the dilation when within the margin of a voxel's
/// cube of the segment; spacing is axis-aligned in the family).
fn outside_ratio(m: &Labels, label: i16, spheres: &[([f64; 3], f64)]) -> f64 {
    let s = [0, 1, 2].map(|k| m.ijk_to_ras[k][k]);
    let reach = s.map(|x| (MARGIN / x).ceil() as i64 + 1);
    let dilated = |g: [i64; 3]| {
        for dz in -reach[2]..=reach[2] {
            for dy in -reach[1]..=reach[1] {
                for dx in -reach[0]..=reach[0] {
                    let v = [g[0] + dx, g[1] + dy, g[2] + dz];
                    if !of(label, label_at(m, v)) {
                        continue;
                    }
                    let d: f64 = [dx, dy, dz]
                        .iter()
                        .zip(s)
                        .map(|(&d, s)| ((d.abs() as f64 - 0.5).max(0.0) * s).powi(2))
                        .sum();
                    if d.sqrt() <= MARGIN {
                        return true;
                    }
                }
            }
        }
        false
    };
    let (mut out, mut inside) = (0usize, 0usize);
    let pad = reach.map(|r| r + 2);
    for k in -pad[2]..m.dims[2] as i64 + pad[2] {
        for j in -pad[1]..m.dims[1] as i64 + pad[1] {
            for i in -pad[0]..m.dims[0] as i64 + pad[0] {
                let p = world(m, [i, j, k].map(|x| x as f64));
                let covered = spheres
                    .iter()
                    .any(|(c, r)| (0..3).map(|a| (p[a] - c[a]).powi(2)).sum::<f64>() <= r * r);
                let d = dilated([i, j, k]);
                inside += usize::from(d);
                out += usize::from(covered && !d);
            }
        }
    }
    out as f64 / inside as f64
}

#[test]
fn the_family_is_covered_whole() {
    let dir = std::env::temp_dir().join(format!("needle-anat-family-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut ratios = Vec::new();
    for seed in 0..20 {
        let case = anatomy_case(seed, 0.6);
        let path = dir.join(format!("case{seed}.nrrd"));
        case.write_map(&path);
        let margin = MARGIN.to_string();
        let r = needle_json(&[
            "cover",
            path.to_str().unwrap(),
            "--margin",
            &margin,
            "--json",
        ]);
        let all = cover_spheres(&r);
        println!("seed {seed}: {} spheres", all.len());
        for seg in r["segments"].as_array().unwrap() {
            let label = seg["label"].as_i64().unwrap() as i16;
            let spheres: Vec<([f64; 3], f64)> = all
                .iter()
                .filter(|s| s.0 == i64::from(label))
                .map(|s| (s.1, s.2))
                .collect();
            assert_eq!(
                unheld(&case.labels, label, &spheres),
                0,
                "seed {seed} label {label}"
            );
            let ratio = outside_ratio(&case.labels, label, &spheres);
            println!(
                "seed {seed} label {label}: {} spheres, outside {ratio:.3}",
                spheres.len()
            );
            ratios.push(ratio);
        }
    }
    ratios.sort_by(f64::total_cmp);
    let median = ratios[ratios.len() / 2];
    let worst = ratios[ratios.len() - 1];
    println!("outside the dilated segments: median {median:.3}, worst {worst:.3}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The family as scenarios: each within the device's 256 spheres (the scenario's budget), every
/// voxel of every segment held whole with the margin to spare, checked here apart from the
/// planner; the spheres and the volume outside the dilated segments (all of them together,
/// at the voxel centres) are printed.
#[test]
fn the_family_fits_the_devices_sphere_budget() {
    use needle_scenario::file::ScenarioFile;
    let dir = std::env::temp_dir().join(format!("needle-anat-budget-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (mut counts, mut ratios) = (Vec::new(), Vec::new());
    for seed in 0..20 {
        let (case, path) = write_scenario(&dir, seed, "");
        let shapes = ScenarioFile::load(&path)
            .and_then(|f| f.obstacle_shapes(None))
            .unwrap_or_else(|e| panic!("seed {seed}: {e:#}"));
        let spheres: Vec<([f64; 3], f64)> = shapes
            .iter()
            .flat_map(|s| &s.circles)
            .map(|c| (c.center.map(f64::from), f64::from(c.radius)))
            .collect();
        assert!(
            spheres.len() <= planner_core::DEVICE_MAX_OBSTACLES,
            "seed {seed}"
        );
        // The planner's spheres are f32: held whole less a micrometre of rounding.
        let widened: Vec<_> = spheres.iter().map(|&(c, r)| (c, r + 1e-3)).collect();
        assert_eq!(unheld(&case.labels, 0, &widened), 0, "seed {seed}");
        let ratio = outside_ratio(&case.labels, 0, &spheres);
        println!("seed {seed}: {} spheres, outside {ratio:.3}", spheres.len());
        counts.push(spheres.len());
        ratios.push(ratio);
    }
    ratios.sort_by(f64::total_cmp);
    counts.sort_unstable();
    // Twenty maps: the median is the mean of the middle two.
    let n = ratios.len();
    let median = 0.5 * (ratios[(n - 1) / 2] + ratios[n / 2]);
    let worst = ratios[n - 1];
    println!(
        "{n} scenarios: spheres {}..{}, outside the dilated segments: median {median:.3} (the \
         middle two {:.3} and {:.3}), worst {worst:.3}",
        counts[0],
        counts[counts.len() - 1],
        ratios[(n - 1) / 2],
        ratios[n / 2],
    );
    // The aim: at most half the dilated segments' volume outside them over the family, and at
    // most as much again on any map.
    assert!(
        median <= 0.5 && worst <= 1.0,
        "median {median}, worst {worst}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Prints how long `needle cover` takes on a map of the family with over 500 000 labelled voxels
/// in five segments, and `needle plan` on a scenario of it, its lesion from above (and, with
/// `NEEDLE_COMPARE=/path/to/an/older/needle`, that binary beside it). A benchmark that prints,
/// not a timed test:
/// `cargo test -p needle-e2e --profile ci --test anatomy_family -- --ignored --nocapture`.
#[test]
#[ignore]
fn cover_benchmark() {
    let dir = std::env::temp_dir().join(format!("needle-anat-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let case = anatomy_case(2, 2.3);
    let voxels = case.labels.labels.iter().filter(|&&l| l != 0).count();
    let path = dir.join("bench.nrrd");
    let style = NrrdStyle {
        space: "right-anterior-superior",
        gzip: true,
        pairs: &[],
    };
    write_nrrd(&path, &case.labels, &style);
    println!("{} labelled voxels, grid {:?}", voxels, case.labels.dims);
    let (d, a) = (case.labels.dims, case.labels.ijk_to_ras);
    let g = [0.5 * d[0] as f64, 0.5 * d[1] as f64, d[2] as f64 + 4.0];
    let top = [0, 1, 2].map(|r| a[r][0] * g[0] + a[r][1] * g[1] + a[r][2] * g[2] + a[r][3]);
    let scenario = dir.join("bench.toml");
    std::fs::write(
        &scenario,
        format!(
            "[needle]\ncurvature_radius = 60.0\n\n[entry]\nposition = {top:?}\ndirection = {:?}\n\n\
             [target]\nposition = {:?}\n\n[[anatomy]]\nfile = \"bench.nrrd\"\nmargin_mm = 1.0\n",
            [0, 1, 2].map(|k| case.target[k] - top[k]),
            case.target
        ),
    )
    .unwrap();
    let mut binaries = vec![("this", needle_e2e::needle_bin().to_path_buf())];
    if let Some(other) = std::env::var_os("NEEDLE_COMPARE") {
        binaries.push(("compared", other.into()));
    }
    for (name, bin) in binaries {
        let start = std::time::Instant::now();
        let out = std::process::Command::new(&bin)
            .args(["cover", path.to_str().unwrap(), "--json"])
            .output()
            .unwrap();
        let secs = start.elapsed().as_secs_f64();
        let r: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap_or_default();
        println!(
            "{name} ({}): {secs:.2} s, {} spheres, {}",
            bin.display(),
            r["spheres"],
            String::from_utf8_lossy(&out.stderr).trim()
        );
        let start = std::time::Instant::now();
        let out = std::process::Command::new(&bin)
            .args(["plan", scenario.to_str().unwrap(), "--json"])
            .output()
            .unwrap();
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap_or_default();
        let stderr = String::from_utf8_lossy(&out.stderr);
        println!(
            "{name}: needle plan on it from above, {:.2} s (covers and plan), best {} mm, {}",
            start.elapsed().as_secs_f64(),
            v["best"]["length"],
            stderr.trim().lines().last().unwrap_or("")
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
