"""nibabel's own test data for needle cover's NIfTI reader: `anatomical.nii` (a 2 mm head scan,
big-endian int16, its x axis flipped) thresholded into a label map that nibabel writes with the
scan's own header (label 1: 8000 < value <= 12000, label 2: value > 12000), and
`standard.nii.gz` (uint8, voxels 1 x 3 x 2 mm, label 255) read as shipped. Prints, as JSON, the
files, nibabel's own affine of each, and the voxels (i, j, k) of each label, for the caller to
check every voxel corner against the cover.

usage: nibabel_data.py OUT_DIR
"""
import json
import pathlib
import sys

import nibabel
import numpy as np

out = pathlib.Path(sys.argv[1])
data = pathlib.Path(nibabel.__file__).parent / "tests" / "data"


def voxels(a, label):
    return np.argwhere(a == label).tolist()


scan = nibabel.load(str(data / "anatomical.nii"))
values = np.asanyarray(scan.dataobj)
labels = np.zeros(values.shape, dtype=values.dtype)
labels[(values > 8000) & (values <= 12000)] = 1
labels[values > 12000] = 2
thresholded = out / "anatomical-labels.nii"
nibabel.save(nibabel.Nifti1Image(labels, scan.affine, scan.header), str(thresholded))

standard = nibabel.load(str(data / "standard.nii.gz"))
s = np.asanyarray(standard.dataobj)
print(
    json.dumps(
        {
            "nibabel": nibabel.__version__,
            "anatomical": {
                "file": str(thresholded),
                "dtype": str(scan.get_data_dtype()),
                "affine": scan.affine.tolist(),
                "labels": {"1": voxels(labels, 1), "2": voxels(labels, 2)},
            },
            "standard": {
                "file": str(data / "standard.nii.gz"),
                "affine": standard.affine.tolist(),
                "labels": {"255": voxels(s, 255)},
            },
        }
    )
)
