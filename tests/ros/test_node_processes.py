"""A tug_msgs message crosses between two node processes over DDS, and a run in another domain
does not see it; the vessel node rejects NaN commands."""
import math
import subprocess

import pytest

from conftest import executable_path, spin_until

pytestmark = [pytest.mark.ros, pytest.mark.timeout(120)]

TUG = ["--ros-args", "-r", "__ns:=/tug", "-r", "__node:=vessel", "-p", "ship_file:=harbour_tug.yaml",
       "-p", "exchange_rate:=20.0"]


def _status_listener(ctx, topic="/tug/status"):
    from rclpy.node import Node
    from tug_msgs.msg import VesselStatus
    from sim_plumbing import ros_common as rc
    node = Node("test_listener", context=ctx)
    received = []
    node.create_subscription(VesselStatus, topic, received.append, rc.LATCHED_STATE_QOS)
    return node, received


def _send(domain, *args, timeout=60):
    import os
    env = dict(os.environ, ROS_DOMAIN_ID=str(domain))
    return subprocess.run([executable_path("scenario_runner", "send_command"), "tug", *args],
                          env=env, capture_output=True, text=True, timeout=timeout)


def test_command_crosses_from_one_process_to_another(start_node, rclpy_context, ros_domain):
    vessel = start_node("tug_dynamics", "vessel_node", *TUG)
    node, received = _status_listener(rclpy_context)
    assert spin_until(node, lambda: len(received) > 0, 60), vessel.log()
    # send_command (a second process) -> /tug/command (tug_msgs/VesselCommand) -> vessel_node
    sent = _send(ros_domain, "--engine", "0.5", "--steering-deg", "10")
    assert sent.returncode == 0, sent.stderr
    assert spin_until(node, lambda: abs(received[-1].engine_order - 0.5) < 1e-12, 20), vessel.log()
    assert received[-1].steering_angle_ordered == pytest.approx(math.radians(10.0))
    # an order sets what it names: the helm alone leaves the engine where it is
    sent = _send(ros_domain, "--steering-deg", "-5")
    assert sent.returncode == 0, sent.stderr
    assert "engine +0.50, steering -5.0 deg" in sent.stdout
    assert spin_until(node, lambda: abs(received[-1].steering_angle_ordered - math.radians(-5.0)) < 1e-12, 20)
    assert received[-1].engine_order == 0.5

    # Another domain: the same command finds no vessel there and is never delivered here.
    from domain_coordinator import domain_id
    with domain_id() as other:
        assert other != ros_domain
        missed = _send(other, "--engine", "-0.7", "--wait", "3")
    assert missed.returncode == 1 and "no subscriber" in missed.stderr
    n = len(received)
    spin_until(node, lambda: False, 2.0)
    assert len(received) > n  # the vessel is still publishing ...
    assert all(abs(m.engine_order - 0.5) < 1e-12 for m in received[n:])  # ... with the old order
    node.destroy_node()


def test_nan_command_is_rejected_and_logged(start_node, rclpy_context, ros_domain):
    vessel = start_node("tug_dynamics", "vessel_node", *TUG)
    node, received = _status_listener(rclpy_context)
    assert spin_until(node, lambda: len(received) > 0, 60), vessel.log()
    assert _send(ros_domain, "--engine", "0.4").returncode == 0
    assert spin_until(node, lambda: abs(received[-1].engine_order - 0.4) < 1e-12, 20)
    # send_command itself refuses NaN (exit 2), so a raw publisher sends it
    from sim_plumbing import ros_common as rc
    from tug_msgs.msg import VesselCommand
    assert _send(ros_domain, "--engine", "nan").returncode == 2
    pub = node.create_publisher(VesselCommand, "/tug/command", rc.COMMAND_QOS)
    assert spin_until(node, lambda: pub.get_subscription_count() > 0, 20)
    pub.publish(VesselCommand(engine_order=float("nan")))
    assert spin_until(node, lambda: received[-1].commands_rejected == 1, 20), vessel.log()
    assert received[-1].engine_order == pytest.approx(0.4)  # last valid order kept
    assert _send(ros_domain, "--engine", "3.0").returncode == 0  # out of range: clamped to full ahead
    assert spin_until(node, lambda: received[-1].commands_clamped >= 1, 20), vessel.log()
    node.destroy_node()
    vessel.stop()
    log = vessel.log()
    assert "command rejected" in log and "engine_order=nan" in log
    assert "command clamped" in log


