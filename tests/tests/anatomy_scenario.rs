//! `[[anatomy]]` in a scenario: a target the margin puts inside a segment's cover is an error
//! that names the segment, by how much, and the largest margin that plans (and that margin
//! plans); a scenario whose covers need more than the device's spheres is loosened to fit,
//! `needle plan` says so and the device plans it as the host does; the clearance reported
//! against the label map is the distance to the voxels.

use needle_e2e::anatomy_family::anatomy_case;
use needle_e2e::label_files::{write_nrrd, Labels, NrrdStyle};
use needle_e2e::needle;
use std::path::{Path, PathBuf};
use wire_support::{run_needle, SimProcess};

mod wire_support;

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("needle-anat-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn write_map(dir: &Path, labels: &Labels) {
    let style = NrrdStyle {
        space: "right-anterior-superior",
        gzip: true,
        pairs: &[],
    };
    write_nrrd(&dir.join("map.nrrd"), labels, &style);
}

/// The cover, the clearance, the messages and the device's plan are under test, at targets a
/// few millimetres from an organ, so the scenarios opt out of the default collision bound: under
/// it such a target is refused with the predicted probability as the reason.
const UNBOUNDED: &str = "\n[planner]\nmax_collision_probability = \"off\"\n";

fn scenario(dir: &Path, entry: [f64; 3], target: [f64; 3], margin: f64) -> PathBuf {
    let d: Vec<f64> = (0..3).map(|k| target[k] - entry[k]).collect();
    let text = format!(
        "[needle]\ncurvature_radius = 60.0\n\n[entry]\nposition = {entry:?}\ndirection = {d:?}\n\n\
         [target]\nposition = {target:?}\n\n[[anatomy]]\nfile = \"map.nrrd\"\nmargin_mm = {margin:?}\n{UNBOUNDED}"
    );
    let path = dir.join(format!("margin-{margin}.toml"));
    std::fs::write(&path, text).unwrap();
    path
}

