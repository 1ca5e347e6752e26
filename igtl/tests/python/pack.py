"""Frames packed by pyigtl, no socket: written back to back to stdout for a decode test.

Usage: pack.py

For header version 1, then 2 (protocol v3, message id and metadata), in this order:
  TRANSFORM  "Tip"      rotation 90 degrees about z, translation (10, 20, 30) mm
  STRING     "Message"  "needle at target" (US-ASCII)
  POINT      "Entry"    two fiducials: "F-0" at (1, 2, 3), "F-1" at (-4, 5.5, 120.25)
  POLYDATA   "Path"     five points joined by one polyline
  POLYDATA   "Mesh"     the same points, the polyline and a triangle (a polygon cell)
  POSITION   "Probe"    as pyigtl writes it, which is not the spec's 28-byte body
Every frame has the timestamp 1 700 000 000.25 s. Metadata values are US-ASCII: pyigtl 0.3.4
raises UnicodeEncodeError when packing any non-ASCII text (it catches the wrong exception).
"""

import sys

import numpy as np
import pyigtl

TIMESTAMP = 1_700_000_000.25
PATH = [[0.0, 0.0, 0.0], [0.5, 0.0, 10.0], [1.0, 0.25, 20.0], [1.5, 0.5, 30.0], [2.0, 1.0, 40.0]]
POLYLINE = [5, 0, 1, 2, 3, 4]  # a VTK cell array: count, then indices


def messages():
    t = dict(timestamp=TIMESTAMP)
    rot_z_90 = [[0, -1, 0, 10], [1, 0, 0, 20], [0, 0, 1, 30], [0, 0, 0, 1]]
    yield pyigtl.TransformMessage(np.array(rot_z_90), device_name="Tip", **t)
    yield pyigtl.StringMessage("needle at target", device_name="Message", **t)
    yield pyigtl.PointMessage(
        positions=[[1, 2, 3], [-4, 5.5, 120.25]],
        names=["F-0", "F-1"],
        rgba_colors=[10, 20, 30, 255],
        diameters=[2.5, 3.0],
        groups="Fiducial",
        owners="CT",
        device_name="Entry",
        **t,
    )
    yield pyigtl.PolyDataMessage(points=PATH, lines=np.array(POLYLINE), device_name="Path", **t)
    yield pyigtl.PolyDataMessage(
        points=PATH,
        lines=np.array(POLYLINE),
        polygons=np.array([3, 0, 1, 2]),
        device_name="Mesh",
        **t,
    )
    yield pyigtl.PositionMessage(
        positions=[1, 2, 3], quaternions=[0, 0, 0, 1], device_name="Probe", **t
    )


def main():
    out = sys.stdout.buffer
    for header_version in (1, 2):
        for message_id, m in enumerate(messages(), start=1):
            if header_version == 2:
                m.header_version = 2
                m.message_id = message_id
                m.metadata = {"TransformStatus": "OK", "Source": "pyigtl"}
            out.write(m.pack())
    out.flush()


if __name__ == "__main__":
    main()
