"""ASD tug (asd_tug.yaml): azimuth thrusters in the displacement model.

Truths used:
- bollard pull: the thruster model evaluated by hand here from the ship file's numbers
  (sum over units of (1 - t(azimuth)) x ABS interaction ratio x rho n^2 D^4 K_T(0)), and the
  file's documented figures (ahead and astern published, Marine Log 2017; sideways the model's
  own figure, stated in the file's header). The rated rpm and the 180 deg deduction were set for
  the published ahead and astern pulls (the file's `estimated:`), so those two comparisons are
  calibration checks; the hand evaluation and the sideways figure are verification.
- crabbing: in a steady state the summed thruster force balances the hull's forces, computed
  here by hand from the file's low-speed derivatives and resistance table at the velocity the
  model reached (heading held by a pure yaw moment, so r = 0 and no Coriolis terms).
- actuator laws: the azimuth moves at the slew rate, the shortest way round; the rpm follows the
  first-order lag n(t) = n* (1 - exp(-t / T_n)).
"""
import math
import os

import numpy as np
import pytest
import yaml

from tug_dynamics import maneuvering as mv
from tug_dynamics.ship_file import ShipFileError, load_ship
from tug_dynamics.vessel import Command, CommandRejected, ExternalWrench, ThrusterOrder

G = 9.80665
DOCUMENTED_T = {"ahead": 57.56, "astern": 53.87, "sideways": 40.6}   # asd_tug.yaml header
SHIP = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "ros_ws", "src", "tug_dynamics", "ships",
                    "asd_tug.yaml")


@pytest.fixture(scope="module")
def cfg():
    with open(SHIP) as fh:
        return yaml.safe_load(fh)


def _deduction(th, az_deg):
    """The file's t(azimuth) table, periodic linear interpolation (by hand)."""
    a = list(th["thrust_deduction"]["azimuth_deg"])
    v = list(th["thrust_deduction"]["value"])
    return float(np.interp(az_deg, a + [a[0] + 360.0], v + [v[0]], period=360.0))


def _abs_ratio(x_over_d, phi_deg):
    """ABS (2013) DP guide, App. 1: thrust ratio of a unit in another's jet."""
    t = 1.0 - 0.75 ** (x_over_d ** (2.0 / 3.0))
    return t + (1.0 - t) * phi_deg ** 3 / (130.0 / t ** 3 + phi_deg ** 3)


def _held(tug, duration=60.0, dt=0.1):
    """Hold the tug at the origin, heading 0, with stiff springs (surge, sway, yaw) at its
    reference point; returns the mean holding force over the last 10 s in body axes (x, and y
    of the heeled body: the sideways pull heels the tug about 6 deg, and the model's thrust
    acts in its heeled body frame, 4 DOF)."""
    # the holding wrench is held over each step (explicit): gains keep |lambda dt| < 0.6
    kx, cx = 2.0e6, 4.0e6
    kpsi, cpsi = 5.0e8, 2.0e8
    forces = []

    def wrench():
        s = tug.state
        f = np.array([-kx * s.position[0] - cx * s.linear_velocity_body[0],
                      -kx * s.position[1] - cx * s.linear_velocity_body[1], 0.0])
        m = np.array([0.0, 0.0, -kpsi * s.rpy[2] - cpsi * s.angular_velocity_body[2]])
        return [ExternalWrench(f, np.zeros(3), m)]

    n = int(round(duration / dt))
    for i in range(n):
        w = wrench()
        tug.step(dt, w)
        if i >= n - int(10.0 / dt):
            f = w[0].force_world
            psi, phi = tug.state.rpy[2], tug.state.rpy[0]
            fx = math.cos(psi) * f[0] + math.sin(psi) * f[1]
            fy = -math.sin(psi) * f[0] + math.cos(psi) * f[1]
            forces.append([fx, math.cos(phi) * fy])
    return np.mean(forces, axis=0)


