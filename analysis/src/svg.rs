//! A minimal SVG writer: plots are a few shapes and labels, so the markup is written directly
//! (no fonts are needed to produce it; viewers pick a sans-serif face to show the labels).

use std::fmt::Write;

/// An SVG document being built.
pub struct Svg {
    width: f64,
    height: f64,
    body: String,
}

/// Escapes text for element content and attribute values.
pub fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

fn f(v: f64) -> String {
    let s = format!("{v:.2}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".into()
    } else {
        s.into()
    }
}

impl Svg {
    /// An empty `width` × `height` drawing with a white background.
    pub fn new(width: f64, height: f64) -> Svg {
        let mut s = Svg {
            width,
            height,
            body: String::new(),
        };
        s.raw(&format!(
            r#"<rect class="background" x="0" y="0" width="{}" height="{}" fill="white"/>"#,
            f(width),
            f(height)
        ));
        s
    }

    /// Appends markup as is.
    pub fn raw(&mut self, markup: &str) {
        self.body.push_str(markup);
        self.body.push('\n');
    }

    /// Opens a group with a class.
    pub fn group(&mut self, class: &str) {
        self.raw(&format!(r#"<g class="{}">"#, esc(class)));
    }

    /// Closes the last group.
    pub fn end_group(&mut self) {
        self.raw("</g>");
    }

    /// A circle.
    pub fn circle(&mut self, c: [f64; 2], r: f64, class: &str, style: &str) {
        self.raw(&format!(
            r#"<circle class="{}" cx="{}" cy="{}" r="{}" style="{}"/>"#,
            esc(class),
            f(c[0]),
            f(c[1]),
            f(r),
            esc(style)
        ));
    }

    /// A straight line.
    pub fn line(&mut self, a: [f64; 2], b: [f64; 2], class: &str, style: &str) {
        self.raw(&format!(
            r#"<line class="{}" x1="{}" y1="{}" x2="{}" y2="{}" style="{}"/>"#,
            esc(class),
            f(a[0]),
            f(a[1]),
            f(b[0]),
            f(b[1]),
            esc(style)
        ));
    }

    fn points(pts: &[[f64; 2]]) -> String {
        let mut s = String::with_capacity(pts.len() * 12);
        for p in pts {
            let _ = write!(s, "{},{} ", f(p[0]), f(p[1]));
        }
        s.trim_end().to_string()
    }

    /// An open polyline; `extra` is added to the element's attributes as is.
    pub fn polyline(&mut self, pts: &[[f64; 2]], class: &str, style: &str, extra: &str) {
        self.raw(&format!(
            r#"<polyline class="{}" points="{}" style="fill:none;{}" {extra}/>"#,
            esc(class),
            Self::points(pts),
            esc(style)
        ));
    }

    /// A closed polygon.
    pub fn polygon(&mut self, pts: &[[f64; 2]], class: &str, style: &str) {
        self.raw(&format!(
            r#"<polygon class="{}" points="{}" style="{}"/>"#,
            esc(class),
            Self::points(pts),
            esc(style)
        ));
    }

    /// Many disconnected polylines as one path element (cheap for thousands of tree edges).
    pub fn multi_path(&mut self, lines: &[Vec<[f64; 2]>], class: &str, style: &str) {
        let mut d = String::new();
        for l in lines {
            for (i, p) in l.iter().enumerate() {
                let _ = write!(
                    d,
                    "{}{},{} ",
                    if i == 0 { 'M' } else { 'L' },
                    f(p[0]),
                    f(p[1])
                );
            }
        }
        self.raw(&format!(
            r#"<path class="{}" d="{}" style="fill:none;{}"/>"#,
            esc(class),
            d.trim_end(),
            esc(style)
        ));
    }

    /// A text label turned a quarter turn anticlockwise about its anchor point (a y-axis title).
    pub fn vertical_text(&mut self, at: [f64; 2], text: &str, size: f64, class: &str) {
        self.raw(&format!(
            r#"<text class="{}" x="{x}" y="{y}" font-size="{}" text-anchor="middle" font-family="sans-serif" transform="rotate(-90 {x} {y})">{}</text>"#,
            esc(class),
            f(size),
            esc(text),
            x = f(at[0]),
            y = f(at[1]),
        ));
    }

    /// A text label; `anchor` is start, middle or end.
    pub fn text(&mut self, at: [f64; 2], text: &str, size: f64, anchor: &str, class: &str) {
        self.raw(&format!(
            r#"<text class="{}" x="{}" y="{}" font-size="{}" text-anchor="{}" font-family="sans-serif">{}</text>"#,
            esc(class),
            f(at[0]),
            f(at[1]),
            f(size),
            anchor,
            esc(text)
        ));
    }

    /// The finished document.
    pub fn finish(self) -> String {
        format!(
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\">\n{}</svg>\n",
            self.body,
            w = f(self.width),
            h = f(self.height)
        )
    }
}

/// A colour per path form, fixed by catalogue index so a form looks the same in every plot.
pub fn form_colour(index: usize) -> &'static str {
    const PALETTE: [&str; 10] = [
        "#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf",
        "#bcbd22", "#7f7f7f",
    ];
    PALETTE[index % PALETTE.len()]
}

/// Round tick values covering `[lo, hi]` (about `count` of them).
pub fn ticks(lo: f64, hi: f64, count: usize) -> Vec<f64> {
    if hi <= lo || !lo.is_finite() || !hi.is_finite() {
        return vec![lo];
    }
    let raw = (hi - lo) / count.max(1) as f64;
    let mag = 10f64.powf(raw.log10().floor());
    // The round step whose tick count is nearest the one asked for.
    let want = count.max(1) as f64;
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .min_by(|a, b| {
            let da = ((hi - lo) / a - want).abs();
            let db = ((hi - lo) / b - want).abs();
            da.total_cmp(&db)
        })
        .unwrap_or(mag);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    (first..=last).map(|k| k as f64 * step).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn document_is_well_formed_and_escaped() {
        let mut s = Svg::new(100.0, 50.0);
        s.text([1.0, 2.0], "a < b & \"c\"", 10.0, "start", "label");
        s.polyline(&[[0.0, 0.0], [1.5, -0.0]], "path", "stroke:red", "");
        let out = s.finish();
        assert!(out.starts_with("<svg xmlns=\"http://www.w3.org/2000/svg\""));
        assert!(out.contains("a &lt; b &amp; &quot;c&quot;"));
        assert!(out.contains(r#"points="0,0 1.5,0""#));
        assert!(out.trim_end().ends_with("</svg>"));
    }

    #[test]
    fn ticks_are_round() {
        assert_eq!(ticks(0.0, 10.0, 5), vec![0.0, 2.0, 4.0, 6.0, 8.0, 10.0]);
        assert_eq!(ticks(-53.0, 42.0, 4), vec![-40.0, -20.0, 0.0, 20.0, 40.0]);
    }
}
