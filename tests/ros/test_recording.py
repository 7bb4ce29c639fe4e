"""Recordings read back with two third-party readers; identical decoded physics on
repeated runs and in both process layouts; a killed node stops the run cleanly."""
import os
import signal
import subprocess
import time
from collections import defaultdict

import numpy as np
import pytest

from conftest import executable_path, reserved_domain

pytestmark = [pytest.mark.ros, pytest.mark.timeout(300)]

SCENARIO = "seed000_straight_tow_5kn.yaml"
DURATION = 4.0
RATE = 50.0
STEPS = int(DURATION * RATE)


def run(out, *extra):
    proc = subprocess.run([executable_path("scenario_runner", "run_scenario"), SCENARIO, "--duration", str(DURATION),
                           "--output", str(out), "--quiet", "--layout", "processes", *extra],   # a later --layout wins
                          capture_output=True, text=True, timeout=240)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return proc


def decoded(path, topics=None, until_s=None):
    """topic -> list of decoded messages (of `topics`, or all; with until_s those logged before
    that simulated time: the recorder logs at simulated time from 0), with mcap-ros2-support.
    Its decoder is pure Python: asking only for what a test reads saves most of the time."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory
    out = defaultdict(list)
    end = None if until_s is None else int(until_s * 1e9)
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        for _schema, channel, _message, msg in reader.iter_decoded_messages(topics=topics, ending_before=end):
            out[channel.topic].append(msg)
    return out


def physics(path):
    """The decoded vessel and rope states as arrays, keyed by topic and step."""
    msgs = decoded(path, ["/tug/odom", "/barge/odom", "/towline/state"])
    values = {}
    for v in ("tug", "barge"):
        values[v] = np.array([[m.pose.pose.position.x, m.pose.pose.position.y, m.pose.pose.orientation.z,
                               m.pose.pose.orientation.w, m.twist.twist.linear.x, m.twist.twist.linear.y,
                               m.twist.twist.angular.z] for m in msgs[f"/{v}/odom"]])
    rope = msgs["/towline/state"]
    values["rope_positions"] = np.array([[(p.position.x, p.position.y, p.position.z) for p in m.element_poses]
                                         for m in rope])
    values["rope_tensions"] = np.array([list(m.connection_tensions) for m in rope])
    values["steps"] = np.array([m.step for m in rope])
    return values


@pytest.fixture(scope="module")
def recordings(tmp_path_factory):
    base = tmp_path_factory.mktemp("rec")
    paths = {}
    with reserved_domain():
        for name, extra in (("first", ()), ("second", ()), ("one_process", ("--layout", "one_process")),
                            ("groups", ("--layout", "groups", "--groups", "2"))):
            paths[name] = base / f"{name}.mcap"
            run(paths[name], *extra)
    return paths


def test_rosbags_reads_every_topic_with_the_predicted_counts(recordings):
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore
    from pathlib import Path
    with AnyReader([Path(recordings["first"])], default_typestore=get_typestore(Stores.ROS2_JAZZY)) as reader:
        counts = {c.topic: c.msgcount for c in reader.connections}
        for per_step in ("/tug/odom", "/tug/attachments", "/tug/status", "/barge/odom", "/barge/attachments",
                         "/barge/status", "/towline/state", "/towline/end_a/wrench",
                         "/towline/end_b/wrench"):
            assert counts[per_step] == STEPS + 1, per_step  # steps 0..N
        assert counts["/sim/step"] == STEPS and counts["/clock"] == STEPS
        # markers at 10 Hz: every 5th step, at the node's own phase (41 with phase 0, else 40)
        assert counts["/towline/markers"] in (STEPS // 5, STEPS // 5 + 1)
        decoded_any = 0
        for conn, _t, raw in reader.messages():
            reader.deserialize(raw, conn.msgtype)
            decoded_any += 1
        assert decoded_any == sum(counts.values())


def test_mcap_ros2_support_decodes_every_message(recordings):
    msgs = decoded(recordings["first"])
    assert len(msgs["/towline/state"]) == STEPS + 1
    done = {(m.node, m.step) for m in msgs["/sim/step_done"]}
    assert done == {(n, k) for n in ("/tug/vessel", "/barge/vessel", "/towline/rope") for k in range(STEPS + 1)}
    assert [m.step for m in msgs["/towline/state"]] == list(range(STEPS + 1))


def test_repeated_runs_and_every_layout_give_identical_physics(recordings):
    """Every node its own process, all in the runner's, and the tow split over the runner and a
    node group process (issue 34): the same messages, bit for bit."""
    first = physics(recordings["first"])
    assert np.all(first["rope_tensions"][-1] > 0)  # a real tow, not a trivial state
    # the same messages on every topic; a node repeats its ready answer (StepDone 0) until step 0
    # comes, as many times as the start-up takes: those are compared as (node, step) pairs
    counts = {name: _topic_counts(recordings[name]) for name in ("first", "one_process", "groups")}
    for c in counts.values():
        c.pop("/sim/step_done")
    assert counts["groups"] == counts["first"] == counts["one_process"]
    done = {name: {(m.node, m.step) for m in decoded(recordings[name], ["/sim/step_done"])["/sim/step_done"]}
            for name in ("first", "groups")}
    assert done["groups"] == done["first"]
    for other in ("second", "one_process", "groups"):
        again = physics(recordings[other])
        for key in first:
            np.testing.assert_array_equal(first[key], again[key], err_msg=f"{other}: {key}")


def _topic_counts(path):
    from mcap.reader import make_reader
    with open(path, "rb") as f:
        summary = make_reader(f).get_summary()
    return {summary.channels[c].topic: n for c, n in summary.statistics.channel_message_counts.items()}


def _node_pid(pattern, domain):
    """pid of the node process of this test's domain whose command line matches pattern."""
    for pid in subprocess.run(["pgrep", "-f", pattern], capture_output=True, text=True).stdout.split():
        try:
            env = open(f"/proc/{pid}/environ", "rb").read().decode(errors="replace").split("\0")
        except OSError:
            continue
        if f"ROS_DOMAIN_ID={domain}" in env:
            return int(pid)
    return None


