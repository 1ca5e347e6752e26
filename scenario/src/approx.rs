//! Turning polygon obstacles into circles that cover them (the paper's Figure 9).
//!
//! * circumscribed: one circle, the smallest enclosing the polygon;
//! * segmented: the polygon is cut into slabs across its principal axis and each slab's piece gets
//!   its smallest enclosing circle; the slab count is the smallest whose added area is within 10 %
//!   of the polygon's area of the best count up to [`MAX_SEGMENTS`];
//! * bordered: circles centred on the outline, sized so that the band they cover reaches every
//!   interior point (its half-width is the polygon's inscribed radius), so thin, very irregular
//!   obstacles are hugged closely.
//!
//! Every method covers the whole polygon, not only its outline: a planner that only sees the
//! circles must never be able to pass through the obstacle.

use super::geometry::{
    bounding_box, clip_slab, dist, dist_to_boundary, enclosing_circle, principal_axis, union_area,
    Circle,
};
use super::polygon::Polygon;
use anyhow::{anyhow, Result};
use std::fmt;
use std::str::FromStr;

/// Most slabs the segmented method tries.
pub const MAX_SEGMENTS: usize = 8;

/// How a polygon becomes circles; `circle` and `edged` are accepted as older names.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Method {
    /// One smallest enclosing circle: regular, compact obstacles.
    Circumscribed,
    /// A few circles over slabs of the polygon: irregular obstacles without deep notches.
    #[default]
    Segmented,
    /// Small circles along the outline: very irregular or thin obstacles.
    Bordered,
}

impl Method {
    /// All methods, in the paper's order.
    pub const ALL: [Method; 3] = [Method::Circumscribed, Method::Segmented, Method::Bordered];

    /// The name used in files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Method::Circumscribed => "circumscribed",
            Method::Segmented => "segmented",
            Method::Bordered => "bordered",
        }
    }

    /// The older name still accepted for it, if it had one.
    pub fn older_name(self) -> Option<&'static str> {
        match self {
            Method::Circumscribed => Some("circle"),
            Method::Segmented => None,
            Method::Bordered => Some("edged"),
        }
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A scenario file's `approx` key: the command line's spellings, in any case, spaces around.
impl FromStr for Method {
    type Err = anyhow::Error;
    fn from_str(s: &str) -> Result<Method> {
        let name = s.trim();
        let named = |n: &str| n.eq_ignore_ascii_case(name);
        Method::ALL
            .into_iter()
            .find(|m| named(m.name()) || m.older_name().is_some_and(named))
            .ok_or_else(|| {
                anyhow!(
                    "approximation {:?}: use circumscribed, segmented or bordered",
                    name.to_ascii_lowercase()
                )
            })
    }
}

/// A polygon's circles and what they cost.
#[derive(Clone, Debug, PartialEq)]
pub struct Approximation {
    /// The method used.
    pub method: Method,
    /// Circles covering the polygon.
    pub circles: Vec<Circle>,
    /// Area of the polygon (mm²).
    pub polygon_area: f64,
    /// Area of the circles' union (mm²), exact.
    pub covered_area: f64,
}

impl Approximation {
    /// Area the circles add beyond the polygon (mm²): tissue the planner will treat as obstacle.
    pub fn added_area(&self) -> f64 {
        (self.covered_area - self.polygon_area).max(0.0)
    }
}

/// Covers `poly` with circles by `method`.
pub fn approximate(poly: &Polygon, method: Method) -> Approximation {
    let circles = match method {
        Method::Circumscribed => vec![enclosing_circle(poly.vertices())],
        Method::Segmented => segmented(poly),
        Method::Bordered => bordered(poly),
    };
    Approximation {
        method,
        polygon_area: poly.area(),
        covered_area: union_area(&circles),
        circles,
    }
}

