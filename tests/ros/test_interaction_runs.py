"""Issue 33 item 3 in a run: an S-175 passing a stopped S-175 at 6 kn (passing_moored_s175_1p5B /
_3B). The interaction node's recorded loads are tug_dynamics.hull_interaction's at the pair's
recorded positions of the step before carried on to the middle of the step the load acts over
(recomputed here from the odometry by hand: stagger, separation and speed in the stopped ship's
axes), the sway force is attraction abeam and repulsion
at a stagger of +-0.7 L and the surge force changes sign with the stagger, the stopped ship is
moved by them, a run in one process is identical, the lowest exchange rate (1 Hz) moves it as
10 Hz does, and a pair starting inside each other's hulls exits 2 before start."""
import math

import numpy as np
import pytest
import yaml

from conftest import record_scenario, reserved_domain
from test_recording import decoded

pytestmark = [pytest.mark.ros, pytest.mark.timeout(600)]

DURATION = 80.0
RATE = 10.0
TOPICS = ["/passing/odom", "/moored/odom", "/moored_passing_interaction/on_a/wrench",
          "/moored_passing_interaction/on_b/wrench"]


def _yaw(odom):
    q = odom.pose.pose.orientation
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def _states(msgs, vessel):
    """x, y, yaw, world velocity (vx, vy) per step."""
    rows = []
    for m in msgs[f"/{vessel}/odom"]:
        yaw, u, v = _yaw(m), m.twist.twist.linear.x, m.twist.twist.linear.y
        rows.append([m.pose.pose.position.x, m.pose.pose.position.y, yaw,
                     math.cos(yaw) * u - math.sin(yaw) * v, math.sin(yaw) * u + math.cos(yaw) * v])
    return np.array(rows)


def _wrenches(msgs, end):
    return np.array([[m.wrench.force.x, m.wrench.force.y, m.wrench.torque.z]
                     for m in msgs[f"/moored_passing_interaction/on_{end}/wrench"]])


def _physics(msgs):
    return {"moored": _states(msgs, "moored"), "passing": _states(msgs, "passing"),
            "on_a": _wrenches(msgs, "a"), "on_b": _wrenches(msgs, "b")}


def _library(name):
    import os
    return os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "ros_ws", "src", "scenario_runner",
                        "scenarios", name)


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    base = tmp_path_factory.mktemp("interaction")
    slow = yaml.safe_load(open(_library("passing_moored_s175_1p5B.yaml")))
    slow.update(name="passing_moored_s175_1p5B_1Hz", exchange_rate=1.0)
    (base / "slow.yaml").write_text(yaml.safe_dump(slow))
    out = {}
    with reserved_domain():
        for name, scenario, layout in (("1p5B", "passing_moored_s175_1p5B.yaml", "processes"),
                                       ("1p5B_one_process", "passing_moored_s175_1p5B.yaml", "one_process"),
                                       ("3B", "passing_moored_s175_3B.yaml", "processes"),
                                       ("1p5B_1Hz", base / "slow.yaml", "processes")):
            record_scenario(scenario, base / f"{name}.mcap", "--duration", DURATION, layout=layout, timeout=400)
            out[name] = _physics(decoded(base / f"{name}.mcap", TOPICS))
    return out


def _wang(own, other, lead):
    """hull_interaction's (X, Y, N) on `own` from `other` (rows x, y, yaw, vx, vy), both carried
    on at their velocities for `lead` seconds, by hand."""
    from tug_dynamics.hull_interaction import pair_from_ship_configs
    from tug_dynamics.ship_file import ship_config
    cfg = ship_config("s175_003.yaml")[1]
    pair = pair_from_ship_configs(cfg, cfg)
    c, s = math.cos(own[2]), math.sin(own[2])
    dx = other[0] + other[3] * lead - own[0] - own[3] * lead
    dy = other[1] + other[4] * lead - own[1] - own[4] * lead
    return pair.loads(c * dx + s * dy, -s * dx + c * dy, c * other[3] + s * other[4])


@pytest.mark.parametrize("run", ["1p5B", "3B", "1p5B_1Hz"])
def test_recorded_loads_are_wang_at_the_recorded_positions(runs, run):
    r = runs[run]
    rate = 1.0 if run.endswith("1Hz") else RATE
    steps = int(DURATION * rate)
    assert len(r["on_a"]) == len(r["moored"]) == steps + 1
    for end, own, other in (("on_a", "moored", "passing"), ("on_b", "passing", "moored")):
        # the load stamped k (k >= 1) is computed from the odometry of step k - 1, carried on to the
        # middle of the step it acts over (k -> k + 1: 1.5 steps on); step 0's from step 0, half a step on
        expected = np.array([_wang(r[own][max(k - 1, 0)], r[other][max(k - 1, 0)], (1.5 if k else 0.5) / rate)
                             for k in range(steps + 1)])
        scale = np.abs(expected).max(axis=0) + 1.0
        np.testing.assert_allclose(r[end] / scale, expected / scale, rtol=0, atol=1e-6, err_msg=f"{run} {end}")
    # the stopped ship barely moves, so the passing ship feels (Wang: the moored pressure) almost nothing
    assert np.abs(r["on_b"][:, 1]).max() < 1e-3 * np.abs(r["on_a"][:, 1]).max()


