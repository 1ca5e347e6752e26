#!/usr/bin/env python3
"""Writes seed inputs for the `service` fuzz target: byte streams of valid request frames
(postcard + CRC-32 + COBS), so the fuzzer starts from frames that pass the CRC."""
import os, struct, zlib

def varint(n):
    out = b""
    while True:
        b = n & 0x7F
        n >>= 7
        if n:
            out += bytes([b | 0x80])
        else:
            return out + bytes([b])

def cobs(data):
    out, block = bytearray(), bytearray()
    for b in data:
        if b == 0:
            out += bytes([len(block) + 1]) + block
            block = bytearray()
        else:
            block.append(b)
            if len(block) == 254:
                out += b"\xff" + block
                block = bytearray()
    return bytes(out + bytes([len(block) + 1]) + block)

def frame(payload):
    # The CRC covers an unsent direction byte: 1 for requests.
    return b"\x00" + cobs(payload + struct.pack("<I", zlib.crc32(b"\x01" + payload))) + b"\x00"

def req(id_, variant, fields=b"", version=1):
    return bytes([version]) + varint(id_) + varint(variant) + fields

f32 = lambda *v: struct.pack("<%df" % len(v), *v)

def plan_request(nan=False, forms=0b11):
    s = f32(63.7, 180.0, 0.0)                      # needle
    s += f32(0, 0, 0, 0, 0, 1, 60.0)               # entry
    s += f32(0, 0, float("nan") if nan else 90.0, 0.1)  # target
    s += varint(1) + f32(0, 30, 50, 10)            # one obstacle
    s += f32(1, 1, 1000, 2)                        # weights
    s += bytes([1]) + varint(forms) + varint(1) + varint(0) + f32(0.0)  # options, plane yz
    return s

def upload(id_, body, chunk=40):
    out = b""
    crc = zlib.crc32(body)
    for off in range(0, len(body), chunk):
        data = body[off:off + chunk]
        fields = varint(off) + varint(len(body)) + varint(crc) + varint(len(data)) + data
        out += frame(req(id_, 2, fields))
    return out

seeds = {
    "hello": frame(req(1, 0)),
    "ping": frame(req(2, 1, varint(12345))),
    "status_fetch_cancel": frame(req(3, 3)) + frame(req(3, 4, varint(0) + varint(64))) + frame(req(3, 5)),
    "wrong_version": frame(req(4, 0, version=2)),
    "upload_nan": upload(5, plan_request(nan=True)) + frame(req(5, 3)) + frame(req(5, 4, varint(0) + varint(192))),
    "upload_plan_r": upload(6, plan_request(forms=0b1)) + frame(req(6, 4, varint(0) + varint(192))),
}
os.makedirs("seeds", exist_ok=True)
for name, data in seeds.items():
    # First byte: the fuzz target's chunk size selector.
    with open(os.path.join("seeds", name), "wb") as f:
        f.write(bytes([17]) + data)
