//! Pictures: the scenario with every form's path (the paper's Figure 10), the RRT tree and path
//! (Figure 11), covering circles of polygon obstacles (Figure 9) and weight sweeps (Figures 6-8).
//!
//! Plane scenarios are drawn in the y-z plane; 3-D scenarios as two orthogonal projections
//! (z-y and z-x). Elements carry classes (`obstacle`, `polygon`, `path`, `best`, `legend`, ...)
//! so tests and scripts can read the structure back.

use super::svg::{esc, form_colour, ticks, Svg};
use needle_scenario::ObstacleShape;
use planner_core::model::scenario::Workspace;
use planner_core::Scenario;

/// One path to draw.
#[derive(Clone, Debug)]
pub struct PlotPath {
    /// Legend text.
    pub label: String,
    /// Form word (an attribute of the element), e.g. `RL` or `RRT`.
    pub form: String,
    /// Stroke colour.
    pub colour: String,
    /// Points along the path (mm).
    pub points: Vec<[f32; 3]>,
    /// Drawn thicker and marked in the legend.
    pub best: bool,
}

/// What a scenario picture shows.
#[derive(Clone, Debug, Default)]
pub struct Scene<'a> {
    /// Title line.
    pub title: String,
    /// Obstacle shapes (polygons and their circles); empty to draw the scenario's circles.
    pub shapes: &'a [ObstacleShape],
    /// Paths, one per form.
    pub paths: Vec<PlotPath>,
    /// Extra legend lines (forms without a path, RRT statistics, ...).
    pub notes: Vec<String>,
    /// RRT tree edges as point lists, drawn thin and grey.
    pub tree: Vec<Vec<[f32; 3]>>,
    /// Simulated executed paths, kind by kind, drawn thin and translucent: together tubes
    /// around the plan.
    pub executed: Vec<Strands>,
}

/// Executed paths of one kind (say the runs that reached the target), with a legend entry.
#[derive(Clone, Debug)]
pub struct Strands {
    /// Legend text.
    pub label: String,
    /// Class of the element (`executed` and more, e.g. `executed stopped`).
    pub class: String,
    /// Stroke colour.
    pub colour: String,
    /// Drawn dashed and stronger: few paths that must stand out of the tube.
    pub dashed: bool,
    /// The paths.
    pub lines: Vec<Vec<[f32; 3]>>,
}

impl Strands {
    pub(crate) fn style(&self) -> String {
        if self.dashed {
            format!(
                "stroke:{};stroke-opacity:0.7;stroke-width:1.2;stroke-dasharray:4 2",
                self.colour
            )
        } else {
            format!(
                "stroke:{};stroke-opacity:0.15;stroke-width:0.8",
                self.colour
            )
        }
    }

    pub(crate) fn swatch_style(&self) -> String {
        let dash = if self.dashed {
            ";stroke-dasharray:4 2"
        } else {
            ""
        };
        format!("stroke:{};stroke-width:2{dash}", self.colour)
    }
}

/// One frame of a picture: world axes `h` (across) and `v` (up) drawn from `lo` at `scale` px
/// per mm, the frame's top-left corner at `origin` and its size `size` (px).
pub(crate) struct View {
    pub(crate) h: usize,
    pub(crate) v: usize,
    pub(crate) lo: [f64; 2],
    pub(crate) scale: f64,
    pub(crate) origin: [f64; 2],
    pub(crate) size: [f64; 2],
}

impl View {
    pub(crate) fn px(&self, p: [f32; 3]) -> [f64; 2] {
        let (h, v) = (f64::from(p[self.h]), f64::from(p[self.v]));
        [
            self.origin[0] + (h - self.lo[0]) * self.scale,
            self.origin[1] + self.size[1] - (v - self.lo[1]) * self.scale,
        ]
    }