fn slabs(poly: &Polygon, count: usize) -> Vec<Circle> {
    let axis = principal_axis(poly.vertices());
    let along: Vec<f64> = poly
        .vertices()
        .iter()
        .map(|p| p[0] * axis[0] + p[1] * axis[1])
        .collect();
    let lo = along.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = along.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let width = (hi - lo) / count as f64;
    (0..count)
        .filter_map(|k| {
            let a = lo + width * k as f64;
            let b = if k + 1 == count { hi } else { a + width };
            let piece = clip_slab(poly.vertices(), axis, a, b);
            (!piece.is_empty()).then(|| enclosing_circle(&piece))
        })
        .collect()
}

fn segmented(poly: &Polygon) -> Vec<Circle> {
    let options: Vec<(Vec<Circle>, f64)> = (1..=MAX_SEGMENTS)
        .map(|k| {
            let c = slabs(poly, k);
            let a = union_area(&c);
            (c, a)
        })
        .collect();
    let best = options.iter().map(|o| o.1).fold(f64::INFINITY, f64::min);
    let good_enough = best + 0.1 * poly.area();
    options
        .into_iter()
        .find(|o| o.1 <= good_enough)
        .map(|o| o.0)
        .unwrap_or_default()
}

/// Largest distance from an interior point to the outline, bounded from above: a grid estimate
/// plus the grid's half-diagonal (the distance is 1-Lipschitz, so no interior point can be farther).
fn inscribed_radius_bound(poly: &Polygon) -> f64 {
    let v = poly.vertices();
    let (lo, hi) = bounding_box(v);
    let n = 160;
    let step = (hi[0] - lo[0]).max(hi[1] - lo[1]) / n as f64;
    let mut best = 0.0f64;
    for i in 0..=n {
        for j in 0..=n {
            let p = [lo[0] + step * i as f64, lo[1] + step * j as f64];
            if p[0] <= hi[0] && p[1] <= hi[1] && poly.contains(p) {
                best = best.max(dist_to_boundary(v, p));
            }
        }
    }
    best + step * std::f64::consts::FRAC_1_SQRT_2
}

fn bordered(poly: &Polygon) -> Vec<Circle> {
    let v = poly.vertices();
    // Circles of radius r centred at most 2a apart along an edge cover the band of half-width
    // sqrt(r² - a²) on both sides; with r = √2 w and a = w the band is w, the inscribed radius.
    let w = inscribed_radius_bound(poly);
    let radius = w * std::f64::consts::SQRT_2;
    let spacing = 2.0 * w;
    let mut circles = Vec::new();
    for i in 0..v.len() {
        let (a, b) = (v[i], v[(i + 1) % v.len()]);
        let pieces = (dist(a, b) / spacing).ceil().max(1.0) as usize;
        // Centres at the edge's start and at every interior division; the end is the next
        // edge's start, so every vertex carries a circle (it covers the corner's wedge).
        for k in 0..pieces {
            let t = k as f64 / pieces as f64;
            circles.push(Circle {
                center: [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t],
                radius,
            });
        }
    }
    circles
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn segmented_uses_more_circles_for_a_long_bar_and_adds_less_area() {
        let bar = Polygon::new(vec![[0.0, 0.0], [60.0, 0.0], [60.0, 8.0], [0.0, 8.0]]).unwrap();
        let one = approximate(&bar, Method::Circumscribed);
        let seg = approximate(&bar, Method::Segmented);
        assert_eq!(one.circles.len(), 1);
        assert!(seg.circles.len() >= 4, "{} circles", seg.circles.len());
        assert!(seg.added_area() < 0.3 * one.added_area());
    }

    #[test]
    fn bordered_hugs_a_thin_l_shape() {
        let l = Polygon::new(vec![
            [0.0, 0.0],
            [40.0, 0.0],
            [40.0, 4.0],
            [4.0, 4.0],
            [4.0, 40.0],
            [0.0, 40.0],
        ])
        .unwrap();
        let b = approximate(&l, Method::Bordered);
        let c = approximate(&l, Method::Circumscribed);
        assert!(b.circles.iter().all(|c| c.radius < 4.0), "{:?}", b.circles);
        assert!(
            b.added_area() < 0.3 * c.added_area(),
            "{} vs {}",
            b.added_area(),
            c.added_area()
        );
    }
}
