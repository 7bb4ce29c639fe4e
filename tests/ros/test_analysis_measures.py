"""The manoeuvre measures of `analyze` on synthetic tracks with known answers (ROS-free).

A vessel on an exact circle of radius R from the execute point has advance = transfer = R,
tactical diameter = 2 R and steady diameter = 2 R, whatever the approach course (the heading
is given wrapped to +-pi, so it crosses the +-180 deg seam) and the turn direction.
"""
import math

import numpy as np
import pytest

from sim_math.turning import circle_fit, turning_measures


def circle_track(radius=50.0, speed=4.0, psi0=2.8, side=-1.0, turns=2.2, dt=0.1, lead=5.0):
    """Straight for `lead` s, then a circle; heading wrapped to (-pi, pi]."""
    r = side * speed / radius
    t = np.arange(0.0, lead + turns * 2 * math.pi / abs(r), dt)
    psi = np.where(t < lead, psi0, psi0 + r * (t - lead))
    x = np.empty_like(t)
    y = np.empty_like(t)
    x0, y0 = lead * speed * math.cos(psi0), lead * speed * math.sin(psi0)
    straight = t < lead
    x[straight], y[straight] = speed * t[straight] * math.cos(psi0), speed * t[straight] * math.sin(psi0)
    tc = t[~straight] - lead
    # centre to the side of the turn
    cx, cy = x0 - side * radius * math.sin(psi0), y0 + side * radius * math.cos(psi0)
    ang = psi0 - side * math.pi / 2 + r * tc
    x[~straight], y[~straight] = cx + radius * np.cos(ang), cy + radius * np.sin(ang)
    wrapped = np.arctan2(np.sin(psi), np.cos(psi))
    yaw_rate = np.where(t < lead, 0.0, r)
    return t, x, y, wrapped, np.full_like(t, speed), np.zeros_like(t), yaw_rate


@pytest.mark.parametrize("side,psi0", [(-1.0, 2.8), (1.0, -3.0), (1.0, 0.0), (-1.0, math.pi / 2)])
def test_exact_circle_gives_textbook_measures(side, psi0):
    t, x, y, psi, u, v, r = circle_track(psi0=psi0, side=side)
    m = turning_measures(t, x, y, psi, u, v, r, t0=5.0)
    assert m["turn_direction"] == side
    assert m["advance"] == pytest.approx(50.0, abs=0.05)
    assert m["transfer"] == pytest.approx(50.0, abs=0.05)
    assert m["tactical_diameter"] == pytest.approx(100.0, abs=0.05)
    assert m["steady_diameter"] == pytest.approx(100.0, rel=1e-6)
    assert m["steady_diameter_kinematic"] == pytest.approx(100.0, rel=1e-9)
    assert m["steady_speed"] == pytest.approx(4.0) and abs(m["steady_yaw_rate"]) == pytest.approx(0.08)
    assert m["time_to_90"] == pytest.approx((math.pi / 2) / 0.08, abs=0.11)
    assert m["approach_heading"] == pytest.approx(psi0)
    assert m["notes"] == ""


def test_short_turn_says_what_is_missing():
    t, x, y, psi, u, v, r = circle_track(turns=0.4)
    m = turning_measures(t, x, y, psi, u, v, r, t0=5.0)
    assert math.isfinite(m["advance"]) and math.isnan(m["tactical_diameter"]) and math.isnan(m["steady_diameter"])
    assert "no tactical diameter" in m["notes"] and "turn too short" in m["notes"]


def test_circle_fit_on_noisy_arc():
    rng = np.random.default_rng(2)
    a = np.linspace(0.3, 2.0, 200)
    x = 10 + 30 * np.cos(a) + rng.normal(0, 0.05, a.size)
    y = -5 + 30 * np.sin(a) + rng.normal(0, 0.05, a.size)
    xc, yc, radius, rms = circle_fit(x, y)
    assert (xc, yc, radius) == pytest.approx((10.0, -5.0, 30.0), abs=0.1)
    assert rms == pytest.approx(0.05, rel=0.3)
