"""The hull interaction node: Wang's (1975) passing-ship loads between two vessels, or the bank
suction on one vessel from a declared vertical bank, every step.

    ros2 run hull_contact interaction_node --ros-args -r __ns:=/passing \
        -p vessel_a:=ship -p ship_file_a:=s175_003.yaml -p vessel_b:=moored -p ship_file_b:=s175_003.yaml

Subscribes ``/<vessel_a>/odom`` and ``/<vessel_b>/odom`` and publishes ``on_a/wrench`` and
``on_b/wrench`` (geometry_msgs/WrenchStamped in ``<vessel>/base_link``, body axes, about midship):
the surge and sway force and yaw moment of tug_dynamics.hull_interaction on each vessel from the
other, computed from the pair's odometry of step k, each position carried on at its velocity to
the middle of the step the load acts over (k+1 -> k+2, 1.5 steps on), and applied by the vessel
nodes (their ``wrench_topics``) over that step (docs/confined-water.md, "In a run"). With
``bank`` (a polyline, the water on its left) and no ``vessel_b`` the node publishes only
``on_a/wrench``: tug_dynamics.bank_effect's image-method suction on vessel a. The physics lives in
tug_dynamics.hull_interaction and bank_effect; this node converts poses and messages.
"""
from __future__ import annotations

import json
import math
import sys
from typing import List, NamedTuple, Optional, Tuple

from geometry_msgs.msg import WrenchStamped
from nav_msgs.msg import Odometry
from tug_msgs.msg import ScenarioEvent

from sim_contract import topics as T
from sim_contract.node_params import INTERACTION_NODE
from sim_math.data_files import resolve as resolve_data_file
from sim_math.rotations import yaw_from_quaternion
from sim_plumbing import cdr
from sim_plumbing import ros_common as rc
from sim_plumbing.stepping import SteppedNode, StepInput
from tug_dynamics.bank_effect import BankEffect, BankPolyline
from tug_dynamics.hull_interaction import HullPair, SectionalAreaCurve, pair_from_ship_configs
from tug_dynamics.ship_file import ship_config

ZERO_LOADS = (0.0, 0.0, 0.0)


class PlanarState(NamedTuple):
    """A vessel's horizontal position, heading and velocity over ground (world, REP-103)."""
    x: float
    y: float
    yaw: float
    vx: float
    vy: float


def planar_state(msg: cdr.OdometryIn) -> PlanarState:
    yaw = yaw_from_quaternion(*msg.orientation)
    u, v, _ = msg.linear        # twist in body axes (REP-105)
    c, s = math.cos(yaw), math.sin(yaw)
    return PlanarState(msg.position[0], msg.position[1], yaw, c * u - s * v, s * u + c * v)


def ahead(state: PlanarState, seconds: float) -> PlanarState:
    """The state carried on at its velocity (heading and velocity held): where the vessel is in
    the middle of the step a load computed now acts over."""
    return state._replace(x=state.x + state.vx * seconds, y=state.y + state.vy * seconds)


def wang_arguments(own: PlanarState, other: PlanarState) -> Tuple[float, float, float]:
    """(stagger, separation, speed) of `other` seen from `own`: its midship ahead and to port in
    own's body axes, and its velocity over ground along own's x axis (Wang's parallel courses)."""
    c, s = math.cos(own.yaw), math.sin(own.yaw)
    dx, dy = other.x - own.x, other.y - own.y
    return c * dx + s * dy, -s * dx + c * dy, c * other.vx + s * other.vy


def loads_on(pair: HullPair, own: PlanarState, other: PlanarState, depth: float) -> Optional[Tuple[float, ...]]:
    """(X, Y, N) on `own` from `other` (body axes), or None while the hulls overlap (the theory's
    limit: HullPair.check)."""
    try:
        return pair.loads(*wang_arguments(own, other), depth)
    except ValueError:
        return None


def ship_configs(gp, ends: str) -> dict:
    """The ship files' mappings of the given ends, with their overrides."""
    configs = {}
    for end in ends:
        text = gp(f"ship_overrides_{end}")
        try:
            overrides = json.loads(text) if text else None
        except json.JSONDecodeError as exc:
            raise ValueError(f"parameter ship_overrides_{end}: not JSON ({exc})") from None
        path = resolve_data_file("tug_dynamics", "ships", gp(f"ship_file_{end}"))
        configs[end] = ship_config(path, overrides)[1]
    return configs


def bank_polyline(flat: List[float]) -> BankPolyline:
    if len(flat) % 2:
        raise ValueError(f"parameter bank: x, y pairs expected, got {len(flat)} numbers")
    try:
        return BankPolyline([flat[i:i + 2] for i in range(0, len(flat), 2)])
    except ValueError as exc:
        raise ValueError(f"parameter bank: {exc}") from None


