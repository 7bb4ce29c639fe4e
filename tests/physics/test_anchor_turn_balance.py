"""Issue 36: the S-175 of S. D. Yoon ("A Study on the Control of Ship Maneuvering by the Simulation
of Anchor Dredging") turning with its bow anchor dredging, checked term by term.

In a steady turn every derivative of the state is zero, so the surge force terms the model sums
(Vessel.force_terms) must cancel: propeller + hull + rudder + anchor + the centripetal term
(m + m_y) v r of Eq 1 (moved to the right-hand side) = 0. Each term the test can write from the
paper is computed here by hand from the recorded state (u, v, r, n) and the ship file's printed
particulars, not taken from the model: the anchor (Eq 5 as read in the package README, "Anchor
readings (issue 36)"), the hull (Eq 3, X'uu and X'vr), the propeller (Eq 4 with Eq 8's wake) and
the centripetal term (Eq 1, Table 2's m_y / m). The rudder (Eq 7-8) is the one term taken from
the model; the balance then checks it too.
"""
import math

import numpy as np
import pytest

from tug_dynamics.maneuver_trials import KN, run
from tug_dynamics.ship_file import load_ship
from tug_dynamics.vessel import ANCHOR_LET_GO, Command, VesselState

RATED = 89.0
HALF, SLOW = 44.5 / RATED, 29.69 / RATED      # Table 1: half ahead 44.5 rpm, slow ahead 29.69 rpm
HARD = math.radians(35.0)

# seed 003 Table 1-2 and the ship file s175_003.yaml (its printed particulars)
RHO, L, D_DRAFT = 1025.0, 175.0, 8.5
MASS = 21648428.0                      # rho L B d Cb
MY_OVER_M = 0.721
XUU, XVR = -0.00957, -0.0663
LAMBDA_A, W_A, L_A = 1.5, 70608.0, 175.0      # Table 2: lambda_a, W_a g (7200 kg x g, the file's N), l_a
PROP_D, C1, C2, C3, WP0, T_DED, X_P = 6.533, 0.5277, -0.4264, -0.115, 0.26, 0.20, -92.05


def _ship(u_kn, order):
    s = load_ship("s175_003.yaml")
    s.set_state(VesselState(np.zeros(3), np.zeros(3), np.array([u_kn * KN, 0, 0.0]), np.zeros(3)),
                shaft_rps=order * RATED / 60.0)
    return s


def _anchor_by_hand(u, v, turning):
    """Eq 5 (turning) / Eq 6 (straight) as the README reads them: X_A = -lambda_a W_a,
    Y_A = X_A v/u (resists the sway), N_A = lambda_a W_a l_a with the turn (port here: +)."""
    xa = -LAMBDA_A * W_A
    return (xa, xa * v / u, LAMBDA_A * W_A * L_A) if turning else (xa, 0.0, 0.0)


def _hull_x_by_hand(u, v, r):
    """Eq 3 (README reading 2): X_H = 0.5 rho L d (X'uu u|u| + X'vr v r L)."""
    return 0.5 * RHO * L * D_DRAFT * (XUU * u * abs(u) + XVR * v * r * L)


def _propeller_x_by_hand(u, v, r, n):
    """Eq 4 with Eq 8's wake: (1 - t) rho n^2 D^4 K_T(J), J = u (1 - w_P) / (n D),
    w_P = w_P0 exp(-4 beta_P^2), beta_P the flow angle at the propeller (x_P = -0.526 L)."""
    beta_p = math.atan2(v + X_P * r, u)
    wake = WP0 * math.exp(-4.0 * beta_p ** 2)
    j = u * (1.0 - wake) / (n * PROP_D)
    return (1.0 - T_DED) * RHO * n * n * PROP_D ** 4 * (C1 + C2 * j + C3 * j * j)


def _surge_balance(s):
    """The recorded surge terms and the hand-computed ones at the vessel's present state."""
    st = s.state
    u, v = st.linear_velocity_body[0], st.linear_velocity_body[1]
    r = st.angular_velocity_body[2]
    n = s.status().engine_rpm / 60.0
    terms = s.force_terms()
    hand = {"anchor": _anchor_by_hand(u, v, abs(r) > 1e-6)[0], "hull": _hull_x_by_hand(u, v, r),
            "propeller": _propeller_x_by_hand(u, v, r, n), "coriolis": (1.0 + MY_OVER_M) * MASS * v * r}
    return terms, hand, (u, v, r)


