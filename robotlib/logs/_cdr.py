"""CDR (little-endian) encoders for the fixed ROS 2 messages of a recorded run.

The generic encoder of `mcap_ros2` walks each message field by field in
Python (about 0.7 ms per `nav_msgs/Odometry`); these write the same bytes
with a few ``struct`` calls, for the message types of
`robotlib.logs._messages` only. The tests compare every one, byte for byte,
with `mcap_ros2`'s encoder. Imports nothing of robotlib.
"""

from __future__ import annotations

import math
import struct

import numpy as np

__all__ = [
    "encode_state",
    "encode_odometry",
    "encode_cloud",
    "encode_pose_stamped",
    "encode_string",
    "encode_twist",
    "encode_laser",
]

_ZERO36 = struct.pack("<36d", *([0.0] * 36))


class _Cdr:
    """A CDR_LE buffer: the encapsulation header, then aligned fields."""

    def __init__(self):
        self.buf = bytearray(b"\x00\x01\x00\x00")

    def align(self, n: int) -> None:
        self.buf += b"\0" * ((-(len(self.buf) - 4)) % n)

    def pack(self, fmt: str, *values, align: int = 0) -> None:
        if align:
            self.align(align)
        self.buf += struct.pack("<" + fmt, *values)

    def string(self, s: str) -> None:
        b = s.encode() + b"\0"
        self.pack("I", len(b), align=4)
        self.buf += b

    def header(self, t: float, frame: str) -> None:
        ns = int(round(t * 1e9))
        self.pack("iI", ns // 1_000_000_000, ns % 1_000_000_000, align=4)
        self.string(frame)

    def pose(self, x: float, y: float, th: float) -> None:
        self.pack(
            "7d", x, y, 0.0, 0.0, 0.0, math.sin(th / 2), math.cos(th / 2), align=8
        )

    def raw(self, data: bytes, align: int) -> None:
        self.align(align)
        self.buf += data


def encode_state(row: np.ndarray, label: str) -> bytes:
    """``std_msgs/Float64MultiArray``: one dimension named ``label``."""
    c = _Cdr()
    c.pack("I", 1, align=4)
    c.string(label)
    c.pack("III", len(row), len(row), 0, align=4)
    c.pack("I", len(row), align=4)
    c.raw(np.ascontiguousarray(row, dtype="<f8").tobytes(), 8)
    return bytes(c.buf)


def encode_odometry(t: float, pose, velocity) -> bytes:
    """``nav_msgs/Odometry`` in ``odom``, child ``base_link``, zero covariances."""
    c = _Cdr()
    c.header(t, "odom")
    c.string("base_link")
    c.pose(*(float(v) for v in pose))
    c.raw(_ZERO36, 8)
    c.pack("6d", float(velocity[0]), 0.0, 0.0, 0.0, 0.0, float(velocity[1]), align=8)
    c.raw(_ZERO36, 8)
    return bytes(c.buf)


def encode_cloud(t: float, fields, data: bytes, width: int, step: int) -> bytes:
    """``sensor_msgs/PointCloud2``: one row of ``width`` points."""
    c = _Cdr()
    c.header(t, "base_link")
    c.pack("II", 1, width, align=4)
    c.pack("I", len(fields), align=4)
    for f in fields:
        c.string(f["name"])
        c.pack("I", f["offset"], align=4)
        c.pack("B", f["datatype"])
        c.pack("I", f["count"], align=4)
    c.pack("B", 0)  # is_bigendian
    c.pack("II", step, step * width, align=4)
    c.pack("I", len(data), align=4)
    c.buf += data
    c.pack("B", 1)  # is_dense
    return bytes(c.buf)


def encode_pose_stamped(t: float, frame: str, pose) -> bytes:
    """``geometry_msgs/PoseStamped``."""
    c = _Cdr()
    c.header(t, frame)
    c.pose(*(float(v) for v in pose))
    return bytes(c.buf)


def encode_string(text: str) -> bytes:
    """``std_msgs/String``."""
    c = _Cdr()
    c.string(text)
    return bytes(c.buf)


def encode_twist(v: float, w: float) -> bytes:
    """``geometry_msgs/Twist``: forward speed and turn rate."""
    c = _Cdr()
    c.pack("6d", float(v), 0.0, 0.0, 0.0, 0.0, float(w), align=8)
    return bytes(c.buf)


def encode_laser(t: float, ranges, lo: float, hi: float, rmax: float) -> bytes:
    """``sensor_msgs/LaserScan`` in ``laser`` (float32 ranges, no intensities)."""
    r = np.ascontiguousarray(ranges, dtype="<f4")
    c = _Cdr()
    c.header(t, "laser")
    inc = (hi - lo) / max(len(r) - 1, 1)
    c.pack("7f", lo, hi, inc, 0.0, 0.0, 0.0, rmax, align=4)
    c.pack("I", len(r), align=4)
    c.buf += r.tobytes()
    c.pack("I", 0, align=4)
    return bytes(c.buf)


def decode_state(data: bytes) -> np.ndarray:
    """Read back `encode_state`'s values (any ``Float64MultiArray``), float64."""
    if data[:2] != b"\x00\x01":
        raise ValueError("not a little-endian CDR message")
    pos = 4

    def align(n: int) -> None:
        nonlocal pos
        pos += (-(pos - 4)) % n

    def u32() -> int:
        nonlocal pos
        align(4)
        (v,) = struct.unpack_from("<I", data, pos)
        pos += 4
        return v

    for _ in range(u32()):  # dimensions: label, size, stride
        length = u32()
        pos += length
        u32()
        u32()
    u32()  # data_offset
    n = u32()
    align(8)
    if pos + 8 * n > len(data):
        raise ValueError(f"a Float64MultiArray of {n} values in {len(data)} bytes")
    return np.frombuffer(data, dtype="<f8", count=n, offset=pos).astype(float)
