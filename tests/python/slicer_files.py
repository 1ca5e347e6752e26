"""Reads needle's exported files with 3D Slicer's own readers (slicer-core from PyPI: Slicer's
MRML library, the code Slicer itself loads files with), or writes a markups file with Slicer's
writer, and prints what Slicer sees as JSON.

    slicer_files.py read FILE...          each .mrk.json / .vtk as Slicer loads it (RAS, mm)
    slicer_files.py write OUT NAME X Y Z  a point list with one point at RAS (X, Y, Z), saved as
                                          Slicer saves it (its default coordinate system)
"""

import json
import sys

from slicer_core import MRMLCore as core
from slicer_core import vtkSlicerMarkupsModuleMRML as markups


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
    else:
        sys.exit(__doc__)


if __name__ == "__main__":
    main()
