"""Conservation, actuator dynamics against their analytic solutions, input checking."""
import dataclasses
import math
import os

import numpy as np
import pytest
import yaml

from tug_dynamics.maneuver_trials import run
from tug_dynamics.ship_file import ShipFileError, list_ship_files, load_ship
from tug_dynamics.vessel import (ANCHOR_LET_GO, AnchorState, Command, CommandRejected, ExternalWrench, VesselState)

DISPLACEMENT = [f for f in list_ship_files() if yaml.safe_load(open(f))["model"] == "displacement"]


def _state(u=0.0, v=0.0, r=0.0, yaw=0.0):
    return VesselState(np.zeros(3), np.array([0.0, 0.0, yaw]), np.array([u, v, 0.0]), np.array([0.0, 0.0, r]))


@pytest.mark.parametrize("path", DISPLACEMENT, ids=os.path.basename)
def test_at_rest_stays_at_rest(path):
    ship = load_ship(path)
    run(ship, 200.0, 0.5)
    s = ship.state
    assert np.all(s.position == 0.0) and np.all(s.linear_velocity_body == 0.0)
    assert np.all(s.rpy == 0.0) and np.all(s.angular_velocity_body == 0.0)


@pytest.mark.parametrize("path", DISPLACEMENT, ids=os.path.basename)
def test_coasting_rigid_body_conserves_momentum(path):
    """Hull (and with it added mass), propulsion off: a free rigid body in the plane.
    World linear momentum, angular momentum about the world origin and kinetic energy are
    constant (exact invariants of Euler's equations)."""
    with open(path) as fh:
        cfg = yaml.safe_load(fh)
    ov = {"hull": {"enabled": False}, "propellers": [], "rudders": [], "engine": None, "steering": None,
          "anchor": None, "roll": None}
    if "towline_simple" in cfg:
        ov["towline_simple"] = {"enabled": False}
    ship = load_ship(path, overrides=ov)
    L = cfg["hull"]["length"]
    u0 = 0.3 * math.sqrt(9.81 * L)
    ship.set_state(_state(u=u0, v=0.1 * u0, r=0.2 * u0 / L))
    m, xg, kzz = cfg["hull"]["mass"], cfg["hull"].get("x_g", 0.0), cfg["hull"]["yaw_radius_of_gyration"]

    def invariants():
        s = ship.state
        psi, (u, v), r = s.rpy[2], s.linear_velocity_body[:2], s.angular_velocity_body[2]
        c, sn = math.cos(psi), math.sin(psi)
        vg = np.array([u - r * 0.0, v + r * xg])                  # velocity of G, body axes
        vw = np.array([c * vg[0] - sn * vg[1], sn * vg[0] + c * vg[1]])
        pg = s.position[:2] + np.array([c * xg, sn * xg])
        p = m * vw
        h = m * (pg[0] * vw[1] - pg[1] * vw[0]) + m * kzz ** 2 * r
        e = 0.5 * m * vw @ vw + 0.5 * m * kzz ** 2 * r * r
        return np.array([*p, h, e])

    i0 = invariants()
    run(ship, 30.0 * L / u0, 0.05 * L / u0)
    i1 = invariants()
    scale = np.array([m * u0, m * u0, m * u0 * L, 0.5 * m * u0 ** 2])
    assert np.all(np.abs(i1 - i0) / scale < 1e-6), (i0, i1)


def test_coasting_straight_keeps_speed_exactly():
    ship = load_ship("s175_003.yaml", overrides={"hull": {"enabled": False}, "propellers": [], "rudders": [],
                                                 "anchor": None})
    ship.set_state(_state(u=4.0))
    run(ship, 600.0, 1.0)
    assert ship.state.linear_velocity_body[0] == pytest.approx(4.0, abs=1e-12)
    assert ship.state.position[0] == pytest.approx(2400.0, rel=1e-12)


