//! The sweep picture (the paper's Figures 6-8): F and L of the best path against the weight, each
//! point coloured and labelled by its form, with every form's own F as a faint curve.

use super::svg::{form_colour, ticks, Svg};
use super::sweep::{forms_seen, Point, Weight};
use planner_core::{Form, FormOutcome};

const W: f64 = 640.0;
const H: f64 = 220.0;
const LEFT: f64 = 70.0;
const TOP: f64 = 50.0;
const GAP: f64 = 60.0;

struct Axis {
    lo: f64,
    hi: f64,
    log: bool,
}

impl Axis {
    fn of(values: impl Iterator<Item = f64>, log: bool) -> Axis {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for v in values.filter(|v| v.is_finite() && (!log || *v > 0.0)) {
            let v = if log { v.log10() } else { v };
            lo = lo.min(v);
            hi = hi.max(v);
        }
        if !lo.is_finite() {
            (lo, hi) = (0.0, 1.0);
        }
        if hi - lo < 1e-9 {
            let pad = if lo.abs() > 1.0 { lo.abs() * 0.05 } else { 0.5 };
            (lo, hi) = (lo - pad, hi + pad);
        } else if !log {
            let pad = 0.08 * (hi - lo);
            (lo, hi) = (lo - pad, hi + pad);
        }
        Axis { lo, hi, log }
    }

    fn at(&self, v: f64, len: f64) -> f64 {
        let v = if self.log { v.log10() } else { v };
        (v - self.lo) / (self.hi - self.lo) * len
    }

    fn ticks(&self) -> Vec<(f64, String)> {
        if self.log {
            let (a, b) = (self.lo.ceil() as i32, self.hi.floor() as i32);
            let every = ((b - a) / 6).max(1);
            (a..=b)
                .step_by(every as usize)
                .map(|e| (10f64.powi(e), format!("1e{e}")))
                .collect()
        } else {
            ticks(self.lo, self.hi, 6)
                .into_iter()
                .map(|t| (t, format!("{}", (t * 1e6).round() / 1e6)))
                .collect()
        }
    }
}

fn panel(svg: &mut Svg, top: f64, x: &Axis, y: &Axis, label: &str, weight: Weight) {
    svg.raw(&format!(
        r#"<rect class="frame" x="{LEFT}" y="{top}" width="{W}" height="{H}" style="fill:none;stroke:#444"/>"#
    ));
    for (t, text) in x.ticks() {
        let px = LEFT + x.at(t, W);
        svg.line([px, top], [px, top + H], "grid", "stroke:#eee");
        svg.text([px, top + H + 15.0], &text, 10.0, "middle", "tick-label");
    }
    for (t, text) in y.ticks() {
        let py = top + H - y.at(t, H);
        svg.line([LEFT, py], [LEFT + W, py], "grid", "stroke:#eee");
        svg.text([LEFT - 6.0, py + 3.5], &text, 10.0, "end", "tick-label");
    }
    let (lx, ly) = (LEFT - 48.0, top + H / 2.0);
    svg.raw(&format!(
        r#"<text class="axis-label" x="{lx}" y="{ly}" font-size="11" text-anchor="middle" font-family="sans-serif" transform="rotate(-90 {lx} {ly})">{label}</text>"#
    ));
    svg.text(
        [LEFT + W / 2.0, top + H + 32.0],
        &format!(
            "weight {} {}",
            weight.name(),
            if x.log { "(log scale)" } else { "" }
        ),
        11.0,
        "middle",
        "axis-label",
    );
}

/// Which of the two panels: F of the best form (with each form's own F), or its length L.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Panel {
    Objective,
    Length,
}

impl Panel {
    fn value(self, b: &FormOutcome) -> f64 {
        match self {
            Panel::Objective => f64::from(b.objective),
            Panel::Length => f64::from(b.length),
        }
    }
}

/// Where a (weight value, figure) pair is drawn in a panel.
type Place<'a> = &'a dyn Fn(f64, f64) -> [f64; 2];

