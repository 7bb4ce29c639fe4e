"""tug_msgs/RopeState serialized straight from numpy arrays (no ROS import).

Building the message as Python objects costs one Pose and one Twist object per element and a
field-by-field conversion on publish: most of the rope node's step at 11 elements. The rope
state is instead written here as the CDR bytes (XCDR1, little endian, what rmw_fastrtps sends
for ROS 2 Jazzy) and published as a serialized message. rclpy's own deserializer is checked
to read back exactly the message built field by field (tests/ros/test_rope_state_cdr.py).

The CDR rules and the writer are those of sim_plumbing.cdr (the other per-step messages).
"""
from __future__ import annotations

import math
import struct

import numpy as np

from sim_plumbing.cdr import CdrWriter


def rope_state_cdr(*, stamp_ns: int, frame_id: str, step: int, rope: str, model: str,
                   positions, quaternions, velocities, angular_velocities, lengths, tensions,
                   piece_starts, unstretched_length: float, stretched_length: float, mass: float,
                   end_a_force, end_b_force, broken: bool, kinetic_energy: float = math.nan,
                   potential_energy: float = math.nan) -> bytes:
    """The serialized tug_msgs/RopeState. positions, velocities, angular_velocities (N,3),
    quaternions (N,4) as (x, y, z, w); stamp in nanoseconds (>= 0)."""
    pos = np.asarray(positions, float).reshape(-1, 3)
    n = pos.shape[0]
    w = CdrWriter()
    w.stamp(stamp_ns)  # Header.stamp
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
    w.float64s(np.array([kinetic_energy, potential_energy], float))
    return w.getvalue()
