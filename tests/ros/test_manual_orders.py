"""Manual orders stick (issue 32, "At the controls"): a paced run (a lockstep file run with
run_scenario --realtime) of three tugs where

- the script puts tug's helm 10 deg to port, then gives an engine-only order: the helm stays;
- send_command gives tug engine 0.8 and helm 10 deg starboard: announced `manual_order` (engine
  and helm, by /send_command, "script yields"); the script's later engine and helm orders for tug
  yield (`scripted_order_yielded`) while its order for tug2 fires: the recording shows the manual
  order held by the vessel until changed;
- send_command --hand-back engine gives the engine back (`manual_handed_back`): the script's next
  engine order fires, its helm order still yields;
- tug3 is manned: announced at the start, never sent an order by the script;
- the run is paced: 27 s of simulated time take about 27 s of wall time.

Read back with the recording's own reader (recording.recorded_run.Recording)."""
import math
import re
import subprocess
import time

import numpy as np
import pytest
import yaml

from conftest import executable_path, spin_until

pytestmark = [pytest.mark.ros, pytest.mark.timeout(300)]

RATE = 20.0
DURATION = 27.0


def _scenario(tmp_path):
    tug = lambda name, y, **extra: {"name": name, "ship_file": "harbour_tug.yaml",  # noqa: E731
                                     "initial": {"x": 0.0, "y": y, "heading_deg": 0.0}, **extra}
    sc = {"name": "manual_orders", "duration": DURATION, "exchange_rate": RATE, "mode": "lockstep",
          "vessels": [tug("tug", 0.0), tug("tug2", 100.0),
                      tug("tug3", 200.0, manned=True, initial={"x": 0.0, "y": 200.0, "engine_order": 0.4})],
          "events": [{"time": 0.0, "vessel": "tug", "engine_order": 0.5},
                     {"time": 0.0, "vessel": "tug2", "engine_order": 0.3},
                     {"time": 1.0, "vessel": "tug", "steering_deg": 10.0},
                     {"time": 2.0, "vessel": "tug", "engine_order": 0.6},             # engine only
                     {"time": 14.0, "vessel": "tug", "engine_order": 0.2},            # yields (manual)
                     {"time": 14.0, "vessel": "tug2", "engine_order": 0.6},           # fires
                     {"time": 24.0, "vessel": "tug", "engine_order": 0.1, "steering_deg": 0.0}]}  # engine fires
    path = tmp_path / "manual_orders.yaml"
    path.write_text(yaml.safe_dump(sc))
    return path


def _wait_for_sim_time(node, clock, t, run):
    assert spin_until(node, lambda: clock[0] >= t or run.poll() is not None, 120.0), f"/clock never reached {t} s"
    assert run.poll() is None, run.communicate()


