"""The terminal console (bridge_instruments console, Textual) driven in a pseudo-terminal
(pexpect) during a paced run built to reach the girting limit: an abeam towline to a fixed
point, the tug driven ahead.

- keys raise the engine order and put the helm to starboard: the orders are in the recording
  on /tug/command, the vessel holds and applies them (status: engine order, helm ordered and
  actual, shaft speed);
- the screen shows the towline tension in kN against the breaking load and the girting warning;
- invalid keys and a flood of engine keys never produce an out-of-range order.

Times (issue 17, item 4), folded into the same run: `send_command` sent while /clock runs says
it stamps with simulation time, and its order is in the recording stamped on the step grid
within the run; and `analyze` of a copy of the recording whose commands carry wall-clock stamps
(as an older tool wrote them) says so and takes the orders from the commanded values in
/tug/status: the turn starts at the console's first helm order.
"""
import collections
import math
import os
import re
import subprocess
import time

import pytest
import yaml

from conftest import executable_path
from test_recording import decoded

pytestmark = [pytest.mark.ros, pytest.mark.timeout(300)]


def _scenario(tmp_path):
    sc = {"name": "girt", "duration": 24.0, "exchange_rate": 50.0, "mode": "realtime",
          "vessels": [{"name": "tug", "ship_file": "harbour_tug.yaml",
                       "initial": {"x": 0.0, "y": 0.0, "heading_true_deg": 90.0, "speed_kn": 5.0},
                       "ship_overrides": {"attachments": {"towing_hook": [-1.0, 0.0, 5.0]},
                                          "roll": {"girting_threshold": 0.35}}}],
          "ropes": [{"name": "towline", "rope_file": "table1.yaml", "end_a": "tug/towing_hook", "end_b": "fixed",
                     "end_b_position": [-1.0, 99.0, 0.0], "layout": "straight"}],
          "events": [{"time": 0.0, "vessel": "tug", "engine_order": 0.8}]}
    # the Table 1 rope with the stretch of Table 1 but a 200 kN breaking load: the line holds
    # until the tug girts (with Table 1's 156.9 kN it parts first when the helm goes over)
    from ament_index_python.packages import get_package_share_directory
    rope = yaml.safe_load(open(f"{get_package_share_directory('rope_model')}/ropes/table1.yaml"))
    rope.update(name="strong", breaking_load=200000.0, axial_stiffness=156906.4 / 0.15)
    (tmp_path / "strong.yaml").write_text(yaml.safe_dump(rope))
    sc["ropes"][0]["rope_file"] = "strong.yaml"
    path = tmp_path / "girt.yaml"
    path.write_text(yaml.safe_dump(sc))
    return path


