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
# the pair (moored, passing): each vessel's summed interaction load (here its one pair's)
ON = {"a": "/interactions/on_moored/wrench", "b": "/interactions/on_passing/wrench"}
TOPICS = ["/passing/odom", "/moored/odom", ON["a"], ON["b"]]


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
                     for m in msgs[ON[end]]])


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


# --- a ship along a channel bank, and a tug at a ship's bow (issue 33 items 2 and 6) ---------------

BANK_DURATION = 60.0
TUG_DURATION = 60.0
BANK_TOPICS = ["/ship/odom", "/interactions/on_ship/wrench"]
TUG_TOPICS = ["/ship/odom", "/tug/odom", "/interactions/on_tug/wrench", "/interactions/on_ship/wrench"]


def _loads(msgs, topic):
    return np.array([[m.wrench.force.x, m.wrench.force.y, m.wrench.torque.z] for m in msgs[topic]])


@pytest.fixture(scope="module")
def confined_runs(tmp_path_factory):
    base = tmp_path_factory.mktemp("confined")
    out = {}
    with reserved_domain():
        for name, scenario, duration, topics in (("bank", "bank_s175_channel.yaml", BANK_DURATION, BANK_TOPICS),
                                                 ("tug", "tug_bow_s175_6kn.yaml", TUG_DURATION, TUG_TOPICS)):
            for layout in ("processes", "one_process"):
                path = base / f"{name}_{layout}.mcap"
                record_scenario(scenario, path, "--duration", duration, layout=layout, timeout=400)
                msgs = decoded(path, topics)
                run = {t.split("/")[1] if t.endswith("odom") else t: (
                    _states(msgs, t.split("/")[1]) if t.endswith("odom") else _loads(msgs, t)) for t in topics}
                out[f"{name}_{layout}"] = run
    return out


def _bank_by_hand(row, lead):
    """bank_effect's (Y, N) on the S-175 at the row's state carried on `lead` s: the bank y = -40 m
    runs east, so the distance is y + 40 and the bank lies to starboard while the ship heads east."""
    from tug_dynamics.bank_effect import BankEffect
    from tug_dynamics.hull_interaction import SectionalAreaCurve
    from tug_dynamics.ship_file import ship_config
    effect = BankEffect(SectionalAreaCurve.from_ship_config(ship_config("s175_003.yaml")[1]))
    x, y, yaw, vx, vy = row
    y += vy * lead
    return effect.loads(y + 40.0, math.cos(yaw) * vx + math.sin(yaw) * vy, 12.75,
                        bank_to_port=math.cos(yaw) < 0.0)


def test_bank_run_loads_are_the_bank_model_at_the_recorded_positions(confined_runs):
    r = confined_runs["bank_processes"]
    ship, loads = r["ship"], r["/interactions/on_ship/wrench"]
    steps = int(BANK_DURATION * RATE)
    assert len(loads) == len(ship) == steps + 1
    expected = np.array([[0.0, *_bank_by_hand(ship[max(k - 1, 0)], (1.5 if k else 0.5) / RATE)]
                         for k in range(steps + 1)])
    scale = np.abs(expected).max(axis=0) + 1.0
    np.testing.assert_allclose(loads / scale, expected / scale, rtol=0, atol=1e-6)
    # drawn toward the bank (starboard, -y) from the start: 40 m off at h/T 1.5, 6 kn
    assert expected[0, 1] < -1e4 and np.all(loads[:, 1] < 0.0)
    assert ship[-1, 1] < ship[0, 1] - 0.5          # the free ship is drawn toward the bank