    /// Many thin polylines as one path element (nothing when there are none).
    pub(crate) fn lines(&self, svg: &mut Svg, lines: &[Vec<[f32; 3]>], class: &str, style: &str) {
        if lines.is_empty() {
            return;
        }
        let px: Vec<Vec<[f64; 2]>> = lines
            .iter()
            .map(|l| l.iter().map(|p| self.px(*p)).collect())
            .collect();
        svg.multi_path(&px, class, style);
    }
}

const AXIS: [&str; 3] = ["x", "y", "z"];

const VIEW_W: f64 = 560.0;
const LEGEND_W: f64 = 340.0;
const PAD: f64 = 50.0;

/// Under the legend of a 3-D scene: the views are projections.
const PROJECTION_NOTE: [&str; 3] = [
    "3-D: each view is a projection; a path drawn",
    "across a disc passes in front of or behind",
    "that sphere (clearances are measured in 3-D)",
];

fn extent(s: &Scene<'_>, scenario: &Scenario, h: usize, v: usize) -> ([f64; 2], [f64; 2]) {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    let mut grow = |p: [f32; 3], r: f32| {
        for (k, axis) in [h, v].into_iter().enumerate() {
            lo[k] = lo[k].min(f64::from(p[axis] - r));
            hi[k] = hi[k].max(f64::from(p[axis] + r));
        }
    };
    grow(scenario.entry.position, 0.0);
    grow(scenario.target.position, 0.0);
    for o in &scenario.obstacles {
        grow(o.center, o.radius);
    }
    for p in s.paths.iter().flat_map(|p| &p.points) {
        grow(*p, 0.0);
    }
    let executed = s.executed.iter().flat_map(|e| &e.lines);
    for p in s.tree.iter().chain(executed).flatten() {
        grow(*p, 0.0);
    }
    for (lo_k, hi_k) in lo.iter_mut().zip(hi.iter_mut()) {
        let span = (*hi_k - *lo_k).max(10.0);
        *lo_k -= 0.05 * span;
        *hi_k += 0.05 * span;
    }
    (lo, hi)
}

/// The frame, ticks, grid and axis titles of `view`, whose axes end at `hi`.
pub(crate) fn axes(svg: &mut Svg, view: &View, hi: [f64; 2]) {
    let [x0, y0] = view.origin;
    let [w, hgt] = view.size;
    svg.group("axes");
    svg.raw(&format!(
        r#"<rect class="frame" x="{x0:.1}" y="{y0:.1}" width="{w:.1}" height="{hgt:.1}" style="fill:none;stroke:#444"/>"#
    ));
    for t in ticks(view.lo[0], hi[0], 6) {
        let x = x0 + (t - view.lo[0]) * view.scale;
        svg.line([x, y0 + hgt], [x, y0 + hgt + 4.0], "tick", "stroke:#444");
        svg.line([x, y0], [x, y0 + hgt], "grid", "stroke:#eee");
        svg.text(
            [x, y0 + hgt + 16.0],
            &format!("{t}"),
            10.0,
            "middle",
            "tick-label",
        );
    }
    for t in ticks(view.lo[1], hi[1], 6) {
        let y = y0 + hgt - (t - view.lo[1]) * view.scale;
        svg.line([x0 - 4.0, y], [x0, y], "tick", "stroke:#444");
        svg.line([x0, y], [x0 + w, y], "grid", "stroke:#eee");
        svg.text(
            [x0 - 6.0, y + 3.5],
            &format!("{t}"),
            10.0,
            "end",
            "tick-label",
        );
    }
    svg.text(
        [x0 + w / 2.0, y0 + hgt + 32.0],
        &format!("{} (mm)", AXIS[view.h]),
        11.0,
        "middle",
        "axis-label",
    );
    // Upright and left of the widest tick label ("-100" is about 24 px), so the two never meet.
    svg.vertical_text(
        [x0 - 40.0, y0 + hgt / 2.0],
        &format!("{} (mm)", AXIS[view.v]),
        11.0,
        "axis-label",
    );
    svg.end_group();
}

