//! Where the tracker thinks the tip is, against where it is: a smooth position bias from field
//! distortion ([`BiasField`]) and a rigid error between the tracker's frame and the imaging
//! frame ([`Registration`]), both drawn once per run.

use crate::random::{Draw, SplitMix64};
use planner_core::model::kinematics::{rotate, Frame, V3};
use serde::Serialize;

/// Sinusoidal modes per axis of the bias field.
const MODES: usize = 3;

/// Shortest and longest wavelength of a mode (mm): low frequencies across a ~100 mm workspace.
const WAVELENGTH_MM: (f64, f64) = (100.0, 300.0);

/// One sinusoidal mode: amplitude · sin(k · p + phase).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
struct Mode {
    k: [f32; 3],
    phase: f32,
    amplitude: f32,
}

/// A smooth error field over the workspace, per axis a constant offset plus three
/// sinusoidal modes of drawn direction, wavelength, phase and amplitude. The offset's variance
/// is half of sd², the modes' the other half (a sine of amplitude A has variance A²/2), so over
/// runs and points each axis has RMS `sd`; its slope is at most about 2π/100 mm × the
/// amplitudes, so points 1 mm apart differ by a few hundredths of it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BiasField {
    offset: [f32; 3],
    modes: [[Mode; MODES]; 3],
}

fn unit_vector(g: &mut SplitMix64) -> V3 {
    loop {
        let v = V3::new(g.gauss() as f32, g.gauss() as f32, g.gauss() as f32);
        let n = v.norm();
        if n > 1e-3 {
            return v / n;
        }
    }
}

impl BiasField {
    /// The field of RMS `sd` per axis drawn from `g`.
    pub fn draw(g: &mut SplitMix64, sd: f32) -> BiasField {
        let sd = f64::from(sd);
        let offset = [0; 3].map(|_| g.normal(sd * core::f64::consts::FRAC_1_SQRT_2) as f32);
        let mode_sd = sd / (MODES as f64).sqrt();
        let modes = [0; 3].map(|_| {
            [0; MODES].map(|_| {
                let wavelength = g.range(WAVELENGTH_MM.0, WAVELENGTH_MM.1);
                let k = unit_vector(g) * (core::f64::consts::TAU / wavelength) as f32;
                Mode {
                    k: [k.x, k.y, k.z],
                    phase: g.range(0.0, core::f64::consts::TAU) as f32,
                    amplitude: g.normal(mode_sd) as f32,
                }
            })
        });
        BiasField { offset, modes }
    }

    /// The bias at `p` (mm).
    pub fn at(&self, p: V3) -> V3 {
        let axis = |a: usize| {
            self.modes[a].iter().fold(self.offset[a], |sum, m| {
                let arg = m.k[0] * p.x + m.k[1] * p.y + m.k[2] * p.z + m.phase;
                sum + m.amplitude * libm::sinf(arg)
            })
        };
        V3::new(axis(0), axis(1), axis(2))
    }
}

/// A rigid transform from the true (imaging) frame to the tracker's: rotations about x, y and z
/// through `centre`, then a translation.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Registration {
    /// Rotation angles about x, y, z (radians).
    pub angles: [f32; 3],
    /// Translation (mm).
    pub translation: [f32; 3],
    /// The point the rotation turns about (mm).
    pub centre: [f32; 3],
}

impl Registration {
    /// A registration error of `sd` mm drawn from `g`: translation N(0, sd) per axis, angles
    /// N(0, sd / 100 mm) radians (so a point 100 mm from the centre moves by about sd).
    pub fn draw(g: &mut SplitMix64, sd: f32, centre: V3) -> Registration {
        let sd = f64::from(sd);
        let translation = [0; 3].map(|_| g.normal(sd) as f32);
        let angles = [0; 3].map(|_| g.normal(sd / 100.0) as f32);
        Registration {
            angles,
            translation,
            centre: [centre.x, centre.y, centre.z],
        }
    }

    fn turn(&self, v: V3) -> V3 {
        let axes = [V3::x(), V3::y(), V3::z()];
        axes.iter()
            .zip(self.angles)
            .fold(v, |v, (axis, angle)| rotate(v, *axis, angle))
    }

    /// A point of the true frame as the tracker's frame has it.
    pub fn point(&self, p: V3) -> V3 {
        let c = V3::new(self.centre[0], self.centre[1], self.centre[2]);
        let t = V3::new(
            self.translation[0],
            self.translation[1],
            self.translation[2],
        );
        c + self.turn(p - c) + t
    }

    /// A direction of the true frame as the tracker's frame has it.
    pub fn direction(&self, v: V3) -> V3 {
        self.turn(v)
    }

    /// A tip frame as the tracker's frame has it.
    pub fn frame(&self, f: &Frame) -> Frame {
        let mut out = *f;
        out.p = self.point(f.p);
        for i in 0..3 {
            out.r.set_column(i, &self.turn(f.r.column(i).into()));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::random::seeded;

    /// Over many seeds the field has RMS sd per axis; along 1 mm it changes by a few
    /// hundredths of that.
    #[test]
    fn the_field_is_smooth_and_of_its_size() {
        let sd = 0.5f32;
        let (mut sum2, mut n, mut worst_step) = (0.0f64, 0usize, 0.0f32);
        for seed in 0..400 {
            let f = BiasField::draw(&mut seeded(seed), sd);
            for i in 0..20 {
                let p = V3::new(i as f32 * 5.0 - 50.0, 30.0 - i as f32 * 3.0, i as f32 * 4.0);
                let b = f.at(p);
                sum2 += f64::from(b.norm_squared());
                n += 3;
                let step = (f.at(p + V3::new(0.6, 0.6, 0.5292)) - b).norm();
                worst_step = worst_step.max(step);
            }
        }
        let rms = (sum2 / n as f64).sqrt() as f32;
        assert!((rms - sd).abs() < 0.1 * sd, "rms {rms}");
        assert!(worst_step < 0.15 * sd, "1 mm step {worst_step}");
    }

    /// The registration moves points rigidly: distances and angles are kept.
    #[test]
    fn the_registration_is_rigid() {
        let r = Registration::draw(&mut seeded(3), 2.0, V3::new(0.0, 0.0, 50.0));
        let (a, b) = (V3::new(1.0, 2.0, 3.0), V3::new(-20.0, 15.0, 90.0));
        let d = (r.point(a) - r.point(b)).norm();
        assert!((d - (a - b).norm()).abs() < 1e-3, "{d}");
        assert!((r.point(a) - a).norm() > 0.1, "it does move points");
        let v = V3::new(0.0, 0.6, 0.8);
        assert!((r.direction(v).norm() - 1.0).abs() < 1e-5);
    }
}
