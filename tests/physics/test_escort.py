"""Escort (indirect towing, issue 19 item 4): the cross-flow hull form (`hull.form: crossflow`,
maneuvering._hull_crossflow) of the ASD tug, and the tug held at a drift angle in a 10 kn flow.

Truths used:
- cross-flow drag at 90 deg drift: the hand formula 0.5 rho C_D L T v^2 (Hoerner's C_D from the
  file, C_D = -Y'vv) - verification of the implementation;
- the strip integral (Hooft 1994) over the lateral plane: scipy.integrate.quad of
  0.5 rho C_D T (v + x r)|v + x r| (and x times it), split at the zero of the cross-flow
  velocity - an independent numerical reference for the exact piecewise integral; pure yaw:
  the closed form N = -0.5 rho C_D T r|r| L^4 / 32;
- the small-drift lift slope: dY/dv = q Y'v U, dN/dv = q L N'v U at v = 0 (the linear
  derivatives of the file; the cross-flow term is second order) - verification;
- symmetry and continuity over 0..180 deg drift (exact invariants of the model's form);
- a tug held at a drift angle in a 10 kn flow: the holding force equals the hull force by hand
  (thrusters off), and on a line at the bow staple with the thrusters holding the angle, the
  steady line force balances hull + thrusters and has no moment about the staple (static
  equilibrium, verification of the time-stepped model against the hand balance).
"""
import math
import os

import numpy as np
import pytest
import yaml
from scipy.integrate import quad

from tug_dynamics import maneuvering as mv
from tug_dynamics.ship_file import ShipFileError, load_ship
from tug_dynamics.vessel import ExternalWrench, ThrusterOrder, VesselState

KN = 0.514444
V10 = 10.0 * KN
SHIPS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "ros_ws", "src", "tug_dynamics", "ships")
SHIP = os.path.join(SHIPS, "asd_tug.yaml")


@pytest.fixture(scope="module")
def cfg():
    with open(SHIP) as fh:
        return yaml.safe_load(fh)


@pytest.fixture(scope="module")
def tug():
    return load_ship(SHIP)


def _hull(tug, u, v, r=0.0):
    return np.array(mv._hull_forces(tug.hp, tug.rv, tug.rf, u, v, r))


def _table_resistance(cfg, u):
    h = cfg["hull"]
    sp, fr = h["resistance"]["speed"], h["resistance"]["force"]
    a = abs(u)
    if a <= sp[0]:
        R = fr[0] * (a / sp[0]) ** 2
    elif a >= sp[-1]:
        R = fr[-1] * (a / sp[-1]) ** 2
    else:
        R = float(np.interp(a, sp, fr))
    return -math.copysign(R, u) if u != 0.0 else 0.0


def _hand_hull(cfg, u, v, r):
    """The cross-flow hull by hand: linear (lift) terms plus the strip integral by quadrature."""
    h = cfg["hull"]
    d = h["derivatives"]
    rho, L, T = cfg["water_density"], h["length"], h["draft"]
    a, b = h["crossflow"]["x_aft"], h["crossflow"]["x_fore"]
    cd = -d["Yvv"]
    q = 0.5 * rho * L * T
    pts = [-v / r] if r != 0.0 and a < -v / r < b else None
    w = lambda x: (v + x * r) * abs(v + x * r)  # noqa: E731
    i0 = quad(w, a, b, points=pts, epsabs=1e-6, epsrel=1e-11, limit=200)[0]
    i1 = quad(lambda x: x * w(x), a, b, points=pts, epsabs=1e-6, epsrel=1e-11, limit=200)[0]
    X = q * (d["Xuu"] * u * abs(u) + d["Xvr"] * v * r * L) + _table_resistance(cfg, u)
    Y = q * (d["Yv"] * abs(u) * v + d["Yr"] * u * r * L) - 0.5 * rho * cd * T * i0
    N = q * L * (d["Nv"] * u * v + d["Nr"] * abs(u) * r * L) - 0.5 * rho * cd * T * i1
    return np.array([X, Y, N])


def test_file_selects_crossflow(tug, cfg):
    assert cfg["hull"]["form"] == "crossflow"
    assert int(tug.hp[mv.H_FORM]) == mv.FORM_CROSSFLOW
    # the other ships keep their forms
    assert int(load_ship(os.path.join(SHIPS, "s175_003.yaml")).hp[mv.H_FORM]) == mv.FORM_LOWSPEED
    assert int(load_ship(os.path.join(SHIPS, "harbour_tug.yaml")).hp[mv.H_FORM]) == mv.FORM_LOWSPEED


