//! Reading a label map from a file, by its extension: each format has its reader (`nrrd`,
//! `nifti_file`, a closed mesh voxelised by `mesh`), and every map read is validated.

use crate::label_map::LabelMap;
use anyhow::{bail, Result};
use std::path::Path;

impl LabelMap {
    /// Reads a label map, by its extension: `.nrrd` (and `.seg.nrrd`), `.nii`, `.nii.gz`; or a
    /// closed mesh (`.stl`, `.obj`) as the solid it bounds, in voxels of the default size.
    pub fn read(path: &Path) -> Result<LabelMap> {
        Self::read_with(path, crate::mesh::DEFAULT_VOXEL_MM, None)
    }

    /// [`LabelMap::read`], a mesh voxelised at `voxel_mm`, its coordinates in `unit` (mm, cm, m
    /// or um; `None`: millimetres, and a mesh whose extent is implausible for them is refused).
    pub fn read_with(path: &Path, voxel_mm: f64, unit: Option<&str>) -> Result<LabelMap> {
        let name = path.to_string_lossy().to_lowercase();
        let mesh = name.ends_with(".stl") || name.ends_with(".obj");
        if unit.is_some() && !mesh {
            bail!(
                "{}: a unit is given, but only a mesh takes one (a label map's header gives its \
                 own)",
                path.display()
            );
        }
        let map = if mesh {
            crate::mesh::read(path, voxel_mm, unit)
                .map_err(|e| anyhow::anyhow!("{}: {e:#}", path.display()))?
        } else if name.ends_with(".nrrd") || name.ends_with(".nhdr") {
            crate::nrrd::read(path)?
        } else if name.ends_with(".nii") || name.ends_with(".nii.gz") {
            crate::nifti_file::read(path)?
        } else {
            bail!(
                "{}: not a label map or mesh this reads (by its extension: .nrrd, .seg.nrrd, .nii, \
                 .nii.gz, .stl, .obj)",
                path.display()
            )
        };
        map.validated()
            .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))
    }
}
