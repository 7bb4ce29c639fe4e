"""Example autopilot: an outside controller written only against the topic contract.

    ros2 run scenario_runner autopilot --ros-args -r __ns:=/tug_autopilot \\
        -p vessel:=tug -p heading:=90.0 -p speed:=3.0
    ros2 run scenario_runner autopilot --ros-args -r __ns:=/tug_autopilot \\
        -p vessel:=tug -p heading_true_deg:=0.0 -p speed:=3.0     # the same order as a compass heading
    ros2 run scenario_runner autopilot --ros-args -r __ns:=/tug_autopilot \\
        -p vessel:=tug -p mode:=track -p track:="[0.0, 0.0, 400.0, 0.0, 700.0, 300.0]"

Subscribes /<vessel>/odom (nav_msgs/Odometry: pose in map, twist in <vessel>/base_link) and,
for speed control on speed through the water, /<vessel>/status (tug_msgs/VesselStatus).
Publishes tug_msgs/VesselCommand on /<vessel>/command. The control law (heading PID with
yaw-rate damping, speed feed-forward + PI, line-of-sight track guidance) is ROS-free, in
scenario_runner/autopilot_law.py; this node only converts messages and keeps the step
protocol (sim_plumbing/stepping.py):

free-running (lockstep:=false, default)
    A wall-clock timer at exchange_rate computes a command from the latest odometry and
    publishes it stamped with that odometry's stamp. For a simulation paced in real time
    (free-running vessel node, or a realtime scenario). Integrators advance by the difference
    of the odometry stamps (simulation time). Odometry older than odom_timeout s (wall time)
    stops the commands (the vessel keeps its last one) until fresh odometry arrives.

lockstep (lockstep:=true)
    At start-up the node waits for the vessel's step-0 odometry (and status), publishes the
    command stamped 0 computed from it once the vessel's command subscription is matched, then
    reports ready (StepDone(0)). On SimStep(k) it
    takes the odometry stamped k, publishes the command stamped k+1 (the vessel applies it
    from step k+1) and StepDone(k+1). The scenario runner lists the vessel in
    SimStep.ordered at every step, so the vessel waits for that command: runs are
    reproducible.

Non-finite odometry or status is ignored and logged; in lockstep the last command is held
for that step (the step still completes).
"""
from __future__ import annotations

import dataclasses
import math
import sys
import time
from typing import List, Optional

from nav_msgs.msg import Odometry
from rclpy.duration import Duration
from rclpy.parameter import Parameter
from tug_msgs.msg import VesselCommand, VesselStatus

from sim_contract import topics as T
from sim_contract.geo import yaw_from_compass
from scenario_runner.autopilot_law import (NODE_TABLE, SPEED_SOURCES, AutopilotConfig, AutopilotLaw, Measurement,
                                           Output, parse_waypoints)
from sim_math.rotations import yaw_from_quaternion
from sim_plumbing import ros_common as rc
from sim_plumbing.stepping import SteppedNode, StepInput



def heading_from_true_deg(heading_true_deg: float) -> float:
    """The ordered heading as the controller takes it (REP-103 yaw, rad: 0 = east, counter-
    clockwise) of a compass heading as a person gives it (deg true: 0 = north, clockwise, 0-360),
    converted by sim_contract.geo; the inverse of sim_math.trials.compass_deg. ValueError
    for anything else."""
    if (isinstance(heading_true_deg, bool) or not isinstance(heading_true_deg, (int, float))
            or not math.isfinite(heading_true_deg) or not 0.0 <= heading_true_deg <= 360.0):
        raise ValueError(f"heading_true_deg: expected a compass heading of 0-360 deg true, got {heading_true_deg!r}")
    return yaw_from_compass(float(heading_true_deg))


def _odom_values(msg: Odometry):
    p, q, v, w = msg.pose.pose.position, msg.pose.pose.orientation, msg.twist.twist.linear, msg.twist.twist.angular
    return (p.x, p.y, q.x, q.y, q.z, q.w, v.x, v.y, w.z)


