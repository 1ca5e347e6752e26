"""A tracker and an insertion robot written from docs/lab.md alone (not from hil-sim), with
pyigtl's message classes and kinematics of their own.

    python doc_lab.py SCENARIO.toml [--curvature-factor 0.95] [--start-roll DEG]
        [--tracker-hz 40] [--time-scale 0.02] [--seed S] [--noise-mm 0.05]

Prints `tracker ADDRESS robot ADDRESS`, then for each insertion (one robot connection each)
one JSON line: the true tip's distance to the target, the true path's least clearance to the
scenario's spheres (null without any), the pieces, how it ended.

pyigtl's server keeps one received message per device name, and a step list is several in a
row: the robot reads its socket itself and uses pyigtl to pack and unpack the frames.
"""

import json
import math
import random
import socket
import sys
import threading
import time
import tomllib

import numpy as np
import pyigtl
from pyigtl.messages import MessageBase


def unit(v):
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v)


class Needle:
    """The tip frame: p, e1, e2 (the bevel), e3 (the heading), as docs/lab.md defines it."""

    def __init__(self, scenario, radius):
        entry = scenario["entry"]
        self.p = np.asarray(entry["position"], dtype=float)
        E3 = unit(entry["direction"])
        x = np.array([1.0, 0.0, 0.0]) if abs(E3[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
        E1 = unit(x - E3 * x.dot(E3))
        E2 = np.cross(E3, E1)
        self.E = np.column_stack([E1, E2, E3])
        self.radius = radius
        self.obstacles = [(np.asarray(o["center"], dtype=float), float(o["radius"]))
                          for o in scenario.get("obstacles", [])]
        self.min_clearance = math.inf
        self.set_posture(0.0, 0.0, 0.0)

    def set_posture(self, a_deg, b_deg, roll_deg):
        a, b = math.radians(a_deg), math.radians(b_deg)
        e3 = [math.sin(b), -math.sin(a) * math.cos(b), math.cos(a) * math.cos(b)]
        e2 = [0.0, math.cos(a), math.sin(a)]
        e1 = [math.cos(b), math.sin(a) * math.sin(b), -math.cos(a) * math.sin(b)]
        self.e1, self.e2, self.e3 = (self.E @ np.array(v) for v in (e1, e2, e3))
        self.roll(roll_deg)

    def roll(self, deg):
        r = math.radians(deg)
        e1 = self.e1 * math.cos(r) + self.e2 * math.sin(r)
        e2 = self.e2 * math.cos(r) - self.e1 * math.sin(r)
        self.e1, self.e2 = e1, e2

    def along(self, s, k):
        """The point s mm along the arc of curvature k from the tip (0: a line)."""
        if k == 0.0:
            return self.p + self.e3 * s
        return self.p + self.e2 * ((1 - math.cos(s * k)) / k) + self.e3 * (math.sin(s * k) / k)

    def clearance_along(self, length, k):
        """The true path's least distance to an obstacle's surface, every 0.1 mm."""
        n = max(1, math.ceil(length / 0.1))
        for i in range(1, n + 1):
            q = self.along(length * i / n, k)
            for c, r in self.obstacles:
                self.min_clearance = min(self.min_clearance, float(np.linalg.norm(q - c)) - r)

    def push(self, length, curvature_share):
        """An arc curving towards the bevel (a share of the full curvature; 0: a line)."""
        k = curvature_share / self.radius
        self.clearance_along(length, k)
        if k == 0.0:
            self.p = self.p + self.e3 * length
            return
        a = length * k
        r = 1.0 / k
        self.p = self.p + self.e2 * (r * (1 - math.cos(a))) + self.e3 * (r * math.sin(a))
        e2 = self.e2 * math.cos(a) - self.e3 * math.sin(a)
        self.e3 = unit(self.e3 * math.cos(a) + self.e2 * math.sin(a))
        self.e2 = unit(e2 - self.e3 * e2.dot(self.e3))
        self.e1 = np.cross(self.e2, self.e3)

    def matrix(self, noise, rng):
        m = np.eye(4)
        m[:3, 0], m[:3, 1], m[:3, 2] = self.e1, self.e2, self.e3
        m[:3, 3] = self.p + np.array([rng.gauss(0, noise) for _ in range(3)])
        return m


class Tracker:
    """An OpenIGTLink server streaming the tip and the target at its own rate, each sample
    stamped when taken."""

    def __init__(self, target, hz, noise, seed):
        self.server = pyigtl.OpenIGTLinkServer(port=0, local_server=True)
        self.port = self.server.server_address[1]
        self.target = target
        self.lock = threading.Lock()
        self.tip = None
        self.rng = random.Random(seed)
        self.noise = noise
        threading.Thread(target=self.stream, args=(1.0 / hz,), daemon=True).start()

    def show(self, needle):
        with self.lock:
            self.tip = needle

    def stream(self, period):
        while True:
            time.sleep(period)
            with self.lock:
                stamp = time.time()
                tip = None if self.tip is None else self.tip.matrix(self.noise, self.rng)
            if tip is None or not self.server.is_connected():
                continue
            t = np.eye(4)
            t[:3, 3] = self.target
            self.server.send_message(
                pyigtl.TransformMessage(t, timestamp=stamp, device_name="TargetToReference"),
                wait=False)
            self.server.send_message(
                pyigtl.TransformMessage(tip, timestamp=stamp, device_name="NeedleTipToReference"),
                wait=False)


def frames(conn):
    """The frames off a socket, unpacked by pyigtl, as they arrive."""
    buf = b""
    while True:
        while len(buf) >= MessageBase.IGTL_HEADER_SIZE:
            header = MessageBase.parse_header(buf[:MessageBase.IGTL_HEADER_SIZE])
            end = MessageBase.IGTL_HEADER_SIZE + header["body_size"]
            if len(buf) < end:
                break
            body, buf = buf[MessageBase.IGTL_HEADER_SIZE:end], buf[end:]
            message = MessageBase.create_message(header["message_type"])
            if message:
                message.unpack(header, body)
                yield message
        chunk = conn.recv(65536)
        if not chunk:
            return
        buf += chunk


def parse(text):
    word, *pairs = text.split()
    return word, {k: float(v) for k, v in (p.split("=") for p in pairs)}


class Robot:
    """One insertion over one connection, lock-step as docs/lab.md's robot mapping says."""

    def __init__(self, conn, needle, tracker, args):
        self.conn, self.needle, self.tracker, self.args = conn, needle, tracker, args
        self.words = frames(conn)
        self.depth, self.base, self.pieces = 0.0, args["start_roll"], 0

    def send(self, text, stamp=None):
        m = pyigtl.StringMessage(text, device_name="NeedleRobotState",
                                 timestamp=time.time() if stamp is None else stamp)
        self.conn.sendall(m.pack())

    def word(self):
        for m in self.words:
            if m.device_name == "NeedleRobotCommand":
                return parse(m.string)
        return ("lost", {})

    def steps(self, count):
        return [self.word() for _ in range(int(count))]

    def run(self):
        steps = None
        while steps is None:
            word, kv = self.word()
            if word == "posture":
                r = kv["roll_deg"]
                # The shorter way round from where the base stands.
                self.base = r + 360.0 * math.floor((self.base - r) / 360.0 + 0.5)
                self.needle.set_posture(kv["theta1_deg"], kv["theta2_deg"], r)
                self.send(f"posture-set depth_mm=0 base_deg={self.base!r}")
            elif word == "hold":
                self.send("holding")
            elif word == "steps":
                steps = self.steps(kv["count"])
            else:
                return "stopped" if word == "stop" else "lost"
        self.tracker.show(self.needle)
        while True:
            replaced = None
            for word, kv in steps:
                outcome = self.step(word, kv)
                if isinstance(outcome, list):
                    replaced = outcome
                    break
                if outcome is not None:
                    return outcome
            if replaced is None:
                self.send("done")
                if self.word()[0] == "stop":
                    self.send("stopped")
                return "done"
            steps = replaced

    def step(self, word, kv):
        """Executes one step piece by piece; gives a new list, an ending, or None."""
        duration = kv.get("duration_s", 0.0)
        if word == "rotate":
            pieces = [(0.0, kv["angle_deg"], duration)]
        else:
            length = kv["length_mm"]
            n = max(1, math.ceil(length - 1e-9))
            pieces = [(length / n, 0.0, duration / n)] * n
        share = {"insert": 1.0, "spin-insert": 0.0, "duty-insert": kv.get("duty", 0.0)}
        for push, turn, seconds in pieces:
            time.sleep(seconds * self.args["time_scale"])
            moved = Needle.__new__(Needle)
            moved.__dict__ = dict(self.needle.__dict__)
            if turn:
                moved.roll(turn)
                self.base += turn
            else:
                # The true needle curves by the factor of the nominal curvature.
                moved.push(push, share.get(word, 1.0) * self.args["curvature_factor"])
                self.depth += push
            self.needle = moved
            # The tip is where this piece left it from this instant: the piece's end.
            with self.tracker.lock:
                ended = time.time()
                self.tracker.tip = moved
            self.pieces += 1
            self.send(f"progress piece={self.pieces} depth_mm={self.depth!r} "
                      f"base_deg={self.base!r}", stamp=ended)
            word2, kv2 = self.word()
            while word2 == "hold":
                self.send("holding")
                word2, kv2 = self.word()
            if word2 == "steps":
                return self.steps(kv2["count"])
            if word2 == "stop":
                self.send("stopped")
                return "stopped"
            if word2 != "go":
                return "lost"
        return None


def main():
    path = sys.argv[1]
    opts = dict(zip(sys.argv[2::2], sys.argv[3::2]))
    args = {
        "curvature_factor": float(opts.get("--curvature-factor", 0.95)),
        "start_roll": float(opts.get("--start-roll", 0.0)),
        "time_scale": float(opts.get("--time-scale", 0.02)),
    }
    with open(path, "rb") as f:
        scenario = tomllib.load(f)
    seed = int(opts.get("--seed", 1))
    target = np.asarray(scenario["target"]["position"], dtype=float)
    tracker = Tracker(target, float(opts.get("--tracker-hz", 40)),
                      float(opts.get("--noise-mm", 0.05)), seed)
    listener = socket.socket()
    listener.bind(("127.0.0.1", 0))
    listener.listen()
    print(f"tracker 127.0.0.1:{tracker.port} robot 127.0.0.1:{listener.getsockname()[1]}",
          flush=True)
    while True:
        conn, _ = listener.accept()
        conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        needle = Needle(scenario, scenario["needle"]["curvature_radius"])
        robot = Robot(conn, needle, tracker, args)
        end = robot.run()
        miss = float(np.linalg.norm(robot.needle.p - target))
        tracker.show(None)
        conn.close()
        clearance = robot.needle.min_clearance
        print(json.dumps({"end": end, "pieces": robot.pieces, "target_error": miss,
                          "min_clearance": clearance if math.isfinite(clearance) else None}),
              flush=True)


if __name__ == "__main__":
    main()
