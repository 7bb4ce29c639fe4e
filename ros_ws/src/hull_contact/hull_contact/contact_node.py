"""The hull contact node: a tug's fender pushing on another vessel's hull.

    ros2 run hull_contact contact_node --ros-args -r __ns:=/push_aft \
        -p fender_vessel:=tug2 -p fender:=bow_fender -p fender_ship_file:=asd_tug.yaml \
        -p hull_vessel:=ship -p hull_ship_file:=s175_003.yaml

Subscribes ``/<fender_vessel>/odom`` and ``/<hull_vessel>/odom`` (nav_msgs/Odometry) and publishes
``state`` (tug_msgs/HullContact) once per exchange step: the contact force and point
(hull_contact.fender: spring-dashpot with friction against the hull's waterline outline). The two
vessel nodes take ``state`` as an input (their ``contact_topics``) and apply the force, each at
its own point, over the next step. The physics lives in hull_contact.fender; this node only
converts messages.
"""
from __future__ import annotations

import json
import math
import sys
from typing import List, Optional

import numpy as np
from nav_msgs.msg import Odometry
from tug_msgs.msg import HullContact, ScenarioEvent

from hull_contact.fender import FenderSpec, PlanarPose, contact_from_ship_files
from sim_contract import topics as T
from sim_math.rotations import yaw_from_quaternion
from sim_plumbing import cdr
from sim_contract.node_params import CONTACT_NODE
from sim_math.data_files import resolve as resolve_data_file
from sim_plumbing import ros_common as rc
from sim_plumbing.ros_common import ModelDiverged
from sim_plumbing.stepping import SteppedNode, StepInput


def _pose(msg: cdr.OdometryIn) -> PlanarPose:
    """The odometry's horizontal pose and velocity (world; twist is in body axes, REP-105)."""
    yaw = yaw_from_quaternion(*msg.orientation)
    u, v, _ = msg.linear
    c, s = math.cos(yaw), math.sin(yaw)
    return PlanarPose(msg.position[0], msg.position[1], yaw, c * u - s * v, s * u + c * v, msg.angular[2])


