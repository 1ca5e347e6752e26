//! `needle plot` of a scenario with `[[anatomy]]`: three orthogonal slices of its label maps
//! (axial, coronal, sagittal) through one point, with the chosen segments filled, the other
//! labels faint, the covering spheres cut by each plane, and the planned (and simulated) paths
//! projected onto it, the best path's stretches within [`SLAB_MM`] of the plane marked (a path
//! projected from far off the plane would seem to cross what the plane shows).
//!
//! Every panel carries `data-px="A B S"`: a world point (h, v) in mm is drawn at pixel
//! (A + S h, B - S v), so tests and scripts can read coordinates back.

use super::plot::{axes, plan_paths, PlotPath, Strands, View};
use super::slice_maps::{label_at, map_box, SliceMap};
use super::svg::{esc, Svg};
use planner_core::Scenario;
use std::fmt::Write as _;

/// How near the plane (mm) a stretch of the best path is marked as in the slice.
pub const SLAB_MM: f64 = 2.0;

/// What the slice picture shows.
pub struct SliceScene<'a> {
    /// Title line.
    pub title: String,
    /// The label maps.
    pub maps: &'a [SliceMap],
    /// Paths, one per form (projected onto each plane).
    pub paths: &'a [PlotPath],
    /// Extra legend lines.
    pub notes: &'a [String],
    /// Simulated paths, kind by kind (projected, thin: together tubes around the plan).
    pub executed: &'a [Strands],
    /// Where the three planes cross (RAS, mm).
    pub at: [f64; 3],
}

/// Fill colours of the chosen segments, in the order the maps list them.
const FILLS: [&str; 8] = [
    "#e07b39", "#3a8fd0", "#c94f7c", "#4daf4a", "#984ea3", "#d4b72c", "#17becf", "#8c564b",
];

/// The three planes: (across, up, the fixed axis, name).
const PLANES: [(usize, usize, usize, &str); 3] = [
    (0, 1, 2, "axial"),
    (0, 2, 1, "coronal"),
    (1, 2, 0, "sagittal"),
];

const PANEL: f64 = 360.0;
const PAD: f64 = 60.0;
const LEGEND_H: f64 = 18.0;
/// The longest legend line (characters), about 6.5 px each at 11 px.
const LEGEND_WIDEST: f64 = 100.0;

/// The world box every panel shows: the maps, the entry, the target and the paths.
fn scene_box(scenario: &Scenario, s: &SliceScene<'_>) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    let mut grow = |p: [f64; 3]| {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    };
    for m in s.maps {
        let (a, b) = map_box(&m.map);
        grow(a);
        grow(b);
    }
    grow(scenario.entry.position.map(f64::from));
    grow(scenario.target.position.map(f64::from));
    let executed = s.executed.iter().flat_map(|e| &e.lines).flatten();
    for p in s.paths.iter().flat_map(|p| &p.points).chain(executed) {
        grow(p.map(f64::from));
    }
    for k in 0..3 {
        let pad = 0.04 * (hi[k] - lo[k]).max(10.0);
        lo[k] -= pad;
        hi[k] += pad;
    }
    (lo, hi)
}

/// The slice picture as an SVG document: three panels in a row, the legend below.
pub fn slices_svg(scenario: &Scenario, s: &SliceScene<'_>) -> String {
    let (lo, hi) = scene_box(scenario, s);
    // Each panel as large as the box allows: a slice across a long path stays readable.
    let scales = PLANES.map(|(h, v, _, _)| (PANEL / (hi[h] - lo[h])).min(PANEL / (hi[v] - lo[v])));
    let legend = legend_lines(s);
    let top = PAD;
    let height_panels = PLANES
        .iter()
        .zip(scales)
        .map(|(&(_, v, _, _), scale)| (hi[v] - lo[v]) * scale)
        .fold(0.0, f64::max);
    let width = PAD
        + PLANES
            .iter()
            .zip(scales)
            .map(|(&(h, _, _, _), scale)| (hi[h] - lo[h]) * scale + PAD)
            .sum::<f64>();
    let width = width.max(PAD + 7.0 * LEGEND_WIDEST);
    let legend_top = top + height_panels + 60.0;
    let height = legend_top + LEGEND_H * (legend.len() as f64 + 1.0);
    let mut svg = Svg::new(width, height);
    svg.text([PAD, 24.0], &s.title, 14.0, "start", "title");
    let mut x = PAD;
    for (k, (&(h, v, fixed, name), scale)) in PLANES.iter().zip(scales).enumerate() {
        let view = View {
            h,
            v,
            lo: [lo[h], lo[v]],
            scale,
            origin: [x, top],
            size: [(hi[h] - lo[h]) * scale, (hi[v] - lo[v]) * scale],
        };
        panel(
            &mut svg,
            k,
            &view,
            [hi[h], hi[v]],
            (fixed, name),
            scenario,
            s,
        );
        x += view.size[0] + PAD;
    }
    draw_legend(&mut svg, &legend, legend_top);
    svg.finish()
}

