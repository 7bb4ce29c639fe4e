"""The barge of Yun & Kim (captive model test): simple-towline turns (Eq 3, Table 6) and Froude
similarity."""
import math

import numpy as np
import pytest

from tug_dynamics.maneuver_trials import run, turning_metrics
from tug_dynamics.ship_file import load_ship
from tug_dynamics.vessel import VesselState

U_MODEL = 0.857       # Table 6 (5 kn full scale)


def _turn(file, gamma, u0, duration, dt):
    ship = load_ship(file, overrides={"towline_simple": {"enabled": True, "gamma_max_deg": gamma}})
    ship.set_state(VesselState(np.zeros(3), np.zeros(3), np.array([u0, 0.0, 0.0]), np.zeros(3)))
    return ship, run(ship, duration, dt)


@pytest.fixture(scope="module")
def turns():
    return {g: _turn("barge_002_model.yaml", g, U_MODEL, 400.0, 0.05)[1] for g in (10, 20, 30)}


def test_straight_tow_keeps_reference_speed():
    """gamma = 0: the towline force X(u_c) equals the resistance at u_c, so u stays u_c."""
    ship, tr = _turn("barge_002_model.yaml", 0.0, U_MODEL, 100.0, 0.1)
    assert tr.u[-1] == pytest.approx(U_MODEL, rel=1e-6)
    assert abs(tr.r[-1]) < 1e-12


@pytest.mark.parametrize("gamma", [10, 20, 30])
def test_towline_turn_reaches_steady_state(turns, gamma):
    tr = turns[gamma]
    tail = tr.t > 300.0
    r, u = tr.r[tail], tr.u[tail]
    assert np.ptp(r) < 1e-3 * abs(np.mean(r)) and np.ptp(u) < 1e-3 * np.mean(u)
    assert np.mean(r) > 0.0                         # positive gamma leads the line to port
    # steady circle: the track radius equals speed / yaw rate (kinematics of a steady turn)
    x, y = tr.x[tail], tr.y[tail]
    A = np.c_[2 * x, 2 * y, np.ones_like(x)]
    cx, cy, c = np.linalg.lstsq(A, x * x + y * y, rcond=None)[0]
    radius = math.sqrt(c + cx * cx + cy * cy)
    speed = np.mean(np.hypot(tr.u[tail], tr.v[tail]))
    assert radius == pytest.approx(speed / np.mean(r), rel=1e-3)
    assert np.mean(u) < U_MODEL                     # speed lost in the turn (Table 6 discussion)


def test_turning_diameter_decreases_with_gamma(turns):
    d = [turning_metrics(turns[g])["steady_diameter"] for g in (10, 20, 30)]
    r = [turning_metrics(turns[g])["steady_yaw_rate"] for g in (10, 20, 30)]
    assert d[0] > d[1] > d[2]
    assert r[0] < r[1] < r[2]                       # "yaw rate grows with gamma" (section 3.2)


def test_model_and_full_scale_agree_after_froude_scaling():
    lam = 9.0
    t_scale = math.sqrt(lam)
    _, m = _turn("barge_002_model.yaml", 20.0, U_MODEL, 200.0, 0.05)
    _, f = _turn("barge_002_full.yaml", 20.0, U_MODEL * t_scale, 200.0 * t_scale, 0.05 * t_scale)
    L_m, U_m = 5.0, U_MODEL
    # non-dimensional trajectories: x/L, y/L, psi, u/U, r L/U against t U/L
    for a, b, scale in ((m.x, f.x, 1 / L_m), (m.y, f.y, 1 / L_m)):
        nm, nf = a * scale, b / (lam * L_m)
        assert np.max(np.abs(nm - nf)) < 0.01 * np.max(np.abs(nm))
    assert np.max(np.abs(m.psi - f.psi)) < 0.01 * np.max(np.abs(m.psi))
    assert np.max(np.abs(m.u / U_m - f.u / (U_m * t_scale))) < 0.01
    assert np.max(np.abs(m.r * L_m / U_m - f.r * lam * L_m / (U_m * t_scale))) < 0.01 * np.max(np.abs(m.r * L_m / U_m))
