"""Reads needle's exported files with 3D Slicer's own readers (slicer-core from PyPI: Slicer's
MRML library, the code Slicer itself loads files with), or writes a markups file with Slicer's
writer, and prints what Slicer sees as JSON.

    slicer_files.py read FILE...          each .mrk.json / .vtk as Slicer loads it (RAS, mm)
    slicer_files.py write OUT NAME X Y Z  a point list with one point at RAS (X, Y, Z), saved as
                                          Slicer saves it (its default coordinate system)
    slicer_files.py segmentation OUT      a segmentation (.seg.nrrd) as Slicer's Segment Editor
                                          saves one: on 1 mm voxels, voxel (i, j, k) at RAS
                                          (-15 + i, 5 + j, 20 + k), segment "lesion" the voxels
                                          within 6 of (10, 12, 14), segment "rib" the box
                                          20 <= i < 26, 5 <= j < 25, 3 <= k < 12
"""

import json
import sys

import numpy as np
import vtk
from vtk.util import numpy_support

from slicer_core import MRMLCore as core
from slicer_core import vtkSlicerMarkupsModuleMRML as markups
import slicer_core
import slicer_core.vtkSegmentationCore as segmentation_core


def scene():
    s = core.vtkMRMLScene()
    for name in dir(markups):
        if name.startswith("vtkMRMLMarkups") and name.endswith("Node"):
            s.RegisterNodeClass(getattr(markups, name)())
    return s


def read_markups(s, path):
    storage = markups.vtkMRMLMarkupsJsonStorageNode()
    s.AddNode(storage)
    node = storage.AddNewMarkupsNodeFromFile(path, "")
    if node is None:
        return {"file": path, "loaded": False}
    n = node.GetNumberOfControlPoints()
    return {
        "file": path,
        "loaded": True,
        "class": node.GetClassName(),
        "name": node.GetName(),
        "labels": [node.GetNthControlPointLabel(i) for i in range(n)],
        "points": [list(node.GetNthControlPointPosition(i)) for i in range(n)],
    }


def read_model(s, path):
    model = core.vtkMRMLModelNode()
    s.AddNode(model)
    storage = core.vtkMRMLModelStorageNode()
    s.AddNode(storage)
    storage.SetFileName(path)
    ok = storage.ReadData(model) == 1
    poly = model.GetPolyData() if ok else None
    if poly is None:
        return {"file": path, "loaded": False}
    return {
        "file": path,
        "loaded": True,
        "points": poly.GetNumberOfPoints(),
        "cells": poly.GetNumberOfCells(),
        "bounds": list(poly.GetBounds()),
    }


def write_point(out, name, xyz):
    s = scene()
    # Created by class name: the Python module does not expose every markups class.
    node = s.AddNewNodeByClass("vtkMRMLMarkupsFiducialNode", name)
    node.AddControlPoint(xyz, name)
    storage = markups.vtkMRMLMarkupsJsonStorageNode()
    s.AddNode(storage)
    storage.SetFileName(out)
    if storage.WriteData(node) != 1:
        sys.exit(f"Slicer could not write {out}")


def labelmap(mask, origin):
    """A binary labelmap of 1 mm voxels, x fastest as VTK stores it."""
    img = segmentation_core.vtkOrientedImageData()
    img.SetDimensions(*mask.shape)
    img.SetSpacing(1.0, 1.0, 1.0)
    img.SetOrigin(*origin)
    flat = mask.transpose(2, 1, 0).ravel().astype(np.uint8)
    img.GetPointData().SetScalars(
        numpy_support.numpy_to_vtk(flat, deep=1, array_type=vtk.VTK_UNSIGNED_CHAR)
    )
    return img


def write_segmentation(out):
    s = core.vtkMRMLScene()
    for name in ["vtkMRMLSegmentationNode", "vtkMRMLSegmentationStorageNode"]:
        s.RegisterNodeClass(getattr(slicer_core, name)())
    node = s.AddNewNodeByClass("vtkMRMLSegmentationNode", "anatomy")
    seg = node.GetSegmentation()
    seg.SetSourceRepresentationName("Binary labelmap")
    i, j, k = np.meshgrid(np.arange(30), np.arange(30), np.arange(30), indexing="ij")
    masks = [
        ("lesion", (i - 10) ** 2 + (j - 12) ** 2 + (k - 14) ** 2 <= 36),
        ("rib", (i >= 20) & (i < 26) & (j >= 5) & (j < 25) & (k >= 3) & (k < 12)),
    ]
    for name, mask in masks:
        segment = segmentation_core.vtkSegment()
        segment.SetName(name)
        segment.AddRepresentation("Binary labelmap", labelmap(mask, (-15.0, 5.0, 20.0)))
        seg.AddSegment(segment, name)
    storage = s.AddNewNodeByClass("vtkMRMLSegmentationStorageNode")
    storage.SetFileName(out)
    if storage.WriteData(node) != 1:
        sys.exit(f"Slicer could not write {out}")


def main():
    if len(sys.argv) >= 3 and sys.argv[1] == "read":
        s = scene()
        out = [
            read_markups(s, p) if p.endswith(".mrk.json") else read_model(s, p)
            for p in sys.argv[2:]
        ]
        print(json.dumps(out))
    elif len(sys.argv) == 7 and sys.argv[1] == "write":
        write_point(sys.argv[2], sys.argv[3], [float(v) for v in sys.argv[4:7]])
    elif len(sys.argv) == 3 and sys.argv[1] == "segmentation":
        write_segmentation(sys.argv[2])
    else:
        sys.exit(__doc__)


if __name__ == "__main__":
    main()
