"""Acceptance of the analysis tool (`analyze`, recording/analysis.py):

- a turning recording (harbour tug, engine order 0.6, 20 deg helm from rest, 120 s at 20 Hz)
  gives the steady turning diameter the vessel library measures: the analysis of the MCAP
  file is compared with an independent run of tug_dynamics (load_ship + the same dt and
  commands) measured two ways in this test: its own least-squares circle over the last
  revolution (tolerance 0.5 %) and the library's turning_metrics (the same sim_math.turning
  measures on the library's own track, tolerance 1 %); advance, transfer and tactical diameter against turning_metrics within 0.5 m;
- the figures render: every PNG exists and is a non-trivial image (size, pixel spread, share
  of non-background pixels), for a towing recording with a rope (default demo, 10 s);
- bad input: a recording cut in the middle is reported with its path and "truncated" (exit
  status 1) and its readable part is still analysed (same turn measures as the full file); a
  file damaged in the middle is reported and the messages after the damage are analysed; a
  file that is not MCAP is refused with its path (exit status 2); messages that do not decode
  are reported with their topic and count; an error while reading a decoded message is not
  turned into a note, except a field an older version of a type lacks.
"""
import json
import math
import os
import subprocess

import numpy as np
import pytest

from conftest import executable_path, record_scenario

pytestmark = [pytest.mark.ros, pytest.mark.timeout(180)]

TURN_SCENARIO = """\
name: tug_turn_test
description: "harbour tug, engine 0.6 and 20 deg helm to port from rest, 120 s"
duration: 120.0
exchange_rate: 20.0
mode: lockstep
vessels:
  - name: tug
    ship_file: harbour_tug.yaml
    initial: {x: 0.0, y: 0.0, heading_deg: 0.0, speed: 0.0}
events:
  - {time: 0.0, vessel: tug, engine_order: 0.6, steering_deg: 20.0}
"""
DT = 0.05  # 1 / exchange_rate
EXPECTED_FIGURES = ["tracks.png", "yaw.png", "speed_yaw_rate.png", "motions.png", "towline_tension.png",
                    "rope_heights.png", "rope_pitch.png", "orders_tug.png"]  # the barge has no engine: no orders
KN = 1852.0 / 3600.0


def tool(executable):
    """The installed executable of the recording package (`ros2 run recording <executable>`)."""
    return [executable_path("recording", executable)]


def analyze(*args, timeout=120):
    return subprocess.run(tool("analyze") + [str(a) for a in args],
                          capture_output=True, text=True, timeout=timeout)