/// The sweep picture as an SVG document.
pub fn sweep_svg(weight: Weight, points: &[Point], log: bool, title: &str) -> String {
    let forms = forms_seen(points);
    let x = Axis::of(points.iter().map(|p| p.value), log);
    let best: Vec<(f64, &FormOutcome)> = points
        .iter()
        .filter_map(|p| p.best().map(|b| (p.value, b)))
        .collect();
    let per_form_f = points.iter().flat_map(|p| {
        p.plan
            .iter()
            .flat_map(|r| r.forms.iter())
            .filter(|o| o.feasible)
            .map(|o| f64::from(o.objective))
    });
    let fy = Axis::of(
        best.iter()
            .map(|(_, b)| f64::from(b.objective))
            .chain(per_form_f),
        false,
    );
    let ly = Axis::of(best.iter().map(|(_, b)| f64::from(b.length)), false);
    let mut svg = Svg::new(LEFT + W + 170.0, TOP + 2.0 * H + GAP + 60.0);
    svg.text([LEFT, 26.0], title, 14.0, "start", "title");
    let panels = [
        (Panel::Objective, &fy, TOP, "F (best)"),
        (Panel::Length, &ly, TOP + H + GAP, "L (mm)"),
    ];
    for (which, axis, top, label) in panels {
        panel(&mut svg, top, &x, axis, label, weight);
        let px = |v: f64, y: f64| [LEFT + x.at(v, W), top + H - axis.at(y, H)];
        if which == Panel::Objective {
            form_curves(&mut svg, &forms, points, &px);
        }
        best_points(&mut svg, &best, which, &px);
    }
    legend(&mut svg, &forms, &best, points.len());
    svg.finish()
}

/// Each form's own optimum, faint: where the best form switches, two curves cross.
fn form_curves(svg: &mut Svg, forms: &[Form], points: &[Point], px: Place) {
    for f in forms {
        let pts: Vec<[f64; 2]> = points
            .iter()
            .filter_map(|p| {
                let o = p.plan.as_ref().ok()?.forms.iter().find(|o| o.form == *f)?;
                o.feasible.then(|| px(p.value, f64::from(o.objective)))
            })
            .collect();
        svg.polyline(
            &pts,
            "form-curve",
            &format!(
                "stroke:{};stroke-width:1;stroke-opacity:0.45",
                form_colour(f.index())
            ),
            &format!(r#"data-form="{f}""#),
        );
    }
}

/// The best form's figure at each value: a line through points coloured by form, each labelled
/// (only where the form changes when there are many).
fn best_points(svg: &mut Svg, best: &[(f64, &FormOutcome)], which: Panel, px: Place) {
    let label_every = if best.len() <= 25 { 1 } else { usize::MAX };
    let line: Vec<[f64; 2]> = best.iter().map(|(v, b)| px(*v, which.value(b))).collect();
    svg.polyline(&line, "sweep-line", "stroke:#333;stroke-width:1.2", "");
    let mut previous = None;
    for (i, (v, b)) in best.iter().enumerate() {
        let at = px(*v, which.value(b));
        svg.raw(&format!(
            r#"<circle class="sweep-point" data-form="{}" cx="{:.2}" cy="{:.2}" r="4" style="fill:{};stroke:#000;stroke-width:0.5"/>"#,
            b.form,
            at[0],
            at[1],
            form_colour(b.form.index())
        ));
        if i % label_every == 0 || previous != Some(b.form) {
            svg.text(
                [at[0], at[1] - 8.0],
                &b.form.to_string(),
                9.0,
                "middle",
                "form-label",
            );
        }
        previous = Some(b.form);
    }
}

/// The forms that were best somewhere, how often, and the values without a plan.
fn legend(svg: &mut Svg, forms: &[Form], best: &[(f64, &FormOutcome)], values: usize) {
    svg.group("legend");
    let lx = LEFT + W + 20.0;
    svg.text([lx, TOP + 4.0], "best form", 11.0, "start", "legend-title");
    let mut y = TOP + 22.0;
    for f in forms {
        let wins = best.iter().filter(|(_, b)| b.form == *f).count();
        if wins == 0 {
            continue;
        }
        svg.circle(
            [lx + 5.0, y - 4.0],
            4.0,
            "legend-swatch",
            &format!("fill:{}", form_colour(f.index())),
        );
        svg.text(
            [lx + 16.0, y],
            &format!("{f} (best at {wins} of {values})"),
            11.0,
            "start",
            "legend-entry",
        );
        y += 18.0;
    }
    svg.text(
        [lx, y + 6.0],
        "faint lines: each form's F",
        10.0,
        "start",
        "legend-note",
    );
    y += 24.0;
    let failed = values - best.len();
    if failed > 0 {
        svg.text(
            [lx, y],
            &format!("{failed} value(s) without a plan"),
            11.0,
            "start",
            "legend-note",
        );
    }
    svg.end_group();
}
