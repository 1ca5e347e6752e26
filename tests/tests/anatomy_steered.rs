//! The seeded family of anatomy-like maps (`needle_e2e::anatomy_family`, seeds 0-9) steered in
//! simulated tissue and judged against the label maps themselves, not the spheres: each map's
//! lesion planned from above as a newcomer's file plans it (closed loop, the 1 % collision
//! bound), and again unbounded, then `needle simulate --closed-loop`. Every run's true path is
//! walked here through the map's voxels (apart from the command) and must enter none, and the
//! command's own count (`summary.entered_voxels`) must agree. In a wild open-loop world, where
//! paths do stray into the organs, the two counts agree too.

use needle_e2e::anatomy_family::write_scenario;
use needle_e2e::label_files::Labels;
use serde_json::Value;
use std::path::Path;
use std::process::Command;

/// The voxel (i, j, k) whose box holds `p` (RAS, mm), by the inverse of the map's affine.
fn voxel_of(m: &Labels, p: [f64; 3]) -> [i64; 3] {
    let a = &m.ijk_to_ras;
    let l = |r: usize, c: usize| a[r][c];
    let det = l(0, 0) * (l(1, 1) * l(2, 2) - l(1, 2) * l(2, 1))
        - l(0, 1) * (l(1, 0) * l(2, 2) - l(1, 2) * l(2, 0))
        + l(0, 2) * (l(1, 0) * l(2, 1) - l(1, 1) * l(2, 0));
    let d = [0, 1, 2].map(|r| p[r] - a[r][3]);
    // Cramer's rule, column by column.
    [0, 1, 2].map(|c| {
        let col = |r: usize, k: usize| if k == c { d[r] } else { l(r, k) };
        let num = col(0, 0) * (col(1, 1) * col(2, 2) - col(1, 2) * col(2, 1))
            - col(0, 1) * (col(1, 0) * col(2, 2) - col(1, 2) * col(2, 0))
            + col(0, 2) * (col(1, 0) * col(2, 1) - col(1, 1) * col(2, 0));
        (num / det).round() as i64
    })
}

fn labelled(m: &Labels, g: [i64; 3]) -> bool {
    if (0..3).any(|k| g[k] < 0 || g[k] >= m.dims[k] as i64) {
        return false;
    }
    m.labels[(g[0] + m.dims[0] as i64 * (g[1] + m.dims[1] as i64 * g[2])) as usize] != 0
}

/// Whether the path through `points` (straight between them) enters a labelled voxel, looked
/// at every 0.02 mm.
fn enters(m: &Labels, points: &[Value]) -> bool {
    let pts: Vec<[f64; 3]> = points
        .iter()
        .map(|p| [0, 1, 2].map(|k| p[k].as_f64().unwrap()))
        .collect();
    pts.windows(2).any(|w| {
        let len = (0..3)
            .map(|k| (w[1][k] - w[0][k]).powi(2))
            .sum::<f64>()
            .sqrt();
        let n = (len / 0.02).ceil().max(1.0) as usize;
        (0..=n).any(|i| {
            let t = i as f64 / n as f64;
            labelled(
                m,
                voxel_of(m, [0, 1, 2].map(|k| w[0][k] + t * (w[1][k] - w[0][k]))),
            )
        })
    })
}

/// `needle simulate FILE --runs 20 --json --detail` with `extra`: the JSON, or `None` when the
/// scenario is refused (its reason printed).
fn simulate(path: &Path, extra: &[&str]) -> Option<Value> {
    let out = Command::new(needle_e2e::needle_bin())
        .arg("simulate")
        .arg(path)
        .args(["--runs", "20", "--json", "--detail"])
        .args(extra)
        .output()
        .unwrap();
    if !out.status.success() {
        println!(
            "{}: refused: {}",
            path.display(),
            String::from_utf8_lossy(&out.stderr).trim()
        );
        return None;
    }
    Some(serde_json::from_slice(&out.stdout).unwrap())
}

/// The runs whose true path entered a voxel, as walked here.
fn entered(m: &Labels, v: &Value) -> usize {
    v["runs_detail"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|r| enters(m, r["points"].as_array().unwrap()))
        .count()
}

/// Steers each map of seeds 0..10 closed loop as `extra` plans it: (maps planned, runs,
/// runs reached), every run judged here and by the command against the voxels.
fn steer_family(dir: &Path, extra: &str) -> (u64, u64, u64) {
    let (mut planned, mut runs, mut reached) = (0, 0, 0);
    for seed in 0..10 {
        let (map, path) = {
            let (case, path) = write_scenario(dir, seed, extra);
            (case.labels, path)
        };
        let Some(v) = simulate(&path, &["--closed-loop"]) else {
            continue;
        };
        planned += 1;
        let s = &v["summary"];
        runs += v["runs"].as_u64().unwrap();
        reached += s["outcomes"]["reached"].as_u64().unwrap();
        let here = entered(&map, &v);
        println!(
            "seed {seed} {extra:?}: {here} runs entered; {}",
            s["outcomes"]
        );
        assert_eq!(here, 0, "seed {seed}: a run entered an organ");
        assert_eq!(s["entered_voxels"], 0, "seed {seed}: {s}");
    }
    (planned, runs, reached)
}

#[test]
fn steered_runs_keep_out_of_the_organs_voxels() {
    let dir = std::env::temp_dir().join(format!("needle-anat-steered-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (planned, runs, reached) = steer_family(&dir, "");
    println!("as written (1 % bound): {planned} of 10 maps planned; {reached} of {runs} reached");
    let unbounded = "\n[planner]\nmax_collision_probability = \"off\"\n";
    let (planned_u, runs_u, reached_u) = steer_family(&dir, unbounded);
    println!("unbounded: {planned_u} of 10 maps planned; {reached_u} of {runs_u} reached");
    assert!(planned_u >= 8, "{planned_u} of 10 maps planned unbounded");
    // Open loop in a wild world (the curvature off by half, the insertion by millimetres):
    // paths stray into the organs, and the command counts each as walked here.
    let wild = [
        "--perturb",
        "curvature_spread=0.5",
        "--perturb",
        "insertion_error_mm=3",
    ];
    let mut strayed = 0;
    for seed in 0..10 {
        let (map, path) = {
            let (case, path) = write_scenario(&dir, seed, unbounded);
            (case.labels, path)
        };
        let Some(v) = simulate(&path, &wild) else {
            continue;
        };
        let here = entered(&map, &v);
        assert_eq!(
            v["summary"]["entered_voxels"].as_u64(),
            Some(here as u64),
            "seed {seed}"
        );
        assert!(v["summary"]["collisions"].as_u64().unwrap() >= here as u64);
        strayed += here;
    }
    println!("open loop, wild world: {strayed} runs entered an organ");
    assert!(
        strayed > 0,
        "the wild runs were meant to stray into an organ"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