@pytest.fixture(scope="module")
def anchor_turn():
    """Scenario 3: 35 deg to port from half ahead, anchor let go 30 s after the helm order; 2400 s
    (the turn settles within ~900 s)."""
    s = _ship(8.75, HALF)
    tr = run(s, 2400.0, 1.0, {0.0: Command(HALF, HARD), 30.0: Command(HALF, HARD, ANCHOR_LET_GO)})
    return s, tr


def test_steady_anchor_turn_surge_terms_cancel(anchor_turn):
    s, tr = anchor_turn
    assert np.ptp(tr.u[-100:]) < 1e-6 and np.ptp(tr.r[-100:]) < 1e-8        # steady
    terms, hand, (u, v, r) = _surge_balance(s)
    assert r > 0.0 and v < 0.0              # turning to port, sliding outward (to starboard)
    for name, value in hand.items():
        assert terms[name][0] == pytest.approx(value, rel=1e-6), name
    # the rudder's surge force (Eq 7) is the model's; with the hand-written terms the steady
    # surge balance must close to 1 % of the propeller's thrust
    total = sum(hand.values()) + terms["rudder"][0]
    assert abs(total) < 0.01 * hand["propeller"]
    # nothing else acts on this ship
    for name in ("thruster", "towline", "external"):
        assert terms[name] == (0.0, 0.0, 0.0), name


def test_steady_anchor_turn_anchor_term_is_eq5(anchor_turn):
    """The anchor's three terms at the recorded state are Eq 5 as read (README, issue 36), and the
    status anchor_force is its surge part, lambda_a W_a g."""
    s, _ = anchor_turn
    st = s.state
    u, v = st.linear_velocity_body[0], st.linear_velocity_body[1]
    want = _anchor_by_hand(u, v, turning=True)
    assert s.force_terms()["anchor"] == pytest.approx(want, rel=1e-9)
    assert want[1] > 0.0                    # a resistance to the outward slide: toward the centre
    assert s.status().anchor_force == pytest.approx(LAMBDA_A * W_A, rel=1e-9)


def test_steady_anchor_turn_sway_and_yaw_terms_cancel(anchor_turn):
    """The same steady state in sway and yaw: every term recorded, their sums zero (to 1 % of the
    largest term)."""
    s, _ = anchor_turn
    terms = s.force_terms()
    for axis in (1, 2):
        values = [t[axis] for t in terms.values()]
        assert abs(sum(values)) < 0.01 * max(abs(x) for x in values), axis


def test_straight_dredging_surge_terms_cancel():
    """Scenario 1 (Eq 6): straight at slow ahead with the anchor dredging; the steady surge
    balance propeller + hull + anchor = 0, no sway force or moment from the anchor."""
    s = _ship(5.84, SLOW)
    tr = run(s, 4000.0, 2.0, {0.0: Command(SLOW, 0.0, ANCHOR_LET_GO)})
    assert np.ptp(tr.u[-50:]) < 1e-5          # steady: (m + m_x) du/dt < 3 N
    terms, hand, (u, v, r) = _surge_balance(s)
    assert v == 0.0 and r == 0.0
    assert terms["anchor"] == pytest.approx(_anchor_by_hand(u, v, turning=False), rel=1e-9)
    for name in ("anchor", "hull", "propeller"):
        assert terms[name][0] == pytest.approx(hand[name], rel=1e-6), name
    assert abs(hand["anchor"] + hand["hull"] + hand["propeller"]) < 0.01 * hand["propeller"]


@pytest.mark.parametrize("v", [-0.3, 0.3])
def test_eq5_lateral_term_resists_the_sway_either_way(v):
    """Y_A = X_A v/u (the text): whichever way the ship slides while it turns to port toward the
    port anchor, the anchor's lateral force opposes the slide; the moment stays with the turn."""
    from tug_dynamics import maneuvering as mv
    s = load_ship("s175_003.yaml")
    ctrl = s.ctrl.copy()
    ctrl[mv.C_ANC_F], ctrl[mv.C_ANC_SIDE] = 1.0, 1.0        # dredging, port anchor
    u, r = 2.0, 0.01                                        # r' = 0.875: fully Eq 5
    xa, ya, na = mv._anchor_dredging(s.hp, ctrl, u, v, r)
    assert (xa, ya, na) == pytest.approx(_anchor_by_hand(u, v, turning=True), rel=1e-12)
    assert ya * v < 0.0 and na > 0.0
