"""Slicer stand-in: a pyigtl OpenIGTLinkClient that prints one JSON line per message received.

Usage: slicer_client.py PORT COUNT TIMEOUT_S

Connects to 127.0.0.1:PORT, prints COUNT lines and exits 0, or exits 1 after TIMEOUT_S seconds.
Each line has the type, device name, header version, timestamp, message id, metadata, whether
the body's CRC matched the header ("crc_ok") and the content: "matrix" (TRANSFORM), "points"
and "lines" (POLYDATA), "code", "subcode", "error_name", "text" (STATUS), "string" (STRING).

pyigtl 0.3.4 as installed needs three additions here, each marked below:
- it never checks the CRC (parse_header drops the field): this script checks every body with
  pyigtl's own CRC64 function and reports the result instead of the content on a mismatch;
- it has no STATUS message: STATUS is read here per the spec;
- its POLYDATA reader raises TypeError on every message: the reader here is pyigtl's own with
  that line fixed, and pyigtl's writer must give back the very bytes that were received.
Its messages reach the application one per device name, newest only: this script takes every
message as it is unpacked, in order, instead.
"""

import json
import queue
import struct
import sys
import time

import numpy as np
import pyigtl
from pyigtl.messages import CRC64, MessageBase, message_type_to_class_constructor

# Every unpacked message, in stream order (filled by pyigtl's communication thread).
received = queue.Queue()

# Addition 1: the CRC check.
_parse_header = MessageBase.parse_header
_unpack = MessageBase.unpack


def parse_header_with_crc(header):
    fields = _parse_header(header)
    fields["crc"] = struct.unpack(">Q", header[50:58])[0]
    return fields


def unpack_checked(self, header_fields, body):
    self.crc_ok = CRC64(body) == header_fields["crc"]
    self.error = None
    try:
        if self.crc_ok:
            _unpack(self, header_fields, body)
        else:
            # A receiver that checks drops the content; keep what identifies the frame.
            self.device_name = header_fields["device_name"]
            self.header_version = header_fields["header_version"]
    except Exception as exp:  # reported to the test rather than breaking the connection
        self.error = f"{type(exp).__name__}: {exp}"
    received.put(self)


MessageBase.parse_header = staticmethod(parse_header_with_crc)
MessageBase.unpack = unpack_checked


class StatusMessage(MessageBase):
    """Addition 2: STATUS: code u16, subcode i64, error name char[20], text up to a NUL."""

    def __init__(self, timestamp=None, device_name=None):
        MessageBase.__init__(self, timestamp=timestamp, device_name=device_name)
        self._message_type = "STATUS"
        self._valid_message = True

    def _unpack_content(self, content):
        self.code, self.subcode, name = struct.unpack_from("> H q 20s", content)
        self.error_name = name.split(b"\0")[0].decode("ascii")
        self.text = content[30:].split(b"\0")[0].decode("utf8")


class PolyDataMessage(pyigtl.PolyDataMessage):
    """Addition 3: pyigtl's POLYDATA reader, its header line fixed (it indexed the Struct)."""

    def _unpack_content(self, content):
        counts = struct.unpack_from("> 10I", content)
        npoints, sizes = counts[0], counts[2:9:2]  # vertices, lines, polygons, strips
        at = 40
        self.points = np.frombuffer(content[at : at + 12 * npoints], dtype=">f").reshape(-1, 3)
        at += 12 * npoints
        cells = []
        for size in sizes:
            cells.append(np.frombuffer(content[at : at + size], dtype=">I"))
            at += size
        self.vertices, self.lines, self.polygons, self.triangle_strips = cells
        self.attributes = None
        # pyigtl's writer is the independent check of the layout: same content, same bytes.
        self.repacked_identical = self._pack_content() == content


message_type_to_class_constructor["STATUS"] = StatusMessage
message_type_to_class_constructor["POLYDATA"] = PolyDataMessage


def cells(array):
    """A VTK cell array [n, i0 .. in-1, n, ...] as a list of index lists."""
    out, at = [], 0
    while at < len(array):
        n = int(array[at])
        out.append([int(i) for i in array[at + 1 : at + 1 + n]])
        at += 1 + n
    return out


def describe(m):
    d = {
        "type": m.message_type,
        "device": m.device_name,
        "header_version": m.header_version,
        "crc_ok": m.crc_ok,
        "error": m.error,
    }
    if not m.crc_ok or m.error:
        return d
    d.update(timestamp=m.timestamp, message_id=m.message_id, metadata=m.metadata)
    if m.message_type == "TRANSFORM":
        d["matrix"] = np.asarray(m.matrix, dtype=float).tolist()
    elif m.message_type == "POLYDATA":
        d["points"] = m.points.astype(float).tolist()
        d["lines"] = cells(m.lines)
        d["polygons"] = cells(m.polygons)
        d["repacked_identical"] = m.repacked_identical
    elif m.message_type == "STATUS":
        d.update(code=m.code, subcode=m.subcode, error_name=m.error_name, text=m.text)
    elif m.message_type == "STRING":
        d["string"] = m.string
    return d


def main():
    port, count, timeout = int(sys.argv[1]), int(sys.argv[2]), float(sys.argv[3])
    client = pyigtl.OpenIGTLinkClient(host="127.0.0.1", port=port)
    deadline = time.monotonic() + timeout
    for printed in range(count):
        try:
            m = received.get(timeout=max(0.0, deadline - time.monotonic()))
        except queue.Empty:
            sys.exit(f"slicer_client: timed out after {printed} of {count} messages")
        print(json.dumps(describe(m)), flush=True)
    client.stop()


if __name__ == "__main__":
    main()
