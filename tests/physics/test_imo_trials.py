"""The IMO trial measures of sim_math.trials on tracks whose answers are known in closed form,
and the MSC.137(76) criteria against the resolution's text (5.4)."""
import math

import numpy as np
import pytest

from sim_math import trials

DEG = math.radians(1.0)


def _zigzag_heading(a_first, a_second, omega, t):
    """h = a_first sin(w t) over the first half period, a_second sin(w t) over the second
    (continuous through 0): peaks a_first at pi/(2w) and -a_second at 3pi/(2w)."""
    return np.where(t <= math.pi / omega, a_first, a_second) * np.sin(omega * t)


def test_zigzag_overshoots_are_the_peaks_beyond_the_check_heading():
    omega, psi = 0.02, 10 * DEG
    a1, a2 = 17 * DEG, 23 * DEG
    t = np.arange(0.0, 2 * math.pi / omega + 20.0, 0.01)
    h = 0.3 + _zigzag_heading(a1, a2, omega, t)  # approach heading 0.3 rad
    t1 = math.asin(psi / a1) / omega                       # h reaches +psi: first reversal
    t2 = (math.pi + math.asin(psi / a2)) / omega           # h reaches -psi: second reversal
    t3 = 2 * math.pi / omega + 10.0
    U = 5.0
    x, y = np.cumsum(U * np.cos(h)) * 0.01, np.cumsum(U * np.sin(h)) * 0.01
    z = trials.zigzag_measures(t, h, [0.0, t1, t2, t3], [psi, -psi, psi, -psi], x, y, np.full_like(t, U))
    assert z["turn_direction"] == 1.0 and z["delta"] == pytest.approx(psi) and z["heading_triggered"]
    assert z["check_angles"][:2] == pytest.approx([psi, psi], abs=1e-7)
    assert z["overshoots"][:2] == pytest.approx([a1 - psi, a2 - psi], abs=1e-7)
    assert z["overshoot_times"][:2] == pytest.approx([math.pi / (2 * omega), 3 * math.pi / (2 * omega)], abs=0.011)
    # heading 10 deg off at t1 (the first reversal): a constant-speed track is U t1 long
    assert z["initial_turning_distance"] == pytest.approx(U * t1, rel=1e-4)
    assert z["approach_speed"] == pytest.approx(U)


def test_zigzag_to_starboard_and_a_swing_still_going_at_the_end():
    omega, psi, a = 0.02, 20 * DEG, 30 * DEG
    t = np.arange(0.0, math.pi / omega + 30.0, 0.05)  # ends before the second peak
    h = -_zigzag_heading(a, a, omega, t)
    t1 = math.asin(psi / a) / omega
    t2 = (math.pi + math.asin(psi / a)) / omega
    z = trials.zigzag_measures(t, h, [0.0, t1, t2], [-psi, psi, -psi])
    assert z["turn_direction"] == -1.0
    assert z["overshoots"] == pytest.approx([a - psi], abs=1e-6)  # no second peak in the data


def test_a_zigzag_timed_by_the_clock_is_measured_but_not_judged():
    """Reversals at fixed times (5 and 15 deg of heading change here), not at delta: no IMO
    zig-zag, so imo_criteria leaves its overshoots (and initial turning) out."""
    omega, psi, a = 0.02, 10 * DEG, 20 * DEG
    t = np.arange(0.0, 2 * math.pi / omega + 20.0, 0.05)
    h = _zigzag_heading(a, a, omega, t)
    t1 = math.asin(5 * DEG / a) / omega
    t2 = (math.pi + math.asin(15 * DEG / a)) / omega
    z = trials.zigzag_measures(t, h, [0.0, t1, t2, t[-1] - 1.0], [psi, -psi, psi, -psi])
    assert z["check_angles"][:2] == pytest.approx([5 * DEG, 15 * DEG], abs=1e-5)
    assert not z["heading_triggered"]
    z["approach_speed"] = 5.0
    assert trials.imo_criteria(100.0, zigzag=z) == []


