"""Rotations and quaternions in the convention of every interface of the simulator (REP-103):
R = Rz(yaw) Ry(pitch) Rx(roll) maps body (x forward, y port, z up) to world (ENU),
v_world = R @ v_body; quaternions are (x, y, z, w) as in geometry_msgs.

Scalar functions are numba-compiled (cache=True) so that kernels call them and Python callers
get the same code; the array functions are numpy."""
import math

import numpy as np
from numba import njit


@njit(cache=True, inline="always")
def matrix_entries_from_trig(cf: float, sf: float, ct: float, st: float, cp: float, sp: float):
    """R = Rz(yaw) Ry(pitch) Rx(roll) as the tuple (R00, R01, R02, R10, ..., R22) from the cosines
    and sines of roll (f), pitch (t) and yaw (p): for kernels that have the trig values already
    and want no array allocation."""
    return (cp * ct, cp * st * sf - sp * cf, cp * st * cf + sp * sf,
            sp * ct, sp * st * sf + cp * cf, sp * st * cf - cp * sf,
            -st, ct * sf, ct * cf)


@njit(cache=True)
def matrix_from_rpy(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """3x3 R = Rz(yaw) Ry(pitch) Rx(roll), body -> world."""
    e = matrix_entries_from_trig(math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch),
                                 math.cos(yaw), math.sin(yaw))
    R = np.empty((3, 3))
    R[0, 0], R[0, 1], R[0, 2] = e[0], e[1], e[2]
    R[1, 0], R[1, 1], R[1, 2] = e[3], e[4], e[5]
    R[2, 0], R[2, 1], R[2, 2] = e[6], e[7], e[8]
    return R


@njit(cache=True)
def quaternion_from_rpy(roll: float, pitch: float, yaw: float):
    """(x, y, z, w) of R = Rz(yaw) Ry(pitch) Rx(roll)."""
    cr, sr = math.cos(0.5 * roll), math.sin(0.5 * roll)
    cp, sp = math.cos(0.5 * pitch), math.sin(0.5 * pitch)
    cy, sy = math.cos(0.5 * yaw), math.sin(0.5 * yaw)
    return (sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy,
            cr * cp * cy + sr * sp * sy)


def matrix_from_quaternion(x: float, y: float, z: float, w: float) -> np.ndarray:
    """3x3 rotation (frame -> world) of the quaternion (x, y, z, w), normalised here; a zero or
    non-finite quaternion is not a rotation (ValueError naming it)."""
    n = w * w + x * x + y * y + z * z
    if not (math.isfinite(n) and n > 1e-12):
        raise ValueError(f"quaternion ({x}, {y}, {z}, {w}) is not a rotation")
    s = 2.0 / n
    return np.array([
        [1 - s * (y * y + z * z), s * (x * y - z * w), s * (x * z + y * w)],
        [s * (x * y + z * w), 1 - s * (x * x + z * z), s * (y * z - x * w)],
        [s * (x * z - y * w), s * (y * z + x * w), 1 - s * (x * x + y * y)],
    ])


def rpy_from_quaternion(x, y, z, w):
    """(roll, pitch, yaw) of the quaternion(s) (x, y, z, w): scalars or arrays of equal shape;
    pitch in [-pi/2, pi/2], roll and yaw in [-pi, pi]. Normalised first; a zero quaternion
    reads as the identity."""
    x, y, z, w = (np.asarray(a, float) for a in (x, y, z, w))
    n = np.sqrt(x * x + y * y + z * z + w * w)
    n = np.where(n == 0.0, 1.0, n)
    x, y, z, w = x / n, y / n, z / n, w / n
    roll = np.arctan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    pitch = np.arcsin(np.clip(2 * (w * y - z * x), -1.0, 1.0))
    yaw = np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    return roll, pitch, yaw


def yaw_from_quaternion(x: float, y: float, z: float, w: float) -> float:
    """Yaw of the quaternion (x, y, z, w) of a unit rotation, rad in [-pi, pi]."""
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def yaw_pitch_quaternions(axes: np.ndarray) -> np.ndarray:
    """(N, 4) quaternions (x, y, z, w) of R = Rz(yaw) Ry(pitch) with R e_x along each axis (no
    roll): the orientation of a line element (rope link, cable segment) from its direction."""
    axes = np.asarray(axes, float).reshape(-1, 3)
    yaw = np.arctan2(axes[:, 1], axes[:, 0])
    pitch = np.arctan2(-axes[:, 2], np.hypot(axes[:, 0], axes[:, 1]))
    cy, sy, cp, sp = np.cos(yaw / 2), np.sin(yaw / 2), np.cos(pitch / 2), np.sin(pitch / 2)
    return np.stack([-sy * sp, cy * sp, sy * cp, cy * cp], axis=1)
