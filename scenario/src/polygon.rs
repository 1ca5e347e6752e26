//! A polygon obstacle's outline: checked on construction (simple, with area, counter-clockwise)
//! and read from the scenario file inline or from a text file of vertices.

use super::geometry::{inside, self_intersects, signed_area, Pt};
use anyhow::{bail, Result};

/// A checked simple polygon, counter-clockwise.
#[derive(Clone, Debug, PartialEq)]
pub struct Polygon(Vec<Pt>);

impl Polygon {
    /// Checks the outline: at least three finite vertices, a non-zero area, no crossing edges.
    /// A repeated closing vertex is dropped and clockwise outlines are reversed.
    pub fn new(mut pts: Vec<Pt>) -> Result<Polygon> {
        if pts.len() > 1 && pts.first() == pts.last() {
            pts.pop();
        }
        if pts.len() < 3 {
            bail!("a polygon needs at least 3 vertices, got {}", pts.len());
        }
        if let Some(i) = pts
            .iter()
            .position(|p| !p[0].is_finite() || !p[1].is_finite())
        {
            bail!("polygon vertex {i} is not a finite number");
        }
        for i in 0..pts.len() {
            if pts[i] == pts[(i + 1) % pts.len()] {
                bail!("polygon vertices {i} and {} coincide", (i + 1) % pts.len());
            }
        }
        if self_intersects(&pts) {
            bail!("the polygon's outline crosses itself");
        }
        let area = signed_area(&pts);
        let span = pts
            .iter()
            .flat_map(|p| [p[0].abs(), p[1].abs()])
            .fold(1.0f64, f64::max);
        if area.abs() <= 1e-9 * span * span {
            bail!("the polygon has no area (its vertices are collinear)");
        }
        if area < 0.0 {
            pts.reverse();
        }
        Ok(Polygon(pts))
    }

    /// Vertices, counter-clockwise.
    pub fn vertices(&self) -> &[Pt] {
        &self.0
    }

    /// Area (mm²).
    pub fn area(&self) -> f64 {
        signed_area(&self.0)
    }

    /// Whether `p` is inside.
    pub fn contains(&self, p: Pt) -> bool {
        inside(&self.0, p)
    }

    /// Parses a polygon file: one vertex per line as `y z` or `y, z`; `#` starts a comment.
    pub fn parse_text(text: &str) -> Result<Polygon> {
        let mut pts = Vec::new();
        for (n, line) in text.lines().enumerate() {
            let line = line.split('#').next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            let nums: Vec<&str> = line
                .split(|c: char| c == ',' || c.is_whitespace())
                .filter(|s| !s.is_empty())
                .collect();
            let parsed: Vec<f64> = nums.iter().filter_map(|s| s.parse().ok()).collect();
            if nums.len() != 2 || parsed.len() != 2 {
                bail!("line {}: expected two numbers `y z`, got {line:?}", n + 1);
            }
            pts.push([parsed[0], parsed[1]]);
        }
        Polygon::new(pts)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn polygon_checks_reject_bad_outlines() {
        assert!(Polygon::new(vec![[0.0, 0.0], [1.0, 0.0]]).is_err());
        assert!(Polygon::new(vec![[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]).is_err());
        assert!(Polygon::new(vec![[0.0, 0.0], [2.0, 2.0], [2.0, 0.0], [0.0, 2.0]]).is_err());
        assert!(Polygon::new(vec![[0.0, 0.0], [f64::NAN, 0.0], [0.0, 1.0]]).is_err());
        let cw = Polygon::new(vec![
            [0.0, 0.0],
            [0.0, 1.0],
            [1.0, 1.0],
            [1.0, 0.0],
            [0.0, 0.0],
        ])
        .expect("square");
        assert_eq!(cw.vertices().len(), 4);
        assert!(cw.area() > 0.0);
    }

    #[test]
    fn polygon_text_format() {
        let p = Polygon::parse_text("# a triangle\n0 0\n10, 0\n 5 8 # apex\n").expect("parse");
        assert_eq!(p.vertices().len(), 3);
        assert!(Polygon::parse_text("0 0\n1\n2 2\n").is_err());
    }
}
