"""The live view of a paced run (run_scenario --live), seen by WebSocket clients speaking the
Foxglove protocol (live_view.probe, on the `websockets` package) and by an outside DDS observer:

- the advertised channels are every contract topic plus /tf, /tf_static and the vessel scenes,
  CDR with ros2msg schemas equal to the recorder's; a message of every topic decodes with rclpy;
- every /tf transform equals the odometry pose of its step, exactly; /tf_static holds every
  attachment of the ship files (read here with yaml);
- bad input (malformed bytes, NaN, an unknown anchor order, out-of-range values, topics clients
  may not publish, a wrong schema, a flood of 10,000 messages) is refused or clamped and logged,
  with ten viewers connected, and the run finishes with every step recorded.
"""
import ast
import asyncio
import math
import re
import socket
import subprocess
import threading
import time

import pytest
import yaml

from conftest import executable_path, free_port
from test_recording import decoded

pytestmark = [pytest.mark.ros, pytest.mark.timeout(300)]

# the viewers watch the run's first 10 s of sim time; the 10 s after are the margin for the
# attacker's inputs and flood, which must reach a run still going when the test's one event loop
# (ten viewers and the flood) is starved on loaded cores (with 2 s, CI saw the run end first)
DURATION = 20.0
WATCH_UNTIL_S = DURATION - 10.0
LIVE_RATE_HZ = 20.0  # the live view's default sender rate (live_view_node parameter `rate`)
FLOOD = 10_000


def _free_port() -> int:
    return free_port()


def _expected_topics(sc):
    topics = {"/clock", "/sim/step", "/sim/step_done", "/scenario/events", "/tf", "/tf_static"}
    for v in sc["vessels"]:
        topics |= {f"/{v['name']}/{t}" for t in ("odom", "attachments", "status", "command", "markers")}
    for r in sc["ropes"]:
        topics |= {f"/{r['name']}/{t}" for t in ("state", "markers", "end_a/wrench", "end_b/wrench", "winch")}
    return topics


def _msg_class(full_type):
    import importlib
    pkg, sub, name = full_type.split("/")
    return getattr(importlib.import_module(f"{pkg}.{sub}"), name)


class Observer:
    """Outside DDS subscriber of /tf, /tf_static and the odometry (keep-all)."""

    def __init__(self, context, vessels):
        from nav_msgs.msg import Odometry
        from rclpy.node import Node
        from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
        from tf2_msgs.msg import TFMessage
        self.node = Node("observer", context=context)
        keep_all = dict(history=HistoryPolicy.KEEP_ALL, reliability=ReliabilityPolicy.RELIABLE)
        self.tf, self.tf_static, self.odom = [], [], {v: [] for v in vessels}
        self.node.create_subscription(TFMessage, "/tf", self.tf.append,
                                      QoSProfile(durability=DurabilityPolicy.VOLATILE, **keep_all))
        latched = QoSProfile(durability=DurabilityPolicy.TRANSIENT_LOCAL, **keep_all)
        self.node.create_subscription(TFMessage, "/tf_static", self.tf_static.append, latched)
        for v in vessels:
            self.node.create_subscription(Odometry, f"/{v}/odom", self.odom[v].append, latched)
        from rclpy.executors import SingleThreadedExecutor
        self.executor = SingleThreadedExecutor(context=context)
        self.executor.add_node(self.node)
        self.stop = False
        self.thread = threading.Thread(target=self._spin, daemon=True)
        self.thread.start()

    def _spin(self):
        while not self.stop:
            self.executor.spin_once(timeout_sec=0.05)

    def close(self):
        self.stop = True
        self.thread.join(5)
        self.executor.shutdown()
        self.node.destroy_node()


def _odom_log_times_s(viewer):
    return [t * 1e-9 for t, _ in viewer.messages.get("/tug/odom", [])]


async def _watch_until_sim_time(viewer, until_s, timeout):
    """Read until the viewer has seen the run's odometry at sim time until_s (or timeout s)."""
    loop = asyncio.get_running_loop()
    end = loop.time() + timeout
    while loop.time() < end and max(_odom_log_times_s(viewer), default=-1.0) < until_s:
        await viewer.receive(max(0.001, min(0.1, end - loop.time())))


