"""Harbour tug: bollard pull and free speed (calibration), heel under an abeam towline, girting.

The ship file is tuned to its stated bollard pull and free speed (engine.rated_rpm and the
resistance's Fn^4 term, harbour_tug.yaml `estimated:`): the tests comparing with them are
calibration checks. Independent truths: Eq 4 at J = 0 for the bollard thrust, the static heel
balance, and the righting moment of a heeled wall-sided section integrated numerically here."""
import math

import numpy as np
import pytest
import yaml

from tug_dynamics import maneuvering as mv
from tug_dynamics.maneuver_trials import KN, run
from tug_dynamics.ship_file import list_ship_files, load_ship
from tug_dynamics.vessel import Command, ExternalWrench, rotation_body_to_world

G = 9.80665
STATED_BOLLARD_PULL_T = 35.4      # harbour_tug.yaml header: calibration targets
STATED_FREE_SPEED_KN = 12.0


@pytest.fixture(scope="module")
def cfg():
    path = [f for f in list_ship_files() if f.endswith("harbour_tug.yaml")][0]
    return yaml.safe_load(open(path))


def _bollard_pull_t():
    """Tug held by a stiff horizontal spring at the towing hook: spring force = bollard pull (t)."""
    tug = load_ship("harbour_tug.yaml")
    k, c = 2.0e5, 2.0e6
    hook = tug.attachments["towing_hook"]

    def line(v, t):
        x, u = v.state.position[0], v.state.linear_velocity_body[0]
        return [ExternalWrench(np.array([-k * x - c * u, 0.0, 0.0]), hook)]

    run(tug, 120.0, 0.1, {0.0: Command(1.0, 0.0)}, wrenches=line)
    return k * tug.state.position[0] / (1000 * G)


def test_bollard_pull_is_eq4_at_zero_advance(cfg):
    """Verification: held at rest (J = 0) the pull is sum (1 - t) rho n^2 D^4 K_T(0) (Eq 4) of
    the file's propellers at rated rpm, evaluated here by hand."""
    n = cfg["engine"]["rated_rpm"] / 60.0
    truth = sum((1.0 - p["thrust_deduction"]) * cfg["water_density"] * n * n * p["diameter"] ** 4 * p["kt"][0]
                for p in cfg["propellers"]) / (1000 * G)
    assert _bollard_pull_t() == pytest.approx(truth, rel=1e-3)


def test_bollard_pull_calibration():
    """Calibration: engine.rated_rpm was chosen for the stated 35.4 t."""
    assert _bollard_pull_t() == pytest.approx(STATED_BOLLARD_PULL_T, rel=0.01)


def test_free_running_speed_calibration():
    """Calibration: the resistance's Fn^4 term was set so full power balances at 12 kn."""
    tug = load_ship("harbour_tug.yaml")
    tr = run(tug, 300.0, 0.2, {0.0: Command(1.0, 0.0)})
    assert abs(tr.u[-1] - tr.u[-100]) < 1e-3
    assert tr.u[-1] / KN == pytest.approx(STATED_FREE_SPEED_KN, rel=0.01)


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
    assert tug.status().heel == pytest.approx(expected, rel=0.05)
    assert abs(tug.state.angular_velocity_body[0]) < 1e-4


def _clip_below(poly, level):
    """Sutherland-Hodgman: the part of polygon (n, 2) [y, z] with z <= level."""
    out = []
    for a, b in zip(poly, np.roll(poly, -1, axis=0)):
        ina, inb = a[1] <= level, b[1] <= level
        if ina:
            out.append(a)
        if ina != inb:
            out.append(a + (level - a[1]) / (b[1] - a[1]) * (b - a))
    return np.array(out)


def _area_centroid(p):
    y, z = p[:, 0], p[:, 1]
    y1, z1 = np.roll(y, -1), np.roll(z, -1)
    c = y * z1 - y1 * z
    a = 0.5 * c.sum()
    return a, np.array([((y + y1) * c).sum(), ((z + z1) * c).sum()]) / (6.0 * a)


def box_gz(beam, draft, depth, kg, phi):
    """Righting lever of a box section heeled by phi: the immersed polygon of the same area is
    found and its centroid (the centre of buoyancy) integrated, here, with numpy."""
    from scipy.optimize import brentq
    rect = np.array([[-beam / 2, 0.0], [beam / 2, 0.0], [beam / 2, depth], [-beam / 2, depth]])
    c, s = math.cos(phi), math.sin(phi)
    rot = np.array([[c, -s], [s, c]])
    heeled = rect @ rot.T
    level = brentq(lambda h: _area_centroid(_clip_below(heeled, h))[0] - beam * draft,
                   heeled[:, 1].min() + 1e-9, heeled[:, 1].max())
    return (rot @ np.array([0.0, kg]))[0] - _area_centroid(_clip_below(heeled, level))[1][0]


def test_girting_warning(cfg):
    """Truth: the righting moment at deck-edge immersion of a box section with the file's beam,
    freeboard, GM and BM (draft B^2 / (12 BM), KG = KB + BM - GM), integrated numerically."""
    m, gm, bm, fb, B = (cfg["hull"]["mass"], cfg["roll"]["gm"], cfg["roll"]["bm"], cfg["roll"]["freeboard"],
                        cfg["hull"]["beam"])
    phi = math.atan2(fb, B / 2)
    T = B * B / (12.0 * bm)
    righting = m * G * box_gz(B, T, T + fb, T / 2 + bm - gm, phi)
    lever = cfg["attachments"]["towing_hook"][2] - cfg["roll"]["z_lateral_resistance"]
    low = _abeam(load_ship("harbour_tug.yaml"), 5.0 * 1000 * G, 60.0).status()
    assert low.girting_ratio == pytest.approx(5.0 * 1000 * G * lever / righting, rel=1e-3)
    assert not low.girting_warning
    high = _abeam(load_ship("harbour_tug.yaml"), 20.0 * 1000 * G, 20.0).status()
    assert high.girting_ratio > cfg["roll"]["girting_threshold"] and high.girting_warning


def test_course_stable_with_rudder_amidships():
    """A yaw disturbance at full speed dies out (linear stability index of the file's
    derivatives is positive), so a trainee's tug does not sheer on its own."""
    from tug_dynamics.vessel import VesselState
    tug = load_ship("harbour_tug.yaml")
    tug.set_state(VesselState(np.zeros(3), np.zeros(3), np.array([12 * KN, 0, 0.0]), np.array([0, 0, 0.05])),
                  shaft_rps=tug.limits["rated_rps"])
    run(tug, 300.0, 0.2, {0.0: Command(1.0, 0.0)})
    assert abs(tug.state.angular_velocity_body[2]) < 0.01 * 0.05
