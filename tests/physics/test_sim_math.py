"""The shared numerics against independent truths: scipy's Rotation for the rotations, the
exact solution of the harmonic oscillator for RK4 (4th-order convergence), an exact circle and an
exact straight-then-circle track for the turning measures, numpy.linalg.solve (LAPACK) for the
LU solves."""
import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from sim_math import integration, linalg, rotations, turning

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


def _lu_solved(M, b):
    """linalg's solve of M x = b (vector or matrix b) on copies: (ok, x, piv)."""
    F, x = np.array(M, float), np.array(b, float)
    piv = np.empty(F.shape[0], np.int64)
    ok = linalg.lu_factor(F, piv)
    if ok:
        if x.ndim == 1:
            linalg.lu_solve(F, piv, x)
        else:
            linalg.lu_solve_columns(F, piv, x, x.shape[1])
    return ok, x, piv


@pytest.mark.parametrize("n", [2, 5, 6, 10])
def test_lu_solve_agrees_with_numpy_on_random_well_conditioned_matrices(n):
    """Gaussian random matrices with condition number <= 1e3 (they need row interchanges):
    relative error <= 1e-12 against LAPACK (the bound is about cond * eps = 2e-13); the
    matrix right-hand side gives every column the vector solve's answer to rounding (1e-14 of
    its norm). Not bit for bit: the two are different compiled loops, which a host's code
    generation may vectorise differently, and no result relies on their bitwise identity (a
    layout's identity across processes runs one and the same loop)."""
    rng = np.random.default_rng(n)
    for _ in range(20):
        M = rng.normal(size=(n, n))
        while np.linalg.cond(M) > 1e3:
            M = rng.normal(size=(n, n))
        B = rng.normal(size=(n, 3))
        ok, X, piv = _lu_solved(M, B)
        assert ok
        X_ref = np.linalg.solve(M, B)
        assert np.linalg.norm(X - X_ref) <= 1e-12 * np.linalg.norm(X_ref)
        for c in range(3):
            ok_c, x, _ = _lu_solved(M, B[:, c])
            assert ok_c and np.linalg.norm(x - X[:, c]) <= 1e-14 * np.linalg.norm(x)


def test_lu_solve_columns_solves_only_the_first_m_columns():
    rng = np.random.default_rng(7)
    M = rng.normal(size=(5, 5)) + 5.0 * np.eye(5)
    B = rng.normal(size=(5, 5))
    F, X = M.copy(), B.copy()
    piv = np.empty(5, np.int64)
    assert linalg.lu_factor(F, piv)
    linalg.lu_solve_columns(F, piv, X, 2)
    np.testing.assert_allclose(X[:, :2], np.linalg.solve(M, B[:, :2]), rtol=1e-12, atol=1e-14)
    assert np.array_equal(X[:, 2:], B[:, 2:])
    linalg.lu_solve_columns(F, piv, X, 0)  # no column: nothing changes
    assert np.array_equal(X[:, 2:], B[:, 2:])


def test_lu_solve_pivots_past_a_zero_on_the_diagonal():
    """Zeros on the diagonal (a permutation matrix, a 6x6 mass-matrix-like one with a zero
    first pivot): elimination without row interchanges would divide by zero."""
    P = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])
    ok, x, piv = _lu_solved(P, [1.0, 2.0, 3.0])
    assert ok and list(x) == [3.0, 1.0, 2.0] and piv[0] == 2  # exact
    rng = np.random.default_rng(3)
    M = rng.normal(size=(6, 6)) + 6.0 * np.eye(6)
    M[0, 0] = 0.0
    M[3, 3] = 0.0
    b = rng.normal(size=6)
    ok, x, piv = _lu_solved(M, b)
    assert ok and piv[0] != 0
    x_ref = np.linalg.solve(M, b)
    assert np.linalg.norm(x - x_ref) <= 1e-12 * np.linalg.norm(x_ref)


@pytest.mark.parametrize("M", [
    np.zeros((3, 3)),
    [[1.0, 2.0, 3.0], [2.0, 4.0, 6.0], [1.0, 0.0, 1.0]],                    # row 2 = 2 row 1
    [[2.0, 1.0, 0.0, 1.0], [4.0, 2.0, 1.0, 3.0], [0.0, 0.0, 0.0, 0.0], [1.0, 3.0, 1.0, 0.0]],
    [[1.0, 1.0], [1.0, math.nan]],
    [[math.inf, 1.0], [1.0, 1.0]],
])
def test_lu_factor_refuses_a_singular_or_non_finite_matrix(M):
    ok, _, _ = _lu_solved(M, np.ones(len(M)))
    assert not ok