def _hand_bollard(cfg, azimuth_deg):
    """Summed thruster force (N, body x, y) at rest, both units at rated rpm and one azimuth,
    by hand from the file: open-water K_T(0), t(azimuth), and the ABS ratio of a unit lying in
    the other's jet (azimuth +-90 deg: in line)."""
    rho = cfg["water_density"]
    total = np.zeros(2)
    units = cfg["thrusters"]
    a = math.radians(azimuth_deg)
    e = np.array([math.cos(a), math.sin(a)])
    for k, th in enumerate(units):
        n = th["rated_rpm"] / 60.0
        T0 = rho * n * n * th["diameter"] ** 4 * th["kt"][0]
        f = 1.0 - _deduction(th, azimuth_deg)
        for i, other in enumerate(units):
            if i == k:
                continue
            d = np.array(th["position"][:2]) - np.array(other["position"][:2])
            jet = -e
            phi = math.degrees(math.acos(np.clip(d @ jet / np.linalg.norm(d), -1.0, 1.0)))
            f *= _abs_ratio(np.linalg.norm(d) / other["diameter"], phi)
        total += f * T0 * e
    return total


@pytest.mark.parametrize("case,azimuth_deg", [("ahead", 0.0), ("astern", 180.0), ("sideways", 90.0)])
def test_bollard_pull(cfg, case, azimuth_deg):
    """Held at rest with both thrusters at rated rpm: the holding force equals the thruster
    model by hand (1e-3) and the documented figure (1 %; ahead / astern calibration, sideways
    the file's stated model figure)."""
    tug = load_ship(SHIP)
    msgs = tug.set_thruster_command([ThrusterOrder(0, math.radians(azimuth_deg), 1.0),
                                     ThrusterOrder("starboard", math.radians(azimuth_deg), 1.0)])
    assert msgs == []
    hold = _held(tug)
    thrust = -hold
    hand = _hand_bollard(cfg, azimuth_deg)
    assert np.linalg.norm(thrust - hand) < 1e-3 * np.linalg.norm(hand)
    st = tug.status()
    assert sum(u.thrust for u in st.thrusters) == pytest.approx(np.linalg.norm(hand), rel=1e-3)
    assert np.linalg.norm(thrust) / (1000.0 * G) == pytest.approx(DOCUMENTED_T[case], rel=0.01)


def test_engine_order_maps_onto_thrusters():
    """Command on an ASD tug: both units at |engine_order|, azimuth -steering ahead and
    pi + steering astern; positive steering gives a positive (port) yaw moment either way."""
    tug = load_ship(SHIP)
    tug.settle_command(Command(0.5, 0.3))
    assert tug.thruster_orders == [pytest.approx((-0.3, 0.5))] * 2
    d = mv._deriv_t(tug.s.copy(), tug.hp, tug.props, tug.ruds, tug.thrs, tug.rv, tug.rf, tug.minv, tug.ctrl,
                    np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3)), tug.out)
    assert d[mv.S_R] > 0.0
    tug.settle_command(Command(-0.5, 0.3))
    assert tug.thruster_orders[0] == pytest.approx((math.pi + 0.3 - 2 * math.pi, 0.5))
    d = mv._deriv_t(tug.s.copy(), tug.hp, tug.props, tug.ruds, tug.thrs, tug.rv, tug.rf, tug.minv, tug.ctrl,
                    np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3)), tug.out)
    assert d[mv.S_R] > 0.0
    assert tug.status().steering_angle == pytest.approx(0.3, abs=1e-12)


def _hull_force_by_hand(cfg, u, v):
    """X_H, Y_H of the file's low-speed hull (S. D. Yoon Eq 3 as the README writes it) at r = 0:
    X = q X'uu u|u| - R(u) (resistance table, linear inside, quadratic beyond), Y = q (Y'v |u| v
    + Y'vv v|v|), q = 0.5 rho L T."""
    h = cfg["hull"]
    d = h["derivatives"]
    q = 0.5 * cfg["water_density"] * h["length"] * h["draft"]
    sp, fr = h["resistance"]["speed"], h["resistance"]["force"]
    a = abs(u)
    if a <= sp[0]:
        R = fr[0] * (a / sp[0]) ** 2
    elif a >= sp[-1]:
        R = fr[-1] * (a / sp[-1]) ** 2
    else:
        R = float(np.interp(a, sp, fr))
    X = q * d["Xuu"] * u * abs(u) - math.copysign(R, u)
    Y = q * (d["Yv"] * abs(u) * v + d["Yvv"] * v * abs(v))
    return np.array([X, Y])