/// The views of the scene (one for a plane scenario, two projections in 3-D) with the upper
/// ends of their axes, and the height they take.
fn layout(scenario: &Scenario, scene: &Scene<'_>) -> (Vec<(View, [f64; 2])>, f64) {
    let planes: &[(usize, usize)] = match scenario.options.workspace {
        Workspace::PlaneYz => &[(2, 1)],
        Workspace::Space => &[(2, 1), (2, 0)],
    };
    let mut views = Vec::new();
    let mut top = PAD;
    for &(h, v) in planes {
        let (lo, hi) = extent(scene, scenario, h, v);
        let scale = (VIEW_W / (hi[0] - lo[0])).min(520.0 / (hi[1] - lo[1]));
        let size = [(hi[0] - lo[0]) * scale, (hi[1] - lo[1]) * scale];
        views.push((
            View {
                h,
                v,
                lo,
                scale,
                origin: [PAD + 20.0, top],
                size,
            },
            hi,
        ));
        top += size[1] + PAD + 10.0;
    }
    (views, top)
}

/// The scenario picture as an SVG document.
pub fn scene_svg(scenario: &Scenario, scene: &Scene<'_>) -> String {
    let (views, top) = layout(scenario, scene);
    let mut notes = scene.notes.clone();
    if views.len() > 1 {
        notes.extend(PROJECTION_NOTE.iter().map(|n| n.to_string()));
    }
    let legend_lines = scene.paths.len() + scene.executed.len() + notes.len() + 3;
    let height = top.max(PAD + 30.0 + 18.0 * legend_lines as f64);
    // Wide enough for the longest legend line (about 6.5 px a character at 11 px).
    let longest = scene
        .paths
        .iter()
        .map(|p| p.label.chars().count() + 5)
        .chain(scene.executed.iter().map(|e| e.label.chars().count() + 5))
        .chain(notes.iter().map(|n| n.chars().count()))
        .max()
        .unwrap_or(0);
    let legend_w = LEGEND_W.max(6.5 * longest as f64 + 20.0);
    let width = PAD + 20.0 + VIEW_W + 30.0 + legend_w;
    let mut svg = Svg::new(width, height);
    svg.text([PAD, 24.0], &scene.title, 14.0, "start", "title");
    for (k, (view, hi)) in views.iter().enumerate() {
        axes(&mut svg, view, *hi);
        draw_view(&mut svg, k, view, scenario, scene);
    }
    legend(&mut svg, scene, &notes, PAD + 20.0 + VIEW_W + 30.0);
    svg.finish()
}

/// What view `k` shows inside its frame, bottom to top: the RRT tree, the obstacles, the
/// executed paths, the planned paths, the entry and the target.
fn draw_view(svg: &mut Svg, k: usize, view: &View, scenario: &Scenario, scene: &Scene<'_>) {
    // Paths and trees stay inside the frame.
    svg.raw(&format!(
        r#"<clipPath id="view{k}"><rect x="{:.1}" y="{:.1}" width="{:.1}" height="{:.1}"/></clipPath><g clip-path="url(#view{k})">"#,
        view.origin[0], view.origin[1], view.size[0], view.size[1]
    ));
    view.lines(svg, &scene.tree, "rrt-tree", "stroke:#bbb;stroke-width:0.6");
    obstacles(svg, view, scenario, scene.shapes);
    // Executed paths above the obstacles, so a run that enters one shows.
    for e in &scene.executed {
        view.lines(svg, &e.lines, &e.class, &e.style());
    }
    plan_paths(svg, view, &scene.paths);
    let entry = view.px(scenario.entry.position);
    svg.polygon(
        &[
            [entry[0] - 6.0, entry[1] - 6.0],
            [entry[0] + 6.0, entry[1] - 6.0],
            [entry[0], entry[1] + 6.0],
        ],
        "entry",
        "fill:#000",
    );
    let target = view.px(scenario.target.position);
    svg.circle(
        target,
        5.0,
        "target",
        "fill:none;stroke:#000;stroke-width:2",
    );
    svg.circle(target, 1.5, "target", "fill:#000");
    svg.raw("</g>");
}

