"""PlaningHull (Yoon & Kang) unit physics: rest, hydrostatics, steady runs, commands, config errors.

Truths used: analytic hydrostatics of the ship file's displacement law V(d) = V0 (d/d0)^2, the
paper's Table 5 lift polynomial (evaluated here independently of the model code), and
sign/direction physics. The paper's Table 2 trims at 17.5-35 kn are a calibration (M_w was fitted
to them), not an independent check. Never the model's own earlier output.
"""
import copy
import math
import os

import numpy as np
import pytest
import yaml

from tug_dynamics import planing
from tug_dynamics.vessel import Command, CommandRejected, ExternalWrench, VesselState

KNOT = 1852.0 / 3600.0
SHIP = os.path.join(os.path.dirname(__file__), "..", "..", "ros_ws", "src", "tug_dynamics", "ships",
                    "planing_40ft.yaml")
RHO, G, MASS, D0 = 1025.0, 9.81, 18900.0, 0.9
W = MASS * G
TABLE2_TRIM = [(15, 5.25), (20, 6.14), (25, 5.93), (30, 5.25), (35, 4.55), (40, 3.95)]
TABLE5_CL = [-2.05e-3, 2.10e-2, -1.71e-3, 4.75e-5, -4.31e-7]
B_LIFT = 4.52  # Eq 14's B-bar as in the ship file (Table 1 beam)


@pytest.fixture(scope="module")
def cfg():
    with open(SHIP, encoding="utf-8") as fh:
        return yaml.safe_load(fh)


def make(cfg, **kw):
    return planing.PlaningHull.from_config(copy.deepcopy(cfg), SHIP, **kw)


def run(m, seconds, dt=0.05, wrenches=()):
    for _ in range(int(round(seconds / dt))):
        m.step(dt, wrenches)


# ---------------------------------------------------------------- rest and hydrostatics
def test_at_rest_stays_at_rest_at_static_draft(cfg):
    m = make(cfg)
    run(m, 60.0)
    s, st = m.state, m.status()
    assert np.all(np.abs(s.position) < 1e-9) and np.all(np.abs(s.rpy) < 1e-9)
    assert np.all(np.abs(s.linear_velocity_body) < 1e-9) and np.all(np.abs(s.angular_velocity_body) < 1e-9)
    assert st.draft_at_reference == pytest.approx(D0, abs=1e-9)  # Table 1 draft
    assert st.rise == 0.0 and st.thrust == 0.0 and st.lift == 0.0


def test_sinkage_under_a_known_load_matches_hydrostatics(cfg):
    # 10 % of the weight pressed down at the origin: rho g (V(d) - V0) = F, V = V0 (d/d0)^2
    m = make(cfg)
    f = 0.1 * W
    wr = [ExternalWrench(np.array([0.0, 0.0, -f]), np.zeros(3))]
    run(m, 60.0, wrenches=wr)
    d_true = D0 * math.sqrt(1.0 + f / W)
    assert m.status().draft_at_reference == pytest.approx(d_true, abs=1e-3)
    assert abs(m.state.rpy[1]) < 1e-6  # a force at the origin gives no pitch (Eq 4: M = M_S theta)


def test_heave_pitch_periods_match_the_analytic_two_dof_system(cfg):
    # released 5 cm high at rest: the heave-pitch pair oscillates at the eigenfrequencies of
    # the hydrostatic stiffness (rho g A_wp, -M_S(0) rho g V0 L) and the rigid-body + added mass
    m = make(cfg, initial_state=VesselState(np.array([0.0, 0.0, 0.05]), np.zeros(3), np.zeros(3), np.zeros(3)))
    dt, n = 0.01, 3000
    z = np.empty(n)
    for i in range(n):
        m.step(dt)
        z[i] = m.state.position[2]
    h, hyd = cfg["hull"], cfg["hydrodynamics"]
    v0 = MASS / RHO
    xg = h["lcg_from_transom"] - h["reference_point_from_transom"]
    zg = h["vcg_above_waterline"]
    iyy = MASS * h["radii_of_gyration"][1] ** 2 + MASS * (xg ** 2 + zg ** 2) - hyd["M_qdot"]
    M = np.array([[MASS - hyd["Z_wdot"], -MASS * xg], [-MASS * xg, iyy]])
    K = np.diag([RHO * G * 2.0 * v0 / D0, -hyd["polynomials"]["M_S"][0] * RHO * G * v0 * 13.0])
    w = np.sqrt(np.sort(np.linalg.eigvals(np.linalg.solve(M, K)).real))
    # dominant heave period from zero crossings of z
    zc = np.flatnonzero(np.diff(np.sign(z)) != 0) * dt
    period = 2.0 * np.mean(np.diff(zc[:6]))
    heave_w = w[np.argmin(np.abs(w - 2 * math.pi / period))]
    assert period == pytest.approx(2 * math.pi / heave_w, rel=0.03)
    assert z[-1] == pytest.approx(0.0, abs=2e-3)  # back to the static draft