def _send(*args):
    done = subprocess.run([executable_path("scenario_runner", "send_command"), *args], capture_output=True,
                          text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    return float(re.search(r"stamped (\d+\.\d+) s", done.stdout).group(1))


def test_manual_orders_stick_until_handed_back(tmp_path, rclpy_context):
    from rclpy.node import Node
    from rosgraph_msgs.msg import Clock
    path = _scenario(tmp_path)
    out = tmp_path / "manual_orders.mcap"
    node = Node("clock_watch", context=rclpy_context)
    clock = [0.0]
    node.create_subscription(Clock, "/clock", lambda m: clock.__setitem__(0, m.clock.sec + m.clock.nanosec * 1e-9),
                             10)
    run = subprocess.Popen([executable_path("scenario_runner", "run_scenario"), str(path), "--output", str(out),
                            "--quiet", "--realtime"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        _wait_for_sim_time(node, clock, 3.0, run)
        t_manual = _send("tug", "--engine", "0.8", "--steering-deg", "-10")
        assert 3.0 <= t_manual < 13.0, t_manual  # before the script's next tug order (14 s)
        _wait_for_sim_time(node, clock, 15.0, run)
        t_back = _send("tug", "--hand-back", "engine")
        assert 15.0 <= t_back < 23.0, t_back
        stdout, stderr = run.communicate(timeout=120)
    finally:
        if run.poll() is None:
            run.kill()
    assert run.returncode == 0, stderr

    from recording.recorded_run import Recording, status_column
    rec = Recording(str(out))
    status = {v: (rec.vessels[v]["status"]["t"], status_column(rec.vessels[v]["status"], "engine_order"),
                  np.degrees(status_column(rec.vessels[v]["status"], "steering_angle_ordered")))
              for v in ("tug", "tug2", "tug3")}

    def held(vessel, t0, t1):
        """(engine orders, helm orders in deg) the vessel held in its states of t0 < t <= t1."""
        t, engine, helm = status[vessel]
        sel = (t > t0 + 1e-6) & (t <= t1 + 1e-6)
        assert sel.any(), (vessel, t0, t1)
        return set(np.round(engine[sel], 9)), set(np.round(helm[sel], 6))

    dt = 1.0 / RATE
    # the script's helm 10 deg port stays through its engine-only order at 2 s
    assert held("tug", 1.0 + dt, 2.0) == ({0.5}, {10.0})
    t, engine, _ = status["tug"]
    t_applied = t[np.argmax(engine == 0.8)]  # the vessel's first state under the manual order
    assert held("tug", 2.0 + dt, t_applied - dt) == ({0.6}, {10.0})
    assert t_manual <= t_applied <= t_manual + 1.0, (t_manual, t_applied)
    # the manual order stays in force through the script's engine order at 14 s, until handed back
    # and the script's next engine order (24 s); the helm stays the person's to the end
    assert held("tug", t_applied, 24.0) == ({0.8}, {-10.0})
    assert held("tug", 24.0 + dt, DURATION) == ({0.1}, {-10.0})
    # tug2's scripted orders fire
    assert held("tug2", dt, 14.0) == ({0.3}, {0.0}) and held("tug2", 14.0 + dt, DURATION) == ({0.6}, {0.0})
    # tug3 (manned) holds its initial order; the script never ordered it
    assert held("tug3", 0.0, DURATION) == ({0.4}, {0.0})
    assert "command" not in rec.vessels["tug3"] or rec.vessels["tug3"]["command"]["t"].size == 0

    ev = [(round(e["time"], 3), e["kind"], e["target"], e["detail"]) for e in rec.events]
    manual = [e for e in ev if e[1] == "manual_order"]
    assert [(e[2], e[3].split(":")[0]) for e in manual] == [("tug3", "tug3 is manned (vessels[2].manned)"),
                                                            ("tug", "tug engine"), ("tug", "tug helm")], manual
    for e in manual[1:]:
        assert "/send_command" in e[3] and "script yields" in e[3] and t_manual <= e[0] <= t_applied + dt, e
    yielded = [(e[0], e[3].split(":")[0]) for e in ev if e[1] == "scripted_order_yielded"]
    assert yielded == [(14.0, "events[4]"), (24.0, "events[6]")], yielded
    assert "helm midships not given" in [e for e in ev if e[1] == "scripted_order_yielded"][1][3]
    back = [e for e in ev if e[1] == "manual_handed_back"]
    assert len(back) == 1 and back[0][2] == "tug" and "engine" in back[0][3] and t_back <= back[0][0] <= 24.0
    # the script's orders as sent: tug2 at 14 s, tug at 24 s (engine 0.1, the person's helm)
    orders = [(e[0], e[2], e[3]) for e in ev if e[1] == "order" and e[0] >= 14.0]
    assert (14.0, "tug2", "engine +0.60, steering +0.0 deg") in orders
    assert (24.0, "tug", "engine +0.10, steering -10.0 deg") in orders
    assert not [o for o in orders if o[1] == "tug" and o[0] < 24.0], orders
    # nothing to confirm: the runner had sent tug no order since the manual order's stamp
    assert not [e for e in ev if "confirms" in e[3]], ev

    # paced: the stepping's wall time (scenario_finished) is the simulated time, within a loose margin
    finished = [e for e in ev if e[1] == "scenario_finished"]
    wall = float(re.search(r"in (\d+\.\d) s wall", finished[0][3]).group(1))
    assert 0.95 * DURATION <= wall <= 2.0 * DURATION, finished


def test_an_outside_autopilot_takes_the_helm(tmp_path, rclpy_context, start_node):
    """The example autopilot started by hand (free-running, fixed engine order 0.5 as the script
    gave) during a paced run: its helm orders take the helm (`manual_order` naming it), the
    script's later helm order yields; the script's engine order fires, and the autopilot's next
    order (engine 0.5 again) takes the engine back: an outside controller ordering every step
    owns what it orders."""
    from rclpy.node import Node
    from rosgraph_msgs.msg import Clock
    sc = {"name": "autopilot_orders", "duration": 24.0, "exchange_rate": RATE, "mode": "realtime",
          "vessels": [{"name": "tug", "ship_file": "harbour_tug.yaml"}],
          "events": [{"time": 0.0, "vessel": "tug", "engine_order": 0.5},
                     {"time": 20.0, "vessel": "tug", "engine_order": 0.7, "steering_deg": 0.0}]}
    path = tmp_path / "autopilot_orders.yaml"
    path.write_text(yaml.safe_dump(sc))
    out = tmp_path / "autopilot_orders.mcap"
    node = Node("clock_watch", context=rclpy_context)
    clock = [0.0]
    node.create_subscription(Clock, "/clock", lambda m: clock.__setitem__(0, m.clock.sec + m.clock.nanosec * 1e-9),
                             10)
    run = subprocess.Popen([executable_path("scenario_runner", "run_scenario"), str(path), "--output", str(out),
                            "--quiet"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        _wait_for_sim_time(node, clock, 1.0, run)
        start_node("scenario_runner", "autopilot", "--ros-args", "-r", "__ns:=/tug_autopilot", "-p", "vessel:=tug",
                   "-p", "heading:=90.0", "-p", "speed_control:=false", "-p", "engine_order:=0.5")
        stdout, stderr = run.communicate(timeout=120)
    finally:
        if run.poll() is None:
            run.kill()
    assert run.returncode == 0, stderr

    from recording.recorded_run import Recording, status_column
    rec = Recording(str(out))
    ev = [(round(e["time"], 3), e["kind"], e["target"], e["detail"]) for e in rec.events]
    manual = [e for e in ev if e[1] == "manual_order"]
    assert [e[3].split(":")[0] for e in manual] == ["tug helm", "tug engine"], manual
    assert all("/tug_autopilot/autopilot" in e[3] for e in manual), manual
    assert manual[0][0] < 19.0 and 20.0 <= manual[1][0] <= 21.0, manual  # the engine: after the script's 0.7
    yielded = [(e[0], e[3].split(":")[0]) for e in ev if e[1] == "scripted_order_yielded"]
    assert yielded == [(20.0, "events[1]")], yielded
    assert [e for e in ev if e[:3] == (20.0, "order", "tug") and e[3].startswith("engine +0.70, steering ")], ev
    st = rec.vessels["tug"]["status"]
    t, engine = st["t"], status_column(st, "engine_order")
    helm = np.degrees(status_column(st, "steering_angle_ordered"))
    after = t > 20.0 + 1e-6
    # (the script's 0.7 holds a step or so: the pilot's next order takes the engine back)
    assert engine[-1] == 0.5 and np.count_nonzero(engine[after] == 0.7) <= 3
    assert np.count_nonzero(helm[after]) > 0.5 * np.count_nonzero(after)  # still the pilot's helm, not midships
