"""The example autopilot as a lockstep participant declared in the scenario: it brings
the tug to the ordered heading and speed, and the run is reproducible (identical decoded
states twice)."""
import math
import subprocess

import numpy as np
import pytest

from conftest import executable_path

pytestmark = [pytest.mark.ros, pytest.mark.timeout(300)]


def run(out):
    proc = subprocess.run([executable_path("scenario_runner", "run_scenario"), "tug_autopilot_heading.yaml",
                           "--output", str(out), "--quiet"], capture_output=True, text=True, timeout=240)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory
    odom, cmds = [], []
    with open(out, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        for _s, c, _m, msg in reader.iter_decoded_messages(topics=["/tug/odom", "/tug/command"]):
            if c.topic == "/tug/odom":
                q, v = msg.pose.pose.orientation, msg.twist.twist
                odom.append((msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec, msg.pose.pose.position.x,
                             msg.pose.pose.position.y, 2 * math.atan2(q.z, q.w), v.linear.x, v.angular.z))
            else:
                cmds.append((msg.header.stamp.sec, msg.header.stamp.nanosec, msg.engine_order, msg.steering_angle))
    return np.array(odom), np.array(cmds)


def test_autopilot_participant_reaches_heading_and_is_reproducible(tmp_path, ros_domain):
    odom, cmds = run(tmp_path / "a.mcap")
    t, yaw, u = odom[:, 0], odom[:, 3], odom[:, 4]
    # a command for every step 1 .. N-1 (the step-0 one is sent at start-up and may precede the
    # recorder's discovery of the autopilot; a re-sent step-0 command may add a duplicate)
    stamps = {round(s + 1e-9 * ns, 6) for s, ns in cmds[:, :2]}
    assert {round(x, 6) for x in t[1:-1]} <= stamps
    late = t >= 90.0
    # ordered: heading 90 deg, 3 m/s; stated tolerance 2 deg and 0.1 m/s after 90 s
    assert np.all(np.abs(np.degrees(yaw[late]) - 90.0) < 2.0)
    assert np.all(np.abs(u[late] - 3.0) < 0.1)
    odom2, cmds2 = run(tmp_path / "b.mcap")
    np.testing.assert_array_equal(odom, odom2)
    by_stamp = {(s, ns): (e, d) for s, ns, e, d in cmds}
    by_stamp2 = {(s, ns): (e, d) for s, ns, e, d in cmds2}
    common = sorted(set(by_stamp) & set(by_stamp2))
    assert len(common) >= len(odom) - 2
    assert [by_stamp[k] for k in common] == [by_stamp2[k] for k in common]