def record(scenario, output, *extra):
    """run_scenario in a domain of its own; the recording's path."""
    from domain_coordinator import domain_id
    with domain_id() as did:
        env = dict(os.environ, ROS_DOMAIN_ID=str(did), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
        record_scenario(scenario, output, *extra, env=env, timeout=150)
    return output


@pytest.fixture(scope="module")
def turn_recording(tmp_path_factory):
    d = tmp_path_factory.mktemp("turn")
    (d / "turn.yaml").write_text(TURN_SCENARIO)
    return record(d / "turn.yaml", d / "turn.mcap")


@pytest.fixture(scope="module")
def demo_recording(tmp_path_factory):
    d = tmp_path_factory.mktemp("demo")
    return record("default_demo.yaml", d / "demo.mcap", "--duration", "10")


@pytest.fixture(scope="module")
def library_turn():
    """The same turn straight from the vessel library (no ROS)."""
    from tug_dynamics.maneuver_trials import run, turning_metrics
    from tug_dynamics.ship_file import load_ship
    from tug_dynamics.vessel import Command
    tr = run(load_ship("harbour_tug.yaml"), 120.0, DT, {0.0: Command(0.6, math.radians(20.0))})
    return tr, turning_metrics(tr)


def kasa_diameter(x, y):
    """Independent check: algebraic least-squares circle x^2 + y^2 = a x + b y + c."""
    a, b, c = np.linalg.lstsq(np.column_stack([x, y, np.ones_like(x)]), x * x + y * y, rcond=None)[0]
    return 2.0 * math.sqrt(c + a * a / 4 + b * b / 4)


def check_png(path):
    import matplotlib.image as mpimg
    assert os.path.isfile(path), f"{path} missing"
    assert os.path.getsize(path) > 10_000, f"{path}: only {os.path.getsize(path)} bytes"
    img = mpimg.imread(path)
    h, w = img.shape[:2]
    assert h >= 300 and w >= 400, f"{path}: {w}x{h} pixels"
    rgb = img[..., :3]
    assert float(rgb.std()) > 0.03, f"{path}: nearly uniform image (std {rgb.std():.4f})"
    drawn = float(np.mean(np.any(rgb < 0.9, axis=-1)))  # share of pixels that are not white background
    assert 0.01 < drawn < 0.9, f"{path}: {drawn:.3f} of the pixels drawn"
    return img


def test_figures_speak_knots_and_deg_true(demo_recording, tmp_path, monkeypatch):
    """The figures are for people: speed over ground in knots, heading as compass deg true, rate
    of turn in deg/min; no title or label says a word twice in a row ("towline towline"); no orders figure
    for the unpowered barge. The plotted data checked against the recording itself (the demo
    starts heading east, heading_deg 0 in ENU: 090 true)."""
    import re
    from recording import figures
    from recording.recorded_run import Recording
    drawn = {}

    def keep(self, fig, name):
        drawn[name] = [(a.get_title(), a.get_ylabel(), [ln.get_ydata() for ln in a.get_lines()]) for a in fig.axes]
        self.plt.close(fig)
    monkeypatch.setattr(figures._Figures, "save", keep)
    rec = Recording(str(demo_recording))
    figures.make_figures(rec, str(tmp_path))
    assert "orders_barge.png" not in drawn and "orders_tug.png" in drawn
    words = [w for axes in drawn.values() for title, label, _ in axes for w in (title, label) if w]
    assert not [w for w in words if re.search(r"\b(\w+) \1\b", w, re.IGNORECASE)], words
    (title, label, lines), = drawn["yaw.png"]
    assert (title, label) == ("Headings", "heading (deg true)")
    heading = (90.0 - np.degrees(rec.vessels["tug"]["yaw"])) % 360.0
    plotted = np.asarray(lines[0], float)
    ok = np.isfinite(plotted)
    assert ok.sum() >= 0.9 * ok.size and np.allclose(plotted[ok], heading[ok], atol=1e-9)
    assert abs(heading[0] - 90.0) < 0.5  # heading_deg 0 (ENU: east) is 090 true
    speed, rot = drawn["speed_yaw_rate.png"]
    assert speed[1] == "speed over ground (kn)" and rot[1] == "rate of turn (deg/min, + to port)"
    assert np.allclose(speed[2][0], rec.vessels["tug"]["speed"] / KN)
    assert np.allclose(rot[2][0], np.degrees(rec.vessels["tug"]["r"]) * 60.0)
    assert drawn["motions.png"][0][1] == "speed over ground (kn)"
    assert drawn["towline_tension.png"][0][0] == "towline: tension at both ends"


def test_turning_diameter_matches_the_vessel_library(turn_recording, library_turn, tmp_path):
    out = analyze(turn_recording, "-o", tmp_path / "an")
    assert out.returncode == 0, out.stdout + out.stderr
    summary = json.loads((tmp_path / "an" / "summary.json").read_text())
    assert summary["file"]["complete"] and not summary["file"]["problems"]
    turn = summary["vessels"]["tug"]["turn"]
    tr, lib = library_turn

    # the recording holds exactly the library's trajectory (same model, dt and commands)
    v = np.loadtxt(tmp_path / "an" / "vessel_tug.csv", delimiter=",", skiprows=1)
    assert v.shape[0] == tr.t.size
    assert np.max(np.abs(v[:, 1] - tr.x)) < 1e-6 and np.max(np.abs(v[:, 2] - tr.y)) < 1e-6

    # independent steady diameter: circle through the library track's last full revolution
    psi = np.unwrap(tr.psi)
    last = psi >= psi[-1] - 2 * math.pi
    d_circle = kasa_diameter(tr.x[last], tr.y[last])
    print(f"steady turning diameter: analysis {turn['steady_diameter']:.3f} m, independent circle fit "
          f"{d_circle:.3f} m, library turning_metrics {lib['steady_diameter']:.3f} m; "
          f"advance {turn['advance']:.2f} / {lib['advance']:.2f} m, transfer {turn['transfer']:.2f} / "
          f"{lib['transfer']:.2f} m, tactical {turn['tactical_diameter']:.2f} / {lib['tactical_diameter']:.2f} m")
    assert turn["steady_diameter"] == pytest.approx(d_circle, rel=0.005)
    assert turn["steady_diameter"] == pytest.approx(lib["steady_diameter"], rel=0.01)
    assert turn["steady_diameter_kinematic"] == pytest.approx(lib["steady_diameter"], rel=0.01)
    assert turn["steady_fit_rms"] < 0.05  # a steady turn: the track is a circle
    for key in ("advance", "transfer", "tactical_diameter"):
        assert turn[key] == pytest.approx(lib[key], abs=0.5), key
    assert turn["steady_speed"] == pytest.approx(lib["steady_speed"], rel=0.01)
    assert turn["steady_yaw_rate"] == pytest.approx(lib["steady_yaw_rate"], rel=0.01)
    assert turn["t0"] == pytest.approx(0.0) and turn["turn_direction"] == 1.0  # port, from the command
    assert turn["heading_change"] > 2 * math.pi + math.pi  # more than 1.5 turns: one full steady revolution
    assert "tug" in out.stdout and "steady diameter" in out.stdout
    check_png(str(tmp_path / "an" / "turn_tug.png"))
    # for people: knots and a compass course (the scenario starts heading east: 090 deg true)
    assert turn["approach_speed_kn"] == pytest.approx(turn["approach_speed"] / KN)
    assert turn["approach_heading_deg_true"] == pytest.approx(90.0, abs=1e-6)
    # the run's metadata gives the ship file's length; a 20 deg helm is no IMO turning test
    import yaml
    from ament_index_python.packages import get_package_share_directory
    ship = yaml.safe_load(open(os.path.join(get_package_share_directory("tug_dynamics"), "ships",
                                            "harbour_tug.yaml")))
    assert summary["vessels"]["tug"]["length"] == ship["hull"]["length"]
    assert turn["helm_angle"] == pytest.approx(math.radians(20.0))
    assert not [r for r in summary["vessels"]["tug"]["imo"] if r["criterion"].startswith("turning")]


def test_figures_render_for_a_towing_recording(demo_recording, tmp_path):
    out = analyze(demo_recording, "-o", tmp_path / "an")
    assert out.returncode == 0, out.stdout + out.stderr
    summary = json.loads((tmp_path / "an" / "summary.json").read_text())
    assert set(summary["vessels"]) == {"tug", "barge"} and set(summary["ropes"]) == {"towline"}
    names = [os.path.basename(f) for f in summary["figures"]]
    for name in EXPECTED_FIGURES:
        assert name in names
        check_png(str(tmp_path / "an" / name))
    assert "orders_barge.png" not in names, names  # unpowered (barge_002_full.yaml): all-zero orders
    rope = summary["ropes"]["towline"]
    assert rope["tension_a_max"] > 0 and rope["tension_b_max"] > 0 and rope["elements_start"] > 1
    import yaml
    from ament_index_python.packages import get_package_share_directory
    rope_file = yaml.safe_load(open(os.path.join(get_package_share_directory("rope_model"), "ropes", "table1.yaml")))
    assert rope["breaking_load"] == rope_file["breaking_load"]
    assert rope["peak_over_breaking_load"] == pytest.approx(
        max(rope["tension_a_max"], rope["tension_b_max"], rope["tension_max_anywhere"]) / rope_file["breaking_load"])
    # the towline angle: the barge lies dead astern of the tug at the start, so the line leaves
    # the tug's winch astern (+-180 deg) and the barge's bow bollard ahead (0 deg)
    from recording.measures import towline_angle
    from recording.recorded_run import Recording
    rec = Recording(str(demo_recording))
    vessel_a, _, angle_a = towline_angle(rec, "towline", "a")
    vessel_b, _, angle_b = towline_angle(rec, "towline", "b")
    assert (vessel_a, vessel_b) == ("tug", "barge")
    assert abs(math.degrees(abs(angle_a[0])) - 180.0) < 1.0 and abs(math.degrees(angle_b[0])) < 1.0
    assert rope["min_element_height"] < 0  # the towline hangs into the water
    kinds = {e["kind"] for e in summary["events"]}
    assert {"scenario_started", "order"} <= kinds
    rows = (tmp_path / "an" / "summary.csv").read_text().splitlines()
    assert rows[0] == "entity,quantity,value,unit" and any(r.startswith("rope/towline,tension_a_max,") for r in rows)


def test_truncated_recording_is_reported_and_its_readable_part_analysed(turn_recording, tmp_path):
    data = turn_recording.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[:len(data) // 2])
    out = analyze(cut, "-o", tmp_path / "an")
    assert out.returncode == 1, out.stdout + out.stderr
    assert str(cut) in out.stderr and "truncated" in out.stderr
    summary = json.loads((tmp_path / "an" / "summary.json").read_text())
    assert not summary["file"]["complete"] and any("truncated" in p for p in summary["file"]["problems"])
    tug = summary["vessels"]["tug"]
    assert 30.0 < tug["t_end"] < 110.0  # about half of the 120 s
    # what is readable gives the same early measures as the whole file
    analyze(turn_recording, "-o", tmp_path / "full", "--no-figures")
    ref = json.loads((tmp_path / "full" / "summary.json").read_text())["vessels"]["tug"]["turn"]
    assert tug["turn"]["advance"] == pytest.approx(ref["advance"], abs=1e-9)
    assert tug["turn"]["tactical_diameter"] == pytest.approx(ref["tactical_diameter"], abs=1e-9)
    for name in ("tracks.png", "yaw.png", "motions.png"):
        check_png(str(tmp_path / "an" / name))


def test_corrupt_recording_is_reported_and_the_rest_analysed(demo_recording, tmp_path):
    data = bytearray(demo_recording.read_bytes())
    start = len(data) // 3
    data[start:start + 2000] = b"\xa5" * 2000
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(bytes(data))
    out = analyze(bad, "-o", tmp_path / "an", "--no-figures")
    assert out.returncode == 1, out.stdout + out.stderr
    assert str(bad) in out.stderr and ("CRC" in out.stderr or "corrupt" in out.stderr), out.stderr
    summary = json.loads((tmp_path / "an" / "summary.json").read_text())
    assert summary["file"]["problems"]
    assert summary["vessels"]["tug"]["t_end"] == pytest.approx(10.0)  # messages after the damage were read


def test_not_an_mcap_file_is_refused_with_its_path(tmp_path, run_in_process):
    junk = tmp_path / "junk.mcap"
    junk.write_text("not a recording\n")
    out = analyze(junk, "-o", tmp_path / "an")  # the executable's exit status 2
    assert out.returncode == 2 and str(junk) in out.stderr and "not an MCAP file" in out.stderr
    out = run_in_process("analyze", tmp_path / "missing.mcap")  # its entry function, in this process
    assert out.returncode == 2 and "missing.mcap" in out.stderr


# -- errors surface: corrupt messages are reported, a bug is not turned into a note ----------------
OLD_STATUS_SCHEMA = "std_msgs/Header header\nfloat64 engine_order\n"  # a VesselStatus of long ago


def _old_status_cdr(t_ns):
    """CDR of OLD_STATUS_SCHEMA: header (stamp, empty frame_id), engine_order 0.5."""
    import struct
    body = struct.pack("<iII", t_ns // 10 ** 9, t_ns % 10 ** 9, 1) + b"\0"
    body += b"\0" * (-len(body) % 8) + struct.pack("<d", 0.5)
    return b"\x00\x01\x00\x00" + body


def _write_odom_recording(path, n=50, corrupt=(), old_status=False):
    """/tug/odom: n Odometry messages at 10 Hz along x, those at the indices in corrupt cut short;
    with old_status also /tug/status in an older VesselStatus (OLD_STATUS_SCHEMA)."""
    from mcap.writer import Writer
    from nav_msgs.msg import Odometry
    from rclpy.serialization import serialize_message
    from recording.recorder import message_definition
    with open(path, "wb") as f:
        w = Writer(f)
        w.start(profile="ros2", library="test")
        sid = w.register_schema(name="nav_msgs/msg/Odometry", encoding="ros2msg",
                                data=message_definition("nav_msgs/msg/Odometry").encode())
        odom = w.register_channel(topic="/tug/odom", message_encoding="cdr", schema_id=sid)
        if old_status:
            old = OLD_STATUS_SCHEMA + "=" * 80 + "\nMSG: std_msgs/Header\n" + message_definition("std_msgs/msg/Header")
            sid = w.register_schema(name="tug_msgs/msg/VesselStatus", encoding="ros2msg", data=old.encode())
            status = w.register_channel(topic="/tug/status", message_encoding="cdr", schema_id=sid)
        for k in range(n):
            t = k * 100_000_000
            msg = Odometry()
            msg.header.stamp.sec, msg.header.stamp.nanosec = t // 10 ** 9, t % 10 ** 9
            msg.pose.pose.position.x, msg.pose.pose.orientation.w, msg.twist.twist.linear.x = 0.5 * k, 1.0, 5.0
            data = serialize_message(msg)
            w.add_message(channel_id=odom, log_time=t, publish_time=t, sequence=k,
                          data=data[:10] if k in corrupt else data)
            if old_status:
                w.add_message(channel_id=status, log_time=t, publish_time=t, sequence=k, data=_old_status_cdr(t))
        w.finish()
    return path


def test_undecodable_messages_are_reported_with_their_topic_and_count(tmp_path, capsys):
    from recording import analysis
    path = _write_odom_recording(str(tmp_path / "rec.mcap"), corrupt={3, 17, 30})
    assert analysis.main([path, "-o", str(tmp_path / "an"), "--no-figures", "--quiet"]) == analysis.EXIT_OK
    err = capsys.readouterr().err
    assert "/tug/odom: 3 message(s) do not decode" in err, err
    summary = json.loads((tmp_path / "an" / "summary.json").read_text())
    assert summary["file"]["undecodable_messages"] == {"/tug/odom": 3}
    assert summary["vessels"]["tug"]["samples"] == 47


def test_a_programming_error_while_reading_is_not_turned_into_a_note(tmp_path, monkeypatch):
    from recording.recorded_run import Recording
    path = _write_odom_recording(str(tmp_path / "rec.mcap"))

    def typo(msg):
        return msg.pose.pose.positon  # AttributeError, as a typo in the reader would raise
    monkeypatch.setattr(Recording, "_odom_row", staticmethod(typo))
    with pytest.raises(AttributeError, match="positon"):
        Recording(path)


def test_an_older_message_without_a_field_read_is_left_out_with_a_note(tmp_path, monkeypatch):
    """A type that does not import here is decoded with the file's own schema; an older version
    of it lacks fields the analysis reads: its topic is left out, and a note names the fields."""
    from recording import mcap_io
    from recording.recorded_run import Recording
    installed = mcap_io.message_class

    def without_tug_msgs(type_name):
        if type_name.startswith("tug_msgs/"):
            raise ImportError(f"type {type_name} is not importable here")
        return installed(type_name)
    monkeypatch.setattr(mcap_io, "message_class", without_tug_msgs)
    rec = Recording(_write_odom_recording(str(tmp_path / "rec.mcap"), old_status=True))
    assert "status" not in rec.vessels["tug"] and rec.vessels["tug"]["t"].size == 50
    note = [n for n in rec.decoder.notes if n.startswith("/tug/status: its tug_msgs/msg/VesselStatus")]
    assert note and "girting_ratio" in note[0] and "not analysed" in note[0], rec.decoder.notes
    assert not rec.decoder.errors
