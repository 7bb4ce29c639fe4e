"""Per-thruster orders of the ASD tug through the vessel node (tug_msgs/ThrusterCommand on
/<vessel>/thruster_command, tug_msgs/ThrusterStatus on /<vessel>/thrusters): a valid order moves
the azimuths at the ship file's slew rate, clamps are counted; NaN, an unknown thruster, mismatched
lengths, too many orders by index are refused, counted and logged, and the last valid order holds;
a VesselCommand announced to the step protocol does not wait for a thruster order; a ship without
thrusters refuses them."""
import math

import pytest

from conftest import spin_until

pytestmark = [pytest.mark.ros, pytest.mark.timeout(60)]

PERIOD_NS = 20_000_000            # the default exchange rate, 50 Hz
SLEW = math.radians(18.0)         # ships/asd_tug.yaml: slew_rate_deg_s
RATED_RPM = 237.0                 # ships/asd_tug.yaml: rated_rpm


class Driver:
    """The test as the scenario runner of one lockstep vessel node (/tug)."""

    def __init__(self, rclpy_context, run_id):
        from rclpy.node import Node
        from sim_plumbing import ros_common as rc
        from tug_msgs.msg import (ScenarioEvent, SimStep, StepDone, ThrusterCommand, ThrusterStatus, VesselCommand,
                                  VesselStatus)
        self.rc, self.run_id = rc, run_id
        self.SimStep, self.ThrusterCommand, self.VesselCommand = SimStep, ThrusterCommand, VesselCommand
        self.node = Node("thruster_driver", context=rclpy_context)
        self.done, self.status, self.thrusters, self.events = set(), {}, {}, []
        sub = self.node.create_subscription
        sub(StepDone, rc.STEP_DONE_TOPIC, lambda m: self.done.add(m.step), rc.PROTOCOL_QOS)
        sub(VesselStatus, "/tug/status", lambda m: self.status.__setitem__(m.step, m), rc.LATCHED_STATE_QOS)
        sub(ThrusterStatus, "/tug/thrusters", lambda m: self.thrusters.__setitem__(m.step, m), rc.LATCHED_STATE_QOS)
        sub(ScenarioEvent, rc.EVENTS_TOPIC, self.events.append, rc.EVENTS_QOS)
        self.step_pub = self.node.create_publisher(SimStep, rc.SIM_STEP_TOPIC, rc.PROTOCOL_QOS)
        self.cmd_pub = self.node.create_publisher(VesselCommand, "/tug/command", rc.COMMAND_QOS)
        self.thr_pub = self.node.create_publisher(ThrusterCommand, "/tug/thruster_command", rc.COMMAND_QOS)

    def ready(self, log):
        assert spin_until(self.node, lambda: 0 in self.done and 0 in self.thrusters and all(
            p.get_subscription_count() > 0 for p in (self.step_pub, self.cmd_pub, self.thr_pub)), 30), log()

    def order(self, step, names, azimuth, rpm):
        msg = self.ThrusterCommand(thrusters=list(names), azimuth=list(azimuth), rpm=list(rpm))
        msg.header.stamp = self.rc.step_time(step, PERIOD_NS)
        self.thr_pub.publish(msg)
        spin_until(self.node, lambda: False, 0.2)  # an order from outside the protocol: let it arrive

    def steps(self, first, last, log, ordered_at=()):
        """Trigger steps first..last-1 one by one (ordered_at: steps announced as ordered)."""
        for k in range(first, last):
            msg = self.SimStep(run_id=self.run_id, step=k, period=PERIOD_NS * 1e-9,
                               ordered=["tug"] if k in ordered_at else [])
            msg.header.stamp = msg.time = self.rc.step_time(k, PERIOD_NS)
            self.step_pub.publish(msg)
            # the step's thruster status too: its writer keeps the last 50, and a loaded test process
            # triggering 150 steps without reading them lost one (KeyError: 12 under pytest-xdist)
            assert spin_until(self.node, lambda: k + 1 in self.done and k + 1 in self.thrusters, 10), \
                f"step {k} not done\n{log()}"
        assert spin_until(self.node, lambda: last in self.thrusters and last in self.status, 10), log()