/// One legend line: a swatch style (none for a note) and its text.
type LegendLine = (Option<String>, String);

fn legend_lines(s: &SliceScene<'_>) -> Vec<LegendLine> {
    let mut out: Vec<LegendLine> = Vec::new();
    let mut n = 0;
    for m in s.maps {
        for seg in &m.chosen {
            out.push((
                Some(format!("fill:{}", FILLS[n % FILLS.len()])),
                if seg.name == format!("label {}", seg.label) {
                    format!("{}, covered", seg.name)
                } else {
                    format!("{} (label {}), covered", seg.name, seg.label)
                },
            ));
            n += 1;
        }
    }
    out.push((
        Some("fill:#999;fill-opacity:0.35".into()),
        "other labels (not covered)".into(),
    ));
    out.push((
        Some("fill:#000;fill-opacity:0.06;stroke:#222".into()),
        "covering sphere cut by the plane".into(),
    ));
    for e in s.executed {
        out.push((Some(e.swatch_style()), e.label.clone()));
    }
    for p in s.paths {
        out.push((Some(format!("fill:{}", p.colour)), p.label.clone()));
    }
    out.extend(s.notes.iter().map(|n| (None, n.clone())));
    out.push((
        None,
        format!(
            "RAS mm (+x right, +y anterior, +z superior); paths, ▼ entry and ◎ target projected \
             onto each plane; dark band: the best path within {SLAB_MM} mm of the plane; dashed: \
             the other two planes"
        ),
    ));
    out
}

fn draw_legend(svg: &mut Svg, lines: &[LegendLine], top: f64) {
    svg.group("legend");
    let mut y = top;
    for (swatch, text) in lines {
        let x = if let Some(style) = swatch {
            svg.raw(&format!(
                r#"<rect class="legend-swatch" x="{PAD}" y="{:.1}" width="18" height="10" style="{}"/>"#,
                y - 9.0,
                esc(style)
            ));
            PAD + 26.0
        } else {
            PAD
        };
        svg.text([x, y], text, 11.0, "start", "legend-entry");
        y += LEGEND_H;
    }
    svg.end_group();
}

/// One plane's panel: the labels, the sphere sections, the paths, entry and target.
fn panel(
    svg: &mut Svg,
    k: usize,
    view: &View,
    hi: [f64; 2],
    (fixed, name): (usize, &str),
    scenario: &Scenario,
    s: &SliceScene<'_>,
) {
    let (a, b) = (
        view.origin[0] - view.lo[0] * view.scale,
        view.origin[1] + view.size[1] + view.lo[1] * view.scale,
    );
    svg.raw(&format!(
        r#"<g class="slice" data-plane="{name}" data-axes="{}{}" data-fixed="{}" data-at="{:.3}" data-px="{a:.4} {b:.4} {:.6}">"#,
        ["x", "y", "z"][view.h],
        ["x", "y", "z"][view.v],
        ["x", "y", "z"][fixed],
        s.at[fixed],
        view.scale
    ));
    svg.text(
        [view.origin[0], view.origin[1] - 8.0],
        &format!("{name}: {} = {:.1} mm", ["x", "y", "z"][fixed], s.at[fixed]),
        12.0,
        "start",
        "panel-title",
    );
    axes(svg, view, hi);
    svg.raw(&format!(
        r#"<clipPath id="slice{k}"><rect x="{:.1}" y="{:.1}" width="{:.1}" height="{:.1}"/></clipPath><g clip-path="url(#slice{k})">"#,
        view.origin[0], view.origin[1], view.size[0], view.size[1]
    ));
    labels(svg, view, s);
    crosshair(svg, view, s.at);
    sections(svg, view, fixed, scenario, s.at[fixed]);
    strands(svg, view, s.executed);
    plan_paths(svg, view, s.paths);
    in_slice(svg, view, s.paths, fixed, s.at[fixed]);
    ends(svg, view, scenario);
    svg.raw("</g></g>");
}