def test_an_order_to_a_vessel_on_a_prescribed_motion_is_refused_aloud(start_node, rclpy_context, ros_domain):
    """The motion law moves the vessel whatever it is ordered: an order is refused, counted and
    logged with the reason (it was ignored without a word), and the motion goes on."""
    vessel = start_node("tug_dynamics", "vessel_node", *TUG, "-p", "motion:=constant_speed", "-p", "motion_speed:=1.0")
    node, received = _status_listener(rclpy_context)
    assert spin_until(node, lambda: len(received) > 0, 60), vessel.log()
    assert _send(ros_domain, "--engine", "0.4").returncode == 0
    assert spin_until(node, lambda: received[-1].commands_rejected == 1, 20), vessel.log()
    assert received[-1].engine_order == 0.0
    node.destroy_node()
    vessel.stop()
    assert "'tug' follows a prescribed motion: orders have no effect" in vessel.log()


def test_print_nodes_gives_a_ros2_run_line_per_node(run_in_process, tmp_path):
    """`run_scenario default_demo.yaml --print-nodes` (docs/several-machines.md): one `ros2 run`
    line per node of the scenario; without --run-id no run_id (the node joins the first run it
    sees), with it the same id on every line. A ship or rope file the packages ship goes by its
    bare name (another PC's node finds it in its own installation), a user's own by its path."""
    import shlex
    import shutil
    import yaml
    from scenario_runner import run_nodes
    from scenario_format.scenario import load_scenario
    from ament_index_python.packages import get_package_share_directory
    import os
    path = os.path.join(get_package_share_directory("scenario_runner"), "scenarios", "default_demo.yaml")
    scenario = load_scenario(path)
    specs = run_nodes.node_specs(scenario, path)
    shipped = {v.ship_file for v in scenario.vessels} | {r.rope_file for r in scenario.ropes}
    for extra, run_id in (((), None), (("--run-id", "study-7"), "study-7")):
        out = run_in_process("run_scenario", "default_demo.yaml", "--print-nodes", *extra)
        assert out.returncode == 0, out.stderr
        lines = out.stdout.strip().splitlines()
        assert len(lines) == len(specs) >= 3
        for line, spec in zip(lines, specs):
            words = shlex.split(line)
            assert words[:4] == ["ros2", "run", spec.package, spec.executable] and words[4] == "--ros-args", line
            params = [w for i, w in enumerate(words) if i > 0 and words[i - 1] == "-p"]
            ids = [p for p in params if p.startswith("run_id:=")]
            assert ids == ([] if run_id is None else [f'run_id:="{run_id}"']), line
            # the files the packages ship by their bare names: another PC finds them in its install
            files = [p.split(":=")[1].strip('"') for p in params if p.split(":=")[0] in ("ship_file", "rope_file")]
            assert len(files) == 1 and files[0] in shipped, line
    # a ship file of the user's own, beside the scenario, keeps its path (the other PC needs it there)
    sc = yaml.safe_load(open(path))
    sc["vessels"][0]["ship_file"] = "my_tug.yaml"
    shutil.copy(os.path.join(get_package_share_directory("tug_dynamics"), "ships", "harbour_tug.yaml"),
                tmp_path / "my_tug.yaml")
    (tmp_path / "own.yaml").write_text(yaml.safe_dump(sc))
    out = run_in_process("run_scenario", tmp_path / "own.yaml", "--print-nodes")
    assert out.returncode == 0, out.stderr
    first = shlex.split(out.stdout.splitlines()[0])
    assert f'ship_file:="{tmp_path / "my_tug.yaml"}"' in first, first