def test_stopping_measures_of_a_decelerating_turning_track():
    """Speed U (1 - t/T) on a heading psi0 + r t: stops at T; track reach U T / 2; head reach
    U (1 - cos rT) / (r^2 T) and lateral deviation U (1/r - sin(rT) / (r^2 T)) (the integrals
    of (1 - t/T) cos and sin of r t)."""
    U, T, r, psi0 = 7.0, 300.0, 0.002, 1.1
    t = np.arange(-50.0, T + 100.0, 0.01)
    tt = np.clip(t, 0.0, None)
    spd = np.where(t < 0, U, U * (1 - tt / T))  # negative after T: going astern
    psi = psi0 + r * tt
    vx, vy = spd * np.cos(psi), spd * np.sin(psi)
    x = np.concatenate([[0.0], np.cumsum(0.5 * (vx[1:] + vx[:-1]) * 0.01)])
    y = np.concatenate([[0.0], np.cumsum(0.5 * (vy[1:] + vy[:-1]) * 0.01)])
    s = trials.stopping_measures(t, x, y, psi, spd, np.abs(spd), 0.0)
    assert s["time_to_stop"] == pytest.approx(T, abs=1e-6)
    assert s["track_reach"] == pytest.approx(U * T / 2, rel=1e-6)
    assert s["head_reach"] == pytest.approx(U * (1 - math.cos(r * T)) / (r * r * T), rel=1e-6)
    assert s["lateral_deviation"] == pytest.approx(U * (1 / r - math.sin(r * T) / (r * r * T)), rel=1e-6)
    assert s["approach_speed"] == pytest.approx(U) and s["approach_heading"] == pytest.approx(psi0)


def test_stopping_measures_when_the_ship_never_stops():
    t = np.linspace(0, 100, 101)
    u = 5.0 - 0.01 * t
    s = trials.stopping_measures(t, 5 * t, 0 * t, 0 * t, u, u, 10.0)
    assert math.isnan(s["track_reach"]) and math.isnan(s["time_to_stop"])


@pytest.mark.parametrize("l_over_v,first,second", [(5.0, 10.0, 25.0), (10.0, 10.0, 25.0), (20.0, 15.0, 32.5),
                                                   (29.9, 19.95, 39.925), (30.0, 20.0, 40.0), (60.0, 20.0, 40.0)])
def test_zigzag_limits_are_msc137_5_4_3(l_over_v, first, second):
    """5.4.3.1: first overshoot 10 deg if L/V < 10 s, 20 deg if L/V >= 30 s, else 5 + (L/V)/2;
    5.4.3.2: second overshoot 25 deg, 40 deg, else 17.5 + 0.75 (L/V); 5.4.3.3: 20/20 first
    overshoot 25 deg."""
    L = 150.0
    limits = trials.zigzag_overshoot_limits(10 * DEG, L, L / l_over_v)
    assert np.degrees(limits) == pytest.approx([first, second])
    assert np.degrees(trials.zigzag_overshoot_limits(20 * DEG, L, L / l_over_v)) == pytest.approx([25.0])
    assert trials.zigzag_overshoot_limits(15 * DEG, L, L / l_over_v) == []


def test_imo_criteria_judge_each_measure():
    L = 100.0
    rows = trials.imo_criteria(L, turn={"advance": 449.0, "tactical_diameter": 501.0},
                               zigzag={"delta": 10 * DEG, "approach_speed": 10.0, "overshoots": [9 * DEG],
                                       "initial_turning_distance": 200.0},
                               stop={"track_reach": math.nan})
    got = {r["criterion"]: r["passed"] for r in rows}
    assert got == {"turning: advance": True, "turning: tactical diameter": False,
                   "initial turning: distance to 10 deg": True, "zig-zag 10/10: first overshoot": True,
                   "zig-zag 10/10: second overshoot": None, "stopping: track reach": None}


@pytest.mark.parametrize("yaw_deg,compass", [(0, 90), (90, 0), (-90, 180), (180, 270), (45, 45), (-135, 225)])
def test_compass_heading_from_enu_yaw(yaw_deg, compass):
    assert trials.compass_deg(math.radians(yaw_deg)) == pytest.approx(compass % 360, abs=1e-9)