/// The obstacles' circles (dashed where they cover a polygon) and the polygons themselves.
fn obstacles(svg: &mut Svg, view: &View, scenario: &Scenario, shapes: &[ObstacleShape]) {
    svg.group("obstacles");
    let mut approximated = vec![false; scenario.obstacles.len()];
    let mut k = 0;
    for shape in shapes {
        for _ in &shape.circles {
            if let Some(a) = approximated.get_mut(k) {
                *a = shape.polygon.is_some();
            }
            k += 1;
        }
    }
    for (i, o) in scenario.obstacles.iter().enumerate() {
        let style = if approximated[i] {
            "fill:#d9d9d9;fill-opacity:0.5;stroke:#666;stroke-dasharray:4 3"
        } else {
            "fill:#c8c8c8;stroke:#333"
        };
        svg.raw(&format!(
            r#"<circle class="obstacle" data-index="{i}" cx="{:.2}" cy="{:.2}" r="{:.2}" style="{style}"/>"#,
            view.px(o.center)[0],
            view.px(o.center)[1],
            f64::from(o.radius) * view.scale
        ));
    }
    let x = scenario.entry.position[0];
    for shape in shapes {
        if let Some((poly, _)) = &shape.polygon {
            let pts: Vec<[f64; 2]> = poly
                .vertices()
                .iter()
                .map(|p| view.px([x, p[0] as f32, p[1] as f32]))
                .collect();
            svg.polygon(&pts, "polygon", "fill:#8c8c8c;fill-opacity:0.8;stroke:#222");
        }
    }
    svg.end_group();
}

/// The planned paths, the best last: on top of the others.
pub(crate) fn plan_paths(svg: &mut Svg, view: &View, paths: &[PlotPath]) {
    let order = paths
        .iter()
        .filter(|p| !p.best)
        .chain(paths.iter().filter(|p| p.best));
    for p in order {
        let pts: Vec<[f64; 2]> = p.points.iter().map(|q| view.px(*q)).collect();
        let (class, width) = if p.best {
            ("path best", 3.5)
        } else {
            ("path", 1.6)
        };
        svg.polyline(
            &pts,
            class,
            &format!("stroke:{};stroke-width:{width}", p.colour),
            &format!(r#"data-form="{}""#, esc(&p.form)),
        );
    }
}

fn legend(svg: &mut Svg, scene: &Scene<'_>, notes: &[String], x: f64) {
    svg.group("legend");
    let mut y = PAD + 10.0;
    for p in &scene.paths {
        let width = if p.best { 3.5 } else { 1.6 };
        svg.line(
            [x, y - 4.0],
            [x + 24.0, y - 4.0],
            "legend-swatch",
            &format!("stroke:{};stroke-width:{width}", p.colour),
        );
        svg.text([x + 30.0, y], &p.label, 11.0, "start", "legend-entry");
        y += 18.0;
    }
    for e in &scene.executed {
        svg.line(
            [x, y - 4.0],
            [x + 24.0, y - 4.0],
            "legend-swatch",
            &e.swatch_style(),
        );
        svg.text([x + 30.0, y], &e.label, 11.0, "start", "legend-entry");
        y += 18.0;
    }
    for n in notes {
        svg.text([x, y], n, 11.0, "start", "legend-note");
        y += 18.0;
    }
    y += 6.0;
    svg.text([x, y], "▼ entry   ◎ target", 11.0, "start", "legend-note");
    svg.end_group();
}

/// Colour for a form, by its catalogue index.
pub fn colour_of(form: planner_core::Form) -> String {
    form_colour(form.index()).to_string()
}
