"""`analyze` on a run at sea (in process, on a synthesized recording: no scenario is run).

The recording is written here with mcap's writer and the project's message definitions: a
vessel `tug` heaving A sin(2 pi t / T) (A = 0.4 m, T = 8 s) and rolling 3 deg at 10 s period
(/tug/odom, 10 Hz, 600 s), a rope `towline` whose end a tension is 100 kN + 20 kN sin(2 pi t / 9)
with two constructed slack intervals (0 N, well below 1 % of its 500 kN breaking load) after
the start-up ramp and one inside it (/towline/state), and the runner's particulars record
naming the scenario `sea.yaml` beside the recording (waves Hs 2 m, Tp 8 s, start-up ramp 60 s).

Independent truth: the window starts at the ramp's end (60 s, the scenario's ramp_time); the
heave's significant value 4 sqrt(m0) = 4 A / sqrt(2) within 1 % and its peak period 8 s within
one Welch bin; roll the same with 3 deg and 10 s; pitch, which is zero, 0 with no peak period
(null, not NaN); two slack events in the window (the one in the ramp is outside); the maximum
120 kN; a sine's mean up-crossing period 9 s within 2 %.
"""
import json
import math

import numpy as np
import pytest

pytestmark = pytest.mark.timeout(120)

HEAVE, HEAVE_T, ROLL_DEG, ROLL_T = 0.4, 8.0, 3.0, 10.0
BREAKING = 500e3
SLACK = [(30.0, 34.0), (200.0, 205.0), (400.0, 403.0)]  # the first is inside the 60 s ramp
SCENARIO = """\
name: sea
duration: 600.0
exchange_rate: 10.0
environment: {waves: {hs: 2.0, tp: 8.0, from_deg: 0.0, ramp_time: 60.0}}
vessels:
  - name: tug
    ship_file: harbour_tug.yaml
    initial: {x: 0.0, y: 0.0, heading_deg: 0.0, speed: 0.0}
"""


def tension_a(t):
    x = 100e3 + 20e3 * np.sin(2 * math.pi * t / 9.0)
    for a, b in SLACK:
        x = np.where((t >= a) & (t < b), 0.0, x)
    return x


def write_sea_recording(path, duration=600.0, dt=0.1):
    from mcap.writer import Writer
    from nav_msgs.msg import Odometry
    from rclpy.serialization import serialize_message
    from geometry_msgs.msg import Pose
    from tug_msgs.msg import RopeState
    from recording.recorder import message_definition
    from scenario_format.particulars import PARTICULARS_METADATA
    t = np.arange(0.0, duration, dt)
    ta = tension_a(t)
    with open(path, "wb") as f:
        w = Writer(f)
        w.start(profile="ros2", library="test")
        chans = {}
        for topic, tname in (("/tug/odom", "nav_msgs/msg/Odometry"), ("/towline/state", "tug_msgs/msg/RopeState")):
            sid = w.register_schema(name=tname, encoding="ros2msg", data=message_definition(tname).encode())
            chans[topic] = w.register_channel(topic=topic, message_encoding="cdr", schema_id=sid)
        odom, rope = Odometry(), RopeState()
        rope.element_poses = [Pose(), Pose()]
        rope.element_poses[1].position.x = 50.0
        for k, tk in enumerate(t):
            ns = int(round(tk * 1e9))
            for msg in (odom, rope):
                msg.header.stamp.sec, msg.header.stamp.nanosec = ns // 10 ** 9, ns % 10 ** 9
            odom.pose.pose.position.x = 2.0 * tk
            odom.pose.pose.position.z = HEAVE * math.sin(2 * math.pi * tk / HEAVE_T)
            half = 0.5 * math.radians(ROLL_DEG) * math.sin(2 * math.pi * tk / ROLL_T)
            odom.pose.pose.orientation.x, odom.pose.pose.orientation.w = math.sin(half), math.cos(half)
            odom.twist.twist.linear.x = 2.0
            rope.end_a_force.x = float(ta[k])
            rope.end_b_force.x = -50e3
            for topic, msg in (("/tug/odom", odom), ("/towline/state", rope)):
                w.add_message(channel_id=chans[topic], log_time=ns, publish_time=ns, sequence=k,
                              data=serialize_message(msg))
        parts = {"scenario": "sea.yaml", "vessels": {"tug": {"ship_file": "harbour_tug.yaml", "length": 20.0}},
                 "ropes": {"towline": {"rope_file": "table1.yaml", "end_a": "tug/towing_hook", "end_b": "fixed",
                                       "breaking_load": BREAKING}}}
        w.add_metadata(PARTICULARS_METADATA, {"particulars": json.dumps(parts)})
        w.finish()
    return path


@pytest.fixture(scope="module")
def sea_recording(tmp_path_factory):
    d = tmp_path_factory.mktemp("sea")
    (d / "sea.yaml").write_text(SCENARIO)
    return write_sea_recording(str(d / "sea.mcap"))