def test_the_sway_force_and_surge_force_reverse_with_stagger(runs):
    for run, abeam_kn in (("1p5B", 85.2), ("3B", 22.9)):
        r = runs[run]
        stagger = r["passing"][:-1, 0] - r["moored"][:-1, 0]    # the passing ship's midship ahead
        loads = r["on_a"][1:]
        abeam = np.argmin(np.abs(stagger))
        # abeam the ships attract: the passing ship is to starboard (-y) of the stopped one
        assert loads[abeam, 1] == pytest.approx(-abeam_kn * 1e3, rel=0.01)
        # 0.7 L before and after: pushed apart (Wang's Y even in the stagger)
        for far in (np.argmin(np.abs(stagger + 120.0)), np.argmin(np.abs(stagger - 120.0))):
            assert loads[far, 1] > 0.0
        # surge and yaw odd in the stagger: they change sign as the midships pass
        before, after = np.argmin(np.abs(stagger + 40.0)), np.argmin(np.abs(stagger - 40.0))
        assert loads[before, 0] < 0.0 < loads[after, 0]
        assert loads[before, 2] > 0.0 > loads[after, 2]
    # the closer passage pulls harder
    assert np.abs(runs["1p5B"]["on_a"][:, 1]).max() > 3.0 * np.abs(runs["3B"]["on_a"][:, 1]).max()


def test_the_stopped_ship_feels_the_loads(runs):
    """It starts at rest with no wind, current or waves: everything it does is the interaction."""
    for run in ("1p5B", "3B"):
        m = runs[run]["moored"]
        assert np.all(m[0, 3:] == 0.0)
        assert np.hypot(m[-1, 0] - m[0, 0], m[-1, 1] - m[0, 1]) > 0.05, run
    assert abs(runs["1p5B"]["moored"][-1, 1] - 38.1) > 2.0 * abs(runs["3B"]["moored"][-1, 1] - 76.2)


def test_identical_in_one_process(runs):
    first, again = runs["1p5B"], runs["1p5B_one_process"]
    for key in first:
        np.testing.assert_array_equal(first[key], again[key], err_msg=key)


def test_the_lowest_exchange_rate_moves_the_stopped_ship_as_10_hz_does(runs):
    """docs/confined-water.md, "In a run": the load acts one exchange late; at 1 Hz the lag's work
    is a small part of what the load does (the load changes over L / U = 57 s, not over a step)."""
    fast, slow = runs["1p5B"]["moored"], runs["1p5B_1Hz"]["moored"]
    every = int(RATE)
    drift_fast = fast[::every] - fast[0]
    drift_slow = slow - slow[0]
    peak = np.abs(drift_fast[:, 1]).max()
    assert peak > 1.0                 # m: the passage draws it 1.6 m towards the passing ship's track
    assert np.abs(drift_slow[:, 1] - drift_fast[:, 1]).max() < 1e-3 * peak   # measured 1.3e-4
    energy = lambda s: 0.5 * (s[:, 3] ** 2 + s[:, 4] ** 2)   # noqa: E731  (per unit mass)
    assert energy(slow).max() == pytest.approx(energy(fast).max(), rel=0.01)   # measured 0.17 %


@pytest.mark.parametrize("edit, message", [
    ({"y": 20.0}, "key 'interactions[0].between': moored and passing at their initial positions: hull interaction: "
                  "separation"),
    ({"between": ["moored", "tug"]}, "key 'interactions[0].between': vessel 'tug' is not in 'vessels'"),
])
def test_a_bad_interaction_exits_2_before_start(tmp_path, run_in_process, edit, message):
    sc = yaml.safe_load(open(_library("passing_moored_s175_1p5B.yaml")))
    if "y" in edit:
        sc["vessels"][1]["initial"]["y"] = edit["y"]
    else:
        sc["interactions"][0]["between"] = edit["between"]
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(sc))
    proc = run_in_process("run_scenario", path, "--no-record", "--quiet")
    assert proc.returncode == 2, proc.stdout + proc.stderr
    assert message in proc.stderr, proc.stderr
