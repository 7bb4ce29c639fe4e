"""Section 4 manoeuvres of Yoon & Kang, "Modeling and Simulation of the 6 DOF Motion of a High
Speed Planing Hull Running in Calm Sea", on its 40 ft planing hull.

The paper's result figures are withheld, so the truths are its statements (4.1-4.3): no lift
astern, trim about zero near zero speed, a planing boat heels INTO its turn (unlike a ship),
small speed loss in the turn, roll in the zig-zag periodic and in phase with the turn. Where
a number is compared with its Table 2 the test says so and names it calibration: the pitch
coupling M_w of Eq 7 is fitted so the steady trim equals Table 2 from 15 to 35 kn (the
independent Table 2 checks are in test_savitsky_table2.py).
Sign reminders: steering_angle -10 deg = the paper's 10 deg starboard bucket; roll > 0 is
starboard side down (REP-103); trim below is bow-up positive = -pitch.
"""
import math

import numpy as np
import pytest

from tug_dynamics import planing_manoeuvres as pm

KNOT = 1852.0 / 3600.0


@pytest.fixture(scope="module")
def accel():
    return pm.acceleration()


@pytest.fixture(scope="module")
def backing():
    return pm.deceleration_backing()


@pytest.fixture(scope="module")
def stbd_turn():
    return pm.turn(bucket_deg=-10.0)


@pytest.fixture(scope="module")
def zigzag():
    return pm.zigzag()


def test_acceleration_trims_bow_up_when_planing(accel):
    h, f = accel["history"], accel["figures"]
    planing = h["u"] > 15 * KNOT
    assert planing.any() and np.all(h["pitch"][planing] < 0)          # bow up
    # Eq 9: never any lift with the bow down
    assert np.all(h["lift"][h["pitch"] >= 0] == 0.0)


def test_acceleration_settles_on_the_steady_state(accel):
    """Output check: the time-integrated run ends on the algebraic steady state of the same
    force model (found by a root solve, PlaningHull.steady_state), a separate computation.
    The speed itself is not a result: Eq 11 sets the jet so that full throttle balances the
    resistance at the file's design speed (35 kn), so u -> 35 kn only shows the run has settled."""
    h, f = accel["history"], accel["figures"]
    tail = h["t"] > h["t"][-1] - 10.0
    assert np.ptp(h["u"][tail]) < 1e-3 * h["u"][-1]                          # settled
    assert f["final_trim_deg"] == pytest.approx(f["steady_trim_deg"], abs=0.01)   # measured 1e-5 deg
    assert f["final_rise"] == pytest.approx(f["steady_rise"], abs=0.001)          # measured 6e-6 m
    assert f["final_speed_kn"] == pytest.approx(35.0, rel=0.01)


def test_acceleration_trim_against_table2_calibration(accel):
    """Calibration, not validation: M_w is fitted so the steady trim equals Table 2 at 15-35 kn.
    This checks the transient stays on the fitted steady curve: the hump (largest trim)
    where Table 2 has it (20 kn, within 15-25 kn) and within 0.5 deg of its 6.14 deg, and
    the final trim within 0.5 deg of Table 2's 4.55 deg at 35 kn."""
    f = accel["figures"]
    assert 15.0 <= f["u_at_max_trim"] / KNOT <= 25.0
    assert f["max_trim_deg"] == pytest.approx(6.14, abs=0.5)
    assert f["final_trim_deg"] == pytest.approx(4.55, abs=0.5)


def test_deceleration_and_backing(backing):
    h, f = backing["history"], backing["figures"]
    assert f["u0_kn"] == pytest.approx(35.0, rel=1e-3)      # set-up: starts from the steady full-speed run
    assert f["t_to_10kn"] < f["t_to_5kn"] < 30.0            # coasts down before the astern order (t = 30 s)
    astern = h["u"] < 0
    assert astern.any() and np.all(h["lift"][astern] == 0.0)  # paper 4.1: no lift astern
    # goes astern, and slower than ahead (paper 4.1: thrust less efficient astern)
    assert -f["u0_kn"] * KNOT < f["astern_speed"] < 0.0
    # near zero speed the trim is about zero (no lift moment), within the hull's natural swing
    slow = np.abs(h["u"]) < 1.0
    assert np.all(np.abs(np.degrees(h["pitch"][slow])) < 0.5)


def test_turn_heels_inward_with_small_speed_loss(stbd_turn):
    h, f = stbd_turn["history"], stbd_turn["figures"]
    assert f["steady_r_deg_s"] < 0                            # starboard turn
    assert f["steady_roll_deg"] > 0.2                         # starboard side down: inward
    late = h["t"] > 60
    assert np.all(h["roll"][late] * h["r"][late] < 0)         # heel opposite to r = inward
    # paper 4.2: "the speed reduction is small"; 5 % is this test's reading of "small"
    assert 0 < f["speed_loss_pct"] < 5.0
    assert f["steady_trim_deg"] > 0.0                         # still bow-up
    # two independent measurements of the turning diameter: the circle fitted to the track
    # (f["diameter"], sim_math.turning) and the steady-turn kinematics 2 U / |r| (measured 6.5e-5)
    assert f["diameter"] == pytest.approx(2 * f["steady_speed"] / math.radians(abs(f["steady_r_deg_s"])), rel=0.02)


def test_port_turn_mirrors_starboard_turn(stbd_turn):
    port = pm.turn(bucket_deg=10.0, duration=60.0)["history"]
    stbd = stbd_turn["history"]
    n = len(port["t"])
    assert np.allclose(port["roll"], -stbd["roll"][:n], atol=1e-9)
    assert np.allclose(port["r"], -stbd["r"][:n], atol=1e-9)
    assert np.allclose(port["u"], stbd["u"][:n], atol=1e-9)


def test_zigzag_roll_is_periodic_in_phase_and_smaller_than_in_the_turn(zigzag, stbd_turn):
    h, f = zigzag["history"], zigzag["figures"]
    peaks = np.array(f["roll_peaks_deg"])
    assert np.all(np.sign(peaks[1:]) == -np.sign(peaks[:-1]))          # alternates every leg
    # periodic, steady amplitude from the second half-cycle on (the first starts from the
    # straight run; since the heel takes longer than a 5 s leg to settle it differs by ~8 %)
    assert np.allclose(np.abs(peaks[1:]), np.abs(peaks[1:]).mean(), rtol=0.05)
    # roll zero crossings follow the 5 s bucket reversals
    t, roll = h["t"], h["roll"]
    zc = t[1:][np.diff(np.sign(roll)) != 0]
    zc = zc[zc > 4.0]
    assert np.allclose(np.diff(zc), 5.0, atol=0.3)
    # in phase with the turn: heel inward (roll opposite to yaw rate) most of the time
    sel = (t > 5.0) & (np.abs(h["r"]) > np.radians(0.5))
    assert np.mean(roll[sel] * h["r"][sel] < 0) > 0.9
    # smaller than in the steady turn: the heel takes longer than a 5 s leg to settle. (This
    # asserted only "peaks < 1.05 x steady" while the old model's heel followed the yaw rate
    # within a second; issue 15 item 2, PLANING.md.) The paper's roll values are withheld:
    # 0.95 is this test's margin.
    steady = stbd_turn["figures"]["steady_roll_deg"]
    assert f["roll_rms_deg"] < 0.95 * steady
    assert f["roll_amplitude_deg"] < 0.95 * steady
    assert f["speed_loss_pct"] < 5.0          # paper 4.3: small speed change (5 % as in the turn)