def _wall_stamped_copy(src, dst, topic):
    """A copy of a recording whose `topic` messages (std_msgs/Header first) are stamped with their
    wall-clock log time, as a tool on wall time stamped them; everything else as it was."""
    import struct
    from mcap.reader import make_reader
    from mcap.writer import Writer
    with open(src, "rb") as f_in, open(dst, "wb") as f_out:
        reader = make_reader(f_in)
        w = Writer(f_out)
        w.start(profile="ros2", library="test_console")
        schemas, channels = {}, {}
        for schema, channel, message in reader.iter_messages(log_time_order=False):
            if schema.id not in schemas:
                schemas[schema.id] = w.register_schema(schema.name, schema.encoding, schema.data)
            if channel.id not in channels:
                channels[channel.id] = w.register_channel(channel.topic, channel.message_encoding,
                                                          schemas[schema.id], channel.metadata)
            data = message.data
            if channel.topic == topic:
                wall_ns = message.log_time if message.log_time > 10**17 else time.time_ns()
                assert data[1] == 1  # CDR little endian: header stamp at bytes 4..12
                data = data[:4] + struct.pack("<iI", wall_ns // 10**9, wall_ns % 10**9) + data[12:]
            w.add_message(channels[channel.id], message.log_time, data, message.publish_time, message.sequence)
        for record in reader.iter_metadata():
            w.add_metadata(record.name, record.metadata)
        w.finish()


def test_console_drives_the_tug_into_a_girting_warning(tmp_path, ros_domain, capsys):
    import pexpect
    path = _scenario(tmp_path)
    out = tmp_path / "girt.mcap"
    run = subprocess.Popen([executable_path("scenario_runner", "run_scenario"), str(path), "--output", str(out),
                            "--quiet"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    screen = open(tmp_path / "console_screen.txt", "w")
    env = dict(os.environ, TERM="xterm-256color", PYTHONUNBUFFERED="1")
    con = pexpect.spawn(executable_path("bridge_instruments", "console"), ["tug", "--scenario", str(path)],
                        env=env, dimensions=(30, 160), encoding="utf-8", codec_errors="replace", timeout=90)
    con.logfile_read = screen
    try:
        con.expect(r"rate of turn", timeout=120)  # the vessel's state is on the screen
        con.expect(r"t +[1-9]\.\d\d s ", timeout=60)  # the run is under way (and /clock published)
        # send_command while /clock runs: the order the tug holds (engine 0.8, midships), so the
        # console's orders below are unchanged; the console's screen is read meanwhile
        sender = subprocess.Popen([executable_path("scenario_runner", "send_command"), "tug", "--engine", "0.8",
                                   "--steering-deg", "0"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        while sender.poll() is None:
            try:
                con.read_nonblocking(65536, timeout=0.1)
            except pexpect.TIMEOUT:
                pass
        sent_out, sent_err = sender.communicate()
        time.sleep(0.3)  # the console follows the held orders (engine 0.8)
        for key in ["z", "9", "!", "\x1b[Z", "w", "w", "d", "d"]:  # junk, then ahead x2, starboard x2
            con.send(key)
            time.sleep(0.15)
        con.expect(r"tension +\d+\.\d kN of breaking load 200\.0 kN", timeout=60)
        con.expect(r"GIRTING WARNING", timeout=60)
        for _ in range(30):  # a flood of ahead orders: clamped at full ahead
            con.send("w")
        time.sleep(0.5)
        con.send("q")
        con.expect(pexpect.EOF, timeout=20)
    finally:
        if con.isalive():
            con.terminate(force=True)
        screen.close()
        try:
            stdout, stderr = run.communicate(timeout=120)
        finally:
            if run.poll() is None:
                run.kill()
    assert run.returncode == 0, stderr
    rec = decoded(str(out), ["/tug/command", "/tug/status"])
    cmds = rec["/tug/command"]
    t = lambda m: m.header.stamp.sec + m.header.stamp.nanosec * 1e-9
    ns = lambda m: m.header.stamp.sec * 10**9 + m.header.stamp.nanosec
    # send_command stamped its order with simulation time: it says so, and the recorded order has
    # its stamp, on the 20 ms step grid (a /clock value), after the screen showed t >= 1 s, in the run
    assert sender.returncode == 0, sent_err
    assert "simulation time (/clock)" in sent_out, sent_out
    stamp = float(re.search(r"stamped (\d+\.\d+) s", sent_out).group(1))
    sent = [c for c in cmds if abs(t(c) - stamp) < 0.0015 and c.engine_order == 0.8 and c.steering_angle == 0.0]
    assert len(sent) == 1 and ns(sent[0]) % 20_000_000 == 0 and 1.0 <= t(sent[0]) <= 24.0, (sent_out, sent)
    # every order in range; the console's orders stamped with simulation time (within the run)
    assert all(-1.0 <= c.engine_order <= 1.0 and abs(c.steering_angle) <= math.radians(35.0) + 1e-12 for c in cmds)
    mine = [c for c in cmds if t(c) > 0.0 and c is not sent[0]]
    assert mine and all(t(c) <= 24.0 for c in mine), [t(c) for c in cmds]
    assert [round(c.engine_order, 3) for c in mine][:4] == [0.9, 1.0, 1.0, 1.0]
    assert [round(math.degrees(c.steering_angle), 3) for c in mine][:4] == [0.0, 0.0, -5.0, -10.0]
    assert max(c.engine_order for c in mine) == 1.0
    # the vessel responds: holds the orders, the helm goes over to starboard, the shaft speeds up
    status = rec["/tug/status"]
    t_helm = t(mine[3])
    after = [s for s in status if t(s) > t_helm + 0.1]
    before = [s for s in status if t(mine[0]) - 1.0 < t(s) <= t(mine[0])]
    assert after and all(s.engine_order == 1.0 for s in after)
    assert all(abs(s.steering_angle_ordered - math.radians(-10.0)) < 1e-9 for s in after)
    assert min(s.steering_angle for s in after) < math.radians(-5.0)
    assert max(s.shaft_speed for s in after) > max(s.shaft_speed for s in before) * 1.05
    assert any(s.girting_warning for s in status)

    # analyze of the recording with its commands stamped on wall time (as send_command stamped
    # them before it read /clock): the orders cannot be placed, it says so and takes them from
    # the commanded values in /tug/status. The turn starts at the console's first helm order
    # (-5 deg, stamped t(mine[2])): the tug applies an order from the step after its stamp, or a
    # few steps later when the console's newest /clock lags (0.1 s: the next helm key came later)
    from recording import analysis
    from recording.measures import find_turn
    from recording.recorded_run import Recording
    wall = tmp_path / "girt_wall_stamped.mcap"
    _wall_stamped_copy(str(out), str(wall), "/tug/command")
    capsys.readouterr()
    assert analysis.main([str(wall), "-o", str(tmp_path / "an"), "--no-figures", "--quiet"]) == 0
    said = capsys.readouterr().err
    assert "/tug/command: " in said and "stamped outside the recording's time" in said, said
    assert "taken from the commanded engine order and steering angle in /tug/status instead" in said, said
    late = Recording(str(wall))
    assert "command" not in late.vessels["tug"]
    t0, _ = find_turn(late, "tug")
    assert t(mine[2]) < t0 <= t(mine[2]) + 0.1 + 1e-9, (t0, t(mine[2]))
    orders_t, orders = late.steering_orders("tug")
    assert [round(math.degrees(o), 6) for o in orders[orders_t >= t0 - 1e-9][:2]] == [-5.0, -10.0]


def _screen_node(status, odom=None, **more):
    """What console.readout reads of a ConsoleNode, without ROS: the vessel's newest state, heard
    just now."""
    from types import SimpleNamespace
    from nav_msgs.msg import Odometry
    from bridge_instruments import console
    if odom is None:
        odom = Odometry()
        odom.pose.pose.orientation.w = 1.0
    node = SimpleNamespace(vessel="tug", sent=0, clock=SimpleNamespace(source="simulation time"), odom=odom,
                           status=status, tension={}, winch_pubs={}, parted={}, finished=None, heard=100.0,
                           events=collections.deque(maxlen=console.EVENT_LINES))
    node.silent_for = lambda now=None: 0.0 if now is None else now - node.heard
    vars(node).update(more)
    return node


def test_console_shows_roll_pitch_and_the_sea():
    """The console's screen text (readout) of a status message with a sea, in process: roll and
    pitch are the totals (heel + roll, trim + pitch) in words (REP-103: roll + starboard down,
    pitch + bow down), the sea's Hs, encounter period and where it comes from; a calm status says
    so."""
    from tug_msgs.msg import VesselStatus
    from bridge_instruments import console, controls
    st = VesselStatus(heel=math.radians(1.5), roll=math.radians(2.0), trim=math.radians(0.25),
                      pitch=math.radians(-1.75), heave=0.42, wave_significant_height=2.5,
                      wave_encounter_period=6.25, wave_encounter_angle=math.radians(-40.0), wave_elevation=-0.8,
                      girting_threshold=0.5)
    node = _screen_node(st)
    text, _ = console.readout(node, controls.Orders(35.0, 0.5), {})
    lines = text.splitlines()
    assert "roll  3.5 deg stbd (heel  +1.5)   pitch  1.5 deg bow up   (trim  +0.2)   heave +0.42 m" in lines, text
    assert "sea Hs  2.5 m   encounter period   6.2 s   from  40 deg stbd (on the bow)   surface -0.80 m" in lines, text
    calm = VesselStatus(heel=math.radians(-3.0), trim=math.radians(0.5), girting_threshold=0.5)
    text, _ = console.readout(_screen_node(calm), controls.Orders(35.0, 0.5), {})
    assert "roll  3.0 deg port (heel  -3.0)   pitch  0.5 deg bow down (trim  +0.5)   heave +0.00 m" in text, text
    assert "sea calm" in text.splitlines(), text


def test_console_signs_and_words():
    """One sign convention, in words: a helm 5 deg to port (+ 5 deg, REP-103) reads "5.0 deg port",
    ordered and actual; a turn to port (yaw rate + 0.01 rad/s) "34.4 deg/min to port"; an engine
    order 0.05 "+0.05 (5 % ahead)"; the screen states the convention; a towline named "towline"
    is named once."""
    from tug_msgs.msg import VesselStatus
    from bridge_instruments import console, controls
    st = VesselStatus(engine_order=0.05, steering_angle_ordered=math.radians(5.0), steering_angle=math.radians(4.96),
                      shaft_speed=2 * math.pi * 2.0, girting_threshold=0.5)
    node = _screen_node(st, tension={"towline": 46_800.0})
    node.odom.twist.twist.angular.z = 0.01
    orders = controls.Orders(35.0, 0.5)
    orders.sync(0.05, 5.0)
    text, warn = console.readout(node, orders, {"towline": 156_906.4})
    lines = text.splitlines()
    assert lines[0].startswith("TUG   orders: engine +0.05 (5 % ahead)   helm 5.0 deg port   (sent 0"), lines[0]
    assert console.SIGNS in lines and "+ to port" in console.SIGNS
    assert "engine +0.05 (5 % ahead)   shaft +120.0 rpm (+ ahead)" in lines, text
    assert "rudder 5.0 deg port (ordered 5.0 deg port)" in lines, text
    assert "rate of turn 34.4 deg/min to port" in lines[2], text  # 0.01 rad/s = 34.38 deg/min
    assert "towline: tension   46.8 kN of breaking load 156.9 kN (30 %)" in lines, text
    assert "towline towline" not in text and warn == []
    starboard = _screen_node(VesselStatus(steering_angle_ordered=math.radians(-10.0),
                                          steering_angle=math.radians(-2.5), girting_threshold=0.5))
    text, _ = console.readout(starboard, controls.Orders(35.0, 0.5), {})
    assert "rudder 2.5 deg stbd (ordered 10.0 deg stbd)" in text.splitlines(), text
    assert controls.engine_words(-0.5) == "-0.50 (50 % astern)" and controls.engine_words(0.0) == "stop"


def test_console_barge_has_no_engine_or_helm_gauges():
    """The equipment a ship file gives (tug_dynamics/ships): the unpowered barges have no engine,
    helm or anchor; the harbour tug engine and helm, the S175 also an anchor, the ASD tug and the
    planing boat (thrusters, waterjet) engine and helm. The barge's screen has no engine, rpm,
    helm or girting line (no roll model: threshold 0), and its engine, helm and anchor keys are
    refused by name."""
    from tug_dynamics.ship_file import ship_config
    from tug_msgs.msg import VesselStatus
    from bridge_instruments import console, controls
    kits = {f: controls.equipment(ship_config(f)[1]) for f in ("box_barge_000.yaml", "barge_002_full.yaml",
                                                              "harbour_tug.yaml", "s175_003.yaml", "asd_tug.yaml",
                                                              "planing_40ft.yaml")}
    none, powered = controls.Equipment(False, False, False), controls.Equipment(True, True, False)
    assert kits == {"box_barge_000.yaml": none, "barge_002_full.yaml": none, "harbour_tug.yaml": powered,
                    "s175_003.yaml": controls.Equipment(True, True, True), "asd_tug.yaml": powered,
                    "planing_40ft.yaml": powered}
    # what `console barge --scenario default_demo.yaml` finds: the barge's end of the towline, no winch
    assert console._scenario_setup("barge", "default_demo.yaml") == ([("towline", "b", False)],
                                                                    {"towline": 156_906.4}, none)
    node = _screen_node(VesselStatus(girting_threshold=0.0), vessel="barge")  # no roll model: 0
    text, _ = console.readout(node, controls.Orders(35.0, 0.5), {}, kits["box_barge_000.yaml"])
    assert not any(w in line for line in text.splitlines()[1:] for w in ("engine", "rpm", "rudder", "helm", "girting")), \
        text
    assert text.splitlines()[0].startswith("BARGE   orders: none (no engine, helm or winch)"), text
    assert [controls.lacks(k, none) for k in ("w", "x", "a", "c", "l", "o", "z")] == \
        ["engine", "engine", "helm", "helm", "anchor", None, None]
    assert [controls.lacks(k, powered) for k in ("w", "a", "l")] == [None, None, "anchor"]


def test_console_shows_what_happens():
    """Events on the screen: a parted towline reads PARTED (not its last tension) with the time
    and load of the parting, also among the warnings; a grounding and a dragging anchor are
    warnings; a vessel silent for more than STALE_AFTER says for how long; the end of the run
    says so; every event's text is in the events area, manual_order / manual_handed_back in bold
    yellow, alarms in bold red."""
    from tug_msgs.msg import VesselStatus
    from bridge_instruments import console, controls
    st = VesselStatus(grounded=True, under_keel_clearance=-0.31, water_depth=4.2, anchor_state=3, girting_threshold=0.5)
    node = _screen_node(st, tension={"towline": 0.0})
    node.odom.twist.twist.linear.x = 1852.0 / 3600.0 * 1.5
    orders = controls.Orders(35.0, 0.5)
    for ev in (console.Event(3.0, "manual_order", "tug", "console took the engine of tug", math.nan),
               console.Event(125.44, "rope_parted", "towline", "rope 'towline' parted at 157.1 kN", 157_100.0),
               console.Event(130.0, "manual_handed_back", "tug", "tug's engine handed back to the script", math.nan),
               console.Event(131.0, "order", "tug", "engine +0.50, steering +0.0 deg", math.nan)):
        console.note_event(node, ev)
    text, warn = console.readout(node, orders, {"towline": 156_906.4}, now=100.5)
    assert "towline: PARTED at t 125.44 s (157.1 kN)" in text.splitlines() and "tension" not in text, text
    assert warn[0] == "TOWLINE PARTED at t 125.44 s (157.1 kN)", warn
    assert "AGROUND: under-keel clearance -0.31 m (depth 4.20 m)" in warn, warn
    assert "ANCHOR DRAGGING over the bottom (dredging) at 1.5 kn" in warn, warn
    assert console.event_lines(node) == [
        ("t     3.00 s  manual_order tug: console took the engine of tug", "bold yellow"),
        ("t   125.44 s  rope_parted towline: rope 'towline' parted at 157.1 kN", "bold red"),
        ("t   130.00 s  manual_handed_back tug: tug's engine handed back to the script", "bold yellow"),
        ("t   131.00 s  order tug: engine +0.50, steering +0.0 deg", "")]
    _, warn = console.readout(node, orders, {}, now=100.0 + console.STALE_AFTER + 2.2)
    assert "NO DATA from tug for 3 s: its node stopped, or the run or replay ended (keys send nothing)" in warn
    console.note_event(node, console.Event(400.0, "scenario_finished", "", "20000 steps in 80.0 s wall", math.nan))
    _, warn = console.readout(node, orders, {}, now=100.0 + console.STALE_AFTER + 2.2)
    assert "RUN FINISHED at t 400.00 s: orders are no longer obeyed (keys send nothing)" in warn, warn
    assert not any(w.startswith("NO DATA") for w in warn), warn


PARTING_SCENARIO = {
    "name": "parting", "duration": 60.0, "exchange_rate": 20.0, "mode": "realtime",
    "vessels": [{"name": "tug", "ship_file": "harbour_tug.yaml",
                 "initial": {"x": 0.0, "y": 0.0, "heading_true_deg": 90.0, "speed_kn": 5.0}}],
    "ropes": [{"name": "towline", "rope_file": "table1.yaml", "end_a": "tug/towing_hook", "end_b": "fixed",
               "end_b_position": [-100.0, 0.0, 0.0], "layout": "straight", "allow_slack": True}]}


class _TugOnALine:
    """An in-test node in the place of a run: the tug's odometry and status (engine 0.8) and its
    towline end's wrench (46.8 kN) at 20 Hz, stamped on a 50 ms grid; events published on
    request; the orders sent to the tug kept (`commands`)."""

    def __init__(self, context):
        import threading
        import rclpy
        from geometry_msgs.msg import WrenchStamped
        from nav_msgs.msg import Odometry
        from rclpy.executors import SingleThreadedExecutor
        from tug_msgs.msg import ScenarioEvent, VesselCommand, VesselStatus
        from sim_contract import topics as T
        from sim_plumbing import ros_common as rc
        self.Odometry, self.VesselStatus, self.WrenchStamped = Odometry, VesselStatus, WrenchStamped
        self.node = rclpy.create_node("parting_source", context=context)
        self.odom_pub = self.node.create_publisher(Odometry, T.vessel_topic("tug", T.ODOM), rc.STATE_QOS)
        self.status_pub = self.node.create_publisher(VesselStatus, T.vessel_topic("tug", T.STATUS), rc.STATE_QOS)
        self.wrench_pub = self.node.create_publisher(WrenchStamped, T.end_wrench_topic("towline", "a"), rc.STATE_QOS)
        self.event_pub = self.node.create_publisher(ScenarioEvent, T.EVENTS, rc.EVENTS_QOS)
        self.commands = []
        self.node.create_subscription(VesselCommand, T.vessel_topic("tug", T.COMMAND), self.commands.append,
                                      rc.COMMAND_QOS)
        self.step = 0
        self.timer = self.node.create_timer(0.05, self.publish_state)
        self.executor = SingleThreadedExecutor(context=context)
        self.executor.add_node(self.node)
        self.running = threading.Event()
        self.running.set()
        self.thread = threading.Thread(target=self._spin, daemon=True)
        self.thread.start()

    def _spin(self):
        while self.running.is_set():
            self.executor.spin_once(timeout_sec=0.05)

    def publish_state(self):
        from sim_plumbing import ros_common as rc
        self.step += 1
        od, st, w = self.Odometry(), self.VesselStatus(girting_threshold=0.5, engine_order=0.8), self.WrenchStamped()
        od.pose.pose.orientation.w = 1.0
        for m in (od, st, w):
            m.header.stamp = rc.step_time(self.step, 50_000_000)
        w.wrench.force.x = 46_800.0
        self.odom_pub.publish(od)
        self.status_pub.publish(st)
        self.wrench_pub.publish(w)

    def event(self, step, kind, target, detail, value=math.nan):
        from tug_msgs.msg import ScenarioEvent
        from sim_plumbing import ros_common as rc
        ev = ScenarioEvent(step=step, source="/test", kind=kind, target=target, detail=detail, value=value)
        ev.header.stamp = rc.step_time(step, 50_000_000)
        self.event_pub.publish(ev)

    def close(self):
        self.running.clear()
        self.thread.join(2.0)
        self.node.destroy_node()


def test_console_shows_parted_within_one_display_period(tmp_path, rclpy_context):
    """The console (in a pseudo-terminal) of a tug on a towline whose state an in-test node
    publishes (odometry, status, the end wrench at 46.8 kN, 20 Hz): the towline's tension is on
    the screen; then a rope_parted ScenarioEvent (as rope_node sends it) and the screen reads
    PARTED, with the time and load of the parting, by its next refresh: within one display period
    (0.1 s) and the time it takes to draw and read the screen (allowed 0.1 s more). Then the state
    stops (NO DATA on the screen) and the run ends (scenario_finished: RUN FINISHED): keys pressed
    meanwhile send no order and the screen says why."""
    import pexpect
    from bridge_instruments import console
    path = tmp_path / "parting.yaml"
    path.write_text(yaml.safe_dump(PARTING_SCENARIO))
    tug = _TugOnALine(rclpy_context)
    commands = tug.commands
    env = dict(os.environ, TERM="xterm-256color", PYTHONUNBUFFERED="1")
    con = pexpect.spawn(executable_path("bridge_instruments", "console"), ["tug", "--scenario", str(path)],
                        env=env, dimensions=(30, 160), encoding="utf-8", codec_errors="replace", timeout=90)
    con.logfile_read = open(tmp_path / "console_screen.txt", "w")
    try:
        con.expect(r"towline: tension +46\.8 kN of breaking load 156\.9 kN \(30 %\)", timeout=120)
        deadline = time.monotonic() + 20.0
        while tug.event_pub.get_subscription_count() < 1 and time.monotonic() < deadline:
            con.expect([pexpect.TIMEOUT, r"\S"], timeout=0.05)
        assert tug.event_pub.get_subscription_count() >= 1, "the console never subscribed to /scenario/events"
        sent = time.monotonic()
        tug.event(2509, "rope_parted", "towline", "rope 'towline' parted at element 3 (157.1 kN)", 157_100.0)
        con.expect(r"towline: PARTED at t 125\.45 s \(157\.1 kN\)", timeout=10)
        shown = time.monotonic() - sent
        con.expect(r"TOWLINE PARTED at t 125\.45 s", timeout=10)
        con.expect(r"rope_parted towline: rope 'towline' parted at element 3", timeout=10)
        # a key while the vessel is heard sends an order (the screen says sent 1) ...
        con.send("w")
        con.expect(r"\(sent 1, ", timeout=10)
        deadline = time.monotonic() + 10.0
        while not commands and time.monotonic() < deadline:
            con.expect([pexpect.TIMEOUT, r"\S"], timeout=0.05)
        assert len(commands) == 1 and commands[0].engine_order == 0.9, commands
        # ... but not once the vessel falls silent (its state stops): the screen says so
        tug.timer.cancel()
        con.expect(r"NO DATA from tug for [12] s", timeout=10)
        con.send("w")
        con.expect(r"order not sent: no data from tug for \d+ s", timeout=10)
        # the run ends: the screen says so, and keys still send nothing
        tug.event(2600, "scenario_finished", "", "2600 steps in 130.0 s wall")
        con.expect(r"RUN FINISHED at t 130\.00 s: orders are no longer obeyed", timeout=10)
        con.send("a")
        con.expect(r"order not sent: the run finished at t 130\.00 s", timeout=10)
        time.sleep(0.3)
        con.send("q")
        con.expect(pexpect.EOF, timeout=20)
    finally:
        if con.isalive():
            con.terminate(force=True)
        con.logfile_read.close()
        tug.close()
    print(f"\nPARTED on the screen {1e3 * shown:.0f} ms after the rope_parted event")
    assert shown <= console.DISPLAY_PERIOD + 0.1, shown
    assert len(commands) == 1, commands  # the keys pressed once the vessel was silent sent nothing