class InteractionNode(SteppedNode):
    def __init__(self, node_name: str = "interaction", **kwargs):
        super().__init__(node_name, **kwargs)
        rc.declare_table(self, INTERACTION_NODE)
        gp = lambda name: self.get_parameter(name).value  # noqa: E731
        flat = [float(c) for c in gp("bank")]
        self.bank = bank_polyline(flat) if flat != [0.0] else None
        ends = "a" if self.bank else "ab"
        for key in [f"{k}_{e}" for e in ends for k in ("vessel", "ship_file")]:
            if not gp(key):
                raise ValueError(f"parameter {key}: required")
        if self.bank and gp("vessel_b"):
            raise ValueError(f"parameters bank and vessel_b: a bank acts on vessel_a alone, got vessel_b "
                             f"'{gp('vessel_b')}'")
        self.vessels = {e: gp(f"vessel_{e}") for e in ends}
        if self.vessels.get("b") == self.vessels["a"]:
            raise ValueError(f"parameters vessel_a and vessel_b: both '{self.vessels['a']}' (a pair of two vessels)")
        configs = ship_configs(gp, ends)
        if self.bank:
            self.bank_effect = BankEffect(SectionalAreaCurve.from_ship_config(configs["a"]),
                                          water_density=float(configs["a"].get("water_density", 1025.0)))
        else:   # "a" feels b's passage, "b" feels a's
            self.pairs = {"a": pair_from_ship_configs(configs["a"], configs["b"]),
                          "b": pair_from_ship_configs(configs["b"], configs["a"])}
        self.depth = gp("depth") or math.inf
        self.name_ = self.get_namespace().strip("/").split("/")[-1] or "interaction"
        self.topics = {T.vessel_topic(self.vessels[e], T.ODOM): e for e in ends}
        self.states = {}
        self.loads = None
        self._overlapping = False
        self.outputs = {e: (self.create_fed_publisher(WrenchStamped, f"on_{e}/wrench", rc.LATCHED_STATE_QOS),
                            cdr.WrenchStampedEncoder(f"{self.vessels[e]}/base_link")) for e in ends}
        self.event_pub = self.create_publisher(ScenarioEvent, rc.EVENTS_TOPIC, rc.EVENTS_QOS)
        self.init_stepping([StepInput(t, Odometry, decode=cdr.decode_odometry) for t in self.topics], ready=False)
        what = (f"bank suction (image method) on {self.vessels['a']}" if self.bank else
                f"Wang (1975) between {self.vessels['a']} and {self.vessels['b']}")
        self.get_logger().info(
            f"interaction '{self.name_}': {what} "
            f"({'deep water' if math.isinf(self.depth) else f'depth {self.depth:g} m'}); waiting for the "
            "step-0 odometry")

    def accept_input(self, spec: StepInput, msg: cdr.OdometryIn) -> bool:
        if not msg.is_finite():
            self.complaints("odom " + spec.topic, f"{spec.topic}: non-finite odometry rejected")
            return False
        if self.loads is None and self.step_of(spec, msg) == 0:
            self.states[self.topics[spec.topic]] = planar_state(msg)
            if len(self.states) == len(self.topics):
                self._compute(0.5 * self.dt)   # step-0 output from the step-0 state: it acts over step 0 -> 1
                self.ready_to_step = True
                self.publish_outputs()
        return True

    def compute_step(self, inputs) -> None:
        for topic, end in self.topics.items():
            msg = inputs.get(topic)
            if msg is not None:
                self.states[end] = planar_state(msg)
        self._compute(1.5 * self.dt)      # from the state of step k, for the step k+1 -> k+2

    def _compute(self, lead: float) -> None:
        if self.bank:
            self._compute_bank(ahead(self.states["a"], lead))
            return
        a, b = ahead(self.states["a"], lead), ahead(self.states["b"], lead)
        loads = {"a": loads_on(self.pairs["a"], a, b, self.depth), "b": loads_on(self.pairs["b"], b, a, self.depth)}
        overlapping = loads["a"] is None or loads["b"] is None
        self._switch(overlapping, f"{self.vessels['a']} and {self.vessels['b']}: hulls "
                                  f"{'overlap (Wang loads off until they part)' if overlapping else 'apart again'}")
        self.loads = {e: ZERO_LOADS if overlapping else loads[e] for e in ("a", "b")}

    def _compute_bank(self, own: PlanarState) -> None:
        speed = math.cos(own.yaw) * own.vx + math.sin(own.yaw) * own.vy
        try:
            y, n = self.bank_effect.loads_along(self.bank, own.x, own.y, own.yaw, speed, self.depth)
            loads = (0.0, y, n)
        except ValueError:        # inside the half beam of the bank or beyond it (grounded): the model's limit
            loads = None
        self._switch(loads is None, f"{self.vessels['a']}: "
                                    f"{'at or over the bank (suction off)' if loads is None else 'clear of the bank'}")
        self.loads = {"a": loads or ZERO_LOADS}

    def _switch(self, off: bool, detail: str) -> None:
        if off != self._overlapping:
            self._overlapping = off
            self.emit_event("interaction_off" if off else "interaction_on", detail)

    def publish_outputs(self) -> None:
        if self.loads is None:
            return
        stamp_ns = self.stamp_ns()
        for end, (pub, encoder) in self.outputs.items():
            x, y, n = self.loads[end]
            pub.publish(encoder.encode(stamp_ns, (x, y, 0.0), (0.0, 0.0, n)), stamp_ns)

    def emit_event(self, kind: str, detail: str) -> None:
        ev = ScenarioEvent(step=self.step_index, source=self.get_fully_qualified_name(), kind=kind,
                           target=self.name_, detail=detail, value=float("nan"))
        ev.header.stamp = self.stamp()
        self.event_pub.publish(ev)
        self.get_logger().info(detail)


def main(args: Optional[List[str]] = None) -> int:
    return rc.run_node(InteractionNode, "interaction_node", args)


if __name__ == "__main__":
    sys.exit(main())
