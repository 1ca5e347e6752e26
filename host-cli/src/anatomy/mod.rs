//! Anatomy in: label maps read into the one world frame (RAS, millimetres) and their segments
//! covered by spheres the planner can avoid (`needle cover`).
//!
//! [`label_map`] holds a map and its voxel-to-world affine; [`nrrd`] reads NRRD (and 3D
//! Slicer's `.seg.nrrd`, whose segment names it keeps), [`nifti_file`] NIfTI-1 through the
//! `nifti` crate; [`cover`] builds the conservative sphere cover and measures it; [`command`] is
//! the command line.

pub mod block;
pub mod budget;
pub mod command;
pub mod cover;
pub mod distance;
pub mod edt;
pub mod interior;
pub mod label_map;
pub mod markups;
pub mod measure;
pub mod medial;
pub mod mesh;
pub mod nifti_file;
pub mod nrrd;
pub mod reach;

#[cfg(test)]
mod tests;