/// A cube of 10 voxels of 1 mm (faces at 4.5 and 14.5 mm) and a target 1.5 mm beyond a face:
/// 2 mm from the nearest voxel centre, so a sphere about that voxel with the margin holds it
/// unless the margin is below 2 less the half diagonal (0.866 mm).
#[test]
fn a_target_the_margin_covers_names_the_segment_and_the_largest_margin() {
    let dir = temp_dir("margin");
    let a = [
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0, 0.0],
        [0.0, 0.0, 1.0, 0.0],
    ];
    let cube = Labels::of([20, 20, 20], a, |i, j, k| {
        i16::from([i, j, k].iter().all(|x| (5..15).contains(x)))
    });
    write_map(&dir, &cube);
    let (entry, target) = ([60.0, 9.0, 9.0], [16.0, 9.0, 9.0]);
    let too_wide = scenario(&dir, entry, target, 2.0);
    let out = needle()
        .args(["plan", too_wide.to_str().unwrap()])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    for part in [
        "the target lies inside the cover of segment \"label 1\"",
        "2.00 mm from the nearest voxel's centre",
        "0.87 mm too far",
        "a margin of at most 1.13 mm keeps the target outside",
    ] {
        assert!(err.contains(part), "{part:?} not in: {err}");
    }
    let largest = scenario(&dir, entry, target, 1.13);
    let out = needle()
        .args(["plan", largest.to_str().unwrap(), "--json"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Writes map 0 of the family and a scenario from above it to its lesion with a 1 mm margin,
/// its cover asked as tight as 1.05 takes more than the device's 256 spheres.
fn budget_map(dir: &Path) -> PathBuf {
    let case = anatomy_case(0, 0.6);
    write_map(dir, &case.labels);
    let d = case.labels.dims;
    let a = case.labels.ijk_to_ras;
    let top = [0, 1, 2].map(|r| {
        let g = [0.5 * d[0] as f64, 0.5 * d[1] as f64, d[2] as f64 + 4.0];
        a[r][0] * g[0] + a[r][1] * g[1] + a[r][2] * g[2] + a[r][3]
    });
    let path = scenario(dir, top, case.target, 1.0);
    let text = std::fs::read_to_string(&path).unwrap();
    let tight = text.replace("margin_mm = 1.0\n", "margin_mm = 1.0\ntightness = 1.05\n");
    std::fs::write(&path, tight).unwrap();
    path
}

/// Map 0 is loosened to the device's 256 spheres; `needle plan` plans it and says on stderr
/// which segments were loosened; `needle send` to hil-sim plans it as the host does, bit for
/// bit, and the host measures the device's plan against the label map alike.
#[test]
fn a_scenario_over_the_devices_spheres_is_loosened_and_the_device_plans_it() {
    let dir = temp_dir("budget");
    let path = budget_map(&dir);
    let file = path.to_str().unwrap();
    let (ok_l, out_l, err_l) = run_needle(&["plan", file, "--json"]);
    assert!(
        err_l.contains("looser than tightness 1.05 asks")
            && err_l.contains("holds at most 256 anatomy spheres"),
        "{err_l}"
    );
    let sim = SimProcess::start(&["--tcp", "127.0.0.1:0"]);
    let send = [
        "send",
        file,
        "--tcp",
        sim.address.as_str(),
        "--timeout",
        "120",
        "--json",
    ];
    let (ok_r, out_r, err_r) = run_needle(&send);
    assert!(ok_l && ok_r, "{err_l} / {err_r}");
    let strip = |s: &str| s.split("\"stats\"").next().unwrap_or(s).to_string();
    assert_eq!(strip(&out_l), strip(&out_r));
    assert!(out_l.contains("\"best\":{"), "{out_l}");
    assert!(out_r.contains("\"label_map_clearance_mm\":"), "{out_r}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `planner.max_anatomy_spheres` sets the budget: raised to the host's 512, map 0 is covered by
/// more than the device's 256 spheres and plans on the host, and a device refuses it with the
/// reason; 0 and more than the host holds are refused naming the key.
#[test]
fn the_sphere_budget_is_a_scenario_key() {
    let dir = temp_dir("budget-key");
    let path = budget_map(&dir);
    let text = std::fs::read_to_string(&path).unwrap();
    let with = |n: &str| {
        let p = dir.join(format!("budget-{n}.toml"));
        std::fs::write(&p, format!("{text}max_anatomy_spheres = {n}\n")).unwrap();
        p.to_str().unwrap().to_string()
    };
    let raised = with("512");
    let (ok, _, err) = run_needle(&["plan", &raised, "--json"]);
    assert!(ok, "{err}");
    assert!(!err.contains("at most 256 anatomy spheres"), "{err}");
    let sim = SimProcess::start(&["--tcp", "127.0.0.1:0"]);
    let (ok_r, _, err_r) = run_needle(&["send", &raised, "--tcp", sim.address.as_str()]);
    assert!(!ok_r && err_r.contains("256"), "{err_r}");
    for (n, says) in [("0", "at least 1"), ("513", "at most 512")] {
        let (ok, _, err) = run_needle(&["plan", &with(n), "--json"]);
        assert!(
            !ok && err.contains("planner.max_anatomy_spheres") && err.contains(says),
            "{err}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The best path's clearance `needle plan` reports against the label map, beside the least
/// distance from the path (its printed points, joined by lines 0.05 mm apart) to the centres
/// of the labelled voxels, found one by one in f64 here: within half a voxel's diagonal, and
/// no nearer than the margin less that. Maps 0 (1 mm voxels) and 1 (0.7 x 0.7 x 2.5 mm) of
/// the family.
#[test]
fn the_label_map_clearance_is_the_distance_to_the_voxels() {
    let dir = temp_dir("clearance");
    for seed in [0u64, 1] {
        let case = anatomy_case(seed, 0.6);
        write_map(&dir, &case.labels);
        let m = &case.labels;
        let a = m.ijk_to_ras;
        let world = |g: [f64; 3]| {
            [0, 1, 2].map(|r| a[r][0] * g[0] + a[r][1] * g[1] + a[r][2] * g[2] + a[r][3])
        };
        let d = m.dims;
        let top = world([0.5 * d[0] as f64, 0.5 * d[1] as f64, d[2] as f64 + 4.0]);
        let path = scenario(&dir, top, case.target, 1.0);
        let out = needle()
            .args(["plan", path.to_str().unwrap(), "--json"])
            .output()
            .unwrap();
        let r: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let best = &r["best"];
        let reported = best["label_map_clearance_mm"].as_f64().unwrap();
        let points: Vec<[f64; 3]> = best["points"]
            .as_array()
            .unwrap()
            .iter()
            .map(|p| [0, 1, 2].map(|k| p[k].as_f64().unwrap()))
            .collect();
        let mut centres = Vec::new();
        for k in 0..d[2] {
            for j in 0..d[1] {
                for i in 0..d[0] {
                    if m.labels[i + d[0] * (j + d[1] * k)] != 0 {
                        centres.push(world([i as f64, j as f64, k as f64]));
                    }
                }
            }
        }
        let mut least = f64::INFINITY;
        for w in points.windows(2) {
            let steps = ((0..3)
                .map(|k| (w[1][k] - w[0][k]).powi(2))
                .sum::<f64>()
                .sqrt()
                / 0.05)
                .ceil()
                .max(1.0) as usize;
            for s in 0..=steps {
                let t = s as f64 / steps as f64;
                let p = [0, 1, 2].map(|k| w[0][k] + t * (w[1][k] - w[0][k]));
                for c in &centres {
                    let d2: f64 = (0..3).map(|k| (p[k] - c[k]).powi(2)).sum();
                    least = least.min(d2);
                }
            }
        }
        let least = least.sqrt();
        let half_diagonal = 0.5 * (0..3).map(|k| a[k][k] * a[k][k]).sum::<f64>().sqrt();
        println!("seed {seed}: reported {reported:.3} mm, reference {least:.3} mm");
        assert!(
            (reported - least).abs() <= half_diagonal,
            "seed {seed}: {reported} against {least}"
        );
        assert!(least >= 1.0 - half_diagonal, "seed {seed}: {least}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `needle plan` prints where the target lies: RAS, and its voxel (i, j, k) in each map (the
/// same voxel whether the file is LPS or RAS); a target given as a label is named and printed
/// (it was never printed).
#[test]
fn the_target_is_printed_in_ras_and_in_voxels() {
    let dir = temp_dir("target");
    let a = [
        [0.5, 0.0, 0.0, -3.0],
        [0.0, 1.0, 0.0, 2.0],
        [0.0, 0.0, 2.0, 1.0],
    ];
    let cube = Labels::of([20, 20, 20], a, |i, j, k| {
        i16::from([i, j, k].iter().all(|x| (5..15).contains(x)))
    });
    for space in ["left-posterior-superior", "right-anterior-superior"] {
        let style = NrrdStyle {
            space,
            gzip: false,
            pairs: &[],
        };
        write_nrrd(&dir.join("map.nrrd"), &cube, &style);
        // Voxel (18, 9, 9): RAS (-3 + 9, 2 + 9, 1 + 18).
        let path = scenario(&dir, [40.0, 11.0, 19.0], [6.0, 11.0, 19.0], 0.5);
        let (ok, out, err) = run_needle(&["plan", path.to_str().unwrap()]);
        assert!(ok, "{err}");
        assert!(out.contains("target: RAS (6.00, 11.00, 19.00) mm"), "{out}");
        assert!(
            out.contains("voxel (i, j, k) (18.00, 9.00, 9.00) of map.nrrd"),
            "{space}: {out}"
        );
    }
    let text = "[needle]\ncurvature_radius = 60.0\n\n[entry]\nposition = [40.0, 11.0, 19.0]\n\
                direction = [-1.0, 0.0, 0.0]\n\n[target]\nlabel = 1\nlabel_file = \"map.nrrd\"\n";
    let path = dir.join("label.toml");
    std::fs::write(&path, format!("{text}{UNBOUNDED}")).unwrap();
    let (ok, out, err) = run_needle(&["plan", path.to_str().unwrap()]);
    assert!(ok, "{err}");
    assert!(
        out.contains("target: the deepest point of label 1, RAS ("),
        "{out}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
