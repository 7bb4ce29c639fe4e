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


def test_console_shows_roll_pitch_and_the_sea():
    """The console's screen text (readout) of a status message with a sea, in process: roll and
    pitch are the totals (heel + roll, trim + pitch) in words (REP-103: roll + starboard down,
    pitch + bow down), the sea's Hs, encounter period and where it comes from; a calm status says
    so."""
    from types import SimpleNamespace
    from nav_msgs.msg import Odometry
    from tug_msgs.msg import VesselStatus
    from bridge_instruments import console, controls
    st = VesselStatus(heel=math.radians(1.5), roll=math.radians(2.0), trim=math.radians(0.25),
                      pitch=math.radians(-1.75), heave=0.42, wave_significant_height=2.5,
                      wave_encounter_period=6.25, wave_encounter_angle=math.radians(-40.0), wave_elevation=-0.8,
                      girting_threshold=0.5)
    od = Odometry()
    od.pose.pose.orientation.w = 1.0
    node = SimpleNamespace(vessel="tug", sent=0, clock=SimpleNamespace(source="simulation time"), odom=od, status=st,
                           tension={})
    text, _ = console.readout(node, controls.Orders(35.0, 0.5), {})
    lines = text.splitlines()
    assert "roll  3.5 deg stbd (heel  +1.5)   pitch  1.5 deg bow up   (trim  +0.2)   heave +0.42 m" in lines, text
    assert "sea Hs  2.5 m   encounter period   6.2 s   from  40 deg stbd (on the bow)   surface -0.80 m" in lines, text
    calm = VesselStatus(heel=math.radians(-3.0), trim=math.radians(0.5), girting_threshold=0.5)
    text, _ = console.readout(SimpleNamespace(**{**vars(node), "status": calm}), controls.Orders(35.0, 0.5), {})
    assert "roll  3.0 deg port (heel  -3.0)   pitch  0.5 deg bow down (trim  +0.5)   heave +0.00 m" in text, text
    assert "sea calm" in text.splitlines(), text
