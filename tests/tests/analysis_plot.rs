//! SVG structure of the plots: one circle per obstacle, one path per feasible form, the best one
//! marked, a legend; two projections in 3-D; polygons drawn with their circles.

use needle_analysis::plot::{scene_svg, PlotPath, Scene};
use needle_e2e::{example, needle};
use planner_core::Scenario;

fn count(svg: &str, needle: &str) -> usize {
    svg.matches(needle).count()
}

fn run(args: &[&str]) -> String {
    let out = needle().args(args).output().unwrap();
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn tmp(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("needle-analysis-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

#[test]
fn plan_plot_has_one_path_per_feasible_form_and_a_legend() {
    let svg_path = tmp("paper.svg");
    let json = run(&[
        "plan",
        "examples/paper.toml",
        "--json",
        "--plot",
        svg_path.to_str().unwrap(),
    ]);
    let plan: serde_json::Value = serde_json::from_str(&json).unwrap();
    let feasible: Vec<&str> = plan["forms"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|f| f["feasible"] == true)
        .map(|f| f["form"].as_str().unwrap())
        .collect();
    let svg = std::fs::read_to_string(&svg_path).unwrap();
    assert!(svg.starts_with("<svg xmlns=\"http://www.w3.org/2000/svg\""));
    assert_eq!(count(&svg, r#"class="obstacle""#), 3);
    assert_eq!(count(&svg, r#"<polyline class="path"#), feasible.len());
    for f in &feasible {
        assert_eq!(count(&svg, &format!(r#"data-form="{f}""#)), 1, "{f}");
    }
    assert_eq!(count(&svg, r#"class="path best""#), 1);
    assert!(svg.contains(r#"class="path best" "#) && svg.contains(r#"data-form="RL""#));
    assert_eq!(count(&svg, r#"<g class="legend">"#), 1);
    assert_eq!(count(&svg, r#"class="legend-entry""#), feasible.len());
    assert!(svg.contains("RL (best)"));
    assert!(svg.contains("L: no feasible path"));
    assert_eq!(count(&svg, r#"class="entry""#), 1);

    // `needle plot --plan` draws the same best path from the saved JSON.
    let plan_file = tmp("paper-plan.json");
    std::fs::write(&plan_file, &json).unwrap();
    let out = tmp("from-plan.svg");
    run(&[
        "plot",
        "examples/paper.toml",
        "--plan",
        plan_file.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    let again = std::fs::read_to_string(&out).unwrap();
    assert_eq!(count(&again, r#"class="path best""#), 1);
    assert_eq!(count(&again, r#"class="obstacle""#), 3);
}

#[test]
fn space_scenarios_are_drawn_as_two_projections() {
    let s = Scenario::paper();
    let mut space = s.clone();
    space.options.workspace = planner_core::model::scenario::Workspace::Space;
    let path = PlotPath {
        label: "hand-made".into(),
        form: "RL".into(),
        colour: "#123456".into(),
        points: vec![[0.0, 0.0, 0.0], [1.0, 2.0, 45.0], [0.0, 0.0, 90.0]],
        best: true,
    };
    let scene = |paths: Vec<PlotPath>| Scene {
        title: "t".into(),
        paths,
        ..Scene::default()
    };
    let plane = scene_svg(&s, &scene(vec![path.clone()]));
    let both = scene_svg(&space, &scene(vec![path]));
    assert_eq!(count(&plane, r#"class="obstacle""#), 3);
    assert_eq!(count(&both, r#"class="obstacle""#), 6);
    assert_eq!(count(&plane, r#"class="path best""#), 1);
    assert_eq!(count(&both, r#"class="path best""#), 2);
    assert!(both.contains("x (mm)") && both.contains("y (mm)"));
    // A real 3-D plan plots too.
    let out = tmp("space.svg");
    run(&[
        "plot",
        example("space").to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    let svg = std::fs::read_to_string(&out).unwrap();
    assert!(
        count(&svg, r#"class="path best""#) == 2,
        "one best path per projection"
    );
}

#[test]
fn sweep_and_approx_plots_show_their_structure() {
    let out = tmp("sweep.svg");
    run(&[
        "sweep",
        "examples/paper.toml",
        "--weight",
        "control",
        "--from",
        "0",
        "--to",
        "10",
        "--steps",
        "6",
        "--plot",
        out.to_str().unwrap(),
    ]);
    let svg = std::fs::read_to_string(&out).unwrap();
    // Two panels (F and L), a marker per value in each, labelled by form.
    assert_eq!(count(&svg, r#"class="sweep-point""#), 12);
    assert_eq!(count(&svg, r#"class="sweep-line""#), 2);
    assert!(svg.contains(">F (best)<") && svg.contains(">L (mm)<"));
    assert!(svg.contains(r#"<g class="legend">"#) && svg.contains("RL (best at"));

    let out = tmp("approx.svg");
    run(&[
        "approx",
        "tests/data/polygons.toml",
        "--method",
        "circumscribed",
        "--plot",
        out.to_str().unwrap(),
    ]);
    let svg = std::fs::read_to_string(&out).unwrap();
    assert_eq!(count(&svg, r#"<polygon class="polygon""#), 3);
    assert_eq!(count(&svg, r#"class="obstacle""#), 3);

    let out = tmp("rrt.svg");
    run(&[
        "rrt",
        "examples/paper.toml",
        "--seed",
        "2",
        "--plot",
        out.to_str().unwrap(),
    ]);
    let svg = std::fs::read_to_string(&out).unwrap();
    assert_eq!(count(&svg, r#"class="rrt-tree""#), 1);
    assert_eq!(count(&svg, r#"data-form="RRT""#), 1);
}

#[test]
fn axis_titles_stand_clear_of_the_ticks_and_the_legend_fits_its_longest_line() {
    let paper = tmp("layout-paper.svg");
    run(&[
        "plot",
        "examples/paper.toml",
        "--output",
        paper.to_str().unwrap(),
    ]);
    let svg = std::fs::read_to_string(&paper).unwrap();
    // The y-axis title is upright (turned a quarter), so it cannot run into the tick labels.
    assert_eq!(count(&svg, r#"transform="rotate(-90"#), 1, "{svg}");
    assert!(
        !svg.contains("in front of or behind"),
        "a plane has no projection note"
    );
    let space = tmp("layout-space.svg");
    run(&[
        "plot",
        "examples/space.toml",
        "--output",
        space.to_str().unwrap(),
    ]);
    let svg = std::fs::read_to_string(&space).unwrap();
    assert_eq!(count(&svg, r#"transform="rotate(-90"#), 2);
    assert!(
        svg.contains("in front of or behind"),
        "3-D views say they are projections"
    );
    // A long legend line widens the picture instead of running off its edge.
    let compare = tmp("layout-compare.svg");
    let _ = needle()
        .args([
            "compare",
            "examples/paper.toml",
            "--plot",
            compare.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let svg = std::fs::read_to_string(&compare).unwrap();
    let width: f64 = svg
        .split("width=\"")
        .nth(1)
        .and_then(|w| w.split('"').next())
        .and_then(|w| w.parse().ok())
        .expect("an SVG width");
    let label = svg
        .split("legend-entry")
        .filter_map(|t| t.split('>').nth(1)?.split('<').next())
        .map(|t| t.chars().count())
        .max()
        .unwrap();
    assert!(svg.contains("target error"), "the RRT's miss is labelled");
    assert!(
        width >= 700.0 + 6.0 * label as f64,
        "width {width}, label {label} chars"
    );
}
