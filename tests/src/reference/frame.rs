//! f64 needle kinematics, written independently of `planner-core` (same conventions).
//!
//! A tip frame has columns `e1` (bending-plane normal), `e2` (bevel direction: arcs curve
//! towards it) and `e3` (heading). A roll by `phi` turns `e1`, `e2` about `e3`; an arc of length
//! `s` and radius `rho` turns `e3` towards `e2` by `s / rho`; a line moves along `e3`.

use core::ops::{Add, Mul, Neg, Sub};

/// A 3-vector in f64.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct V3 {
    /// x
    pub x: f64,
    /// y
    pub y: f64,
    /// z
    pub z: f64,
}

impl V3 {
    /// The vector (x, y, z).
    pub const fn new(x: f64, y: f64, z: f64) -> V3 {
        V3 { x, y, z }
    }
    /// From an f32 triple (scenario numbers).
    pub fn from_f32(a: [f32; 3]) -> V3 {
        V3::new(f64::from(a[0]), f64::from(a[1]), f64::from(a[2]))
    }
    /// Zero.
    pub const ZERO: V3 = V3::new(0.0, 0.0, 0.0);
    /// Dot product.
    pub fn dot(self, o: V3) -> f64 {
        self.x * o.x + self.y * o.y + self.z * o.z
    }
    /// Cross product.
    pub fn cross(self, o: V3) -> V3 {
        V3::new(
            self.y * o.z - self.z * o.y,
            self.z * o.x - self.x * o.z,
            self.x * o.y - self.y * o.x,
        )
    }
    /// Euclidean norm.
    pub fn norm(self) -> f64 {
        self.dot(self).sqrt()
    }
    /// Unit vector (the input must be non-zero).
    pub fn unit(self) -> V3 {
        self * (1.0 / self.norm())
    }
}

impl Add for V3 {
    type Output = V3;
    fn add(self, o: V3) -> V3 {
        V3::new(self.x + o.x, self.y + o.y, self.z + o.z)
    }
}
impl Sub for V3 {
    type Output = V3;
    fn sub(self, o: V3) -> V3 {
        V3::new(self.x - o.x, self.y - o.y, self.z - o.z)
    }
}
impl Mul<f64> for V3 {
    type Output = V3;
    fn mul(self, k: f64) -> V3 {
        V3::new(self.x * k, self.y * k, self.z * k)
    }
}
impl Neg for V3 {
    type Output = V3;
    fn neg(self) -> V3 {
        V3::new(-self.x, -self.y, -self.z)
    }
}

/// The tip: position and the orthonormal frame (e1, e2, e3).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// Position.
    pub p: V3,
    /// Bending-plane normal.
    pub e1: V3,
    /// Bevel direction.
    pub e2: V3,
    /// Heading.
    pub e3: V3,
}

impl Frame {
    /// Rolled by `phi` (radians) about the heading.
    pub fn roll(&self, phi: f64) -> Frame {
        let (s, c) = phi.sin_cos();
        Frame {
            e1: self.e1 * c + self.e2 * s,
            e2: self.e2 * c - self.e1 * s,
            ..*self
        }
    }
    /// After an arc of length `s`, radius `rho`.
    pub fn arc(&self, s: f64, rho: f64) -> Frame {
        let (sn, cs) = (s / rho).sin_cos();
        Frame {
            p: self.p + self.e2 * (rho * (1.0 - cs)) + self.e3 * (rho * sn),
            e1: self.e1,
            e2: self.e2 * cs - self.e3 * sn,
            e3: self.e3 * cs + self.e2 * sn,
        }
    }
    /// After a line of length `s`.
    pub fn line(&self, s: f64) -> Frame {
        Frame {
            p: self.p + self.e3 * s,
            ..*self
        }
    }
    /// The roll that brings `e2` onto the unit vector `u` (which must be normal to `e3`).
    pub fn roll_towards(&self, u: V3) -> f64 {
        (-u.dot(self.e1)).atan2(u.dot(self.e2))
    }
}