def _bank_run_matches(path, out, bank_loads):
    """Record 10 s of the ship-and-bank scenario at `path` in one process; every recorded load on
    the ship is bank_loads(x, y, yaw, speed) (Y, N) at the recorded state of the step before,
    carried on 1.5 steps (half a step for step 0), within 1e-6 of the peak. (ship states, loads)"""
    record_scenario(path, out, "--duration", 10.0, layout="one_process", timeout=240)
    msgs = decoded(out, BANK_TOPICS)
    ship, loads = _states(msgs, "ship"), _loads(msgs, "/interactions/on_ship/wrench")
    expected = []
    for k in range(len(loads)):
        x, y, yaw, vx, vy = ship[max(k - 1, 0)]
        lead = (1.5 if k else 0.5) / RATE
        expected.append([0.0, *bank_loads(x + vx * lead, y + vy * lead, yaw, math.cos(yaw) * vx + math.sin(yaw) * vy)])
    expected = np.array(expected)
    scale = np.abs(expected).max(axis=0) + 1.0
    np.testing.assert_allclose(loads / scale, expected / scale, rtol=0, atol=1e-6)
    return ship, loads


@pytest.mark.timeout(300)
def test_a_sloped_bank_in_a_run_is_its_equivalent_walls_suction(tmp_path, ros_domain):
    """The channel bank with a 1:3 underwater slope from its line (bank_slope 3): 10 s in one
    process; every recorded load is BankEffect.loads_along with the slope at the recorded state,
    and the slope pulls harder than the vertical bank of the same line (test_bank_effect)."""
    from tug_dynamics.bank_effect import BankEffect, BankPolyline
    from tug_dynamics.hull_interaction import SectionalAreaCurve
    from tug_dynamics.ship_file import ship_config
    sc = yaml.safe_load(open(_library("bank_s175_channel.yaml")))
    sc["interactions"][0]["bank_slope"] = 3.0
    path = tmp_path / "sloped_bank.yaml"
    path.write_text(yaml.safe_dump(sc))
    out = tmp_path / "sloped.mcap"
    effect = BankEffect(SectionalAreaCurve.from_ship_config(ship_config("s175_003.yaml")[1]))
    bank = BankPolyline(sc["interactions"][0]["bank"])
    ship, loads = _bank_run_matches(path, out, lambda x, y, yaw, speed: effect.loads_along(
        bank, x, y, yaw, speed, 12.75, 3.0))
    vertical = _bank_by_hand(ship[0], 0.5 / RATE)[0]
    assert loads[0, 1] < vertical < 0.0


@pytest.mark.timeout(300)
def test_the_banks_of_a_depth_grid_in_a_run(tmp_path, ros_domain, run_in_process):
    """bank: depth: an S-175 at 3 kn along the harbour's quay (harbour_berth_s175.asc: the wall's face
    52 m to starboard, an 8-15 m apron before it), 10 s in one process: every recorded load is
    BankEffect.loads_in_depth of the grid at the recorded state, drawing the ship toward the quay.
    Without a depth grid, or with a bank_slope, `bank: depth` exits 2."""
    import os
    from sea_environment.bathymetry import DepthGrid
    from tug_dynamics.bank_effect import BankEffect
    from tug_dynamics.hull_interaction import SectionalAreaCurve
    from tug_dynamics.ship_file import ship_config
    grid = os.path.abspath(_library("harbour_berth_s175.asc"))
    sc = {"name": "quay_bank", "duration": 10.0, "exchange_rate": 10.0, "environment": {"depth": {"grid": grid}},
          "vessels": [{"name": "ship", "ship_file": "s175_003.yaml",
                       "initial": {"x": -200.0, "y": 0.0, "heading_deg": 0.0, "speed": 1.543, "engine_order": 0.17}}],
          "interactions": [{"between": ["ship"], "bank": "depth"}]}
    path = tmp_path / "quay_bank.yaml"
    path.write_text(yaml.safe_dump(sc))
    out = tmp_path / "quay.mcap"
    effect = BankEffect(SectionalAreaCurve.from_ship_config(ship_config("s175_003.yaml")[1]))
    depth_at = DepthGrid.load(grid).depth_at
    _, loads = _bank_run_matches(path, out, lambda x, y, yaw, speed: effect.loads_in_depth(depth_at, x, y, yaw, speed))
    assert np.all(loads[:, 1] < 0.0)               # toward the quay, to starboard
    for edit, message in (({"environment": {"depth": 15.0}}, "'environment.depth' is not a grid"),
                          ({"interactions": [{"between": ["ship"], "bank": "depth", "bank_slope": 3.0}]},
                           "key 'interactions[0].bank_slope': only with a 'bank' line")):
        bad = tmp_path / "bad.yaml"
        bad.write_text(yaml.safe_dump({**sc, **edit}))
        proc = run_in_process("run_scenario", bad, "--no-record", "--quiet")
        assert proc.returncode == 2 and message in proc.stderr, proc.stderr