def test_beam_flow_is_hand_crossflow_drag(tug, cfg):
    """90 deg drift at 10 kn: Y = -0.5 rho C_D L T v|v| within 1 % (here to 1e-9), X = N = 0."""
    h = cfg["hull"]
    hand = 0.5 * cfg["water_density"] * (-h["derivatives"]["Yvv"]) * h["length"] * h["draft"] * V10 ** 2
    X, Y, N = _hull(tug, 0.0, V10)
    assert Y == pytest.approx(-hand, rel=1e-9)
    assert abs(Y + hand) < 0.01 * hand
    assert X == 0.0 and abs(N) < 1e-6 * hand * h["length"]
    assert _hull(tug, 0.0, -V10)[1] == pytest.approx(hand, rel=1e-9)


def test_strip_integral_matches_quadrature(tug, cfg):
    """Combined sway, surge and yaw, including the zero of the cross-flow velocity inside the
    hull: the model's exact integral against scipy's quadrature (1e-9 relative to the size)."""
    rng = np.random.default_rng(19)
    for _ in range(40):
        u, v = rng.uniform(-6.0, 6.0, 2)
        r = rng.uniform(-0.4, 0.4)
        model = _hull(tug, u, v, r)
        hand = _hand_hull(cfg, u, v, r)
        scale = max(1.0, float(np.max(np.abs(hand[:2]))))
        assert np.abs(model[:2] - hand[:2]).max() < 1e-9 * scale
        assert abs(model[2] - hand[2]) < 1e-9 * scale * cfg["hull"]["length"]
    # tiny yaw rate beside large sway: no cancellation in the integral
    assert _hull(tug, 0.0, V10, 1e-12)[1] == pytest.approx(_hull(tug, 0.0, V10, 0.0)[1], rel=1e-12)


def test_pure_yaw_closed_form(tug, cfg):
    """u = v = 0, yaw rate r: N = -0.5 rho C_D T r|r| L^4 / 32 (plane -L/2..L/2), Y = 0."""
    h = cfg["hull"]
    r = 0.1
    X, Y, N = _hull(tug, 0.0, 0.0, r)
    hand = -0.5 * cfg["water_density"] * (-h["derivatives"]["Yvv"]) * h["draft"] * r * abs(r) * h["length"] ** 4 / 32
    assert N == pytest.approx(hand, rel=1e-12)
    assert abs(Y) < 1e-6 * abs(hand) / h["length"]


def test_small_drift_lift_slope_is_the_linear_derivative(tug, cfg):
    """dY/dv and dN/dv at v = 0, u = 10 kn: q Y'v U and q L N'v U (central difference, 1e-6)."""
    h = cfg["hull"]
    d = h["derivatives"]
    q = 0.5 * cfg["water_density"] * h["length"] * h["draft"]
    dv = 1e-7      # the cross-flow term v|v| adds C_D q dv to the difference: 2e-8 relative
    slope = (_hull(tug, V10, dv) - _hull(tug, V10, -dv)) / (2 * dv)
    assert slope[1] == pytest.approx(q * d["Yv"] * V10, rel=1e-6)
    assert slope[2] == pytest.approx(q * h["length"] * d["Nv"] * V10, rel=1e-6)


def test_symmetry_and_continuity_over_drift(tug):
    """Over 0..180 deg drift at 10 kn: X even and Y, N odd in the drift; flow from astern
    (u -> -u) keeps Y (lift opposes sway either way) and reverses the Munk moment N; no jump
    between neighbouring 0.1 deg points beyond the Lipschitz bound of the smooth terms."""
    betas = np.radians(np.arange(0.0, 180.01, 0.1))
    F = np.array([_hull(tug, V10 * math.cos(b), V10 * math.sin(b)) for b in betas])
    Fm = np.array([_hull(tug, V10 * math.cos(b), -V10 * math.sin(b)) for b in betas])
    assert np.allclose(Fm[:, 0], F[:, 0], rtol=0, atol=1e-6)
    assert np.allclose(Fm[:, 1:], -F[:, 1:], rtol=0, atol=1e-6)
    for b in np.radians([10.0, 45.0, 80.0]):
        fwd = _hull(tug, V10 * math.cos(b), V10 * math.sin(b))
        aft = _hull(tug, -V10 * math.cos(b), V10 * math.sin(b))
        assert aft[1] == pytest.approx(fwd[1], rel=1e-12)
        assert aft[2] == pytest.approx(-fwd[2], rel=1e-12)
    # continuity: the largest step of Y and N between 0.1 deg points is small against their range
    for k in (1, 2):
        steps = np.abs(np.diff(F[:, k]))
        assert steps.max() < 0.01 * np.abs(F[:, k]).max()
    # the side force peaks between 45 and 90 deg (lift sin cos + cross-flow sin^2); beam-on it is
    # the cross-flow drag alone
    # (|u| makes Y symmetric about 90 deg: the search covers 0..90)
    ib = int(np.argmax(np.abs(F[:901, 1])))
    assert 45.0 < math.degrees(betas[ib]) < 90.0


