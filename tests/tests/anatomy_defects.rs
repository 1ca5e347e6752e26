//! What a user met covering a real segmented atlas: selections that silently dropped or
//! doubled segments, voxels a `.seg.nrrd` does not name, an `endian` field in capitals, a mesh
//! in metres, options without bounds, and messages with Rust debug text. Each is an error that
//! says what is wrong, or is read as the file means it.

use needle_e2e::label_files::{write_nifti, write_nrrd, write_stl_box, Labels, NrrdStyle};
use needle_e2e::{needle, needle_json};
use std::path::{Path, PathBuf};

fn scratch(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("needle-anat-def-{test}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `needle args` fails without a panic or Rust debug text; its stderr holds every one of `want`.
fn fails_with(args: &[&str], want: &[&str]) -> String {
    let out = needle().args(args).output().unwrap();
    assert!(!out.status.success(), "{args:?} succeeded");
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    for debug in ["panicked", "Some(", "Custom {", "kind:", "tip: to pass"] {
        assert!(!err.contains(debug), "{args:?}: {debug:?} in: {err}");
    }
    for w in want {
        assert!(err.contains(w), "{args:?}: no {w:?} in: {err}");
    }
    err
}

/// Two boxes: label 1 and label 2, on 1 mm voxels.
fn boxes() -> Labels {
    let a = [
        [1.0, 0.0, 0.0, 30.0],
        [0.0, 1.0, 0.0, 30.0],
        [0.0, 0.0, 1.0, 30.0],
    ];
    Labels::of([20, 20, 20], a, |i, j, k| match (i, j, k) {
        (2..=6, 2..=6, 2..=6) => 1,
        (10..=17, 3..=15, 8..=9) => 2,
        _ => 0,
    })
}

/// A scenario whose `[[anatomy]]` entry is `entry` (TOML lines), the map far from the path.
fn scenario(dir: &Path, name: &str, entry: &str) -> String {
    let path = dir.join(name);
    std::fs::write(
        &path,
        format!(
            "[needle]\ncurvature_radius = 63.7\n[entry]\nposition = [0, 0, 0]\n\
             direction = [0, 0, 1]\n[target]\nposition = [0, 0, 80]\n[[anatomy]]\n{entry}\n"
        ),
    )
    .unwrap();
    path.to_str().unwrap().to_string()
}

fn seg_nrrd(dir: &Path) -> PathBuf {
    let path = dir.join("case.seg.nrrd");
    let style = NrrdStyle {
        space: "left-posterior-superior",
        gzip: true,
        pairs: &[("Segment0_Name", "organ"), ("Segment0_LabelValue", "1")],
    };
    write_nrrd(&path, &boxes(), &style);
    path
}

/// `labels` and `segments` together are refused in a scenario (the command refused them); an
/// empty list, which selected everything, and a label or name given twice are refused too.
#[test]
fn selections_that_would_cover_something_else_are_refused() {
    let dir = scratch("select");
    seg_nrrd(&dir);
    let cases: [(&str, &str); 5] = [
        (
            "labels = [2]\nsegments = [\"organ\"]",
            "labels and segments are both given",
        ),
        ("labels = []", "the labels list is empty"),
        ("segments = []", "the segments list is empty"),
        ("labels = [1, 1]", "1 is given twice in labels"),
        (
            "segments = [\"organ\", \"organ\"]",
            "\"organ\" is given twice in segments",
        ),
    ];
    for (n, (entry, want)) in cases.iter().enumerate() {
        let s = scenario(
            &dir,
            &format!("s{n}.toml"),
            &format!("file = \"case.seg.nrrd\"\n{entry}"),
        );
        fails_with(&["plan", &s], &["anatomy[0]", "case.seg.nrrd", want]);
    }
    let map = dir.join("case.seg.nrrd");
    fails_with(
        &["cover", map.to_str().unwrap(), "--labels", "1,1"],
        &["1 is given twice in labels"],
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A `.seg.nrrd` naming label 1 only, whose voxels also hold 2: label 2 is in the map, covered
/// by default and by `--labels 2`, not dropped.
#[test]
fn voxels_a_seg_nrrd_does_not_name_are_kept() {
    let dir = scratch("unnamed");
    let map = seg_nrrd(&dir);
    let all = needle_json(&["cover", map.to_str().unwrap(), "--json"]);
    let labels: Vec<i64> = all["segments"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["label"].as_i64().unwrap())
        .collect();
    assert_eq!(labels, [1, 2], "{all}");
    let two = needle_json(&["cover", map.to_str().unwrap(), "--labels", "2", "--json"]);
    assert_eq!(two["segments"][0]["name"], "label 2");
    assert_eq!(two["segments"][0]["voxels"], 8 * 13 * 2);
    let _ = std::fs::remove_dir_all(&dir);
}

/// `endian: BIG` is big-endian (teem reads the field in any case); an unknown word is refused.
#[test]
fn an_endian_field_in_capitals_is_read() {
    let dir = scratch("endian");
    let m = boxes();
    let header = |endian: &str| {
        format!(
            "NRRD0004\ntype: short\ndimension: 3\nspace: right-anterior-superior\nsizes: 20 20 20\n\
             space directions: (1,0,0) (0,1,0) (0,0,1)\nkinds: domain domain domain\n\
             endian: {endian}\nencoding: raw\nspace origin: (30,30,30)\n\
             Segment0_Name:=organ\nSegment0_LabelValue:=1\nSegment1_Name:=rib\n\
             Segment1_LabelValue:=2\n\n"
        )
    };
    let data: Vec<u8> = m.labels.iter().flat_map(|l| l.to_be_bytes()).collect();
    for endian in ["big", "BIG", "Big"] {
        let path = dir.join(format!("{endian}.seg.nrrd"));
        std::fs::write(&path, [header(endian).into_bytes(), data.clone()].concat()).unwrap();
        let r = needle_json(&["cover", path.to_str().unwrap(), "--json"]);
        let names: Vec<&str> = r["segments"]
            .as_array()
            .unwrap()
            .iter()
            .map(|s| s["name"].as_str().unwrap())
            .collect();
        assert_eq!(names, ["organ", "rib"], "{endian}: {r}");
        assert_eq!(r["segments"][0]["voxels"], 125, "{endian}");
    }
    let odd = dir.join("odd.nrrd");
    std::fs::write(&odd, [header("middle").into_bytes(), data].concat()).unwrap();
    fails_with(
        &["cover", odd.to_str().unwrap()],
        &["odd.nrrd", "endian \"middle\" is neither big nor little"],
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A mesh written in metres (a 20 mm box as 0.02) is refused unless its unit is given; given,
/// it is covered as the 20 mm box it is.
#[test]
fn a_mesh_in_metres_is_refused_unless_its_unit_is_given() {
    let dir = scratch("metres");
    let stl = dir.join("box-m.stl");
    write_stl_box(&stl, [0.0; 3], [0.02, 0.02, 0.02], "SPACE=RAS", false);
    let path = stl.to_str().unwrap();
    fails_with(
        &["cover", path],
        &["box-m.stl", "implausible for millimetres", "--unit m"],
    );
    let s = scenario(&dir, "m.toml", "file = \"box-m.stl\"");
    fails_with(
        &["plan", &s],
        &["anatomy[0]", "implausible for millimetres"],
    );
    let r = needle_json(&["cover", path, "--unit", "m", "--voxel", "1", "--json"]);
    for s in r["segments"][0]["spheres"].as_array().unwrap() {
        let c: Vec<f64> = s["center"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        assert!(c.iter().all(|x| (-2.0..=22.0).contains(x)), "{r}");
    }
    // Every corner of the 20 mm box lies in some sphere.
    let spheres = needle_e2e::label_files::cover_spheres(&r);
    for n in 0..8 {
        let p = [0, 1, 2].map(|k| if n >> k & 1 == 1 { 20.0 } else { 0.0 });
        let inside = spheres.iter().any(|(_, c, r)| {
            let d: f64 = (0..3).map(|k| (p[k] - c[k]).powi(2)).sum();
            d.sqrt() <= *r
        });
        assert!(inside, "corner {p:?} outside the cover: {r}");
    }
    let s = scenario(
        &dir,
        "m-unit.toml",
        "file = \"box-m.stl\"\nunit = \"m\"\nvoxel_mm = 1",
    );
    let out = needle().args(["plan", &s]).output().unwrap();
    assert!(
        !String::from_utf8_lossy(&out.stderr).contains("implausible"),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    fails_with(&["cover", path, "--unit", "furlong"], &["\"furlong\""]);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Margins, voxel sizes and sphere budgets out of range are errors that name the option, from
/// the command and from a scenario; a negative margin gets needle's advice, not clap's.
#[test]
fn options_out_of_range_are_refused() {
    let dir = scratch("bounds");
    let map = dir.join("boxes.nii");
    write_nifti(&map, &boxes());
    let m = map.to_str().unwrap();
    fails_with(
        &["cover", m, "--margin", "1e9"],
        &["margin must be 0 to 100 mm"],
    );
    fails_with(
        &["cover", m, "--margin", "-1"],
        &["margin must be 0 to 100 mm, not -1", "negative margin"],
    );
    fails_with(&["cover", m, "--max-spheres", "0"], &["at least 1, not 0"]);
    let stl = dir.join("box.stl");
    write_stl_box(&stl, [0.0; 3], [20.0; 3], "SPACE=RAS", false);
    fails_with(
        &["cover", stl.to_str().unwrap(), "--voxel", "1e9"],
        &["voxel size must be above 0 and at most 10 mm"],
    );
    for (entry, want) in [
        ("margin_mm = 1e9", "margin must be 0 to 100 mm"),
        ("margin_mm = -1", "not -1"),
        ("max_spheres = 0", "at least 1, not 0"),
    ] {
        let s = scenario(&dir, "b.toml", &format!("file = \"boxes.nii\"\n{entry}"));
        fails_with(&["plan", &s], &["anatomy[0]", want]);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A truncated NIfTI and a markups point without a position: plain words, no Rust debug text.
#[test]
fn messages_carry_no_rust_debug_text() {
    let dir = scratch("debug");
    let map = dir.join("boxes.nii");
    write_nifti(&map, &boxes());
    let bytes = std::fs::read(&map).unwrap();
    let cut = dir.join("cut.nii");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    fails_with(
        &["cover", cut.to_str().unwrap()],
        &["cut.nii", "incompatible"],
    );
    // Gzip cut short: the `nifti` crate's I/O error, which printed as `Io(Custom { kind: ...`.
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    std::io::Write::write_all(&mut gz, &bytes).unwrap();
    let gz = gz.finish().unwrap();
    let cut = dir.join("cut.nii.gz");
    std::fs::write(&cut, &gz[..gz.len() * 2 / 3]).unwrap();
    fails_with(
        &["cover", cut.to_str().unwrap()],
        &["cut.nii.gz", "truncated"],
    );
    let mrk = dir.join("points.mrk.json");
    std::fs::write(
        &mrk,
        r#"{"markups": [{"type": "Fiducial", "coordinateSystem": "RAS",
            "controlPoints": [{"label": "target"}]}]}"#,
    )
    .unwrap();
    let s = dir.join("p.toml");
    std::fs::write(
        &s,
        "[needle]\ncurvature_radius = 63.7\n[entry]\nposition = [0, 0, 0]\n\
         direction = [0, 0, 1]\n[target]\nmarkups = \"points.mrk.json\"\npoint = \"target\"\n",
    )
    .unwrap();
    fails_with(
        &["plan", s.to_str().unwrap()],
        &["control point \"target\" has no position"],
    );
    let _ = std::fs::remove_dir_all(&dir);
}
