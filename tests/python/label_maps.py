"""Writes one label map three ways with implementations nobody on the project wrote: NIfTI by
nibabel (RAS affine), NRRD by pynrrd in LPS (raw) and in RAS (gzip). A ball (label 1, radius
7 mm) and a box (label 2) on anisotropic voxels, placed off the origin.

usage: label_maps.py OUT_DIR
"""
import pathlib
import sys

import nibabel
import nrrd
import numpy as np

out = pathlib.Path(sys.argv[1])
spacing = np.array([0.7, 0.9, 1.2])
origin = np.array([-20.0, 15.0, 40.0])
i, j, k = np.meshgrid(np.arange(32), np.arange(30), np.arange(24), indexing="ij")
world = np.stack([i, j, k], axis=-1) * spacing
centre = np.array([11, 12, 10]) * spacing
labels = np.zeros(i.shape, dtype=np.int16)
labels[np.linalg.norm(world - centre, axis=-1) <= 7.0] = 1
labels[(i >= 24) & (i < 30) & (j >= 4) & (j < 26) & (k >= 3) & (k < 20)] = 2

affine = np.diag([*spacing, 1.0])
affine[:3, 3] = origin
nibabel.save(nibabel.Nifti1Image(labels, affine), str(out / "map.nii.gz"))

lps = np.diag(spacing) * np.array([-1.0, -1.0, 1.0])[:, None]
header = {
    "space": "left-posterior-superior",
    "space directions": lps.T,
    "space origin": origin * np.array([-1.0, -1.0, 1.0]),
    "encoding": "raw",
}
nrrd.write(str(out / "map-lps.nrrd"), labels, header)
header = {
    "space": "right-anterior-superior",
    "space directions": np.diag(spacing),
    "space origin": origin,
    "encoding": "gzip",
}
nrrd.write(str(out / "map-ras.nrrd"), labels, header)