def _no_roll(path=SHIP):
    return load_ship(path, overrides={"roll": None})


def test_held_at_drift_in_10kn_flow_thrusters_off(cfg):
    """The tug held in a 10 kn current at 30 deg drift (stiff springs on position and heading,
    3 DOF), thrusters off: the mean holding force equals minus the hull force by hand within
    1 % (the hull sees the water at 30 deg, r = 0)."""
    tug = _no_roll()
    beta = math.radians(30.0)
    # current flowing from the tug's bow at 30 deg to port: the water moves along -(cos b, -sin b)
    # in body axes, i.e. the tug's velocity through the water is V (cos b, -sin b)
    tug.set_current((-V10, 0.0, 0.0))
    tug.set_state(VesselState(np.zeros(3), np.array([0.0, 0.0, beta]), np.zeros(3), np.zeros(3)))
    kx, cx, kp, cp = 2.0e6, 4.0e6, 5.0e8, 2.0e8
    dt = 0.1
    hold = []
    for i in range(900):
        s = tug.state
        f = np.array([-kx * s.position[0] - cx * _vel_world(s)[0],
                      -kx * s.position[1] - cx * _vel_world(s)[1], 0.0])
        m = np.array([0.0, 0.0, -kp * (s.rpy[2] - beta) - cp * s.angular_velocity_body[2]])
        tug.step(dt, [ExternalWrench(f, np.zeros(3), m)])
        if i >= 800:
            hold.append(np.r_[f[:2], m[2]])
    hold = np.mean(hold, axis=0)
    psi = tug.state.rpy[2]              # the yaw spring leaves the heading 0.8 deg off 30 deg
    assert abs(math.degrees(psi) - 30.0) < 1.0
    u, v = V10 * math.cos(psi), -V10 * math.sin(psi)
    hand = _hand_hull(cfg, u, v, 0.0)
    c, s_ = math.cos(psi), math.sin(psi)
    hand_world = np.array([c * hand[0] - s_ * hand[1], s_ * hand[0] + c * hand[1], hand[2]])
    assert np.linalg.norm(hold[:2] + hand_world[:2]) < 0.01 * np.linalg.norm(hand_world[:2])
    assert abs(hold[2] + hand_world[2]) < 0.01 * abs(hand_world[2])


def _vel_world(s):
    c, sn = math.cos(s.rpy[2]), math.sin(s.rpy[2])
    u, v = s.linear_velocity_body[:2]
    return np.array([c * u - sn * v, sn * u + c * v])