@pytest.mark.parametrize("azimuth_deg", [0.0, 45.0, 90.0])
def test_crabbing_force_balance(cfg, azimuth_deg):
    """Both units at full rpm and one azimuth, heading held by a pure yaw moment: the steady
    summed thruster force (status: delivered thrust along each azimuth) balances the hull's
    forces computed by hand at the reached velocity, within 5 %."""
    tug = load_ship(SHIP)
    a = math.radians(azimuth_deg)
    tug.settle_command(Command(0.0, 0.0))
    tug.set_thruster_command([ThrusterOrder(k, a, 1.0) for k in range(2)])
    tug.settle_thrusters()
    kpsi, cpsi = 5.0e7, 5.0e7      # heading holder (explicit over each step: |lambda dt| < 0.2)
    dt = 0.2
    v_prev = None
    for i in range(int(400.0 / dt)):
        s = tug.state
        m = np.array([0.0, 0.0, -kpsi * s.rpy[2] - cpsi * s.angular_velocity_body[2]])
        tug.step(dt, [ExternalWrench(np.zeros(3), np.zeros(3), m)])
        if i == int(390.0 / dt):
            v_prev = tug.state.linear_velocity_body[:2].copy()
    u, v = tug.state.linear_velocity_body[:2]
    assert np.linalg.norm(np.array([u, v]) - v_prev) < 1e-3       # steady
    assert abs(tug.state.angular_velocity_body[2]) < 1e-6
    st = tug.status()
    thrust = sum(np.array([math.cos(t.azimuth), math.sin(t.azimuth)]) * t.thrust for t in st.thrusters)
    hull = _hull_force_by_hand(cfg, u, v)
    # the direction of motion follows the thrust's side
    assert math.hypot(u, v) > 1.0
    assert np.linalg.norm(thrust + hull) < 0.05 * np.linalg.norm(thrust)


def test_azimuth_slew_rate_shortest_way_and_rpm_lag(cfg):
    """From 0 deg ordered to 170 deg (port way) and then to -170 deg (through 180, 20 deg the
    short way); rpm from 0 to full: n(t) = n* (1 - exp(-t / T_n)) (first-order lag, RK4 1e-4)."""
    th = cfg["thrusters"][0]
    rate = math.radians(th["slew_rate_deg_s"])
    tug = load_ship(SHIP)
    tug.set_thruster_command([ThrusterOrder(0, math.radians(170.0), 1.0)])
    dt = 0.05
    az = [0.0]
    for _ in range(int(5.0 / dt)):
        tug.step(dt)
        az.append(tug.status().thrusters[0].azimuth)
    steps = np.diff(az)
    assert np.max(np.abs(steps)) <= rate * dt * (1 + 1e-9)
    assert az[-1] == pytest.approx(rate * 5.0, rel=1e-9)          # still slewing at the limit, port way
    n_star = th["rated_rpm"]
    assert tug.status().thrusters[0].rpm == pytest.approx(n_star * (1.0 - math.exp(-5.0 / th["time_constant"])),
                                                          rel=1e-4)
    assert tug.status().thrusters[1].rpm == 0.0                  # not ordered
    for _ in range(int(20.0 / dt)):
        tug.step(dt)
    assert tug.status().thrusters[0].azimuth == pytest.approx(math.radians(170.0), abs=1e-6)
    tug.set_thruster_command([ThrusterOrder("port", math.radians(-170.0), 1.0)])
    prev = tug.status().thrusters[0].azimuth
    for _ in range(int(0.5 / dt)):
        tug.step(dt)
        now = tug.status().thrusters[0].azimuth
        step = (now - prev + math.pi) % (2 * math.pi) - math.pi
        assert 0.0 < step <= rate * dt * (1 + 1e-9)              # the short way: through 180 deg
        prev = now
    for _ in range(int(10.0 / dt)):
        tug.step(dt)
    assert tug.status().thrusters[0].azimuth == pytest.approx(math.radians(-170.0), abs=1e-6)