async def _clients(port, expected, report):
    from rclpy.serialization import serialize_message
    from live_view.probe import Probe
    from tug_msgs.msg import VesselCommand
    url = f"ws://127.0.0.1:{port}"
    viewers = [Probe(url) for _ in range(10)]
    for v in viewers:
        await v.connect(timeout=120)
    for v in viewers:
        await v.wait_for_topics(expected, timeout=60)
        await v.subscribe_all()
    # the viewers read all along, as a browser does, while a client misbehaves: until the run's
    # own clock reaches WATCH_UNTIL_S (its start-up after the server listens varies by host)
    watching = [asyncio.create_task(_watch_until_sim_time(v, WATCH_UNTIL_S, timeout=150.0)) for v in viewers]
    attacker = Probe(url)
    await attacker.connect()
    await attacker.advertise(1, "/tug/command", "cdr", "tug_msgs/msg/VesselCommand")
    await attacker.advertise(2, "/tug/odom", "cdr", "nav_msgs/msg/Odometry")          # may not publish
    await attacker.advertise(3, "/towline/winch", "json", "tug_msgs/msg/WinchCommand")
    await attacker.advertise(4, "/barge/command", "cdr", "std_msgs/msg/String")       # wrong schema
    await attacker.advertise(5, "/barge/command", "cdr", "tug_msgs/msg/VesselCommand")
    await attacker.advertise(6, "/sim/step", "cdr", "tug_msgs/msg/SimStep")           # may not publish

    def command(engine, steering=0.0, anchor=0):
        return serialize_message(VesselCommand(engine_order=engine, steering_angle=steering, anchor=anchor))
    bad = [(1, b"\x00\x01"), (1, b"garbage that is not CDR"), (1, command(float("nan"))),
           (1, command(0.2, float("inf"))), (1, command(0.2, 0.0, 7)), (2, b"\x00\x01\x00\x00" + bytes(400)),
           (3, b'{"payout_rate": NaN}'), (3, b'{"payout_rate": 0.0, "speed": 3}'), (3, b"[1, 2]"),
           (4, command(0.0)), (6, bytes(64)), (9, command(0.0))]                        # 9: never advertised
    good = [(1, command(5.0, 0.0)), (3, b'{"payout_rate": 0.0}'), (5, command(0.0))]  # 5.0 is clamped to 1.0
    for cid, payload in bad + good:
        await attacker.publish(cid, payload)
        await asyncio.sleep(0.1)  # within the per-client input rate
    await attacker.receive(0.5)
    t0 = time.monotonic()
    for i in range(FLOOD):
        await attacker.publish(1, command(0.5))
        if i % 1000 == 0:
            await asyncio.sleep(0)
    report["flood_s"] = time.monotonic() - t0
    await asyncio.gather(*watching)
    report["viewers"] = viewers
    report["attacker_status"] = attacker.status
    for p in viewers + [attacker]:
        await p.close()


def _check_sampled(viewer, exchange_rate):
    """In order, new steps only after step 0 (whose state is sent at start-up and again when
    stepped), at most one a step; the count judged against the run's own span and the sender's
    rate (paced: sim time runs with the wall clock), with a factor 10 of margin: foxglove-sdk
    drops what a slow client's queue cannot hold, and these ten viewers and a flooding client
    share one event loop with the test on two loaded cores. Judged by the messages' own stamps:
    the log time is the live view's /clock at its send round, which a step's odometry can
    overtake (then two steps go out in rounds of one log time)."""
    from nav_msgs.msg import Odometry
    from rclpy.serialization import deserialize_message
    stamps = [deserialize_message(payload, Odometry).header.stamp for _, payload in viewer.messages["/tug/odom"]]
    times = [s.sec + s.nanosec * 1e-9 for s in stamps]
    stepped = [t for t in times if t > 0.0]
    assert times[-1] >= WATCH_UNTIL_S and times == sorted(times), times
    assert all(b > a for a, b in zip(stepped, stepped[1:])), [(i, a, b) for i, (a, b) in enumerate(zip(stepped, stepped[1:])) if b <= a]
    span = stepped[-1] - stepped[0]
    assert span * LIVE_RATE_HZ / 10 <= len(stepped) - 1 <= span * exchange_rate + 1e-9, (len(stepped), span, stepped)


def _check_frames(observer, sc, vessels, steps):
    """/tf equals the odometry of its step, exactly; /tf_static holds every attachment. (Counts
    with margin: the writers keep the last 50 odometry and 100 /tf messages, tf2_ros's QoS, so
    this observer, whose process also runs ten viewers and a flood, may lose some when starved
    on loaded cores; the recording, checked below, holds every step.)"""
    from ament_index_python.packages import get_package_share_directory
    for v in vessels:
        odom = {(m.header.stamp.sec, m.header.stamp.nanosec): m.pose.pose for m in observer.odom[v]}
        assert steps / 2 <= len(odom) <= steps + 1, len(odom)
        tf = {(t.header.stamp.sec, t.header.stamp.nanosec): t for m in observer.tf for t in m.transforms
              if t.child_frame_id == f"{v}/base_link"}
        both = set(tf) & set(odom)
        assert len(both) >= steps / 2, (len(tf), len(both))
        for stamp in both:
            t = tf[stamp]
            assert t.header.frame_id == "map"
            p, q = odom[stamp].position, odom[stamp].orientation
            tr, rot = t.transform.translation, t.transform.rotation
            assert (tr.x, tr.y, tr.z, rot.x, rot.y, rot.z, rot.w) == (p.x, p.y, p.z, q.x, q.y, q.z, q.w)
    ship_dir = get_package_share_directory("tug_dynamics") + "/ships/"
    static = {(t.header.frame_id, t.child_frame_id): t.transform for m in observer.tf_static for t in m.transforms}
    for v in sc["vessels"]:
        for name, xyz in yaml.safe_load(open(ship_dir + v["ship_file"]))["attachments"].items():
            tr = static[(f"{v['name']}/base_link", f"{v['name']}/{name}")]
            assert (tr.translation.x, tr.translation.y, tr.translation.z) == tuple(float(c) for c in xyz)
            assert (tr.rotation.x, tr.rotation.y, tr.rotation.z, tr.rotation.w) == (0.0, 0.0, 0.0, 1.0)