def test_escort_line_balances_hull_and_thrusters(cfg):
    """Indirect mode at 20 deg drift, 10 kn: the tug on a stiff line from its bow staple to a
    point running at 10 kn, both thrusters athwartships (thrust to starboard) at a fixed order.
    It settles at a drift angle; there the line force equals minus (hull by hand + thrusters from
    the status) within 1 %, and the moment of hull and thrusters about the staple vanishes
    (within 1 % of the hull's moment), with a steering force of several tens of tonnes."""
    tug = _no_roll()
    beta0 = math.radians(20.0)
    staple = tug.attachments["bow_staple"]
    order = 0.63
    tug.set_thruster_command([ThrusterOrder(k, -0.5 * math.pi, order) for k in range(2)])
    tug.settle_thrusters()
    tug.set_state(VesselState(np.zeros(3), np.array([0.0, 0.0, beta0]),
                              np.array([V10 * math.cos(beta0), -V10 * math.sin(beta0), 0.0]), np.zeros(3)),
                  thrusters=[(-0.5 * math.pi, order * tug.thruster_cfg[k]["rated_rps"]) for k in range(2)])
    k_line, c_line, length = 2.0e5, 4.0e5, 40.0
    # the ship's point: 40 m from the staple along the steady line of this drift (about 63 deg
    # off the course, towards starboard), running east at 10 kn
    e = np.array([math.cos(math.radians(-63.0)), math.sin(math.radians(-63.0))])
    p0 = np.array([math.cos(beta0), math.sin(beta0)]) * staple[0] + e * (length + 2.2)
    dt = 0.05
    prev = None
    F = np.zeros(2)
    for i in range(int(300.0 / dt)):
        s = tug.state
        c, sn = math.cos(s.rpy[2]), math.sin(s.rpy[2])
        pw = s.position[:2] + np.array([c * staple[0], sn * staple[0]])
        vw = np.zeros(2) if prev is None else (pw - prev) / dt
        prev = pw
        d = p0 + np.array([V10 * tug.time, 0.0]) - pw
        dist = np.linalg.norm(d)
        el = d / dist
        T = max(0.0, k_line * (dist - length) - c_line * float((vw - np.array([V10, 0.0])) @ el))
        F = T * el
        tug.step(dt, [ExternalWrench(np.array([F[0], F[1], 0.0]), staple.copy())])
    s = tug.state
    psi = s.rpy[2]
    assert abs(s.angular_velocity_body[2]) < 1e-5
    assert np.linalg.norm(_vel_world(s) - np.array([V10, 0.0])) < 1e-3 * V10     # moving with the ship
    u, v = s.linear_velocity_body[:2]
    drift = math.degrees(math.atan2(-v, u))
    assert 10.0 < drift < 30.0
    hull = _hand_hull(cfg, u, v, 0.0)
    st = tug.status()
    thr = np.zeros(3)
    for k, t in enumerate(st.thrusters):
        fx, fy = t.thrust * math.cos(t.azimuth), t.thrust * math.sin(t.azimuth)
        x, y = tug.thrs[k, mv.T_X], tug.thrs[k, mv.T_Y]
        thr += [fx, fy, x * fy - y * fx]
    c, sn = math.cos(psi), math.sin(psi)
    line_body = np.array([c * F[0] + sn * F[1], -sn * F[0] + c * F[1]])
    total = hull + thr
    assert np.linalg.norm(line_body + total[:2]) < 0.01 * np.linalg.norm(line_body)
    m_staple = total[2] - staple[0] * total[1]        # hull + thrusters about the staple (y_s = 0)
    assert abs(m_staple) < 0.01 * abs(hull[2] - staple[0] * hull[1])
    steering = abs(F[1]) / 9806.65
    assert 20.0 < steering < 80.0
    print(f"escort 10 kn, thruster order {order}: drift {drift:.2f} deg, steering {steering:.1f} t, "
          f"braking {F[0] / 9806.65:.1f} t")


@pytest.mark.parametrize("override,key", [
    ({"hull": {"crossflow": {"x_aft": 10.0, "x_fore": -10.0}}}, "hull.crossflow"),
    ({"hull": {"crossflow": {"x_aft": -40.0, "x_fore": 15.0}}}, "hull.crossflow"),
    ({"hull": {"derivatives": {"Yvv": 0.5}}}, "hull.derivatives.Yvv"),
    ({"hull": {"derivatives": {"Nvvr": -0.1}}}, "hull.derivatives.Nvvr"),
])
def test_bad_crossflow_keys_named(override, key):
    with pytest.raises(ShipFileError, match=key.replace(".", r"\.")):
        load_ship(SHIP, overrides=override)


def test_shallow_water_scales_the_hull_terms_and_leaves_the_plane(tug):
    """set_depth scales the hull's terms (README "Shallow water"; each factor: test_shallow_water),
    the cross-flow C_D growing (UFC 4-159-03 Eq 11), and leaves the lateral plane alone."""
    t = load_ship(SHIP)
    before = t.hp[mv.H_C0:mv.H_C0 + 9].copy()
    t.set_depth(1.5 * t.draft)
    after = t.hp[mv.H_C0:mv.H_C0 + 9]
    assert -after[6] > -before[6] > 0.0
    assert np.array_equal(after[[7, 8]], before[[7, 8]])