def test_ship_moving_with_the_current_feels_no_force():
    """Drifting exactly with a uniform current: zero relative velocity, so no hydrodynamic
    force; the ground track is the current's, to round-off."""
    ship = load_ship("harbour_tug.yaml")
    ship.set_current(np.array([0.6, -0.8, 0.0]))      # the vessel node's call
    yaw = 0.7
    c, s = math.cos(yaw), math.sin(yaw)
    ship.set_state(_state(u=c * 0.6 + s * -0.8, v=-s * 0.6 + c * -0.8, yaw=yaw))
    run(ship, 600.0, 0.5)
    assert ship.state.position[:2] == pytest.approx([360.0, -480.0], abs=1e-6)
    assert ship.state.rpy[2] == pytest.approx(yaw, abs=1e-12)
    assert ship.status().speed_through_water < 1e-9


def test_ship_at_rest_in_current_is_carried_along():
    """Released at rest over ground in a current, the ship accelerates with the water: the
    speed through the water decays towards zero (quadratic damping: slowly)."""
    ship = load_ship("harbour_tug.yaml")
    ship.set_current(np.array([0.6, -0.8, 0.0]))
    stw = []
    for _ in range(6):
        run(ship, 500.0, 1.0)
        stw.append(ship.status().speed_through_water)
    assert all(b < a for a, b in zip(stw, stw[1:]))
    assert stw[-1] < 0.1


def test_engine_lag_eq9_is_first_order():
    ship = load_ship("s175_003.yaml")
    ship.set_command(Command(0.5, 0.0))
    run(ship, 20.0, 0.5)
    n_star = 0.5 * 89.0
    expected = n_star * (1.0 - math.exp(-20.0 / 15.0))     # Eq 9, T_n = 15 s
    assert ship.status().engine_rpm == pytest.approx(expected, rel=1e-4)


def test_steering_gear_eq10_rate_limit_then_lag():
    ship = load_ship("s175_003.yaml")
    ship.set_command(Command(0.0, math.radians(35.0)))
    # Eq 10: 3 deg/s while the error exceeds Te*rate = 7.5 deg (until 27.5 deg at t = 9.1667 s),
    # then delta = 35 - 7.5 exp(-(t - t1) / 2.5)
    run(ship, 5.0, 0.25)
    assert math.degrees(ship.status().steering_angle) == pytest.approx(15.0, abs=0.01)
    run(ship, 10.0, 0.25)
    expected = 35.0 - 7.5 * math.exp(-(15.0 - 27.5 / 3.0) / 2.5)
    assert math.degrees(ship.status().steering_angle) == pytest.approx(expected, abs=0.02)


def test_astern_thrust_acts_astern():
    ship = load_ship("harbour_tug.yaml")
    ship.set_command(Command(-1.0, 0.0))
    run(ship, 60.0, 0.2)
    st = ship.status()
    assert st.thrust < 0.0 and st.shaft_speed < 0.0
    assert ship.state.linear_velocity_body[0] < -1.0


def test_anchor_let_go_takes_its_time_then_dredges():
    ship = load_ship("s175_003.yaml")
    ship.set_state(_state(u=3.0), shaft_rps=0.0)
    ship.set_command(Command(0.0, 0.0, ANCHOR_LET_GO))
    run(ship, 14.0, 1.0)
    assert ship.status().anchor_state == AnchorState.LETTING_GO and ship.status().anchor_force == 0.0
    run(ship, 2.0, 1.0)
    st = ship.status()
    assert st.anchor_state == AnchorState.DREDGING
    assert st.anchor_force == pytest.approx(1.5 * 7200 * 9.80665, rel=1e-4)   # lambda_a W_a g, Eq 5-6


def test_nan_command_rejected_and_held_command_kept():
    ship = load_ship("harbour_tug.yaml")
    ship.set_command(Command(0.4, 0.1))
    for bad in (Command(float("nan"), 0.0), Command(0.2, float("inf"))):
        with pytest.raises(CommandRejected):
            ship.set_command(bad)
        assert ship.command.engine_order == 0.4 and ship.command.steering_angle == 0.1


def test_out_of_range_command_clamped_with_message():
    ship = load_ship("harbour_tug.yaml")
    msgs = ship.set_command(Command(1.7, math.radians(60.0)))
    assert len(msgs) == 2 and "engine_order" in msgs[0] and "steering_angle" in msgs[1]
    assert ship.command.engine_order == 1.0
    assert ship.command.steering_angle == pytest.approx(math.radians(35.0))
    assert ship.set_command(Command(-0.5, -0.2)) == []