def test_live_view_of_a_paced_run(tmp_path, ros_domain, rclpy_context, full_domain_check):
    # full_domain_check: the runner's 3 s of discovery before its nodes start is what lets this
    # test's own observer match them before step 0 (it checks every step's odometry)
    from ament_index_python.packages import get_package_share_directory
    from rclpy.serialization import deserialize_message
    from recording.recorder import message_definition
    share = get_package_share_directory("scenario_runner")
    sc = dict(yaml.safe_load(open(f"{share}/scenarios/default_demo.yaml")), name="live", mode="realtime",
              duration=DURATION)
    sc["events"] = [e for e in sc["events"] if e["time"] < DURATION]
    path = tmp_path / "live.yaml"
    path.write_text(yaml.safe_dump(sc))
    out = tmp_path / "live.mcap"
    port = _free_port()
    vessels = [v["name"] for v in sc["vessels"]]
    observer = Observer(rclpy_context, vessels)
    proc = subprocess.Popen([executable_path("scenario_runner", "run_scenario"), str(path), "--output", str(out),
                             "--quiet", "--live", "--live-port", str(port)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    expected = _expected_topics(sc)
    report = {}
    try:
        asyncio.run(_clients(port, expected, report))
        stdout, stderr = proc.communicate(timeout=200)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
        time.sleep(0.5)
        observer.close()
    print(stdout, stderr[-3000:])
    assert proc.returncode == 0, stdout + stderr

    # channels and schemas
    viewers = report["viewers"]
    channels = {c["topic"]: c for c in viewers[0].channels.values()}
    assert expected <= set(channels), sorted(expected - set(channels))
    for topic in expected:
        c = channels[topic]
        assert c["encoding"] == "cdr" and c["schemaEncoding"] == "ros2msg", c
        assert c["schema"] == message_definition(c["schemaName"]), topic
    # a message of every topic, decoded as its type
    for v in viewers:
        got = set(v.messages)
        assert expected <= got, sorted(expected - got)
    for topic in expected:
        cls = _msg_class(channels[topic]["schemaName"])
        for _, payload in viewers[0].messages[topic]:
            deserialize_message(payload, cls)
    _check_sampled(viewers[0], sc["exchange_rate"])

    steps = int(round(DURATION * sc["exchange_rate"]))
    _check_frames(observer, sc, vessels, steps)

    # bad input refused or clamped, logged; the run lost nothing
    log = stdout + stderr
    for text in ("client input refused", "not a VesselCommand", "clients may publish only", "clamped to 1",
                 "more than 20 messages/s"):
        assert text in log, text  # (one line a second per kind: the others are counted)
    counts = re.search(r"client input: (\d+) accepted \((\d+) clamped\), refused: (\{.*\})", log)
    refused = ast.literal_eval(counts.group(3))
    assert refused["message"] == 8  # malformed x2, NaN, inf, anchor 7, JSON NaN, unknown key, not a mapping
    assert refused["channel"] == 6  # three channels refused, one message on each
    assert refused["rate"] > FLOOD * 0.9 and int(counts.group(2)) == 1
    # the sender (its own thread, outside the lockstep's executor) says what rate it achieved
    assert re.search(r"sender: [\d.]+ Hz achieved while the simulation ran \(\d+ rounds", log), log[-3000:]
    msgs = decoded(out)
    assert len(msgs["/sim/step"]) == steps
    for v in vessels:
        assert len(msgs[f"/{v}/odom"]) == steps + 1
    engines = [m.engine_order for m in msgs["/tug/command"]]
    assert all(math.isfinite(e) for e in engines)
    assert 1.0 in engines  # the 5.0 order, clamped
    flooded = sum(1 for e in engines if e == 0.5)
    assert 0 < flooded < FLOOD / 10  # the flood was rate-limited, not passed on
    assert msgs["/tug/status"][-1].commands_rejected == 0  # nothing invalid reached the vessel
    if "/tf" in msgs:  # recorded once the runner records the frames (contract_topics)
        assert len([t for m in msgs["/tf"] for t in m.transforms]) == len(vessels) * (steps + 1)
