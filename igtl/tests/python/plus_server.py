"""PLUS stand-in: a pyigtl OpenIGTLinkServer that streams N TRANSFORMs at 40 Hz, then exits.

Usage: plus_server.py PORT N [HEADER_VERSION]

PORT 0 binds any free port; the first line on stdout is "port P" with the port actually bound,
so the test never races another process for a port it picked. HEADER_VERSION 1 (default) sends
protocol v1/v2 frames; 2 sends protocol v3 frames with the metadata PLUS puts on a tool's
transform (TransformStatus) and message id k.

Frame k (k = 0..N-1), device NeedleTipToReference: a rotation by k degrees about z and the
translation (k, 2k, 3k) mm, so the receiver can tell each frame's content and position in the
stream from the frame alone.
"""

import math
import sys
import time

import numpy as np
import pyigtl

RATE_HZ = 40.0
DEVICE = "NeedleTipToReference"
CONNECT_TIMEOUT_S = 10.0


def pose(k):
    """The 4x4 matrix of frame k."""
    a = math.radians(k)
    c, s = math.cos(a), math.sin(a)
    return np.array(
        [[c, -s, 0.0, k], [s, c, 0.0, 2.0 * k], [0.0, 0.0, 1.0, 3.0 * k], [0.0, 0.0, 0.0, 1.0]]
    )


def message(k, header_version):
    m = pyigtl.TransformMessage(pose(k), device_name=DEVICE)
    if header_version == 2:
        m.header_version = 2
        m.message_id = k
        m.metadata = {"TransformStatus": "OK"}
    return m


def main():
    port, count = int(sys.argv[1]), int(sys.argv[2])
    header_version = int(sys.argv[3]) if len(sys.argv) > 3 else 1
    server = pyigtl.OpenIGTLinkServer(port=port, local_server=True)
    print(f"port {server.server_address[1]}", flush=True)

    deadline = time.monotonic() + CONNECT_TIMEOUT_S
    while not server.is_connected():
        if time.monotonic() > deadline:
            sys.exit("plus_server: no client connected")
        time.sleep(0.005)

    start = time.monotonic()
    for k in range(count):
        # An absolute schedule, as a tracker's clock: time spent sending does not add up.
        delay = start + k / RATE_HZ - time.monotonic()
        if delay > 0:
            time.sleep(delay)
        server.send_message(message(k, header_version), wait=True)
    # wait=True returns once the queue is empty, which pyigtl reaches before sendall() of the
    # last message returns: give it time to reach the socket.
    time.sleep(0.2)
    server.stop()


if __name__ == "__main__":
    main()
