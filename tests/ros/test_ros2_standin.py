"""The ros2cli stand-in (scripts/ros2 -> ros2cli_standin.graph_verbs): `ros2 topic list/info/
echo/hz`, `ros2 node list` and `ros2 param list/get/set` against a running vessel node, each run
as its own process in this test's domain, checked against what an in-test rclpy node sees
itself (its graph, the messages it receives, its own parameters).

Fast DDS may take up to its 3 s announcement period to discover a running participant, so the
stand-in's lists and counts wait 3.5 s (~4 s a call); independent calls run side by side to keep
this file short.
"""
import array
import math
import os
import signal
import subprocess
import threading
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest
import yaml

from conftest import spin_until

pytestmark = [pytest.mark.ros, pytest.mark.timeout(120)]

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
_INSTALLED = os.path.join(ROOT, ".venv", "bin", "ros2")  # ensure_env.sh links it to scripts/ros2
ROS2 = _INSTALLED if os.path.exists(_INSTALLED) else os.path.join(ROOT, "scripts", "ros2")
RATE = 50.0  # the vessel node's default exchange_rate
TUG = ["--ros-args", "-r", "__ns:=/tug", "-r", "__node:=vessel", "-p", "ship_file:=harbour_tug.yaml"]
VESSEL_TOPICS = {"/tug/odom", "/tug/status", "/tug/attachments", "/tug/command", "/scenario/events"}


def ros2(*argv, timeout=30.0):
    """CompletedProcess of one `ros2 ...` in this test's domain (os.environ holds it)."""
    return ros2_many(list(argv), timeout=timeout)[0]


def ros2_many(*commands, timeout=30.0, parallel=5):
    """Several `ros2 ...`, up to `parallel` side by side; their CompletedProcesses in order."""
    def run(argv):
        try:
            return subprocess.run([ROS2, *argv], capture_output=True, text=True, timeout=timeout)
        except subprocess.TimeoutExpired as exc:
            return subprocess.CompletedProcess([ROS2, *argv], "timeout", exc.stdout, exc.stderr)

    with ThreadPoolExecutor(max_workers=parallel) as pool:
        return list(pool.map(run, commands))


def _show(r) -> str:
    first = f"\n(a second call; the first gave: {r.first_attempt})" if hasattr(r, "first_attempt") else ""
    return f"{' '.join(r.args[1:])} -> rc {r.returncode}\n--- stdout\n{r.stdout}--- stderr\n{r.stderr}{first}"


def complete(result, good):
    """A list or count is only as complete as discovery: the stand-in waits 3.5 s, past Fast DDS's
    3 s announcement period (discovery took 0.03-2.9 s in 30 trials on a quiet machine), but a
    busy machine can be later still. One more call, then, before an answer counts as wrong."""
    if good(result):
        return result
    again = ros2(*result.args[1:])
    again.first_attempt = _show(result)
    return again


@pytest.fixture
def vessel_and_observer(start_node, rclpy_context):
    """A free-running vessel node, and an in-test node that has discovered its topics."""
    from rclpy.node import Node
    vessel = start_node("tug_dynamics", "vessel_node", *TUG)
    node = Node("standin_observer", context=rclpy_context)
    ok = spin_until(node, lambda: VESSEL_TOPICS <= {n for n, _ in node.get_topic_names_and_types()}, 60)
    assert ok, vessel.log()
    yield vessel, node
    node.destroy_node()