/// Rotation of `v` about the unit `axis` by `angle`.
pub fn rotate(v: V3, axis: V3, angle: f64) -> V3 {
    let (s, c) = angle.sin_cos();
    v * c + axis.cross(v) * s + axis * (axis.dot(v) * (1.0 - c))
}

/// The entry basis (b1, b2, b3): b3 along `direction`; b1 is world x made normal to it, or
/// world y when the direction is within acos(0.9) of x; b2 = b3 x b1.
pub fn entry_basis(direction: V3) -> [V3; 3] {
    let b3 = direction.unit();
    let x = V3::new(1.0, 0.0, 0.0);
    let pick = if b3.dot(x).abs() < 0.9 {
        x
    } else {
        V3::new(0.0, 1.0, 0.0)
    };
    let b1 = (pick - b3 * pick.dot(b3)).unit();
    [b1, b3.cross(b1), b3]
}

/// The insertion frame: the basis turned by `theta2` about b2, then by `theta1` about b1.
pub fn insertion(p: V3, b: &[V3; 3], theta1: f64, theta2: f64) -> Frame {
    let turn = |v: V3| rotate(rotate(v, b[1], theta2), b[0], theta1);
    Frame {
        p,
        e1: turn(b[0]),
        e2: turn(b[1]),
        e3: turn(b[2]),
    }
}

/// The (theta1, theta2) whose insertion heading is the unit vector `h`.
///
/// In basis coordinates the heading is (sin t2, -cos t2 sin t1, cos t2 cos t1).
pub fn heading_angles(b: &[V3; 3], h: V3) -> (f64, f64) {
    let (h1, h2, h3) = (h.dot(b[0]), h.dot(b[1]), h.dot(b[2]));
    ((-h2).atan2(h3), h1.clamp(-1.0, 1.0).asin())
}

/// Wraps an angle into (-pi, pi].
pub fn wrap(a: f64) -> f64 {
    let t = core::f64::consts::TAU;
    let mut w = a % t;
    if w <= -core::f64::consts::PI {
        w += t;
    } else if w > core::f64::consts::PI {
        w -= t;
    }
    w
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f64::consts::{FRAC_PI_2, PI};

    #[test]
    fn quarter_arc_and_mirrored_arc() {
        let b = entry_basis(V3::new(0.0, 0.0, 2.0));
        assert_eq!(b[0], V3::new(1.0, 0.0, 0.0));
        assert_eq!(b[1], V3::new(0.0, 1.0, 0.0));
        let f = insertion(V3::ZERO, &b, 0.0, 0.0);
        let q = f.arc(63.7 * FRAC_PI_2, 63.7);
        assert!((q.p - V3::new(0.0, 63.7, 63.7)).norm() < 1e-12);
        assert!((q.e3 - V3::new(0.0, 1.0, 0.0)).norm() < 1e-12);
        let m = f.roll(PI).arc(50.0 * 0.5, 50.0);
        let expect = V3::new(0.0, -50.0 * (1.0 - 0.5f64.cos()), 50.0 * 0.5f64.sin());
        assert!((m.p - expect).norm() < 1e-12);
    }

    #[test]
    fn heading_angles_invert_the_insertion() {
        let b = entry_basis(V3::new(0.3, -0.5, 0.8));
        for (t1, t2) in [(0.3, -0.2), (-0.9, 0.4), (0.0, 0.7)] {
            let h = insertion(V3::ZERO, &b, t1, t2).e3;
            let (a1, a2) = heading_angles(&b, h);
            assert!((a1 - t1).abs() < 1e-12 && (a2 - t2).abs() < 1e-12);
            // cos(tilt) = cos t1 cos t2.
            assert!((h.dot(b[2]) - t1.cos() * t2.cos()).abs() < 1e-12);
        }
    }

    #[test]
    fn roll_towards_reaches_the_vector() {
        let b = entry_basis(V3::new(0.0, 0.2, 1.0));
        let f = insertion(V3::ZERO, &b, 0.2, -0.3);
        let u = (f.e1 * 0.6 - f.e2 * 0.8).unit();
        let g = f.roll(f.roll_towards(u));
        assert!((g.e2 - u).norm() < 1e-12);
        assert!((g.e3 - f.e3).norm() < 1e-15);
    }
}