def test_bad_thruster_orders_rejected_or_clamped():
    tug = load_ship(SHIP)
    assert tug.set_thruster_command([ThrusterOrder(0, 0.5, 0.7), ThrusterOrder(1, -0.5, 0.6)]) == []
    held = tug.thruster_orders
    for bad, words in (([ThrusterOrder(0, math.nan, 0.5)], ("thruster 0 (port)", "azimuth")),
                       ([ThrusterOrder(1, 0.0, math.inf)], ("thruster 1 (starboard)", "rpm")),
                       ([ThrusterOrder(0, 0.0, 0.5), ThrusterOrder(2, 0.0, 0.5)], ("thruster 2", "does not exist")),
                       ([ThrusterOrder("bow", 0.0, 0.5)], ("'bow'", "does not exist")),
                       ([ThrusterOrder(0, 0.0, 0.5), ThrusterOrder("port", 0.1, 0.5)], ("thruster 0 (port)", "twice"))):
        with pytest.raises(CommandRejected) as exc:
            tug.set_thruster_command(bad)
        assert all(w in str(exc.value) for w in words), str(exc.value)
        assert tug.thruster_orders == held                      # the last valid orders are kept
    msgs = tug.set_thruster_command([ThrusterOrder("starboard", 0.2, 1.5), ThrusterOrder(0, 0.1, -0.3)])
    assert len(msgs) == 2
    assert "thruster 1 (starboard) rpm 1.5 clamped to 1" in msgs[0]
    assert "thruster 0 (port) rpm -0.3 clamped to 0" in msgs[1]      # not reversible: 0..1
    assert tug.thruster_orders == [pytest.approx((0.1, 0.0)), pytest.approx((0.2, 1.0))]
    # a 360 deg unit takes any azimuth, wrapped
    assert tug.set_thruster_command([ThrusterOrder(0, 3 * math.pi / 2, 0.5)]) == []
    assert tug.thruster_orders[0] == pytest.approx((-math.pi / 2, 0.5))
    # a unit with a limited range clamps, naming it
    lim = load_ship(SHIP, overrides={"thrusters": [
        dict(yaml.safe_load(open(SHIP))["thrusters"][0], full_360=False, azimuth_range_deg=[-45.0, 45.0])]})
    msgs = lim.set_thruster_command([ThrusterOrder(0, 1.0, 0.5)])
    assert len(msgs) == 1 and "thruster 0 (port) azimuth 1 rad clamped to 0.785398" in msgs[0]
    # a ship without thrusters refuses thruster orders
    with pytest.raises(CommandRejected, match="no azimuth thrusters"):
        load_ship("harbour_tug.yaml").set_thruster_command([ThrusterOrder(0, 0.0, 0.5)])


@pytest.mark.parametrize("override,key", [
    ({"kt": None}, "thrusters.0.kt"),
    ({"thrust_deduction": {"azimuth_deg": [0.0, 0.0], "value": [0.1, 0.1]}},
     "thrusters.0.thrust_deduction.azimuth_deg"),
    ({"full_360": False}, "thrusters.0.azimuth_range_deg"),
    ({"slew_rate_deg_s": "fast"}, "thrusters.0.slew_rate_deg_s"),
    ({"time_constant": 0.01}, "thrusters.0.time_constant"),
    ({"name": "starboard"}, "thrusters.1.name"),   # the second of the two is named
])
def test_ship_file_errors_name_the_key(cfg, override, key):
    th = dict(cfg["thrusters"][0], **override)
    with pytest.raises(ShipFileError) as exc:
        load_ship(SHIP, overrides={"thrusters": [th, cfg["thrusters"][1]]})
    assert "asd_tug.yaml" in str(exc.value) and f"key '{key}'" in str(exc.value), str(exc.value)


def test_open_water_points_are_fitted(cfg):
    """open_water: K_T points of the file's own quadratic give back the same thrusts."""
    c = cfg["thrusters"][0]["kt"]
    J = [0.0, 0.2, 0.4, 0.6, 0.8]
    ow = {"J": J, "KT": [c[0] + c[1] * j + c[2] * j * j for j in J]}
    ths = [{k: v for k, v in th.items() if k != "kt"} | {"open_water": ow} for th in cfg["thrusters"]]
    tug = load_ship(SHIP, overrides={"thrusters": ths})
    ref = load_ship(SHIP)
    assert np.allclose(tug.thrs, ref.thrs, rtol=0, atol=1e-12)