def test_thruster_orders_through_the_vessel_node(start_node, rclpy_context):
    vessel = start_node("tug_dynamics", "vessel_node", "--ros-args", "-r", "__ns:=/tug", "-p",
                        "ship_file:=asd_tug.yaml", "-p", "lockstep:=true", "-p", "run_id:=thr")
    d = Driver(rclpy_context, "thr")
    try:
        d.ready(vessel.log)
        first = d.thrusters[0]
        assert list(first.names) == ["port", "starboard"] and first.header.frame_id == "tug/base_link"
        assert list(first.azimuth) == [0.0, 0.0] and list(first.rpm) == [0.0, 0.0]

        # valid: 45 deg (thrust to port-ahead), starboard's rpm 1.5 clamped to 1
        target = math.radians(45.0)
        d.order(0, ["port", "starboard"], [target, target], [0.5, 1.5])
        d.steps(0, 150, vessel.log)
        th = [d.thrusters[k] for k in range(151)]
        assert th[1].azimuth_ordered[0] == pytest.approx(target) and th[1].rpm_ordered[1] == pytest.approx(RATED_RPM)
        assert th[1].rpm_ordered[0] == pytest.approx(0.5 * RATED_RPM)
        for i in range(2):
            az = [m.azimuth[i] for m in th]
            moves = [b - a for a, b in zip(az, az[1:])]
            assert min(moves) >= 0.0 and max(moves) <= SLEW * PERIOD_NS * 1e-9 * (1 + 1e-9), i  # rate-limited
            assert moves[10] == pytest.approx(SLEW * PERIOD_NS * 1e-9, rel=1e-6)  # at the slew rate, far off
            # at the rate for 2 s (to 9 deg = rate x the 0.5 s azimuth time constant short), then the lag
            assert az[100] == pytest.approx(target - math.radians(9.0), abs=math.radians(0.5))
            assert az[150] == pytest.approx(target, abs=math.radians(2.0))
            assert th[-1].thrust[i] > 0.0
        assert d.status[150].commands_clamped == 1 and d.status[150].commands_rejected == 0

        # invalid: refused on arrival, counted; every held order stays
        d.order(150, ["port", "starboard"], [float("nan"), 0.0], [0.5, 0.5])
        d.order(150, ["port", "bow"], [0.0, 0.0], [0.5, 0.5])
        d.order(150, ["port", "starboard"], [0.0], [0.5, 0.5])
        d.order(150, [], [0.0, 0.0, 0.0], [0.1, 0.1, 0.1])
        d.order(150, ["port", "port"], [0.0, 0.0], [0.5, 0.5])
        d.steps(150, 160, vessel.log)
        assert d.status[160].commands_rejected == 5 and d.status[160].commands_clamped == 1
        last = d.thrusters[160]
        assert list(last.azimuth_ordered) == pytest.approx([target, target])
        assert list(last.rpm_ordered) == pytest.approx([0.5 * RATED_RPM, RATED_RPM])
        log = vessel.log()
        assert "thruster command rejected" in log and "not finite" in log, log  # the first; then rate-limited
        assert spin_until(d.node, lambda: any(e.kind == "command_rejected" and "thruster_command" in e.detail
                                              for e in d.events), 5)

        # by index, announced VesselCommand: a step ordered by the runner waits for `command` only
        d.order(160, [], [-target], [0.2])  # thruster 0 (port) only
        d.steps(160, 161, vessel.log)
        assert list(d.thrusters[161].azimuth_ordered) == pytest.approx([-target, target])
        cmd = d.VesselCommand(engine_order=0.3, steering_angle=0.0)
        cmd.header.stamp = d.rc.step_time(161, PERIOD_NS)
        d.cmd_pub.publish(cmd)
        d.steps(161, 163, vessel.log, ordered_at={161})  # no stall
        assert list(d.thrusters[163].azimuth_ordered) == pytest.approx([0.0, 0.0])  # the command sets every unit
        assert list(d.thrusters[163].rpm_ordered) == pytest.approx([0.3 * RATED_RPM] * 2)
    finally:
        d.node.destroy_node()