# parameter -> (AutopilotConfig field, conversion): orders, gains and limits change while running
_LIVE_CONFIG = {
    "heading": ("heading", math.radians), "heading_true_deg": ("heading", heading_from_true_deg),
    "speed": ("speed", float), "engine_order": ("engine_order", float),
    "lookahead": ("lookahead", float), "acceptance_radius": ("acceptance_radius", float),
    "heading_kp": ("heading_kp", float), "heading_ki": ("heading_ki", float), "heading_kd": ("heading_kd", float),
    "heading_integral_band_deg": ("heading_integral_band", math.radians),
    "heading_integral_limit_deg": ("heading_integral_limit", math.radians),
    "max_steering_deg": ("max_steering", math.radians), "speed_kp": ("speed_kp", float),
    "speed_ki": ("speed_ki", float), "speed_full_ahead": ("speed_full_ahead", float),
    "speed_exponent": ("speed_exponent", float), "speed_integral_band": ("speed_integral_band", float),
    "speed_integral_limit": ("speed_integral_limit", float), "min_engine_order": ("min_engine_order", float),
    "max_engine_order": ("max_engine_order", float),
}


class AutopilotNode(SteppedNode):
    LIVE_PARAMETERS = NODE_TABLE.live

    def __init__(self, node_name: str = "autopilot", **kwargs):
        super().__init__(node_name, **kwargs)
        rc.declare_table(self, NODE_TABLE)
        g = lambda name: self.get_parameter(name).value  # noqa: E731

        self.vessel = str(g("vessel")).strip("/")
        if not self.vessel:
            raise ValueError("parameter vessel: give the vessel's name (its ROS namespace), e.g. vessel:=tug")
        mode = g("mode")
        heading = math.radians(g("heading"))
        heading_text = f"heading {g('heading'):.1f} deg"
        if self._given("heading_true_deg"):
            if "heading" in self._parameter_overrides:
                raise ValueError("parameters heading (deg, REP-103: 0 = east, counter-clockwise) and "
                                 "heading_true_deg (compass, deg true): give one of them, not both")
            heading = heading_from_true_deg(g("heading_true_deg"))
            heading_text = f"heading {g('heading_true_deg'):05.1f} deg true ({math.degrees(heading):.1f} deg)"
        waypoints = parse_waypoints(self._track_values(g("track"))) if mode == "track" else ()
        self.cfg = AutopilotConfig(
            mode=mode, heading=heading, speed_control=bool(g("speed_control")),
            speed=g("speed"), engine_order=g("engine_order"), waypoints=waypoints, lookahead=g("lookahead"),
            acceptance_radius=g("acceptance_radius"), heading_kp=g("heading_kp"), heading_ki=g("heading_ki"),
            heading_kd=g("heading_kd"), heading_integral_band=math.radians(g("heading_integral_band_deg")),
            heading_integral_limit=math.radians(g("heading_integral_limit_deg")),
            max_steering=math.radians(g("max_steering_deg")), speed_kp=g("speed_kp"), speed_ki=g("speed_ki"),
            speed_full_ahead=g("speed_full_ahead"), speed_exponent=g("speed_exponent"),
            speed_integral_band=g("speed_integral_band"), speed_integral_limit=g("speed_integral_limit"),
            min_engine_order=g("min_engine_order"), max_engine_order=g("max_engine_order"))
        self.law = AutopilotLaw(self.cfg)  # checks the configuration
        self.speed_source = g("speed_source")
        if self.speed_source not in SPEED_SOURCES:
            raise ValueError(f"parameter speed_source:={self.speed_source!r}: expected one of {SPEED_SOURCES}")
        self.odom_timeout = g("odom_timeout")
        self.log_period = g("log_period")

        self.odom_topic = T.vessel_topic(self.vessel, T.ODOM)
        self.status_topic = T.vessel_topic(self.vessel, T.STATUS)
        self.use_status = self.cfg.speed_control and self.speed_source == "status"
        self.cmd_topic = T.vessel_topic(self.vessel, T.COMMAND)
        self.cmd_pub = self.create_publisher(VesselCommand, self.cmd_topic, rc.COMMAND_QOS)

        self.command: Optional[VesselCommand] = None  # last command computed
        self.output: Optional[Output] = None
        self.last_stamp_ns: Optional[int] = None  # stamp of the odometry the last update used
        self.last_odom_wall = 0.0
        self.inputs_rejected = 0
        self.stale = False
        self.last_log_ns: Optional[int] = None
        self._initial = {}  # lockstep start-up: step-0 messages
        self._start_timer = None
        self._out_stamp = None
        self._leg = 0
        self._finished = False

        # Lockstep: transient-local, to get the step-0 state however late this node starts.
        # Free-running: volatile, which also matches a volatile publisher (any contract source).
        # (lockstep is read here ahead of init_stepping, which declares it again.)
        lockstep = bool(self.declare_parameter("lockstep", False).value)
        self.undeclare_parameter("lockstep")
        qos = rc.LATCHED_STATE_QOS if lockstep else rc.STATE_QOS
        inputs = [StepInput(self.odom_topic, Odometry, qos=qos)]
        if self.use_status:
            inputs.append(StepInput(self.status_topic, VesselStatus, qos=qos))
        self.init_stepping(inputs, ready=False)
        what = (heading_text if mode == "heading" else
                f"track through {len(waypoints)} waypoints (lookahead {self.cfg.lookahead:g} m)")
        speed = (f"speed {self.cfg.speed:g} m/s ({'through the water' if self.use_status else 'over ground'})"
                 if self.cfg.speed_control else f"engine order {self.cfg.engine_order:g}")
        self.get_logger().info(
            f"autopilot for '{self.vessel}': {what}, {speed}; {1e9 / self.period_ns:g} Hz, "
            f"{'lockstep' if self.lockstep else 'free-running'}; waiting for {self.odom_topic}")

    def _given(self, name: str) -> bool:
        """A parameter declared without a default has been given a value."""
        return self.get_parameter_or(name, Parameter(name, Parameter.Type.NOT_SET)).type_ != Parameter.Type.NOT_SET

    def on_live_parameters(self, changes) -> None:
        """A new order, gain or limit: the law keeps its integrals and its leg. A heading order
        comes as heading (deg, REP-103) or heading_true_deg (compass): the one set last holds."""
        if "heading" in changes and "heading_true_deg" in changes:
            raise ValueError("heading and heading_true_deg are the same order: set one of them, not both")
        cfg = dataclasses.replace(self.cfg, **{_LIVE_CONFIG[k][0]: _LIVE_CONFIG[k][1](v)
                                               for k, v in changes.items() if k in _LIVE_CONFIG})
        self.law.retune(cfg)  # ValueError: refused, nothing changed
        self.cfg = cfg
        self.odom_timeout = changes.get("odom_timeout", self.odom_timeout)
        self.log_period = changes.get("log_period", self.log_period)

    @staticmethod
    def _track_values(value) -> List[float]:
        if isinstance(value, str):
            text = value.strip().strip("[]")
            if not text:
                raise ValueError("mode track: give the waypoints, e.g. track:=\"[0.0, 0.0, 300.0, 0.0]\"")
            try:
                return [float(v) for v in text.replace(",", " ").split()]
            except ValueError:
                raise ValueError(f"parameter track:={value!r}: expected numbers x1, y1, x2, y2, ...") from None
        if isinstance(value, (list, tuple)) or hasattr(value, "tolist"):
            values = list(value)
            if not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values):
                raise ValueError(f"parameter track:={value!r}: expected numbers x1, y1, x2, y2, ...")
            return [float(v) for v in values]
        raise ValueError(f"parameter track:={value!r}: expected a list of numbers x1, y1, x2, y2, ...")

    # -- inputs --------------------------------------------------------------------------
    def _finite(self, spec: StepInput, msg) -> bool:
        if spec.msg_type is Odometry:
            values = _odom_values(msg)
        else:
            values = (msg.speed_through_water,)
        if all(math.isfinite(v) for v in values):
            if spec.msg_type is Odometry:
                q = msg.pose.pose.orientation
                if q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w > 1e-12:
                    return True
            else:
                return True
        return False

    def accept_input(self, spec: StepInput, msg) -> bool:
        if not self._finite(spec, msg):
            self.inputs_rejected += 1
            t = rc.time_to_ns(msg.header.stamp) * 1e-9
            self.get_logger().error(
                f"{spec.topic}: non-finite or invalid values at stamp {t:.3f} s ignored"
                + (", holding the last command for that step" if self.lockstep else ""),
                throttle_duration_sec=1.0)
            # Lockstep: the step must still complete, compute_step holds the last command.
            return self.lockstep
        if spec.msg_type is Odometry:
            self.last_odom_wall = time.monotonic()
        if not self.ready_to_step:
            self._start_up(spec, msg)
        return True

    def _start_up(self, spec: StepInput, msg) -> None:
        """First command: lockstep, from the step-0 odometry (and status), stamped 0; free-running,
        as soon as odometry arrives."""
        if not self.lockstep:
            if spec.msg_type is Odometry:
                self.ready_to_step = True
            return
        k = self.step_of(spec, msg)
        if k != 0:
            self.get_logger().warning(f"{spec.topic}: stamped step {k}, waiting for the step-0 state to start",
                                      throttle_duration_sec=5.0)
            return
        self._initial[spec.topic] = msg
        if self._start_timer is None and all(s.topic in self._initial for s in self.inputs):
            if not self._update(self._initial, dt=0.0):
                return
            self._out_stamp = rc.step_time(0, self.period_ns)
            self._start_wall = time.monotonic()
            # Commands are volatile: send the step-0 command only once the vessel listens.
            self._start_timer = self.create_timer(0.05, self._send_first_command, clock=self._wall_clock)
            self._send_first_command()

    def _vessel_listens(self) -> bool:
        """The command publisher has matched every subscriber the graph shows, among them the
        vessel's (a node in namespace /<vessel>; any subscriber after 5 s without one)."""
        infos = self.get_subscriptions_info_by_topic(self.cmd_topic)
        matched = self.cmd_pub.get_subscription_count()
        if matched == 0 or matched < len(infos):
            return False
        if any(i.node_namespace.rstrip("/") == f"/{self.vessel}" for i in infos):
            return True
        if time.monotonic() - self._start_wall > 5.0:
            self.get_logger().warning(f"no node in namespace /{self.vessel} subscribes {self.cmd_topic}; "
                                      f"sending the step-0 command to the {matched} subscriber(s) found")
            return True
        return False

    def _send_first_command(self) -> None:
        """Timer (0.05 s) until the first SimStep: send the step-0 command once the vessel listens,
        then ready; send it again if it is not acknowledged within 1 s (the vessel waits for it)."""
        if self._triggered:
            self._start_timer.cancel()
            return
        if not self.ready_to_step:
            if not self._vessel_listens():
                return
            self._publish()
            self._sent_wall = time.monotonic()
            self.ready_to_step = True  # StepDone(0) follows from the stepping machinery
            self.get_logger().info("step-0 state received, command stamped 0 sent: ready")
        elif time.monotonic() - self._sent_wall > 1.0:
            if not self.cmd_pub.wait_for_all_acked(Duration(seconds=0)):
                self.get_logger().warning("step-0 command not acknowledged within 1 s: sending it again")
                self._publish()
            self._sent_wall = time.monotonic()

    # -- the law ---------------------------------------------------------------------------
    def _measurement(self, inputs) -> Optional[Measurement]:
        odom = inputs.get(self.odom_topic)
        if odom is None:
            return None
        status = inputs.get(self.status_topic)
        specs = {s.topic: s for s in self.inputs}
        if not self._finite(specs[self.odom_topic], odom):
            return None
        if status is not None and not self._finite(specs[self.status_topic], status):
            return None
        p, q = odom.pose.pose.position, odom.pose.pose.orientation
        u, v = odom.twist.twist.linear.x, odom.twist.twist.linear.y
        if status is not None:
            speed = math.copysign(status.speed_through_water, u)
        else:
            speed = math.copysign(math.hypot(u, v), u)
        return Measurement(x=p.x, y=p.y, yaw=yaw_from_quaternion(q.x, q.y, q.z, q.w),
                           yaw_rate=odom.twist.twist.angular.z, speed=speed)

    def _update(self, inputs, dt: float) -> bool:
        """Compute a new command from the inputs; False (last command held) if they are unusable."""
        m = self._measurement(inputs)
        if m is None:
            return False
        out = self.law.update(m, dt)
        self.output = out
        cmd = VesselCommand(engine_order=float(out.engine_order), steering_angle=float(out.steering_angle),
                            anchor=VesselCommand.ANCHOR_NO_CHANGE)
        self.command = cmd
        stamp_ns = rc.time_to_ns(inputs[self.odom_topic].header.stamp)
        self._report(out, m, stamp_ns)
        return True

    def _report(self, out: Output, m: Measurement, stamp_ns: int) -> None:
        log = self.get_logger()
        if self.law.los is not None:
            if out.leg != self._leg:
                self._leg = out.leg
                log.info(f"waypoint {out.leg + 1} reached, now on leg {out.leg + 1} -> {out.leg + 2}")
            if out.finished and not self._finished:
                self._finished = True
                log.info("last waypoint reached: keeping the extension of the last leg")
        if self.log_period <= 0.0:
            return
        if self.last_log_ns is None or stamp_ns - self.last_log_ns >= self.log_period * 1e9:
            self.last_log_ns = stamp_ns
            extra = f", cross-track {out.cross_track:+.1f} m on leg {out.leg + 1}" if self.law.los is not None else ""
            log.info(f"t {stamp_ns * 1e-9:.1f} s: heading {math.degrees(m.yaw):.1f} deg (ordered "
                     f"{math.degrees(out.heading_ordered):.1f}), speed {m.speed:.2f} m/s{extra} -> engine "
                     f"{out.engine_order:+.3f}, steering {math.degrees(out.steering_angle):+.1f} deg")

    # -- stepping --------------------------------------------------------------------------
    def compute_step(self, inputs) -> None:
        odom = inputs.get(self.odom_topic)
        if self.lockstep:
            # odometry stamped step_index -> command stamped step_index + 1
            self._update(inputs, dt=self.dt)  # unusable inputs: the last command is held
            self._out_stamp = rc.step_time(self.step_index + 1, self.period_ns)
            return
        # free-running: latest odometry; stamps give the simulated time between updates
        self._out_stamp = None
        if odom is None:
            return
        if time.monotonic() - self.last_odom_wall > self.odom_timeout:
            if not self.stale:
                self.stale = True
                self.get_logger().warning(f"no valid odometry on {self.odom_topic} for {self.odom_timeout:g} s: "
                                          "not commanding until it resumes")
            return
        if self.stale:
            self.stale = False
            self.get_logger().info(f"odometry on {self.odom_topic} resumed")
        stamp_ns = rc.time_to_ns(odom.header.stamp)
        if self.last_stamp_ns is None or stamp_ns < self.last_stamp_ns:
            dt = 0.0  # first update, or the simulation restarted
        else:
            dt = min((stamp_ns - self.last_stamp_ns) * 1e-9, 1.0)
        if self._update(inputs, dt):
            self.last_stamp_ns = stamp_ns
            self._out_stamp = odom.header.stamp

    def publish_outputs(self) -> None:
        if self._out_stamp is not None:
            self._publish()

    def _publish(self) -> None:
        if self.command is None or not self.context.ok():  # Ctrl-C shuts the context down under us
            return
        self.command.header.stamp = self._out_stamp
        self.cmd_pub.publish(self.command)


def main(args: Optional[List[str]] = None) -> int:
    return rc.run_node(AutopilotNode, "autopilot", args)


if __name__ == "__main__":
    sys.exit(main())
