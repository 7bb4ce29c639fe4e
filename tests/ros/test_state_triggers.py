"""State-triggered events (`when:` in the scenario format) and the IMO trials built on them.

The library's tug zig-zag 10/10 and crash stop run through run_scenario; from the recording
alone (the vessel's own odometry, decoded here) the test finds the first step at which each
trigger's condition holds and checks that the order was given at exactly that step; then
`analyze` must judge the zig-zag as a heading-triggered one and report the IMO table."""
import json
import math
import os
import subprocess

import numpy as np
import pytest

from conftest import executable_path, record_scenario

pytestmark = [pytest.mark.ros, pytest.mark.timeout(240)]


def _run(name, out, duration):
    from domain_coordinator import domain_id
    with domain_id() as did:
        env = dict(os.environ, ROS_DOMAIN_ID=str(did), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
        res = record_scenario(name if name.endswith(".yaml") else f"{name}.yaml", out, "--duration", duration,
                              env=env, timeout=200)
    _run.stdout = res.stdout
    return out


def _read(path, vessel):
    """(odometry arrays t, yaw unwrapped, u, speed), (command stamps, engine orders, steering)."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory
    odom, cmd = [], []
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        for _s, ch, _m, msg in reader.iter_decoded_messages(topics=[f"/{vessel}/odom", f"/{vessel}/command"]):
            t = msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec
            if ch.topic.endswith("odom"):
                q, lin = msg.pose.pose.orientation, msg.twist.twist.linear
                odom.append((t, math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y ** 2 + q.z ** 2)), lin.x,
                             math.hypot(lin.x, lin.y)))
            else:
                cmd.append((t, msg.engine_order, msg.steering_angle))
    o = np.array(sorted(set(odom)))
    c = np.array(sorted(cmd))
    return (o[:, 0], np.unwrap(o[:, 1]), o[:, 2], o[:, 3]), (c[:, 0], c[:, 1], c[:, 2])


def test_zigzag_reverses_the_helm_at_the_step_the_heading_crosses(tmp_path):
    rec = _run("trial_tug_zigzag_10_10", tmp_path / "zz.mcap", 60.0)
    (t, yaw, _u, _speed), (ct, _eo, steer) = _read(rec, "tug")
    dt = 1.0 / 20.0
    assert ct[0] == pytest.approx(10.0) and steer[0] == pytest.approx(math.radians(-10.0))
    ref = np.interp(10.0, t, yaw)
    k0 = int(np.searchsorted(t, 10.0 - 1e-9))
    side = -1.0  # the heading first swings to starboard
    reversals = 0
    for j in range(1, len(ct)):
        crossed = np.nonzero(side * (yaw[k0:] - ref) >= math.radians(10.0))[0]
        assert crossed.size, "the heading never reached the check angle"
        k = k0 + int(crossed[0])
        assert ct[j] == pytest.approx(t[k], abs=1e-9), f"reversal {j} at {ct[j]} s, the heading crossed at {t[k]} s"
        assert steer[j] == pytest.approx(side * -math.radians(10.0))
        k0, side, reversals = k, -side, reversals + 1
    assert reversals >= 4 and abs(t[1] - t[0] - dt) < 1e-9
    # the summary names exactly the triggered events that had not fired by the end (issue 30)
    from scenario_format.particulars import scenario_path
    from scenario_format.scenario import load_scenario
    triggered = [i for i, e in enumerate(load_scenario(scenario_path("trial_tug_zigzag_10_10")).events) if e.when]
    late = [f"events[{i}] (when tug heading changed" for i in triggered[reversals:]]
    assert all(text in _run.stdout for text in late) and ("never triggered" in _run.stdout) == bool(late), _run.stdout
    assert not any(f"events[{i}] (when" in _run.stdout for i in triggered[:reversals]), _run.stdout
    out = subprocess.run([executable_path("recording", "analyze"), str(rec), "-o", str(tmp_path / "an"),
                          "--no-figures"], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    vs = json.loads((tmp_path / "an" / "summary.json").read_text())["vessels"]["tug"]
    zz = vs["zigzag"]
    assert zz["heading_triggered"] and zz["delta"] == pytest.approx(math.radians(10.0))
    # the check angle is the heading change at the reversal: within one step's yaw of 10 deg
    assert all(math.radians(10.0) <= c < math.radians(11.0) for c in zz["check_angles"])
    assert {r["criterion"] for r in vs["imo"]} == {"initial turning: distance to 10 deg",
                                                  "zig-zag 10/10: first overshoot", "zig-zag 10/10: second overshoot"}
    assert "IMO MSC.137(76)" in out.stdout


def test_crash_stop_stops_the_engine_when_headway_is_lost(tmp_path):
    rec = _run("trial_tug_crash_stop", tmp_path / "stop.mcap", 40.0)
    (t, _yaw, u, _speed), (ct, eo, _steer) = _read(rec, "tug")
    assert list(eo[:2]) == [-1.0, 0.0] and ct[0] == pytest.approx(10.0)
    first_astern = int(np.nonzero((t > 10.0) & (u < 0.0))[0][0])
    assert ct[1] == pytest.approx(t[first_astern], abs=1e-9)
    out = subprocess.run([executable_path("recording", "analyze"), str(rec), "-o", str(tmp_path / "an"),
                          "--no-figures"], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    stop = json.loads((tmp_path / "an" / "summary.json").read_text())["vessels"]["tug"]["stopping"]
    # headway lost between the last step with u >= 0 and the first with u < 0
    assert t[first_astern - 1] - 10.0 <= stop["time_to_stop"] <= t[first_astern] - 10.0


def test_a_trigger_that_never_held_is_named_in_the_summary(tmp_path):
    """A `when:` whose condition never holds before the end leaves its order ungiven: the summary
    says so, naming the event (it was not mentioned)."""
    import yaml
    from scenario_format.particulars import scenario_path
    sc = yaml.safe_load(open(scenario_path("trial_tug_crash_stop")))
    sc["events"] = [{"time": 0.5, "vessel": "tug", "engine_order": 0.5},
                    {"when": {"vessel": "tug", "speed_above": 30.0}, "vessel": "tug", "engine_order": 0.0}]
    path = tmp_path / "never.yaml"
    path.write_text(yaml.safe_dump(sc))
    _run(str(path), tmp_path / "never.mcap", 2.0)
    assert "never triggered (their condition did not hold before the end): events[1] (when tug speed above 30 m/s)" \
        in _run.stdout, _run.stdout