def test_tug_at_the_bow_loads_are_wang_at_the_recorded_positions(confined_runs):
    from tug_dynamics.hull_interaction import pair_from_ship_configs
    from tug_dynamics.ship_file import ship_config
    r = confined_runs["tug_processes"]
    tug, ship = r["tug"], r["ship"]
    cfg = {n: ship_config(f)[1] for n, f in (("tug", "harbour_tug.yaml"), ("ship", "s175_003.yaml"))}
    steps = int(TUG_DURATION * RATE)
    for own, other in (("tug", "ship"), ("ship", "tug")):
        pair = pair_from_ship_configs(cfg[own], cfg[other])
        expected = []
        for k in range(steps + 1):
            o, p, lead = r[own][max(k - 1, 0)], r[other][max(k - 1, 0)], (1.5 if k else 0.5) / RATE
            c, s = math.cos(o[2]), math.sin(o[2])
            dx = p[0] + p[3] * lead - o[0] - o[3] * lead
            dy = p[1] + p[4] * lead - o[1] - o[4] * lead
            try:
                expected.append(pair.loads(c * dx + s * dy, -s * dx + c * dy, c * p[3] + s * p[4]))
            except ValueError:          # hulls overlapping: no Wang load until they part
                expected.append((0.0, 0.0, 0.0))
        expected = np.array(expected)
        got = r[f"/interactions/on_{own}/wrench"]
        scale = np.abs(expected).max(axis=0) + 1.0
        np.testing.assert_allclose(got / scale, expected / scale, rtol=0, atol=1e-6, err_msg=own)
    # at the start (stagger -75 m, 25 m off) the bow's field pushes the tug off to port and turns
    # its bow to port (Wang at stagger -75 m, by hand with HullPair: Y 1.84 kN, N 6.6 kN m) ...
    first = r["/interactions/on_tug/wrench"][0]
    assert first[1] == pytest.approx(1.84e3, rel=0.01) and first[2] == pytest.approx(6.64e3, rel=0.01)
    # ... and then the free tug sheers in toward the ship (alone it runs straight at y = 25 m)
    assert tug[-1, 1] < tug[0, 1] - 3.0 and tug[-1, 2] < -math.radians(4.0)   # measured 6.3 m, 8 deg


@pytest.mark.parametrize("name", ["bank", "tug"])
def test_confined_runs_identical_in_one_process(confined_runs, name):
    first, again = confined_runs[f"{name}_processes"], confined_runs[f"{name}_one_process"]
    for key in first:
        np.testing.assert_array_equal(first[key], again[key], err_msg=key)


@pytest.mark.parametrize("edit, message", [
    ({"bank": [[0.0, -40.0], [1000.0, -40.0], [1000.0, 40.0], [500.0, -100.0]]},
     "key 'interactions[0].bank': bank line crosses itself: segment 0"),
    ({"bank": [[0.0, -40.0], [1000.0, -40.0], [300.0, -40.0]]},
     "key 'interactions[0].bank': bank line crosses itself: segment 1"),
    ({"bank": [[2000.0, -40.0], [-500.0, -40.0]]}, "key 'interactions[0].bank': ship starts at (0, 0) m, 40 m "
                                                    "from the bank line on its land side"),
    ({"bank": [[-500.0, -10.0], [2000.0, -10.0]]}, "key 'interactions[0].bank': ship starts at (0, 0) m, 10 m "
                                                    "from the bank line: it must start on the water side"),
    ({"between": ["ship", "ship"]}, "key 'interactions[0].between': ['ship', 'ship'] with a bank"),
    ({"bank_slope": -1.0}, "interactions[0].bank_slope"),
])
def test_a_bad_bank_exits_2_before_start(tmp_path, run_in_process, edit, message):
    sc = yaml.safe_load(open(_library("bank_s175_channel.yaml")))
    sc["interactions"][0].update(edit)
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(sc))
    proc = run_in_process("run_scenario", path, "--no-record", "--quiet")
    assert proc.returncode == 2, proc.stdout + proc.stderr
    assert message in proc.stderr, proc.stderr


