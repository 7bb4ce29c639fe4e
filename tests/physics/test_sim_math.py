"""The shared numerics against independent truths: scipy's Rotation for the rotations, the
exact solution of the harmonic oscillator for RK4 (4th-order convergence), an exact circle and an
exact straight-then-circle track for the turning measures."""
import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from sim_math import integration, rotations, turning

RNG = np.random.default_rng(2026)
ANGLES = [(0.0, 0.0, 0.0), (0.3, -0.2, 2.5), (-1.2, 1.4, -3.0), (math.pi, 0.1, math.pi / 2)] + [
    tuple(RNG.uniform([-math.pi, -1.5, -math.pi], [math.pi, 1.5, math.pi])) for _ in range(20)]


@pytest.mark.parametrize("rpy", ANGLES)
def test_rotations_agree_with_scipy(rpy):
    ref = Rotation.from_euler("ZYX", rpy[::-1])  # intrinsic yaw, pitch, roll = Rz Ry Rx
    np.testing.assert_allclose(rotations.matrix_from_rpy(*rpy), ref.as_matrix(), atol=1e-14)
    q = np.array(rotations.quaternion_from_rpy(*rpy))
    q_ref = ref.as_quat()  # (x, y, z, w)
    assert min(np.abs(q - q_ref).max(), np.abs(q + q_ref).max()) < 1e-14
    np.testing.assert_allclose(rotations.matrix_from_quaternion(*q), ref.as_matrix(), atol=1e-14)
    np.testing.assert_allclose(rotations.matrix_from_quaternion(*(3.0 * q)), ref.as_matrix(), atol=1e-14)
    rpy_back = np.array(rotations.rpy_from_quaternion(*q), float)
    np.testing.assert_allclose(Rotation.from_euler("ZYX", rpy_back[::-1]).as_matrix(), ref.as_matrix(), atol=1e-12)
    assert rotations.yaw_from_quaternion(*q) == pytest.approx(ref.as_euler("ZYX")[0], abs=1e-12)


def test_rpy_from_quaternion_on_arrays_and_the_zero_quaternion():
    qs = Rotation.from_euler("ZYX", [a[::-1] for a in ANGLES[1:]]).as_quat()
    roll, pitch, yaw = rotations.rpy_from_quaternion(*qs.T)
    np.testing.assert_allclose(Rotation.from_euler("ZYX", np.column_stack([yaw, pitch, roll])).as_matrix(),
                               Rotation.from_quat(qs).as_matrix(), atol=1e-12)
    assert [float(a) for a in rotations.rpy_from_quaternion(0.0, 0.0, 0.0, 0.0)] == [0.0, 0.0, 0.0]


@pytest.mark.parametrize("bad", [(0.0, 0.0, 0.0, 0.0), (math.nan, 0.0, 0.0, 1.0), (math.inf, 0.0, 0.0, 1.0)])
def test_matrix_from_a_quaternion_that_is_no_rotation_is_refused(bad):
    with pytest.raises(ValueError, match="not a rotation"):
        rotations.matrix_from_quaternion(*bad)


def test_yaw_pitch_quaternions_point_the_x_axis_along_each_direction():
    axes = RNG.normal(size=(50, 3))
    q = rotations.yaw_pitch_quaternions(axes)
    x_axis = Rotation.from_quat(q).apply([1.0, 0.0, 0.0])
    np.testing.assert_allclose(x_axis, axes / np.linalg.norm(axes, axis=1)[:, None], atol=1e-12)
    assert np.abs(Rotation.from_quat(q).as_euler("ZYX")[:, 2]).max() < 1e-12  # no roll


def _oscillator_error(n_steps: int) -> float:
    """x'' = -x from (1, 0) over t = 2: RK4 through the shared helpers against cos/sin."""
    h = 2.0 / n_steps
    x = np.array([1.0, 0.0])
    stage = np.empty(2)

    def f(s):
        return np.array([s[1], -s[0]])
    for _ in range(n_steps):
        k1 = f(x)
        k2 = f(integration.rk4_stage(x, 0.5 * h, k1, stage).copy())
        k3 = f(integration.rk4_stage(x, 0.5 * h, k2, stage).copy())
        k4 = f(integration.rk4_stage(x, h, k3, stage).copy())
        integration.rk4_update(x, h, k1, k2, k3, k4)
    return float(np.abs(x - [math.cos(2.0), -math.sin(2.0)]).max())


def test_rk4_converges_at_fourth_order():
    errors = [_oscillator_error(n) for n in (20, 40, 80)]
    orders = [math.log2(errors[i] / errors[i + 1]) for i in range(2)]
    assert all(3.9 < p < 4.1 for p in orders), (errors, orders)


def test_circle_fit_recovers_an_exact_and_a_noisy_circle():
    a = np.linspace(0.3, 5.0, 200)
    xc, yc, radius, rms = turning.circle_fit(120.0 + 85.0 * np.cos(a), -40.0 + 85.0 * np.sin(a))
    assert (xc, yc, radius) == pytest.approx((120.0, -40.0, 85.0), abs=1e-8) and rms < 1e-8
    noisy = turning.circle_fit(85.0 * np.cos(a) + RNG.normal(0, 0.5, a.size), 85.0 * np.sin(a) + RNG.normal(0, 0.5, a.size))
    assert noisy[2] == pytest.approx(85.0, abs=0.3) and noisy[3] == pytest.approx(0.5, rel=0.2)


@pytest.mark.parametrize("side", [1.0, -1.0])
def test_turning_measures_of_an_exact_track(side):
    """Straight at U along heading 30 deg, then from t0 an exact circle of radius R to the side
    of the turn: advance = transfer = R at 90 deg, tactical diameter = 2R at 180 deg, steady
    diameter 2R, yaw rate side*U/R, times pi R / (2U) and pi R / U."""
    U, R, psi0, t0 = 5.0, 300.0, math.radians(30.0), 50.0
    r = side * U / R
    t = np.arange(0.0, t0 + 3.0 * math.pi * R / U, 0.5)
    psi = np.where(t < t0, psi0, psi0 + r * (t - t0))
    centre = np.array([-math.sin(psi0), math.cos(psi0)]) * side * R
    x = np.where(t < t0, U * (t - t0) * math.cos(psi0), centre[0] + side * R * np.sin(psi))
    y = np.where(t < t0, U * (t - t0) * math.sin(psi0), centre[1] - side * R * np.cos(psi))
    m = turning.turning_measures(t, x, y, psi, np.full_like(t, U), np.zeros_like(t), np.where(t < t0, 0.0, r), t0)
    assert m["turn_direction"] == side and m["notes"] == ""
    assert m["advance"] == pytest.approx(R, rel=1e-4) and m["transfer"] == pytest.approx(R, rel=1e-4)
    assert m["tactical_diameter"] == pytest.approx(2 * R, rel=1e-4)
    assert m["time_to_90"] == pytest.approx(math.pi * R / (2 * U), abs=0.01)
    assert m["time_to_180"] == pytest.approx(math.pi * R / U, abs=0.01)
    assert m["steady_diameter"] == pytest.approx(2 * R, rel=1e-9)
    assert m["steady_yaw_rate"] == pytest.approx(r, rel=1e-9) and m["speed_loss"] == pytest.approx(1.0)
