//! Plane geometry for obstacle approximation: polygons, circles, the smallest enclosing circle,
//! clipping, and the exact area of a union of circles. Everything in `f64`, in the scenario's
//! (y, z) plane coordinates (millimetres).

/// A point of the plane.
pub type Pt = [f64; 2];

/// A circle of the plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Circle {
    /// Centre (y, z).
    pub center: Pt,
    /// Radius.
    pub radius: f64,
}

impl Circle {
    /// Whether `p` lies in the closed disc (with an absolute slack `eps`).
    pub fn contains(&self, p: Pt, eps: f64) -> bool {
        dist(self.center, p) <= self.radius + eps
    }
}

/// The smallest axis-aligned box holding `points`: its lowest and highest corner.
pub fn bounding_box(points: &[Pt]) -> (Pt, Pt) {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in points {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (lo, hi)
}

/// Euclidean distance.
pub fn dist(a: Pt, b: Pt) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

fn sub(a: Pt, b: Pt) -> Pt {
    [a[0] - b[0], a[1] - b[1]]
}

fn cross(a: Pt, b: Pt) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

fn dot(a: Pt, b: Pt) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

/// Signed area (positive for counter-clockwise vertices).
pub fn signed_area(poly: &[Pt]) -> f64 {
    let n = poly.len();
    (0..n)
        .map(|i| cross(poly[i], poly[(i + 1) % n]))
        .sum::<f64>()
        / 2.0
}

/// Whether `p` is inside the polygon (even-odd rule; boundary points may go either way).
pub fn inside(poly: &[Pt], p: Pt) -> bool {
    let n = poly.len();
    let mut odd = false;
    let mut j = n - 1;
    for i in 0..n {
        let (a, b) = (poly[i], poly[j]);
        if (a[1] > p[1]) != (b[1] > p[1]) {
            let x = a[0] + (p[1] - a[1]) * (b[0] - a[0]) / (b[1] - a[1]);
            if p[0] < x {
                odd = !odd;
            }
        }
        j = i;
    }
    odd
}

/// Distance from `p` to the segment `a`-`b`.
pub fn dist_to_segment(p: Pt, a: Pt, b: Pt) -> f64 {
    let ab = sub(b, a);
    let len2 = dot(ab, ab);
    let t = if len2 > 0.0 {
        (dot(sub(p, a), ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    dist(p, [a[0] + ab[0] * t, a[1] + ab[1] * t])
}

/// Distance from `p` to the polygon's boundary.
pub fn dist_to_boundary(poly: &[Pt], p: Pt) -> f64 {
    let n = poly.len();
    (0..n)
        .map(|i| dist_to_segment(p, poly[i], poly[(i + 1) % n]))
        .fold(f64::INFINITY, f64::min)
}

fn segments_cross(a: Pt, b: Pt, c: Pt, d: Pt) -> bool {
    let d1 = cross(sub(b, a), sub(c, a));
    let d2 = cross(sub(b, a), sub(d, a));
    let d3 = cross(sub(d, c), sub(a, c));
    let d4 = cross(sub(d, c), sub(b, c));
    (d1 * d2 < 0.0) && (d3 * d4 < 0.0)
}

/// Whether two non-adjacent edges of the polygon cross (a self-intersecting outline).
pub fn self_intersects(poly: &[Pt]) -> bool {
    let n = poly.len();
    for i in 0..n {
        for j in i + 1..n {
            let adjacent = j == i + 1 || (i == 0 && j == n - 1);
            if !adjacent && segments_cross(poly[i], poly[(i + 1) % n], poly[j], poly[(j + 1) % n]) {
                return true;
            }
        }
    }
    false
}

fn circle_two(a: Pt, b: Pt) -> Circle {
    let center = [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
    Circle {
        center,
        radius: dist(a, b) / 2.0,
    }
}

fn circle_three(a: Pt, b: Pt, c: Pt) -> Option<Circle> {
    let (ab, ac) = (sub(b, a), sub(c, a));
    let d = 2.0 * cross(ab, ac);
    if d.abs() < 1e-12 * (dot(ab, ab) + dot(ac, ac)).max(1e-300) {
        return None; // collinear: the two-point circles cover this case
    }
    let (b2, c2) = (dot(ab, ab), dot(ac, ac));
    let ux = (ac[1] * b2 - ab[1] * c2) / d;
    let uy = (ab[0] * c2 - ac[0] * b2) / d;
    let center = [a[0] + ux, a[1] + uy];
    Some(Circle {
        center,
        radius: ux.hypot(uy),
    })
}

fn covers_all(c: &Circle, pts: &[Pt]) -> bool {
    let eps = 1e-9 * (1.0 + c.radius);
    pts.iter().all(|p| c.contains(*p, eps))
}

/// The smallest circle containing every point (Welzl's incremental algorithm, deterministic
/// order), inflated by a relative 1e-9 so rounding never leaves a point outside.
pub fn enclosing_circle(pts: &[Pt]) -> Circle {
    let Some(&first) = pts.first() else {
        return Circle {
            center: [0.0, 0.0],
            radius: 0.0,
        };
    };
    let mut c = Circle {
        center: first,
        radius: 0.0,
    };
    for i in 1..pts.len() {
        if covers_all(&c, &pts[i..=i]) {
            continue;
        }
        c = Circle {
            center: pts[i],
            radius: 0.0,
        };
        for j in 0..i {
            if covers_all(&c, &pts[j..=j]) {
                continue;
            }
            c = circle_two(pts[i], pts[j]);
            for k in 0..j {
                if covers_all(&c, &pts[k..=k]) {
                    continue;
                }
                c = circle_three(pts[i], pts[j], pts[k]).unwrap_or_else(|| {
                    // Collinear triple: the widest pair spans it.
                    let pairs = [(pts[i], pts[j]), (pts[i], pts[k]), (pts[j], pts[k])];
                    pairs.iter().map(|&(a, b)| circle_two(a, b)).fold(
                        circle_two(pts[i], pts[j]),
                        |m, x| {
                            if x.radius > m.radius {
                                x
                            } else {
                                m
                            }
                        },
                    )
                });
            }
        }
    }
    let worst = pts
        .iter()
        .map(|p| dist(c.center, *p))
        .fold(0.0f64, f64::max);
    Circle {
        center: c.center,
        radius: worst.max(c.radius) * (1.0 + 1e-9) + 1e-9,
    }
}

/// The part of the polygon between the lines `dot(p, axis) = lo` and `= hi` (Sutherland-Hodgman).
/// For a concave polygon the result may contain zero-width bridges along the cut lines; its
/// vertices still span every point of the slab's part of the polygon, which is what covering needs.
pub fn clip_slab(poly: &[Pt], axis: Pt, lo: f64, hi: f64) -> Vec<Pt> {
    let keep_above = |p: &Pt| dot(*p, axis) >= lo;
    let keep_below = |p: &Pt| dot(*p, axis) <= hi;
    let cut = |a: Pt, b: Pt, level: f64| {
        let (da, db) = (dot(a, axis), dot(b, axis));
        let t = (level - da) / (db - da);
        [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t]
    };
    let pass = |pts: Vec<Pt>, keep: &dyn Fn(&Pt) -> bool, level: f64| -> Vec<Pt> {
        let n = pts.len();
        let mut out = Vec::with_capacity(n + 4);
        for i in 0..n {
            let (cur, next) = (pts[i], pts[(i + 1) % n]);
            match (keep(&cur), keep(&next)) {
                (true, true) => out.push(next),
                (true, false) => out.push(cut(cur, next, level)),
                (false, true) => {
                    out.push(cut(cur, next, level));
                    out.push(next);
                }
                (false, false) => {}
            }
        }
        out
    };
    let once = pass(poly.to_vec(), &keep_above, lo);
    pass(once, &keep_below, hi)
}

/// The polygon's principal axis (unit vector along its longest spread, from the vertex covariance).
pub fn principal_axis(poly: &[Pt]) -> Pt {
    let n = poly.len() as f64;
    let my = poly.iter().map(|p| p[0]).sum::<f64>() / n;
    let mz = poly.iter().map(|p| p[1]).sum::<f64>() / n;
    let (mut syy, mut szz, mut syz) = (0.0, 0.0, 0.0);
    for p in poly {
        let (a, b) = (p[0] - my, p[1] - mz);
        syy += a * a;
        szz += b * b;
        syz += a * b;
    }
    let angle = 0.5 * (2.0 * syz).atan2(syy - szz);
    [angle.cos(), angle.sin()]
}

/// Exact area of a union of circles: Green's theorem over the boundary arcs no other circle covers.
pub fn union_area(circles: &[Circle]) -> f64 {
    use std::f64::consts::TAU;
    let mut total = 0.0;
    'each: for (i, c) in circles.iter().enumerate() {
        if c.radius <= 0.0 {
            continue;
        }
        let mut covered: Vec<(f64, f64)> = Vec::new();
        for (j, o) in circles.iter().enumerate() {
            if i == j {
                continue;
            }
            let d = dist(c.center, o.center);
            let same = d == 0.0 && o.radius == c.radius;
            if (same && j < i) || (!same && d + c.radius <= o.radius) {
                continue 'each; // inside another circle (or a duplicate already counted)
            }
            if same || d >= c.radius + o.radius || d + o.radius <= c.radius {
                continue; // disjoint, or `o` inside `c`: none of c's boundary is covered
            }
            let mid = (o.center[1] - c.center[1]).atan2(o.center[0] - c.center[0]);
            let cos_half = ((c.radius * c.radius + d * d - o.radius * o.radius)
                / (2.0 * c.radius * d))
                .clamp(-1.0, 1.0);
            let half = cos_half.acos();
            let a = (mid - half).rem_euclid(TAU);
            let b = a + 2.0 * half;
            if b > TAU {
                covered.push((a, TAU));
                covered.push((0.0, b - TAU));
            } else {
                covered.push((a, b));
            }
        }
        covered.sort_by(|x, y| x.0.total_cmp(&y.0));
        let mut free = Vec::new();
        let mut at = 0.0;
        for (a, b) in covered {
            if a > at {
                free.push((at, a));
            }
            at = f64::max(at, b);
        }
        if at < TAU {
            free.push((at, TAU));
        }
        let r = c.radius;
        for (t1, t2) in free {
            total += 0.5
                * (r * r * (t2 - t1) + r * c.center[0] * (t2.sin() - t1.sin())
                    - r * c.center[1] * (t2.cos() - t1.cos()));
        }
    }
    total
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid_area(circles: &[Circle]) -> f64 {
        let (mut lo, mut hi) = ([f64::MAX; 2], [f64::MIN; 2]);
        for c in circles {
            for k in 0..2 {
                lo[k] = lo[k].min(c.center[k] - c.radius);
                hi[k] = hi[k].max(c.center[k] + c.radius);
            }
        }
        let n = 1500;
        let (dy, dz) = ((hi[0] - lo[0]) / n as f64, (hi[1] - lo[1]) / n as f64);
        let mut hits = 0usize;
        for i in 0..n {
            for j in 0..n {
                let p = [lo[0] + (i as f64 + 0.5) * dy, lo[1] + (j as f64 + 0.5) * dz];
                if circles.iter().any(|c| c.contains(p, 0.0)) {
                    hits += 1;
                }
            }
        }
        hits as f64 * dy * dz
    }

    #[test]
    fn union_area_matches_grid_integration() {
        let circles = [
            Circle {
                center: [0.0, 0.0],
                radius: 10.0,
            },
            Circle {
                center: [12.0, 3.0],
                radius: 7.0,
            },
            Circle {
                center: [5.0, -9.0],
                radius: 4.0,
            },
            Circle {
                center: [1.0, 1.0],
                radius: 2.0,
            }, // inside the first
            Circle {
                center: [40.0, 0.0],
                radius: 3.0,
            }, // disjoint
            Circle {
                center: [40.0, 0.0],
                radius: 3.0,
            }, // duplicate
        ];
        let exact = union_area(&circles);
        let grid = grid_area(&circles);
        assert!(
            (exact - grid).abs() < 2e-3 * grid,
            "exact {exact} grid {grid}"
        );
        let single = union_area(&circles[..1]);
        assert!((single - std::f64::consts::PI * 100.0).abs() < 1e-9);
    }

    #[test]
    fn enclosing_circle_is_minimal_for_known_shapes() {
        let square = [[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]];
        let c = enclosing_circle(&square);
        assert!((c.radius - 2f64.sqrt()).abs() < 1e-6);
        assert!(dist(c.center, [1.0, 1.0]) < 1e-6);
        // An obtuse triangle: the longest side is the diameter.
        let tri = [[0.0, 0.0], [10.0, 0.0], [5.0, 1.0]];
        let c = enclosing_circle(&tri);
        assert!((c.radius - 5.0).abs() < 1e-6);
        // Collinear points.
        let line = [[0.0, 0.0], [1.0, 1.0], [3.0, 3.0], [2.0, 2.0]];
        let c = enclosing_circle(&line);
        assert!((c.radius - 18f64.sqrt() / 2.0).abs() < 1e-6);
    }

    #[test]
    fn polygon_predicates() {
        let l_shape = [
            [0.0, 0.0],
            [4.0, 0.0],
            [4.0, 1.0],
            [1.0, 1.0],
            [1.0, 3.0],
            [0.0, 3.0],
        ];
        assert!((signed_area(&l_shape) - 6.0).abs() < 1e-12);
        assert!(inside(&l_shape, [0.5, 2.0]));
        assert!(!inside(&l_shape, [2.0, 2.0]));
        assert!(!self_intersects(&l_shape));
        let bowtie = [[0.0, 0.0], [2.0, 2.0], [2.0, 0.0], [0.0, 2.0]];
        assert!(self_intersects(&bowtie));
        assert!((dist_to_boundary(&l_shape, [0.5, 2.0]) - 0.5).abs() < 1e-12);
    }
}