def _long_tow(tmp_path):
    """The tow lasting an hour (the scenario's own 120 s cap --duration)."""
    import yaml
    from scenario_format.particulars import scenario_path
    path = tmp_path / "seed000_straight_tow_5kn.yaml"
    path.write_text(yaml.safe_dump(dict(yaml.safe_load(open(scenario_path(SCENARIO))), duration=3600.0)))
    return str(path)


def test_killed_node_stops_the_run_naming_it(tmp_path, ros_domain):
    from mcap.reader import make_reader
    out = tmp_path / "killed.mcap"
    proc = subprocess.Popen([executable_path("scenario_runner", "run_scenario"), _long_tow(tmp_path), "--duration", "600",
                             "--output", str(out), "--quiet", "--layout", "processes"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    victim = None
    deadline = time.monotonic() + 120
    while victim is None and time.monotonic() < deadline:
        victim = _node_pid("__ns:=/barge", os.environ["ROS_DOMAIN_ID"])
        time.sleep(0.2)
    assert victim, "barge node never started"
    # kill it once the run is going: the rope has been laid out between the vessels' step-0
    # attachments (so there is something in the recording), however slow the start-up
    rope_log = tmp_path / "killed_logs" / "towline_rope.log"  # logs follow the recording's name
    while time.monotonic() < deadline and not (rope_log.exists() and "laid out" in rope_log.read_text()):
        time.sleep(0.2)
    time.sleep(1.0)
    os.kill(victim, signal.SIGKILL)
    stdout, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 3
    assert "/barge/vessel" in stderr and "died" in stderr
    with open(out, "rb") as f:  # the partial recording is finalised and readable
        summary = make_reader(f).get_summary()
    assert summary.statistics.message_count > 0



def test_killed_group_process_stops_the_run_naming_every_node_it_carried(tmp_path, ros_domain):
    """--layout groups --groups 2 puts the barge and the towline in one node_group process (the
    tug in the runner's own): killed mid-run, the run ends with exit 3 naming both its nodes."""
    from mcap.reader import make_reader
    out = tmp_path / "killed_group.mcap"
    proc = subprocess.Popen([executable_path("scenario_runner", "run_scenario"), _long_tow(tmp_path), "--duration", "600",
                             "--output", str(out), "--quiet", "--layout", "groups", "--groups", "2"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    victim = None
    deadline = time.monotonic() + 120
    while victim is None and time.monotonic() < deadline and proc.poll() is None:
        victim = _node_pid("node_group", os.environ["ROS_DOMAIN_ID"])
        time.sleep(0.2)
    assert victim, "the node group process never started"
    group_log = tmp_path / "killed_group_logs" / "node_group_0.log"   # the first group started
    while time.monotonic() < deadline and not (group_log.exists() and "laid out" in group_log.read_text()):
        time.sleep(0.2)
    time.sleep(1.0)
    os.kill(victim, signal.SIGKILL)
    stdout, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 3, stderr
    assert "died" in stderr and "/barge/vessel" in stderr and "/towline/rope" in stderr, stderr
    with open(out, "rb") as f:  # the partial recording is finalised and readable
        summary = make_reader(f).get_summary()
    assert summary.statistics.message_count > 0

def test_ctrl_c_leaves_a_finalised_recording_and_no_nodes(tmp_path, ros_domain, rclpy_context):
    from mcap.reader import make_reader
    from rclpy.node import Node
    from rosgraph_msgs.msg import Clock
    from conftest import spin_until
    out = tmp_path / "interrupted.mcap"
    node = Node("clock_watch", context=rclpy_context)
    clock = [0.0]
    node.create_subscription(Clock, "/clock", lambda m: clock.__setitem__(0, m.clock.sec + m.clock.nanosec * 1e-9),
                             10)
    proc = subprocess.Popen([executable_path("scenario_runner", "run_scenario"), _long_tow(tmp_path), "--duration", "600",
                             "--output", str(out), "--quiet", "--layout", "processes"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    # interrupted once it steps (a cold numba cache can hold the start for many seconds)
    assert spin_until(node, lambda: clock[0] >= 1.0 or proc.poll() is not None, 180.0), "the run never stepped"
    assert proc.poll() is None, proc.communicate()
    proc.send_signal(signal.SIGINT)
    _, stderr = proc.communicate(timeout=60)
    assert proc.returncode == 130, stderr
    assert "interrupted" in stderr
    with open(out, "rb") as f:
        summary = make_reader(f).get_summary()  # the summary section exists: the file was finalised
    assert summary.statistics.message_count > 0
    assert _node_pid("__ns:=/towline", os.environ["ROS_DOMAIN_ID"]) is None  # nodes were stopped


def test_realtime_mode_is_paced_and_reports_overruns(tmp_path, ros_domain):
    import yaml
    from ament_index_python.packages import get_package_share_directory
    src = f"{get_package_share_directory('scenario_runner')}/scenarios/seed004_turn.yaml"
    sc = dict(yaml.safe_load(open(src)), name="paced", mode="realtime", duration=3.0)
    path = tmp_path / "paced.yaml"
    path.write_text(yaml.safe_dump(sc))
    t0 = time.monotonic()
    proc = subprocess.run([executable_path("scenario_runner", "run_scenario"), str(path), "--output",
                           str(tmp_path / "paced.mcap"), "--quiet"], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert "overrun step(s)" in proc.stdout and "lateness" in proc.stdout
    assert "step 0 (before the clock) took" in proc.stdout
    # Paced: the run cannot be faster than the simulated time (a lower bound, safe on a busy machine).
    assert time.monotonic() - t0 >= 3.0
    assert "3.0 s simulated in" in proc.stdout
    wall = float(proc.stdout.split("simulated in")[1].split("s wall")[0])
    assert wall >= 3.0 - 1.0 / 50.0
