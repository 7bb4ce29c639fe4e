"""The terminal console (bridge_instruments console, Textual) driven in a pseudo-terminal
(pexpect) during a paced run built to reach the girting limit: an abeam towline to a fixed
point, the tug driven ahead.

- keys raise the engine order and put the helm to starboard: the orders are in the recording
  on /tug/command, the vessel holds and applies them (status: engine order, helm ordered and
  actual, shaft speed);
- the screen shows the towline tension in kN against the breaking load and the girting warning;
- invalid keys and a flood of engine keys never produce an out-of-range order.
"""
import math
import os
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


def test_console_drives_the_tug_into_a_girting_warning(tmp_path, ros_domain):
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
    rec = decoded(str(out))
    cmds = rec["/tug/command"]
    t = lambda m: m.header.stamp.sec + m.header.stamp.nanosec * 1e-9
    # every order in range; the console's orders stamped with simulation time (within the run)
    assert all(-1.0 <= c.engine_order <= 1.0 and abs(c.steering_angle) <= math.radians(35.0) + 1e-12 for c in cmds)
    mine = [c for c in cmds if t(c) > 0.0]
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