def test_pitch_oscillates_about_zero_near_zero_speed_and_is_damped_when_planing(cfg):
    # at rest: little damping, the trim swings about zero at the natural period
    m = make(cfg, initial_state=VesselState(np.zeros(3), np.array([0.0, math.radians(1.0), 0.0]),
                                            np.zeros(3), np.zeros(3)))
    dt, n = 0.02, 1000
    th = np.empty(n)
    for i in range(n):
        m.step(dt)
        th[i] = math.degrees(m.state.rpy[1])
    crossings = np.count_nonzero(np.diff(np.sign(th)) != 0)
    assert crossings >= 10                      # oscillates
    assert abs(th.mean()) < 0.1                 # about zero trim
    assert np.abs(th[100:200]).max() > 0.2      # still swinging 2-4 s later: weak damping at rest
    # planing at 12 m/s: the same kick dies within a couple of seconds, about a bow-up trim
    m = make(cfg)
    m.set_steady_run(12.0)
    base = m.state.rpy[1]
    m.state.rpy[1] += math.radians(1.0)
    run(m, 3.0, dt=0.02)
    assert base < 0.0                            # bow up (REP-103 pitch < 0)
    assert abs(m.state.rpy[1] - base) < math.radians(0.1)


# ---------------------------------------------------------------- steady straight runs
def _cl(u):
    return sum(a * u ** k for k, a in enumerate(TABLE5_CL))


@pytest.mark.parametrize("throttle", [0.5, 0.75, 1.0])
def test_steady_runs_settle_at_the_steady_state(cfg, throttle):
    m = make(cfg)
    m.set_command(Command(throttle, 0.0))
    run(m, 90.0)
    u = m.state.linear_velocity_body[0]
    ss = m.steady_state(throttle * m.full_speed)
    # 1) the time integration settles on the algebraic equilibrium of the same model (the speed
    #    itself holds by construction of Eq 11: it only shows the run has settled)
    assert u == pytest.approx(throttle * m.full_speed, rel=0.005)
    assert -math.degrees(m.state.rpy[1]) == pytest.approx(ss["trim_deg"], abs=0.05)
    assert m.state.position[2] == pytest.approx(ss["rise"], abs=0.005)
    # 2) calibration: Table 2 trim (17.5-35 kn, inside the M_w fit); independent truth: the rise
    #    from Table 5 lift and hydrostatics
    kn = u / KNOT
    trim_t2 = np.interp(kn, [r[0] for r in TABLE2_TRIM], [r[1] for r in TABLE2_TRIM])
    assert -math.degrees(m.state.rpy[1]) == pytest.approx(trim_t2, abs=0.5)
    lift = 0.5 * RHO * u ** 2 * B_LIFT ** 2 * _cl(u)
    rise_true = D0 - D0 * math.sqrt(1.0 - lift / W)     # rho g (V0 - V(d1)) = L
    assert m.state.position[2] == pytest.approx(rise_true, abs=0.01)
    assert abs(m.state.rpy[0]) < 1e-9 and abs(m.state.position[1]) < 1e-9  # straight, upright


def test_lift_only_bow_up(cfg):
    m = make(cfg)
    m.set_steady_run(12.0)
    m.step(1e-4)
    assert m.status().lift > 0.3 * W
    m.state.rpy[1] = math.radians(0.5)   # bow down: Eq 9 switches lift and lift moment off
    m.step(1e-4)
    assert m.status().lift == 0.0


def test_positive_steering_turns_to_port_and_heels_inward(cfg):
    m = make(cfg)
    m.set_steady_run(12.0)
    m.set_command(Command(m.command.engine_order, math.radians(10.0)))
    run(m, 20.0)
    assert m.state.angular_velocity_body[2] > 0.0     # to port
    assert m.state.rpy[0] < 0.0                       # port side down = inward


