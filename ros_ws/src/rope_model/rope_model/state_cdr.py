"""tug_msgs/RopeState serialized straight from numpy arrays (no ROS import).

Building the message as Python objects costs one Pose and one Twist object per element and a
field-by-field conversion on publish: most of the rope node's step at 11 elements. The rope
state is instead written here as the CDR bytes (XCDR1, little endian, what rmw_fastrtps sends
for ROS 2 Jazzy) and published as a serialized message. The bytes are checked to be identical
to rclpy's own serialization of the same message (tests/ros/test_rope_state_cdr.py).

CDR rules used: a 4-byte encapsulation header (0x00 0x01 = CDR little endian, options 0);
every primitive aligned to its size counted from the end of that header; strings as uint32
length including the terminating NUL, then the bytes; sequences as a uint32 count, then the
elements.
"""
from __future__ import annotations

import struct

import numpy as np

_ENCAPSULATION = b"\x00\x01\x00\x00"


class _CdrWriter:
    def __init__(self):
        self.parts = [_ENCAPSULATION]
        self.size = 0  # bytes after the encapsulation header

    def _align(self, n: int) -> None:
        pad = (-self.size) % n
        if pad:
            self.parts.append(b"\x00" * pad)
            self.size += pad

    def raw(self, data: bytes, align: int) -> None:
        self._align(align)
        self.parts.append(data)
        self.size += len(data)

    def uint32(self, v: int) -> None:
        self.raw(struct.pack("<I", v), 4)

    def string(self, s: str) -> None:
        b = s.encode() + b"\x00"
        self.uint32(len(b))
        self.parts.append(b)
        self.size += len(b)

    def float64s(self, a: np.ndarray) -> None:
        """Consecutive float64 values (a struct of doubles, or the body of a sequence)."""
        if a.size:
            self.raw(np.ascontiguousarray(a, dtype="<f8").tobytes(), 8)

    def float64_seq(self, a: np.ndarray) -> None:
        self.uint32(a.size)
        self.float64s(a)

    def getvalue(self) -> bytes:
        return b"".join(self.parts)


def rope_state_cdr(*, stamp_ns: int, frame_id: str, step: int, rope: str, model: str,
                   positions, quaternions, velocities, angular_velocities, lengths, tensions,
                   piece_starts, unstretched_length: float, stretched_length: float, mass: float,
                   end_a_force, end_b_force, broken: bool) -> bytes:
    """The serialized tug_msgs/RopeState. positions, velocities, angular_velocities (N,3),
    quaternions (N,4) as (x, y, z, w); stamp in nanoseconds (>= 0)."""
    pos = np.asarray(positions, float).reshape(-1, 3)
    n = pos.shape[0]
    w = _CdrWriter()
    w.raw(struct.pack("<iI", stamp_ns // 1_000_000_000, stamp_ns % 1_000_000_000), 4)  # Header.stamp
    w.string(frame_id)
    w.raw(struct.pack("<Q", step), 8)
    w.string(rope)
    w.string(model)
    # Pose[]: Point (x, y, z) then Quaternion (x, y, z, w), 7 doubles per element
    w.uint32(n)
    w.float64s(np.hstack([pos, np.asarray(quaternions, float).reshape(n, 4)]))
    # Twist[]: linear then angular, 6 doubles per element
    w.uint32(n)
    w.float64s(np.hstack([np.asarray(velocities, float).reshape(n, 3),
                          np.asarray(angular_velocities, float).reshape(n, 3)]))
    w.float64_seq(np.asarray(lengths, float).ravel())
    w.float64_seq(np.asarray(tensions, float).ravel())
    starts = np.asarray(piece_starts, dtype="<u4").ravel()
    w.uint32(starts.size)
    if starts.size:
        w.raw(starts.tobytes(), 4)
    w.float64s(np.array([unstretched_length, stretched_length, mass], float))
    w.float64s(np.concatenate([np.asarray(end_a_force, float).ravel()[:3],
                               np.asarray(end_b_force, float).ravel()[:3]]))
    w.raw(b"\x01" if broken else b"\x00", 1)
    return w.getvalue()