def test_analyze_reports_sea_statistics_of_a_run_in_waves(sea_recording, tmp_path, run_in_process):
    out = run_in_process("analyze", sea_recording, "-o", tmp_path / "an", "--welch-segment", "200")
    assert out.returncode == 0, out.stdout + out.stderr
    assert "sea statistics: waves Hs 2 m, Tp 8 s" in out.stdout and "window 60.0 .. 599.9 s" in out.stdout, out.stdout
    print(out.stdout)
    summary = json.loads((tmp_path / "an" / "summary.json").read_text())
    sea = summary["sea"]
    assert sea["window_start"] == 60.0 and sea["window_source"] == "after the wave start-up ramp"
    assert sea["waves"]["ramp_time"] == 60.0 and sea["welch"]["segment"] == 200.0
    tug = summary["vessels"]["tug"]
    df = 1.0 / 200.0
    heave, roll, pitch = tug["sea_heave"], tug["sea_roll"], tug["sea_pitch"]
    assert heave["significant"] == pytest.approx(4 * HEAVE / math.sqrt(2), rel=0.01)
    assert abs(1 / heave["peak_period"] - 1 / HEAVE_T) <= df
    assert roll["significant"] == pytest.approx(4 * math.radians(ROLL_DEG) / math.sqrt(2), rel=0.01)
    assert abs(1 / roll["peak_period"] - 1 / ROLL_T) <= df
    assert pitch["m0"] == 0.0 and pitch["significant"] == 0.0 and pitch["peak_period"] is None
    end_a = summary["ropes"]["towline"]["sea_end_a"]
    assert end_a["slack_events"] == 2 and end_a["slack_threshold"] == pytest.approx(0.01 * BREAKING)
    assert end_a["slack_time"] == pytest.approx(5.0 + 3.0, abs=0.2)
    assert end_a["window_start"] == pytest.approx(60.0)
    assert end_a["tension_max"] == pytest.approx(120e3, rel=1e-3)
    assert end_a["upcrossing_period"] == pytest.approx(9.0, rel=0.02)
    end_b = summary["ropes"]["towline"]["sea_end_b"]
    assert end_b["tension_std"] == pytest.approx(0.0, abs=1e-6) and end_b["peaks"] == 0
    assert end_b["slack_events"] == 0 and end_b["weibull_shape"] is None
    csv = (tmp_path / "an" / "summary.csv").read_text()
    assert "vessel/tug,sea_heave.significant," in csv and ",m\n" in csv
    assert "rope/towline,sea_end_a.slack_events,2," in csv
    for name in ("sea_peaks.png", "sea_motion_spectra.png"):
        assert (tmp_path / "an" / name).stat().st_size > 10_000, name


def test_sea_window_and_no_waves_options(sea_recording, tmp_path, run_in_process):
    out = run_in_process("analyze", sea_recording, "-o", tmp_path / "w", "--no-figures", "--quiet",
                         "--sea-window", "0", "100")
    assert out.returncode == 0, out.stderr
    summary = json.loads((tmp_path / "w" / "summary.json").read_text())
    assert summary["sea"]["window_source"] == "--sea-window"
    end_a = summary["ropes"]["towline"]["sea_end_a"]
    assert end_a["slack_events"] == 1 and end_a["window_end"] == pytest.approx(100.0)
    out = run_in_process("analyze", sea_recording, "-o", tmp_path / "n", "--no-figures", "--quiet", "--no-waves")
    assert out.returncode == 0
    summary = json.loads((tmp_path / "n" / "summary.json").read_text())
    assert "sea" not in summary and "sea_heave" not in summary["vessels"]["tug"]
    out = run_in_process("analyze", sea_recording, "-o", tmp_path / "x", "--sea-window", "10", "5")
    assert out.returncode == 2 and "--sea-window" in out.stderr
    out = run_in_process("analyze", sea_recording, "-o", tmp_path / "x", "--scenario", tmp_path / "none.yaml")
    assert out.returncode == 2 and "none.yaml" in out.stderr


def test_calm_run_without_its_scenario_gets_the_section_only_when_asked(tmp_path, run_in_process):
    rec = write_sea_recording(str(tmp_path / "calm.mcap"), duration=60.0)  # no sea.yaml beside it
    out = run_in_process("analyze", rec, "-o", tmp_path / "a", "--no-figures")
    assert out.returncode == 0 and "sea.yaml is not beside it" in out.stdout, out.stdout
    assert "sea" not in json.loads((tmp_path / "a" / "summary.json").read_text())
    out = run_in_process("analyze", rec, "-o", tmp_path / "b", "--no-figures", "--quiet", "--waves")
    assert out.returncode == 0, out.stderr
    summary = json.loads((tmp_path / "b" / "summary.json").read_text())
    assert summary["sea"]["window_source"] == "whole run" and summary["sea"]["waves"] is None
    assert summary["vessels"]["tug"]["sea_heave"]["significant"] == pytest.approx(4 * HEAVE / math.sqrt(2), rel=0.03)