def _plain(value):
    """A message as nested dicts and lists of Python numbers and strings (what YAML gives back)."""
    if hasattr(value, "get_fields_and_field_types"):
        return {f: _plain(getattr(value, f)) for f in value.get_fields_and_field_types()}
    if isinstance(value, (list, tuple, array.array, np.ndarray)):
        return [_plain(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value


def _leaves(tree):
    if isinstance(tree, dict):
        for v in tree.values():
            yield from _leaves(v)
    elif isinstance(tree, list):
        for v in tree:
            yield from _leaves(v)
    else:
        yield tree


def test_topic_list_info_and_node_list_show_the_graph(vessel_and_observer):
    """topic list -t and node list equal the in-test node's view of the graph; topic info counts
    publishers and subscriptions, and one more subscription once the in-test node adds one."""
    from nav_msgs.msg import Odometry
    from rclpy.topic_or_service_is_hidden import topic_or_service_is_hidden
    vessel, node = vessel_and_observer
    listed, nodes, info, unknown = ros2_many(["topic", "list", "-t"], ["node", "list"],
                                             ["topic", "info", "/tug/odom"], ["topic", "info", "/tug/nope"])
    for r in (listed, nodes, info):
        assert r.returncode == 0 and not r.stderr, _show(r)

    truth = sorted((n, t) for n, t in node.get_topic_names_and_types() if not topic_or_service_is_hidden(n))
    expected = [f"{n} [{', '.join(t)}]" for n, t in truth]
    listed = complete(listed, lambda r: r.stdout.splitlines() == expected)
    assert listed.stdout.splitlines() == expected, _show(listed)
    assert "/tug/odom [nav_msgs/msg/Odometry]" in expected

    names = sorted(ns.rstrip("/") + "/" + n for n, ns in node.get_node_names_and_namespaces() if not n.startswith("_"))
    nodes = complete(nodes, lambda r: r.stdout.splitlines() == names)
    assert nodes.stdout.splitlines() == names, _show(nodes)
    assert "/tug/vessel" in names and "/standin_observer" in names
    assert "_ros2cli" not in nodes.stdout

    subscriptions = node.count_subscribers("/tug/odom")
    expected = (f"Type: nav_msgs/msg/Odometry\nPublisher count: {node.count_publishers('/tug/odom')}\n"
                f"Subscription count: {subscriptions}\n")
    info = complete(info, lambda r: r.stdout == expected)
    assert info.stdout == expected, _show(info)
    assert node.count_publishers("/tug/odom") == 1
    assert unknown.returncode == 1 and "/tug/nope" in unknown.stderr and not unknown.stdout, _show(unknown)

    node.create_subscription(Odometry, "/tug/odom", lambda msg: None, 10)
    more = complete(ros2("topic", "info", "/tug/odom", "-v"),
                    lambda r: f"Subscription count: {subscriptions + 1}\n" in r.stdout)
    assert more.returncode == 0, _show(more)
    assert f"Subscription count: {subscriptions + 1}\n" in more.stdout, _show(more)
    assert "Publisher count: 1\n" in more.stdout
    assert "Node name: vessel\nNode namespace: /tug\n" in more.stdout  # the publisher, -v
    assert "Node name: standin_observer\n" in more.stdout and "Endpoint type: SUBSCRIPTION" in more.stdout


def test_echo_prints_the_message_a_subscriber_receives(vessel_and_observer):
    """echo --once: YAML that parses into exactly the message (same stamp) the in-test
    subscriber received; --no-arr abbreviates arrays as ros2cli does; an unknown topic fails
    with ros2cli's warning; Ctrl-C ends a running echo quietly."""
    from nav_msgs.msg import Odometry
    from sim_plumbing import ros_common as rc
    vessel, node = vessel_and_observer
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    received = {}
    # deep enough to hold every message of the seconds this node does not spin (the ros2 calls)
    deep = QoSProfile(depth=5000, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    node.create_subscription(Odometry, "/tug/odom", lambda m: received.setdefault(rc.time_to_ns(m.header.stamp), m),
                             deep)
    assert spin_until(node, lambda: received, 30), vessel.log()
    running = subprocess.Popen([ROS2, "topic", "echo", "/tug/status"], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True)
    once, no_arr, best_effort, unknown = ros2_many(
        ["topic", "echo", "/tug/odom", "--once"], ["topic", "echo", "/tug/odom", "--once", "--no-arr"],
        ["topic", "echo", "tug/odom", "--once", "--qos-reliability", "best_effort", "--qos-durability", "volatile"],
        ["topic", "echo", "/tug/nope", "--once"])
    for r in (once, no_arr, best_effort):
        assert r.returncode == 0 and not r.stderr and r.stdout.endswith("\n---\n"), _show(r)
        assert r.stdout.count("---\n") == 1, _show(r)

    echoed = yaml.safe_load(once.stdout[:-len("---\n")])
    stamp = echoed["header"]["stamp"]["sec"] * 1_000_000_000 + echoed["header"]["stamp"]["nanosec"]
    assert spin_until(node, lambda: stamp in received, 10), f"stamp {stamp} never received here"
    assert echoed == _plain(received[stamp])
    numbers = [v for v in _leaves(echoed) if not isinstance(v, str)]
    assert len(numbers) > 80 and all(isinstance(v, (int, float)) and math.isfinite(v) for v in numbers)
    assert echoed["header"]["frame_id"] == "map" and echoed["child_frame_id"] == "tug/base_link"

    abbreviated = yaml.safe_load(no_arr.stdout[:-len("---\n")])
    assert abbreviated["pose"]["covariance"] == "<array type: double[36]>"
    assert abbreviated["pose"]["pose"].keys() == echoed["pose"]["pose"].keys()
    assert yaml.safe_load(best_effort.stdout[:-len("---\n")]).keys() == echoed.keys()

    assert unknown.returncode == 1, _show(unknown)
    assert unknown.stdout == "WARNING: topic [/tug/nope] does not appear to be published yet\n", _show(unknown)
    assert "/tug/nope" in unknown.stderr and "Traceback" not in unknown.stderr

    time.sleep(1.0)  # running for 5 s and more now (the unknown topic took 4 s): discovered, echoing
    running.send_signal(signal.SIGINT)
    out, err = running.communicate(timeout=10)
    assert running.returncode == 0 and "Traceback" not in err, f"rc {running.returncode}\n{err}"
    docs = [d for d in out.split("---\n") if d.strip()]
    assert docs and all(yaml.safe_load(d)["header"]["frame_id"] == "tug/base_link" for d in docs), out[-2000:]


def test_hz_reports_the_exchange_rate(vessel_and_observer):
    """hz: ros2cli's two-line report once a second, the average within 10 % of the node's 50 Hz
    (measured 49.96-50.09 here), --window bounds the window; Ctrl-C ends it quietly (exit 0)."""
    import re
    vessel, node = vessel_and_observer
    procs = [subprocess.Popen([ROS2, "topic", "hz", "/tug/odom", *extra], stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True) for extra in ([], ["--window", "20"])]
    pattern = re.compile(r"average rate: (\d+\.\d{3})\n\tmin: (\d+\.\d{3})s max: (\d+\.\d{3})s "
                         r"std dev: (\d+\.\d{5})s window: (\d+)\n")
    try:
        time.sleep(8.0)  # discovery (up to ~3 s on localhost), then a report each second
    finally:
        for p in procs:
            p.send_signal(signal.SIGINT)
        results = [p.communicate(timeout=10) for p in procs]
    for p, (out, err) in zip(procs, results):
        assert p.returncode == 0 and not err, f"rc {p.returncode}\n{out}\n{err}"
    reports = [pattern.findall(out) for out, _ in results]
    assert all(reports), results
    assert "".join(m.group(0) for m in pattern.finditer(results[0][0])) == results[0][0], results[0][0]
    rate, lo, hi, std, window = reports[0][-1]
    # a wall-clock rate on purpose: `ros2 topic hz` reports the arrival rate of a free-running
    # node's wall-clock timer (its window averages over a loaded host's stalls)
    assert abs(float(rate) - RATE) < 0.10 * RATE, results[0][0]
    # min and max are printed to 1 ms: the mean period may round onto either of them
    assert float(lo) - 0.0005 <= 1.0 / float(rate) <= float(hi) + 0.0005 and int(window) > 2 * RATE
    assert {int(r[4]) for r in reports[1]} <= set(range(1, 21)) and int(reports[1][-1][4]) == 20, results[1][0]


@pytest.fixture
def parameter_node(vessel_and_observer, rclpy_context):
    """An in-test node with parameters of every kind, spun in a thread with the observer (so that
    the services of both answer)."""
    from rcl_interfaces.msg import FloatingPointRange, ParameterDescriptor
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.node import Node
    node = Node("standin_params", context=rclpy_context)
    node.declare_parameter("ratio", 0.5)
    node.declare_parameter("count", 3)
    node.declare_parameter("label", "abc")
    node.declare_parameter("enabled", False)
    node.declare_parameter("flags", [1, 2])
    node.declare_parameter("names", ["a", "b"])
    node.declare_parameter("bounded", 1.0, ParameterDescriptor(floating_point_range=[
        FloatingPointRange(from_value=0.0, to_value=2.0, step=0.0)]))
    executor = SingleThreadedExecutor(context=rclpy_context)
    executor.add_node(node)
    executor.add_node(vessel_and_observer[1])
    stop = threading.Event()

    def spin():
        while not stop.is_set():
            executor.spin_once(timeout_sec=0.05)

    thread = threading.Thread(target=spin, daemon=True)
    thread.start()
    yield node
    stop.set()
    thread.join(5)
    executor.remove_node(node)
    executor.remove_node(vessel_and_observer[1])
    node.destroy_node()


def test_param_list_get_set(vessel_and_observer, parameter_node):
    """get prints ros2cli's labels; set parses values as YAML and the node really has the new
    value; a value outside the declared range, or of another type, is refused with the node's
    reason; unknown nodes and parameters fail naming them."""
    vessel, _ = vessel_and_observer
    node = parameter_node
    (listed, rate, ship, lockstep, refused, vessel_fixed, no_node, no_param, set_ratio, set_flags, set_label,
     set_enabled, wrong_type, out_of_range) = ros2_many(
        ["param", "list", "/tug/vessel"], ["param", "get", "/tug/vessel", "exchange_rate"],
        ["param", "get", "tug/vessel", "ship_file"], ["param", "get", "/tug/vessel", "lockstep"],
        ["param", "set", "/tug/vessel", "exchange_rate", "5000.0"],
        ["param", "set", "/tug/vessel", "exchange_rate", "40.0"],
        ["param", "set", "/tug/nobody", "exchange_rate", "40.0"], ["param", "get", "/tug/vessel", "no_such"],
        ["param", "set", "/standin_params", "ratio", "0.25"], ["param", "set", "/standin_params", "flags", "[4, 5, 6]"],
        ["param", "set", "/standin_params", "label", "hello world"],
        ["param", "set", "/standin_params", "enabled", "true"],
        ["param", "set", "/standin_params", "count", "2.5"],
        ["param", "set", "/standin_params", "bounded", "3.0"])

    assert listed.returncode == 0 and "  exchange_rate\n" in listed.stdout and "  ship_file\n" in listed.stdout
    assert all(line.startswith("  ") for line in listed.stdout.splitlines()), _show(listed)
    assert (rate.returncode, rate.stdout) == (0, "Double value is: 50.0\n"), _show(rate)
    assert ship.stdout == "String value is: harbour_tug.yaml\n", _show(ship)
    assert lockstep.stdout == "Boolean value is: False\n", _show(lockstep)

    assert refused.returncode == 1 and not refused.stdout, _show(refused)
    assert refused.stderr.startswith("Setting parameter failed: ") and "exchange_rate" in refused.stderr
    assert "out of range" in refused.stderr and "1000.0" in refused.stderr, _show(refused)
    assert vessel_fixed.returncode == 1 and "fixed at start-up" in vessel_fixed.stderr, _show(vessel_fixed)
    assert no_node.returncode == 1 and "/tug/nobody" in no_node.stderr and "not found" in no_node.stderr, \
        _show(no_node)
    assert no_param.returncode == 1 and "no_such" in no_param.stderr, _show(no_param)

    for r in (set_ratio, set_flags, set_label, set_enabled):
        assert (r.returncode, r.stdout, r.stderr) == (0, "Set parameter successful\n", ""), _show(r)
    assert node.get_parameter("ratio").value == 0.25
    assert list(node.get_parameter("flags").value) == [4, 5, 6]
    assert node.get_parameter("label").value == "hello world"
    assert node.get_parameter("enabled").value is True
    assert wrong_type.returncode == 1 and "Setting parameter failed" in wrong_type.stderr, _show(wrong_type)
    assert node.get_parameter("count").value == 3
    assert out_of_range.returncode == 1 and "out of range" in out_of_range.stderr, _show(out_of_range)
    assert node.get_parameter("bounded").value == 1.0

    got = ros2_many(*(["param", "get", "/standin_params", name]
                      for name in ("ratio", "count", "label", "enabled", "flags", "names")),
                    ["param", "list"])
    assert [r.stdout for r in got[:-1]] == [
        "Double value is: 0.25\n", "Integer value is: 3\n", "String value is: hello world\n",
        "Boolean value is: True\n", "Integer values are: [4, 5, 6]\n", "String values are: ['a', 'b']\n"], \
        "\n".join(_show(r) for r in got)
    # every node, each "<node>:" then its names; ros2cli's order: by node name, then namespace
    everything = complete(got[-1], lambda r: r.stdout.count(":\n") == 3)
    assert everything.returncode == 0 and not everything.stderr, _show(everything)
    headers = [line for line in everything.stdout.splitlines() if not line.startswith("  ")]
    assert headers == ["/standin_observer:", "/standin_params:", "/tug/vessel:"], _show(everything)
    assert "  bounded\n" in everything.stdout and "  exchange_rate\n" in everything.stdout