# ---------------------------------------------------------------- commands
def test_nan_and_inf_commands_are_rejected_and_the_old_command_kept(cfg):
    m = make(cfg)
    assert m.set_command(Command(0.4, 0.1)) == []
    for bad in (Command(float("nan"), 0.0), Command(0.2, float("inf"))):
        with pytest.raises(CommandRejected):
            m.set_command(bad)
        assert m.command.engine_order == 0.4 and m.command.steering_angle == 0.1
        assert m.status().steering_angle_ordered == 0.1


def test_out_of_range_commands_are_clamped_with_messages(cfg):
    m = make(cfg)
    notes = m.set_command(Command(1.5, math.radians(45.0)))
    assert len(notes) == 2 and "engine_order" in notes[0] and "steering_angle" in notes[1]
    assert m.command.engine_order == 1.0
    assert m.command.steering_angle == pytest.approx(math.radians(30.0))
    run(m, 3.0)
    st = m.status()
    assert st.steering_angle == pytest.approx(math.radians(30.0))  # bucket at its limit
    assert 0 < st.throttle < 1.0 and st.shaft_speed > 0        # impeller still ramping


# ---------------------------------------------------------------- ship file errors
@pytest.mark.parametrize("mutate,key", [
    (lambda c: c["hull"].__setitem__("mas", 1.0), "hull.mas"),
    (lambda c: c["hull"].pop("mass"), "hull.mass"),
    (lambda c: c["waterjet"].__setitem__("nozzle_area", "big"), "waterjet.nozzle_area"),
    (lambda c: c["waterjet"].__setitem__("nozzle_area", -0.1), "waterjet.nozzle_area"),
    (lambda c: c["hydrodynamics"]["polynomials"].__setitem__("Y_v", [1.0, float("nan")]),
     "hydrodynamics.polynomials.Y_v"),
    (lambda c: c["estimated"].__setitem__("hull.keel_depth", "guess"), "estimated.hull.keel_depth"),
    (lambda c: c.__setitem__("model", "mmg_3dof"), "model"),
])
def test_bad_ship_file_names_file_and_key(cfg, mutate, key):
    bad = copy.deepcopy(cfg)
    mutate(bad)
    with pytest.raises(ValueError) as exc:
        planing.PlaningHull.from_config(bad, "ships/broken.yaml")
    assert "ships/broken.yaml" in str(exc.value) and f"'{key}'" in str(exc.value)


def test_every_estimated_value_is_marked(cfg):
    est = cfg["estimated"]
    must = ["hull.chine_beam", "hull.deadrise_deg", "hull.lcg_from_transom", "waterjet.nozzle_area",
            "hydrodynamics.polynomials.M_w", "hydrodynamics.Z_q_per_speed", "hydrodynamics.side_force_froude_range"]
    for key in must:
        assert key in est and len(est[key]) > 10
    with open(SHIP, encoding="utf-8") as fh:
        for line in fh:
            if "# ESTIMATED" in line and not line.lstrip().startswith("#"):
                leaf = line.split(":")[0].strip()
                assert any(k.split(".")[-1] == leaf for k in est), f"{leaf} marked but not explained"


# ---------------------------------------------------------------- interface bits
def test_attachments_and_initial_speed(cfg):
    m = make(cfg, name="speedy", initial_state=VesselState(np.zeros(3), np.zeros(3),
                                                           np.array([12.0, 0, 0]), np.zeros(3)))
    assert m.name == "speedy"
    assert {"bow_eye", "stern_towing_eye"} <= set(m.attachments)
    # steady straight run: every point moves horizontally at the run speed
    pos, vel = m.attachment_kinematics("bow_eye")
    assert vel[0] == pytest.approx(float(np.linalg.norm(m.state.linear_velocity_body)), rel=1e-9)
    assert abs(vel[1]) < 1e-9 and abs(vel[2]) < 1e-9
    assert m.state.rpy[1] < 0 and m.state.position[2] > 0.2   # started in its planing attitude
    run(m, 10.0)
    assert m.state.linear_velocity_body[0] == pytest.approx(12.0, abs=0.01)  # held there


def test_a_free_boat_drifts_with_the_current(cfg):
    # no thrust, uniform current: the hull ends up moving with the water (relative velocity -> 0)
    m = make(cfg)
    m.set_current([0.5, -0.3, 0.0])
    run(m, 400.0)   # slow: only quadratic cross-flow drag acts at such small relative speeds
    pos, vel = m.attachment_kinematics("bow_eye")
    assert vel[0] == pytest.approx(0.5, abs=0.06) and vel[1] == pytest.approx(-0.3, abs=0.06)
    assert m.status().speed_through_water < 0.06
    with pytest.raises(ValueError):
        m.set_current([float("nan"), 0.0, 0.0])
