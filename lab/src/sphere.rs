//! A sphere as a triangle mesh for Slicer: an icosahedron split once (each triangle into four,
//! the new points pushed out onto the sphere), 42 points and 80 triangles: round enough to read
//! as a ball, few enough points that six obstacles fit one `POLYDATA`. Then grown until no face
//! cuts into the sphere (its points about 7 % outside it): an obstacle is never shown smaller
//! than it is.

/// A mesh around the unit sphere, its triangles wound counter-clockwise seen from outside.
pub fn unit_sphere() -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let t = (1.0 + 5.0_f32.sqrt()) / 2.0;
    let mut points: Vec<[f32; 3]> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .map(unit)
    .to_vec();
    let faces: [[u32; 3]; 20] = [
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    // Each edge's midpoint once, shared by the two faces on it.
    let mut midpoints: Vec<([u32; 2], u32)> = Vec::new();
    let mut middle = |a: u32, b: u32, points: &mut Vec<[f32; 3]>| -> u32 {
        let key = [a.min(b), a.max(b)];
        if let Some(&(_, i)) = midpoints.iter().find(|(k, _)| *k == key) {
            return i;
        }
        let (p, q) = (points[a as usize], points[b as usize]);
        points.push(unit([0, 1, 2].map(|i| p[i] + q[i])));
        let i = points.len() as u32 - 1;
        midpoints.push((key, i));
        i
    };
    let mut triangles = Vec::with_capacity(80);
    for [a, b, c] in faces {
        let ab = middle(a, b, &mut points);
        let bc = middle(b, c, &mut points);
        let ca = middle(c, a, &mut points);
        triangles.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
    }
    // Each face's plane at its distance from the centre; the nearest is moved out to 1.
    let nearest = triangles
        .iter()
        .map(|t| plane_distance(t.map(|i| points[i as usize])))
        .fold(f32::INFINITY, f32::min);
    for p in &mut points {
        *p = p.map(|x| x / nearest);
    }
    (points, triangles)
}

/// Distance from the centre to the plane of a triangle.
fn plane_distance([p, q, r]: [[f32; 3]; 3]) -> f32 {
    let (u, v) = (sub(q, p), sub(r, p));
    let n = unit([
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ]);
    (n[0] * p[0] + n[1] * p[1] + n[2] * p[2]).abs()
}

fn sub(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn unit(v: [f32; 3]) -> [f32; 3] {
    let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    v.map(|x| x / n)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 42 points, 80 triangles, a closed surface (every edge in two triangles, Euler's
    /// V - E + F = 2), each wound outwards, no face inside the sphere, every point within 8 %
    /// of it.
    #[test]
    fn the_sphere_is_closed_round_and_wound_outwards() {
        let (points, triangles) = unit_sphere();
        assert_eq!((points.len(), triangles.len()), (42, 80));
        for p in &points {
            let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
            assert!((1.0..1.08).contains(&r), "a point {r} from the centre");
        }
        let mut edges = std::collections::HashMap::new();
        for t in &triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                *edges.entry((a.min(b), a.max(b))).or_insert(0) += 1;
            }
            let [p, q, r] = t.map(|i| points[i as usize]);
            let (u, v) = (sub(q, p), sub(r, p));
            let n = [
                u[1] * v[2] - u[2] * v[1],
                u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0],
            ];
            let c = [0, 1, 2].map(|i| (p[i] + q[i] + r[i]) / 3.0);
            let outwards = n[0] * c[0] + n[1] * c[1] + n[2] * c[2];
            assert!(outwards > 0.0, "{t:?} winds inwards");
            let plane = plane_distance([p, q, r]);
            assert!(plane > 1.0 - 1e-5, "a face's plane {plane} from the centre");
        }
        assert!(edges.values().all(|&n| n == 2));
        assert_eq!(42 - edges.len() as i64 + 80, 2);
    }
}