def test_bad_ship_file_key_is_named(tmp_path):
    src = os.path.join(os.path.dirname(list_ship_files()[0]), "harbour_tug.yaml")
    cfg = yaml.safe_load(open(src))
    cfg["hull"]["derivatives"]["Yvv_typo"] = -0.8
    p = tmp_path / "bad.yaml"
    p.write_text(yaml.safe_dump(cfg))
    with pytest.raises(ShipFileError, match=r"bad\.yaml.*hull\.derivatives\.Yvv_typo"):
        load_ship(str(p))
    del cfg["hull"]["derivatives"]["Yvv_typo"]
    cfg["propellers"][1]["diameter"] = "big"
    p.write_text(yaml.safe_dump(cfg))
    with pytest.raises(ShipFileError, match=r"bad\.yaml.*propellers\.1\.diameter"):
        load_ship(str(p))
    cfg["propellers"][1]["diameter"] = 2.0
    del cfg["hull"]["mass"]
    p.write_text(yaml.safe_dump(cfg))
    with pytest.raises(ShipFileError, match=r"bad\.yaml.*hull\.mass.*missing"):
        load_ship(str(p))
    cfg["model"] = "hovercraft"
    p.write_text(yaml.safe_dump(cfg))
    with pytest.raises(ShipFileError, match=r"bad\.yaml.*'model'"):
        load_ship(str(p))


@pytest.mark.parametrize("path", DISPLACEMENT, ids=os.path.basename)
def test_every_ship_file_lists_sources_and_estimates(path):
    cfg = yaml.safe_load(open(path))
    assert cfg.get("sources") and isinstance(cfg.get("estimated"), dict) and cfg["estimated"]
    load_ship(path)   # also checks every estimated key exists


def test_wrench_world_frame_at_point():
    """A pure world-frame force through the origin on a hull-less ship: a = F/m, no rotation."""
    ship = load_ship("box_barge_000.yaml", overrides={"hull": {"enabled": False}})
    m = ship.mass_matrix[0, 0]
    ship.set_state(_state(yaw=math.radians(30.0)))
    w = [ExternalWrench(np.array([0.0, 1000.0, 0.0]), np.zeros(3))]
    run(ship, 10.0, 0.1, wrenches=lambda v, t: w)
    assert ship.state.position[1] == pytest.approx(0.5 * 1000.0 / m * 100.0, rel=1e-9)
    assert ship.state.position[0] == pytest.approx(0.0, abs=1e-9)
    assert ship.state.angular_velocity_body[2] == pytest.approx(0.0, abs=1e-12)


def test_rk4_substeps_match_scipy_reference():
    """The fixed-step RK4 of the ship files' max_substep against scipy's DOP853 at tight
    tolerance on the same equations (S-175 hard-over turn, 600 s)."""
    from scipy.integrate import solve_ivp
    from tug_dynamics import maneuvering as mv
    ship = load_ship("s175_003.yaml")
    ship.set_state(_state(u=4.5), shaft_rps=0.5 * 89 / 60)
    ship.set_command(Command(0.5, math.radians(35.0)))
    s0 = ship.s.copy()
    args = (ship.hp, ship.props, ship.ruds, ship.rv, ship.rf, ship.minv, ship.ctrl.copy(),
            np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(mv.NOUT))
    ref = solve_ivp(lambda t, y: mv._deriv(y, *args), (0.0, 600.0), s0, method="DOP853",
                    rtol=1e-10, atol=1e-8)
    run(ship, 600.0, 1.0)
    L = 175.0
    assert np.hypot(*(ship.s[:2] - ref.y[:2, -1])) < 1e-3 * L
    assert ship.s[mv.S_R] == pytest.approx(ref.y[mv.S_R, -1], rel=1e-4)


def test_planing_model_dispatch_is_lazy(tmp_path, monkeypatch):
    """model: planing_6dof goes to tug_dynamics.planing.PlaningHull.from_config(cfg, source, name, state)."""
    import sys
    import types
    calls = []

    class Stub:
        @staticmethod
        def from_config(cfg, source, name, initial_state):
            calls.append((cfg["model"], source, name, initial_state))
            return "stub"

    mod = types.ModuleType("tug_dynamics.planing")
    mod.PlaningHull = Stub
    monkeypatch.setitem(sys.modules, "tug_dynamics.planing", mod)
    p = tmp_path / "boat.yaml"
    p.write_text("model: planing_6dof\nname: boat\n")
    st = VesselState.at_rest()
    assert load_ship(str(p), name="b1", initial_state=st) == "stub"
    assert calls == [("planing_6dof", str(p), "b1", st)]


