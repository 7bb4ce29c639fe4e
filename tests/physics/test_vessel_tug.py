"""Harbour tug: stated bollard pull and free speed, heel under an abeam towline, girting."""
import math

import numpy as np
import pytest
import yaml

from tug_dynamics import maneuvering as mv
from tug_dynamics.maneuver_trials import KN, run
from tug_dynamics.ship_file import list_ship_files, load_ship
from tug_dynamics.vessel import Command, ExternalWrench, rotation_body_to_world

G = 9.80665
STATED_BOLLARD_PULL_T = 35.4      # harbour_tug.yaml header
STATED_FREE_SPEED_KN = 12.0


@pytest.fixture(scope="module")
def cfg():
    path = [f for f in list_ship_files() if f.endswith("harbour_tug.yaml")][0]
    return yaml.safe_load(open(path))


def test_bollard_pull():
    """Tug held by a stiff horizontal spring at the towing hook: spring force = bollard pull."""
    tug = load_ship("harbour_tug.yaml")
    k, c = 2.0e5, 2.0e6
    hook = tug.attachments["towing_hook"]

    def line(v, t):
        x, u = v.state.position[0], v.state.linear_velocity_body[0]
        return [ExternalWrench(np.array([-k * x - c * u, 0.0, 0.0]), hook)]

    run(tug, 120.0, 0.1, {0.0: Command(1.0, 0.0)}, wrenches=line)
    pull = k * tug.state.position[0] / (1000 * G)
    assert pull == pytest.approx(STATED_BOLLARD_PULL_T, rel=0.10)


def test_free_running_speed():
    tug = load_ship("harbour_tug.yaml")
    tr = run(tug, 300.0, 0.2, {0.0: Command(1.0, 0.0)})
    assert abs(tr.u[-1] - tr.u[-100]) < 1e-3
    assert tr.u[-1] / KN == pytest.approx(STATED_FREE_SPEED_KN, rel=0.10)


def test_tows_full_scale_barge_at_5_knots():
    """Thrust margin: at 5 kn the tug's own resistance plus the barge's (its towline force
    X(u_c), barge_002_full.yaml) is below the tug's full-power effective thrust."""
    barge = load_ship("barge_002_full.yaml", overrides={"towline_simple": {"enabled": True}})
    tow = barge.hp[mv.H_TOW_F]
    tug = load_ship("harbour_tug.yaml")
    hook = tug.attachments["towing_hook"]

    def line(v, t):
        return [ExternalWrench(rotation_body_to_world(v.state.rpy) @ np.array([-tow, 0.0, 0.0]), hook)]

    tr = run(tug, 400.0, 0.5, {0.0: Command(0.8, 0.0)}, wrenches=line)
    assert tr.u[-1] > 5.0 * KN


def _abeam(tug, force, duration=200.0):
    """Body-fixed abeam pull to port at the hook's height above the reference point."""
    z = tug.attachments["towing_hook"][2]

    def line(v, t):
        return [ExternalWrench(rotation_body_to_world(v.state.rpy) @ np.array([0.0, force, 0.0]),
                               np.array([0.0, 0.0, z]))]

    run(tug, duration, 0.1, wrenches=line)
    return tug


@pytest.mark.parametrize("tonnes", [5.0, 10.0])
def test_abeam_towline_heel_matches_gm(cfg, tonnes):
    """Static balance: F (z_hook - z_lateral_resistance) = Delta g GM sin(phi)."""
    F = tonnes * 1000 * G
    tug = _abeam(load_ship("harbour_tug.yaml"), F)
    lever = cfg["attachments"]["towing_hook"][2] - cfg["roll"]["z_lateral_resistance"]
    expected = -math.asin(F * lever / (cfg["hull"]["mass"] * G * cfg["roll"]["gm"]))   # port side down
    assert tug.status()["heel"] == pytest.approx(expected, rel=0.05)
    assert abs(tug.state.angular_velocity_body[0]) < 1e-4


def test_girting_warning(cfg):
    m, gm, bm, fb, B = (cfg["hull"]["mass"], cfg["roll"]["gm"], cfg["roll"]["bm"], cfg["roll"]["freeboard"],
                        cfg["hull"]["beam"])
    phi = math.atan2(fb, B / 2)
    righting = m * G * math.sin(phi) * (gm + 0.5 * bm * math.tan(phi) ** 2)     # wall-sided GZ at deck edge
    lever = cfg["attachments"]["towing_hook"][2] - cfg["roll"]["z_lateral_resistance"]
    low = _abeam(load_ship("harbour_tug.yaml"), 5.0 * 1000 * G, 60.0).status()
    assert low["girting_ratio"] == pytest.approx(5.0 * 1000 * G * lever / righting, rel=1e-3)
    assert not low["girting_warning"]
    high = _abeam(load_ship("harbour_tug.yaml"), 20.0 * 1000 * G, 20.0).status()
    assert high["girting_ratio"] > cfg["roll"]["girting_threshold"] and high["girting_warning"]


def test_course_stable_with_rudder_amidships():
    """A yaw disturbance at full speed dies out (linear stability index of the file's
    derivatives is positive), so a trainee's tug does not sheer on its own."""
    from tug_dynamics.vessel import VesselState
    tug = load_ship("harbour_tug.yaml")
    tug.set_state(VesselState(np.zeros(3), np.zeros(3), np.array([12 * KN, 0, 0.0]), np.array([0, 0, 0.05])),
                  shaft_rps=tug.limits["rated_rps"])
    run(tug, 300.0, 0.2, {0.0: Command(1.0, 0.0)})
    assert abs(tug.state.angular_velocity_body[2]) < 0.01 * 0.05
