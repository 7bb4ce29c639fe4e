"""S-175 of seed 003: straight speeds at the Table 1 engine orders, the 35 deg turn and the
four anchor scenarios of section 3-2 (directions the paper argues)."""
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
        out[case] = turning_metrics(run(s, 1500.0, 1.0, ev))
    return out


def test_hard_over_turn_from_9_knots(turns):
    m = turns["normal"]
    assert m["steady_yaw_rate"] > 0.0                       # positive steering turns to port
    # plausibility band of a 35 deg turn for a container ship: advance and tactical diameter 2-5 L
    for k in ("advance", "tactical_diameter"):
        assert 2.0 * 175 < m[k] < 5.0 * 175
    assert m["steady_diameter"] == pytest.approx(2 * m["steady_speed"] / m["steady_yaw_rate"])


def test_anchor_tightens_the_turn(turns):
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
    assert res[True][0] < 0.8 * res[False][0] and res[True][1] < res[False][1]
    assert res[False][0] / KN == pytest.approx(6.0, rel=0.05)


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
    assert reach[True] < 0.6 * reach[False]
