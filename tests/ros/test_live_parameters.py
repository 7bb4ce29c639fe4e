"""Parameters that can change while running take effect through on-set
callbacks (the autopilot's orders, gains and limits, the rope's marker rate); every other
parameter is fixed at start-up and a change is refused with the reason, leaving the old value.
Parameters are set here through the standard rcl_interfaces services (rclpy's client), as
`ros2 param set` does."""
import math

import numpy as np
import pytest

from conftest import spin_until
from test_autopilot import AUTOPILOT_NS, TUG, Observer

pytestmark = [pytest.mark.ros, pytest.mark.timeout(120)]


def _set(client_node, target, **values):
    """Set parameters of node `target` one at a time; returns [(successful, reason)]."""
    from rclpy.parameter import Parameter
    from rclpy.parameter_client import AsyncParameterClient
    client = AsyncParameterClient(client_node, target)
    assert client.wait_for_services(timeout_sec=20.0), f"no parameter services of {target}"
    future = client.set_parameters([Parameter(k, value=v) for k, v in values.items()])
    assert spin_until(client_node, future.done, 10.0)
    return [(r.successful, r.reason) for r in future.result().results]


def _get(client_node, target, name):
    from rclpy.parameter import parameter_value_to_python
    from rclpy.parameter_client import AsyncParameterClient
    client = AsyncParameterClient(client_node, target)
    assert client.wait_for_services(timeout_sec=20.0)
    future = client.get_parameters([name])
    assert spin_until(client_node, future.done, 10.0)
    return parameter_value_to_python(future.result().values[0])


def test_autopilot_order_changes_while_running_fixed_ones_are_refused(start_node, rclpy_context):
    start_node("tug_dynamics", "vessel_node", *TUG)
    start_node("scenario_runner", "autopilot", "--ros-args", *AUTOPILOT_NS, "-p", "vessel:=tug", "-p", "heading:=0.0",
               "-p", "speed_control:=false", "-p", "engine_order:=0.3", "-p", "max_steering_deg:=30.0")
    obs = Observer(rclpy_context)
    target = "/tug_autopilot/autopilot"
    try:
        # on the ordered heading (the tug starts heading east = 0 deg): little steering
        assert obs.spin_until(lambda: len(obs.commands) > 20, 30.0)
        assert abs(math.degrees(obs.commands[-1].steering_angle)) < 5.0
        # a new heading 90 deg to port: an error far beyond kp's linear range, so the
        # steering saturates at +max_steering (positive = to port, REP-103) from the next step
        assert _set(obs.node, target, heading=90.0) == [(True, "")]
        n = len(obs.commands)
        assert obs.spin_until(lambda: len(obs.commands) > n + 5, 10.0)
        assert math.degrees(obs.commands[-1].steering_angle) == pytest.approx(30.0, abs=1e-6)
        # a new limit in effect too
        assert _set(obs.node, target, max_steering_deg=20.0) == [(True, "")]
        n = len(obs.commands)
        assert obs.spin_until(lambda: len(obs.commands) > n + 5, 10.0)
        assert math.degrees(obs.commands[-1].steering_angle) == pytest.approx(20.0, abs=1e-6)
        # fixed at start-up: refused with the reason, the value unchanged
        (ok, reason), = _set(obs.node, target, mode="track")
        assert not ok and "mode" in reason and "fixed at start-up" in reason
        assert _get(obs.node, target, "mode") == "heading"
        # outside the declared range: refused by the descriptor
        (ok, reason), = _set(obs.node, target, heading=500.0)
        assert not ok and _get(obs.node, target, "heading") == 90.0
        # a combination the law refuses: refused, old limits kept
        (ok, reason), = _set(obs.node, target, min_engine_order=1.0)  # not below max_engine_order 1.0
        assert not ok and "engine limits" in reason
        assert _get(obs.node, target, "min_engine_order") == 0.0
        # the vessel's parameters shaped its model: all fixed
        (ok, reason), = _set(obs.node, "/tug/vessel", initial_speed=3.0)
        assert not ok and "fixed at start-up" in reason
    finally:
        obs.node.destroy_node()


def test_rope_marker_rate_changes_while_running(start_node, rclpy_context):
    """A free-running rope between two fixed points publishes markers at marker_rate; set to
    another rate it publishes at that one. Measured in simulation time (the spacing of the
    markers' stamps, exact: every n-th step), not wall time, which a loaded machine bunches."""
    from rclpy.node import Node
    from visualization_msgs.msg import MarkerArray
    from sim_plumbing import ros_common as rc
    start_node("rope_model", "rope_node", "--ros-args", "-r", "__ns:=/towline", "-r", "__node:=rope",
               "-p", "end_a:=fixed", "-p", "end_a_position:=[0.0, 0.0, 0.0]", "-p", "end_b:=fixed",
               "-p", "end_b_position:=[95.0, 0.0, 0.0]", "-p", "exchange_rate:=20.0", "-p", "marker_rate:=2.0")
    node = Node("marker_counter", context=rclpy_context)
    stamps = []
    def stamp_s(msg):
        st = msg.markers[0].header.stamp
        return st.sec + st.nanosec * 1e-9

    node.create_subscription(MarkerArray, "/towline/markers", lambda m: stamps.append(stamp_s(m)),
                             rc.LATCHED_STATE_QOS)
    try:
        assert spin_until(node, lambda: len(stamps) >= 3, 60.0), "no markers"

        def measured(markers):
            """Rate (1/s of simulation time) of the next markers after the one now latest."""
            n0 = len(stamps)
            assert spin_until(node, lambda: len(stamps) >= n0 + markers + 1, 60.0), "markers stopped"
            return 1.0 / float(np.median(np.diff(stamps[n0 + 1:])))

        assert measured(3) == pytest.approx(2.0, rel=1e-6)
        assert _set(node, "/towline/rope", marker_rate=10.0) == [(True, "")]
        assert measured(10) == pytest.approx(10.0, rel=1e-6)
    finally:
        node.destroy_node()


def test_nodes_refuse_a_change_they_would_not_apply(rclpy_context, tmp_path):
    """The live view and nmea_out read their parameters at start-up (the sender's rate, the
    sentence rate, the origin...): `ros2 param set` of one is refused with the reason and the old
    value stays; the live view's input_rate, read for each new client, is accepted. Nodes built in
    this process: the set goes through the same on-set callback the parameter service calls."""
    from rclpy.parameter import Parameter
    from bridge_instruments.nmea_out import NmeaOut
    from live_view.live_view_node import LiveViewNode
    view = LiveViewNode(context=rclpy_context, parameter_overrides=[
        Parameter("port", value=0), Parameter("http_port", value=-1), Parameter("discover", value=False)])
    nmea = NmeaOut(context=rclpy_context, parameter_overrides=[Parameter("vessels", value=["tug"])])
    try:
        for node, name, value in ((view, "rate", 5.0), (view, "host", "0.0.0.0"), (nmea, "rate", 2.0),
                                  (nmea, "origin_latitude", 10.0)):
            old = node.get_parameter(name).value
            [result] = node.set_parameters([Parameter(name, value=value)])
            assert not result.successful and f"{name}: fixed at start-up" in result.reason, (node, name)
            assert node.get_parameter(name).value == old
        [result] = view.set_parameters([Parameter("input_rate", value=5.0)])
        assert result.successful and view.get_parameter("input_rate").value == 5.0
    finally:
        view.destroy_node()
        nmea.destroy_node()