def test_rudder_force_continuous_as_engine_stops():
    """Engine stopping (n -> 0+) while making way: the rudder keeps the wake flow, so the yaw
    acceleration from 20 deg of rudder is continuous in n at n = 0."""
    from tug_dynamics import maneuvering as mv
    ship = load_ship("s175_003.yaml")
    rdot = []
    for n in (0.0, 1e-4, 1e-2):
        ship.set_state(_state(u=3.0), shaft_rps=n, rudder=math.radians(20.0))
        d = mv._deriv(ship.s.copy(), ship.hp, ship.props, ship.ruds, ship.rv, ship.rf, ship.minv, ship.ctrl,
                      np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(mv.NOUT))
        rdot.append(d[mv.S_R])
    assert rdot[0] > 0.0
    assert rdot[1] == pytest.approx(rdot[0], rel=1e-3)
    assert rdot[2] == pytest.approx(rdot[0], rel=0.05)


def _vessel_status_fields():
    """(name, type) of the fields of tug_msgs/VesselStatus, read from its .msg file (no ROS)."""
    msg = os.path.join(os.path.dirname(__file__), "..", "..", "ros_ws", "src", "tug_msgs", "msg", "VesselStatus.msg")
    fields = []
    for line in open(msg):
        words = line.split("#")[0].split()
        if len(words) == 2 and "=" not in line:
            fields.append((words[1], words[0]))
    return fields


@pytest.mark.parametrize("path", list_ship_files(), ids=os.path.basename)
def test_every_model_states_every_status_field_the_message_carries(path):
    """The node fills tug_msgs/VesselStatus from status(): each model's record must hold every
    physical field of the message (the float fields the encoder writes, the anchor state and the
    girting warning) with a real value, never a default filled in by the node."""
    from sim_plumbing.cdr import (VESSEL_STATUS_FLOATS_A, VESSEL_STATUS_FLOATS_B, VESSEL_STATUS_FLOATS_ENV,
                                  VESSEL_STATUS_FLOATS_SEA)
    from tug_dynamics.environment_loads import EnvironmentStatus
    from tug_dynamics.seakeeping import SeaStatus
    ship = load_ship(path)
    ship.set_command(Command(0.5, math.radians(10.0)))
    run(ship, 5.0, 0.05)
    st = ship.status()
    node_filled = {"header", "step", "vessel", "commands_rejected", "commands_clamped",  # the node's own
                   "contact_names", "contact_forces", "contact_points"}   # and the hull contacts it takes
    # the environment block comes from the vessel's coupling to its environment, for every model alike
    environment = {f.name for f in dataclasses.fields(EnvironmentStatus)}
    assert environment == set(VESSEL_STATUS_FLOATS_ENV) | {"grounded"}
    node_filled |= environment
    # and the sea block from its response to the waves (tug_dynamics.seakeeping)
    sea = {f.name for f in dataclasses.fields(SeaStatus)}
    assert sea == set(VESSEL_STATUS_FLOATS_SEA)
    node_filled |= sea
    for name, kind in _vessel_status_fields():
        if name in node_filled:
            continue
        value = getattr(st, name)  # AttributeError names a field the model does not state
        if kind == "float64":
            assert isinstance(value, float) and math.isfinite(value), (name, value)
        elif kind == "bool":
            assert isinstance(value, bool), (name, value)
        else:
            assert isinstance(value, AnchorState), (name, value)
    assert set(VESSEL_STATUS_FLOATS_A + VESSEL_STATUS_FLOATS_B + VESSEL_STATUS_FLOATS_ENV + VESSEL_STATUS_FLOATS_SEA) == \
        {n for n, kind in _vessel_status_fields() if kind == "float64"}
    with pytest.raises(TypeError):
        st["heel"]  # a record, read by attribute: no lookup by a string that could be misspelt
