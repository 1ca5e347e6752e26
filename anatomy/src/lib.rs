//! Anatomy in: label maps read into the one world frame (RAS, millimetres) and their segments
//! covered by spheres the planner can avoid (`needle cover`, and `[[anatomy]]` in a scenario
//! file, which `needle-scenario` reads).
//!
//! [`label_map`] holds a map and its voxel-to-world affine ([`LabelMap::read`] reads a file);
//! [`nrrd`] reads NRRD (and 3D Slicer's `.seg.nrrd`, whose segment names it keeps),
//! [`nifti_file`] NIfTI-1 through the `nifti` crate, [`mesh`] a closed STL or OBJ surface as the
//! solid it bounds; [`cover`] builds the conservative sphere cover and measures it; [`markups`]
//! reads and writes Slicer's markups; [`command`] is what `needle cover` is asked and prints
//! (its flags are the `needle` binary's); [`progress`] the progress line of the long covers.
//!
//! Covering a segment, the item most callers start from:
//!
//! ```
//! use needle_anatomy::cover::{cover_segment, CoverOptions, DEFAULT_TIGHTNESS};
//! use needle_anatomy::label_map::LabelMap;
//!
//! // A 6 mm cube of label 1 in the middle of a 10 x 10 x 10 map of 1 mm voxels.
//! let inside = |i: usize| (2..8).contains(&i);
//! let labels = (0..1000)
//!     .map(|n| i64::from(inside(n % 10) && inside(n / 10 % 10) && inside(n / 100)))
//!     .collect();
//! let identity = [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]];
//! let map = LabelMap { dims: [10, 10, 10], labels, ijk_to_ras: identity, named: Vec::new() }
//!     .validated()?;
//! let options = CoverOptions { margin_mm: 0.0, max_spheres: 8, tightness: DEFAULT_TIGHTNESS };
//! let segment = &map.segments()[0];
//! let cover = cover_segment(&map, segment, &options.validated()?)?;
//! assert_eq!(cover.voxels, 216);
//! assert!(!cover.spheres.is_empty() && cover.spheres.len() <= 8);
//! # Ok::<(), anyhow::Error>(())
//! ```

pub use label_map::LabelMap;

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
pub mod progress;
pub mod reach;
pub mod read;
pub mod touching;

#[cfg(test)]
mod tests;