BAD_ORDERS = [  # (thrusters, azimuth, rpm), what the refusal names
    (("port", "starboard"), (float("nan"), 0.0), (0.5, 0.5), "thruster port: azimuth=nan"),
    ((), (0.0, 0.0), (0.5, float("inf")), r"thruster 1 \(starboard\).*rpm=inf"),
    (("port", "bow"), (0.0, 0.0), (0.5, 0.5), r"\['bow'\] do not exist; vessel 'tug' has \['port', 'starboard'\]"),
    (("port", "starboard"), (0.0,), (0.5, 0.5), "lengths differ: 2 thrusters, 1 azimuth, 2 rpm"),
    (("port",), (0.0, 0.0), (0.5, 0.5), "lengths differ"),
    ((), (0.0, 0.0, 0.0), (0.1, 0.1, 0.1), "3 orders by index, vessel 'tug' has 2 thrusters"),
    (("port", "port"), (0.0, 0.0), (0.5, 0.5), r"\['port'\] ordered twice"),
    ((), (), (), "no orders"),
]


def _in_process_vessel(rclpy_context, ship_file):
    from rclpy.parameter import Parameter
    from sim_contract.topics import THRUSTER_COMMAND
    from tug_dynamics.vessel_node import VesselNode
    node = VesselNode(context=rclpy_context, namespace="/tug", parameter_overrides=[
        Parameter("ship_file", value=ship_file), Parameter("lockstep", value=True), Parameter("run_id", value="r")])
    return node, next(s for s in node.inputs if s.topic == THRUSTER_COMMAND)


def test_bad_thruster_orders_are_refused_naming_what_is_wrong(rclpy_context):
    from sim_plumbing import cdr
    from tug_dynamics.vessel import CommandRejected
    node, spec = _in_process_vessel(rclpy_context, "asd_tug.yaml")
    try:
        assert spec.kind == "order"
        held = node.model.status().thrusters
        for i, (names, azimuth, rpm, why) in enumerate(BAD_ORDERS):
            msg = cdr.ThrusterCommandIn(0, names, azimuth, rpm)
            with pytest.raises(CommandRejected, match=why):
                node._thruster_orders(msg)
            assert not node.accept_input(spec, msg) and node.rejected == i + 1
        assert node.complaints.counts["thruster command rejected"] == len(BAD_ORDERS)
        assert node.model.status().thrusters == held
        good = cdr.ThrusterCommandIn(0, (), (0.1,), (0.2,))
        assert node.accept_input(spec, good) and node.rejected == len(BAD_ORDERS)
    finally:
        node.destroy_node()


def test_a_ship_without_thrusters_refuses_thruster_orders(rclpy_context):
    from sim_plumbing import cdr
    node, spec = _in_process_vessel(rclpy_context, "harbour_tug.yaml")
    try:
        assert node.thrusters_pub is None  # no /tug/thrusters topic
        held = node.model.command
        with pytest.raises(Exception, match="vessel 'tug' .*has no azimuth thrusters"):
            node._thruster_orders(cdr.ThrusterCommandIn(0, (), (0.0,), (0.5,)))
        assert not node.accept_input(spec, cdr.ThrusterCommandIn(0, (), (0.0,), (0.5,)))
        assert node.rejected == 1 and node.model.command == held
        assert node.complaints.counts["thruster command rejected"] == 1
    finally:
        node.destroy_node()