class ContactNode(SteppedNode):
    def __init__(self, node_name: str = "contact", **kwargs):
        super().__init__(node_name, **kwargs)
        rc.declare_table(self, CONTACT_NODE)
        gp = lambda name: self.get_parameter(name).value  # noqa: E731
        self.fender_vessel, self.hull_vessel, self.fender_name = gp("fender_vessel"), gp("hull_vessel"), gp("fender")
        for key in ("fender_vessel", "hull_vessel", "fender_ship_file", "hull_ship_file"):
            if not gp(key):
                raise ValueError(f"parameter {key}: required")
        if self.fender_vessel == self.hull_vessel:
            raise ValueError(f"parameters fender_vessel and hull_vessel: both '{self.hull_vessel}' (a vessel cannot "
                             "push on itself)")
        overrides = {}
        for side in ("fender", "hull"):
            text = gp(f"{side}_ship_overrides")
            try:
                overrides[side] = json.loads(text) if text else None
            except json.JSONDecodeError as exc:
                raise ValueError(f"parameter {side}_ship_overrides: not JSON ({exc})") from None
        self.spec = FenderSpec(radius=gp("radius"), stiffness=gp("stiffness"), damping=gp("damping"),
                               friction=gp("friction"))
        ship = lambda key: resolve_data_file("tug_dynamics", "ships", gp(key))  # noqa: E731
        self.contact, self.fender_point = contact_from_ship_files(
            self.spec, ship("fender_ship_file"), self.fender_name, ship("hull_ship_file"),
            overrides["fender"], overrides["hull"])
        self.contact_name = self.get_namespace().strip("/").split("/")[-1] or "contact"
        self.rejected = 0
        self._was_in_contact = False
        self.result = None
        self.topics = {T.vessel_topic(self.fender_vessel, T.ODOM): "fender", T.vessel_topic(self.hull_vessel, T.ODOM): "hull"}
        self.poses = {}
        self.state_pub = self.create_fed_publisher(HullContact, T.STATE, rc.LATCHED_STATE_QOS)
        self.event_pub = self.create_publisher(ScenarioEvent, rc.EVENTS_TOPIC, rc.EVENTS_QOS)
        self._encoder = cdr.HullContactEncoder(rc.WORLD_FRAME, self.contact_name, self.fender_vessel,
                                               self.fender_name, self.hull_vessel)
        self.init_stepping([StepInput(t, Odometry, decode=cdr.decode_odometry) for t in self.topics], ready=False)
        self.get_logger().info(
            f"contact '{self.contact_name}': fender {self.fender_vessel}/{self.fender_name} on the hull of "
            f"{self.hull_vessel} (k {self.spec.stiffness:g} N/m, c {self.spec.damping:g} N s/m, mu "
            f"{self.spec.friction:g}); waiting for both vessels' step-0 odometry")

    # -- inputs --------------------------------------------------------------------------
    def accept_input(self, spec: StepInput, msg: cdr.OdometryIn) -> bool:
        if not msg.is_finite():
            self.rejected += 1
            self.complaints("odom " + spec.topic, f"{spec.topic}: non-finite odometry rejected")
            return False
        if self.result is None and self.step_of(spec, msg) == 0:
            self.poses[self.topics[spec.topic]] = _pose(msg)
            if len(self.poses) == 2:
                # step-0 output from the step-0 state; it acts over step 0 -> 1
                self.result = self.contact.force(self.poses["fender"], self.poses["hull"], 0.5 * self.dt)
                self.ready_to_step = True
                self.publish_outputs()
        return True

    # -- stepping -------------------------------------------------------------------------
    def compute_step(self, inputs) -> None:
        for topic, side in self.topics.items():
            msg = inputs.get(topic)
            if msg is not None:
                self.poses[side] = _pose(msg)
        # from the state of step k, for the step it acts over (k+1 -> k+2): its middle is 1.5 dt on
        self.result = self.contact.force(self.poses["fender"], self.poses["hull"], 1.5 * self.dt)
        # checked here, before any vessel applies it: a diverging exchange is then named by this node
        # (a step or more before the rope or vessel it throws about fails)
        problem = self.contact.divergence(self.result, self.dt)
        if problem is not None:
            k = self.step_index
            detail = (f"contact '{self.contact_name}' (fender {self.fender_vessel}/{self.fender_name} on the hull of "
                      f"{self.hull_vessel}) diverged at step {k} -> {k + 1} (t = {k * self.dt:.3f} s): {problem}; "
                      f"check its stiffness and damping against the exchange rate")
            self.emit_event("contact_failed", detail, self.result.normal_force)
            raise ModelDiverged(detail)

    def publish_outputs(self) -> None:
        r = self.result
        if r is None:
            return
        stamp_ns = self.stamp_ns()
        z = float(self.fender_point[2])
        vectors = (r.force_on_hull[0], r.force_on_hull[1], 0.0, r.point_world[0], r.point_world[1], z,
                   r.hull_point_body[0], r.hull_point_body[1], z, *self.fender_point)
        self.state_pub.publish(self._encoder.encode(stamp_ns, self.step_index, r.in_contact,
                                                    (r.penetration, r.gap, r.normal_force, r.friction_force),
                                                    vectors), stamp_ns)
        if r.in_contact != self._was_in_contact:
            self._was_in_contact = r.in_contact
            kind = "contact_made" if r.in_contact else "contact_lost"
            self.emit_event(kind, f"fender {self.fender_vessel}/{self.fender_name} "
                                  f"{'against' if r.in_contact else 'off'} the hull of {self.hull_vessel}",
                            r.normal_force)

    def emit_event(self, kind: str, detail: str, value: float = float("nan")) -> None:
        ev = ScenarioEvent(step=self.step_index, source=self.get_fully_qualified_name(), kind=kind,
                           target=self.contact_name, detail=detail, value=float(value))
        ev.header.stamp = self.stamp()
        self.event_pub.publish(ev)
        self.get_logger().info(detail)


def main(args: Optional[List[str]] = None) -> int:
    return rc.run_node(ContactNode, "contact_node", args)


if __name__ == "__main__":
    sys.exit(main())