/// The maps sampled on the plane (nearest voxel) as runs of equal label along each row.
fn labels(svg: &mut Svg, view: &View, s: &SliceScene<'_>) {
    let finest = s
        .maps
        .iter()
        .flat_map(|m| m.map.spacing())
        .fold(f64::INFINITY, f64::min);
    // A cell of the finest voxel's size, but no more than 400 across (a 0.25 mm map of 30 cm).
    let span = view.size[0].max(view.size[1]) / view.scale;
    let cell = finest.max(span / 400.0);
    let n = [view.size[0], view.size[1]].map(|w| (w / view.scale / cell).ceil() as usize);
    // Rows of rectangles meet without the hairline gaps anti-aliasing leaves.
    svg.raw(r#"<g class="labels" shape-rendering="crispEdges">"#);
    for (m_index, m) in s.maps.iter().enumerate() {
        let first_fill: usize = s.maps[..m_index].iter().map(|m| m.chosen.len()).sum();
        let style = |l: i64| -> Option<String> {
            if l == 0 {
                return Some("fill:#f2f2f2".into());
            }
            match m.chosen.iter().position(|c| c.label == l) {
                Some(i) => Some(format!("fill:{}", FILLS[(first_fill + i) % FILLS.len()])),
                None => Some("fill:#999;fill-opacity:0.35".into()),
            }
        };
        let mut out = String::new();
        for row in 0..n[1] {
            let v = view.lo[1] + (row as f64 + 0.5) * cell;
            let mut run: Option<(usize, i64)> = None;
            for col in 0..=n[0] {
                let l = (col < n[0])
                    .then(|| {
                        let mut p = s.at;
                        p[view.h] = view.lo[0] + (col as f64 + 0.5) * cell;
                        p[view.v] = v;
                        label_at(&m.map, p)
                    })
                    .flatten();
                if run.map(|r| Some(r.1)) == Some(l) {
                    continue;
                }
                if let Some((start, label)) = run.take() {
                    let (x, w) = (
                        view.origin[0] + start as f64 * cell * view.scale,
                        (col - start) as f64 * cell * view.scale,
                    );
                    let y = view.origin[1] + view.size[1] - (row as f64 + 1.0) * cell * view.scale;
                    let chosen = m.chosen.iter().any(|c| c.label == label);
                    let _ = writeln!(
                        out,
                        r#"<rect class="label{}" data-map="{m_index}" data-label="{label}" x="{x:.2}" y="{y:.2}" width="{w:.2}" height="{:.2}" style="{}"/>"#,
                        if chosen { " chosen" } else { "" },
                        cell * view.scale,
                        style(label).unwrap_or_default()
                    );
                }
                run = l.map(|l| (col, l));
            }
        }
        svg.raw(out.trim_end());
    }
    svg.end_group();
}

/// Dashed lines where the other two planes cut this one.
fn crosshair(svg: &mut Svg, view: &View, at: [f64; 3]) {
    let p = view.px(at.map(|x| x as f32));
    let [x0, y0] = view.origin;
    let [w, h] = view.size;
    let style = "stroke:#555;stroke-width:0.7;stroke-dasharray:3 3";
    svg.line([p[0], y0], [p[0], y0 + h], "slice-line", style);
    svg.line([x0, p[1]], [x0 + w, p[1]], "slice-line", style);
}

/// The circle each obstacle sphere leaves on the plane `axis = at`.
fn sections(svg: &mut Svg, view: &View, axis: usize, scenario: &Scenario, at: f64) {
    svg.group("sections");
    for (i, o) in scenario.obstacles.iter().enumerate() {
        let d = f64::from(o.center[axis]) - at;
        let r = f64::from(o.radius);
        if d.abs() >= r {
            continue;
        }
        let c = view.px(o.center);
        svg.raw(&format!(
            r#"<circle class="sphere-section" data-index="{i}" cx="{:.3}" cy="{:.3}" r="{:.3}" style="fill:#000;fill-opacity:0.06;stroke:#222;stroke-width:1.2"/>"#,
            c[0],
            c[1],
            (r * r - d * d).sqrt() * view.scale
        ));
    }
    svg.end_group();
}

/// The simulated paths, projected onto the plane.
fn strands(svg: &mut Svg, view: &View, executed: &[Strands]) {
    for e in executed {
        svg.group(&e.class);
        let style = e.style();
        for line in &e.lines {
            let pts: Vec<[f64; 2]> = line.iter().map(|q| view.px(*q)).collect();
            svg.polyline(&pts, &e.class, &style, "");
        }
        svg.end_group();
    }
}

/// The best path's runs of points within [`SLAB_MM`] of the plane `axis = at`, as dark bands
/// over its projection (a run of one point as a dot).
fn in_slice(svg: &mut Svg, view: &View, paths: &[PlotPath], axis: usize, at: f64) {
    for p in paths.iter().filter(|p| p.best) {
        let near = |q: &[f32; 3]| (f64::from(q[axis]) - at).abs() <= SLAB_MM;
        let mut run: Vec<[f64; 2]> = Vec::new();
        for q in p.points.iter().chain(std::iter::once(&[f32::NAN; 3])) {
            if near(q) {
                run.push(view.px(*q));
                continue;
            }
            if run.len() == 1 {
                run.push(run[0]);
            }
            if !run.is_empty() {
                svg.polyline(
                    &run,
                    "path in-slice",
                    "stroke:#000;stroke-width:7;stroke-opacity:0.35;stroke-linecap:round",
                    "",
                );
            }
            run.clear();
        }
    }
}

/// The entry and the target, projected.
fn ends(svg: &mut Svg, view: &View, scenario: &Scenario) {
    let e = view.px(scenario.entry.position);
    svg.polygon(
        &[
            [e[0] - 6.0, e[1] - 6.0],
            [e[0] + 6.0, e[1] - 6.0],
            [e[0], e[1] + 6.0],
        ],
        "entry",
        "fill:#000",
    );
    let t = view.px(scenario.target.position);
    svg.circle(t, 5.0, "target", "fill:none;stroke:#000;stroke-width:2");
    svg.circle(t, 1.5, "target", "fill:#000");
}