def test_a_sloped_bank_reaches_the_node_and_a_slope_without_a_bank_exits_2(tmp_path, run_in_process):
    """bank_slope goes to the interaction node's banks entry ("<vessel>:<slope>:x0,y0,..."), which the
    node parses back; on a pair of vessels (no bank) the scenario check refuses it."""
    from hull_contact.interaction_node import parse_banks
    from scenario_format.scenario import load_scenario
    from scenario_runner.run_nodes import _interaction_specs
    sc = yaml.safe_load(open(_library("bank_s175_channel.yaml")))
    sc["interactions"][0]["bank_slope"] = 3.0
    path = tmp_path / "sloped.yaml"
    path.write_text(yaml.safe_dump(sc))
    (spec,) = _interaction_specs(load_scenario(str(path)), str(path), "run")
    (entry,) = parse_banks(spec.params["banks"])
    assert entry.slope == 3.0 and entry.vessel == "ship" and entry.bank.points == [(-500.0, -40.0), (2000.0, -40.0)]
    assert parse_banks(["quay=ship:0.0,1.0,5.0,1.0"])[0].slope == 0.0      # the vertical form, as before
    with pytest.raises(ValueError, match="<slope 0-100>"):
        parse_banks(["quay=ship:-2:0.0,1.0,5.0,1.0"])
    pair = yaml.safe_load(open(_library("passing_moored_s175_1p5B.yaml")))
    pair["interactions"][0]["bank_slope"] = 2.0
    bad = tmp_path / "pair_slope.yaml"
    bad.write_text(yaml.safe_dump(pair))
    proc = run_in_process("run_scenario", bad, "--no-record", "--quiet")
    assert proc.returncode == 2 and "key 'interactions[0].bank_slope': only with a 'bank'" in proc.stderr, proc.stderr


def test_a_bank_in_water_too_shallow_for_the_image_methods_sign_is_warned_of(tmp_path):
    """Below 20 % under-keel clearance model tests measure the ship pushed away from a bank
    (Lataire, Vantorre & Eloot 2009), the image method draws it in: the scenario check says so
    (S-175, draft 8.5 m: 9.9 m of water is 16 %); the library's channel, 12.75 m (50 %), is quiet."""
    from scenario_format.scenario import load_scenario
    assert load_scenario(_library("bank_s175_channel.yaml")).warnings == []
    sc = yaml.safe_load(open(_library("bank_s175_channel.yaml")))
    sc["environment"]["depth"] = 9.9
    path = tmp_path / "shallow_bank.yaml"
    path.write_text(yaml.safe_dump(sc))
    (warning,) = load_scenario(str(path)).warnings
    assert "key 'interactions[0].bank'" in warning and "clearance of 16 %" in warning and "wrong sign" in warning


def test_a_vessel_named_interactions_exits_2_before_start(tmp_path, run_in_process):
    """/interactions is the interaction node's namespace in a run with `interactions`."""
    sc = yaml.safe_load(open(_library("passing_moored_s175_1p5B.yaml")))
    text = yaml.safe_dump(sc).replace("moored", "interactions")
    path = tmp_path / "clash.yaml"
    path.write_text(text)
    proc = run_in_process("run_scenario", path, "--no-record", "--quiet")
    assert proc.returncode == 2, proc.stdout + proc.stderr
    assert "name 'interactions' is the interaction node's namespace" in proc.stderr, proc.stderr
