//! TRANSFORM (`Documents/Protocol/transform.md`): 12 × f32, the upper 3×4 of a homogeneous
//! matrix column by column (R11 R21 R31 R12 R22 R32 R13 R23 R33) then the translation in mm.

use crate::bytes::{Reader, Writer};
use crate::Error;

/// Bytes of a TRANSFORM body.
pub const TRANSFORM_SIZE: usize = 48;

/// How far from orthonormal (each entry of RᵀR − I) and from det +1 a rotation may be: f32
/// trackers round, but a scaled or sheared matrix must not be taken for a pose.
pub const RIGID_TOLERANCE: f32 = 1e-3;

/// A rigid pose: rotation and translation (mm). Only rigid ones exist: a needle tip has no scale.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Transform {
    rotation: [[f32; 3]; 3],
    translation: [f32; 3],
}

impl Transform {
    /// The identity pose.
    pub const IDENTITY: Transform = Transform {
        rotation: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        translation: [0.0; 3],
    };

    /// A pose from a row-major rotation (`rotation[row][col]`) and a translation in mm;
    /// `NotRigid` unless the rotation is orthonormal with det +1 (within [`RIGID_TOLERANCE`]),
    /// `NotFinite` for a NaN or infinite translation.
    pub fn new(rotation: [[f32; 3]; 3], translation: [f32; 3]) -> Result<Self, Error> {
        if !is_rigid(&rotation) {
            return Err(Error::NotRigid);
        }
        if !translation.iter().all(|t| t.is_finite()) {
            return Err(Error::NotFinite);
        }
        Ok(Transform {
            rotation,
            translation,
        })
    }

    /// The rotation, row-major: `rotation()[row][col]`.
    pub fn rotation(&self) -> [[f32; 3]; 3] {
        self.rotation
    }

    /// The translation in mm.
    pub fn translation(&self) -> [f32; 3] {
        self.translation
    }

    /// Writes the 48-byte body; returns 48 or `BufferTooSmall`.
    pub fn encode(&self, out: &mut [u8]) -> Result<usize, Error> {
        let mut w = Writer::new(out);
        for col in 0..3 {
            for row in 0..3 {
                w.f32(self.rotation[row][col])?;
            }
        }
        w.f32s(&self.translation)?;
        Ok(w.len())
    }

    /// Reads a 48-byte body: `BadBodySize` for another size, then as [`Transform::new`].
    pub fn decode(content: &[u8]) -> Result<Self, Error> {
        if content.len() != TRANSFORM_SIZE {
            return Err(Error::BadBodySize);
        }
        let mut r = Reader::new(content);
        let mut rotation = [[0.0; 3]; 3];
        for col in 0..3 {
            for row in 0..3 {
                rotation[row][col] = r.f32()?;
            }
        }
        let translation = [r.f32()?, r.f32()?, r.f32()?];
        Transform::new(rotation, translation)
    }
}

/// Orthonormal with det +1; written so that NaN fails every comparison and so the test.
fn is_rigid(r: &[[f32; 3]; 3]) -> bool {
    let near = |x: f32, want: f32| (x - want).abs() <= RIGID_TOLERANCE;
    for i in 0..3 {
        for j in 0..3 {
            let dot: f32 = (0..3).map(|k| r[k][i] * r[k][j]).sum();
            if !near(dot, if i == j { 1.0 } else { 0.0 }) {
                return false;
            }
        }
    }
    let det = r[0][0] * (r[1][1] * r[2][2] - r[1][2] * r[2][1])
        - r[0][1] * (r[1][0] * r[2][2] - r[1][2] * r[2][0])
        + r[0][2] * (r[1][0] * r[2][1] - r[1][1] * r[2][0]);
    near(det, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_scale_shear_reflection_and_nan() {
        let id = Transform::IDENTITY.rotation();
        let mut scaled = id;
        scaled[0][0] = 1.01;
        let mut sheared = id;
        sheared[0][1] = 0.01;
        let mut reflected = id;
        reflected[2][2] = -1.0;
        let mut nan = id;
        nan[1][1] = f32::NAN;
        for r in [scaled, sheared, reflected, nan] {
            assert_eq!(Transform::new(r, [0.0; 3]), Err(Error::NotRigid));
        }
        let mut within = id;
        within[0][0] = 1.0004;
        assert!(Transform::new(within, [0.0; 3]).is_ok());
        assert_eq!(
            Transform::new(id, [0.0, f32::INFINITY, 0.0]),
            Err(Error::NotFinite)
        );
    }
}
