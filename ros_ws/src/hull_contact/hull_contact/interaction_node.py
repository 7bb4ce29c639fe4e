"""The hull interaction node: every interaction of a run in one node, every step: Wang's (1975)
passing-ship loads between the declared pairs, the bank suction on a vessel from a declared
bank (a vertical line; a sloped one, or the banks of a depth grid, as the vertical wall of the
same d2b), and a declared source's propeller wash on a target's hull side
(tug_dynamics.interaction_set).

    ros2 run hull_contact interaction_node --ros-args -r __ns:=/interactions \
        -p vessels:="[ship, moored]" -p ship_files:="[s175_003.yaml, s175_003.yaml]" \
        -p pairs:="[passing=ship,moored]"

Subscribes ``/<vessel>/odom`` of each of ``vessels`` (and each wash source's ``thrusters``, or its
``status`` when it has propellers) and publishes ``on_<vessel>/wrench``
(geometry_msgs/WrenchStamped in ``<vessel>/base_link``, body axes, about midship): the sum of the
surge and sway forces and yaw moments of its pairs, banks and washes, computed from the odometry of step
k, each position carried on at its velocity to the middle of the step the load acts over
(k+1 -> k+2, 1.5 steps on), and applied by the vessel nodes (their ``wrench_topics``) over that
step (docs/confined-water.md, "In a run"). ``interaction_off`` / ``interaction_on`` events name
the entry whose hulls overlap (or whose ship is at or over its bank) and part again. The
physics lives in tug_dynamics.interaction_set; this node converts poses and messages.
"""
from __future__ import annotations

import json
import math
import sys
from typing import Dict, List, Optional

from geometry_msgs.msg import WrenchStamped
from nav_msgs.msg import Odometry
from tug_msgs.msg import ScenarioEvent, ThrusterStatus, VesselStatus

from sim_contract import topics as T
from sim_contract.node_params import INTERACTION_NODE
from sim_math.data_files import resolve as resolve_data_file
from sim_math.rotations import yaw_from_quaternion
from sim_plumbing import cdr
from sim_plumbing import ros_common as rc
from sim_plumbing.stepping import SteppedNode, StepInput
from tug_dynamics.bank_effect import BankPolyline
from tug_dynamics.hull_interaction import SectionalAreaCurve
from tug_dynamics.interaction_set import (BankEntry, InteractionSet, PairEntry, PlanarState, WashEntry,
                                          propulsors_of)
from tug_dynamics.ship_file import ship_config


def planar_state(msg: cdr.OdometryIn) -> PlanarState:
    u, v, _ = msg.linear        # twist in body axes (REP-105)
    return PlanarState.from_body(msg.position[0], msg.position[1], yaw_from_quaternion(*msg.orientation), u, v)


def _listed(values) -> List[str]:
    return [v for v in values if v]


def _named(param: str, text: str):
    name, sep, rest = text.partition("=")
    if not sep or not name or not rest:
        raise ValueError(f"parameter {param}: expected \"<name>=...\", got {text!r}")
    return name, rest


def parse_pairs(values: List[str]) -> List[PairEntry]:
    out = []
    for text in _listed(values):
        name, rest = _named("pairs", text)
        vessels = rest.split(",")
        if len(vessels) != 2 or not all(vessels):
            raise ValueError(f"parameter pairs: \"{name}\" needs two vessels \"<a>,<b>\", got {rest!r}")
        out.append(PairEntry(name, *vessels))
    return out


def parse_washes(values: List[str]) -> List[WashEntry]:
    out = []
    for text in _listed(values):
        name, rest = _named("washes", text)
        parts = rest.split(",")
        try:
            impingement = float(parts[2]) if len(parts) == 3 else 1.0
        except ValueError:
            impingement = math.nan
        if len(parts) not in (2, 3) or not all(parts[:2]) or not 0.0 <= impingement <= 1.0:
            raise ValueError(f"parameter washes: \"{name}\" needs \"<source>,<target>[,<C_w> 0..1]\", got {rest!r}")
        out.append(WashEntry(name, parts[0], parts[1], impingement))
    return out


def thrust_units(kind: str, msg, count: int):
    """(thrust N, azimuth rad) per propulsor from a source's thruster status (each unit's open-water
    thrust: the jet carries it) or vessel status (its propellers' total, shared equally, along x)."""
    if kind == "thrusters":
        return list(zip(msg.open_water_thrust, msg.azimuth))
    return [(msg.thrust / count, 0.0)] * count


def parse_banks(values: List[str]) -> List[BankEntry]:
    out = []
    for text in _listed(values):
        name, rest = _named("banks", text)
        parts = rest.split(":")
        if len(parts) == 2 and parts[0] and parts[1] == "depth":
            out.append(BankEntry(name, parts[0], None))      # the depth grid's banks
            continue
        if len(parts) == 2:            # the vertical form, "<vessel>:x0,y0,..."
            vessel, slope_text, coords = parts[0], "0", parts[1]
        elif len(parts) == 3:
            vessel, slope_text, coords = parts
        else:
            vessel = slope_text = coords = ""
        try:
            flat = [float(c) for c in coords.split(",")]
            slope = float(slope_text)
        except ValueError:
            flat, slope = [], math.nan
        if not vessel or len(flat) < 4 or len(flat) % 2 or not 0.0 <= slope <= 100.0:
            raise ValueError(f"parameter banks: \"{name}\" needs \"<vessel>:x0,y0,x1,y1,...\" or "
                             f"\"<vessel>:<slope 0-100>:x0,y0,x1,y1,...\", got {rest!r}")
        try:
            bank = BankPolyline([flat[i:i + 2] for i in range(0, len(flat), 2)])
        except ValueError as exc:
            raise ValueError(f"parameter banks: \"{name}\": {exc}") from None
        out.append(BankEntry(name, vessel, bank, slope))
    return out


def hulls_of(vessels: List[str], ship_files: List[str], overrides: List[str]) -> Dict[str, dict]:
    """Each vessel's ship file mapping, with its overrides."""
    if len(ship_files) != len(vessels):
        raise ValueError(f"parameters vessels and ship_files: {len(vessels)} vessels, {len(ship_files)} ship files")
    if overrides == [""]:
        overrides = [""] * len(vessels)
    if len(overrides) != len(vessels):
        raise ValueError(f"parameters vessels and ship_overrides: {len(vessels)} vessels, {len(overrides)} "
                         "overrides (one each, or none)")
    if len(set(vessels)) != len(vessels):
        raise ValueError(f"parameter vessels: a vessel twice in {vessels}")
    configs = {}
    for vessel, file, text in zip(vessels, ship_files, overrides):
        try:
            extra = json.loads(text) if text else None
        except json.JSONDecodeError as exc:
            raise ValueError(f"parameter ship_overrides of '{vessel}': not JSON ({exc})") from None
        configs[vessel] = ship_config(resolve_data_file("tug_dynamics", "ships", file), extra)[1]
    return configs


class InteractionNode(SteppedNode):
    def __init__(self, node_name: str = "interaction", **kwargs):
        super().__init__(node_name, **kwargs)
        rc.declare_table(self, INTERACTION_NODE)
        gp = lambda name: self.get_parameter(name).value  # noqa: E731
        vessels = _listed(gp("vessels"))
        configs = hulls_of(vessels, _listed(gp("ship_files")), list(gp("ship_overrides")))
        pairs, banks, washes = parse_pairs(gp("pairs")), parse_banks(gp("banks")), parse_washes(gp("washes"))
        if not pairs and not banks and not washes:
            raise ValueError("parameters pairs, banks and washes: no interaction declared")
        depth = gp("depth") or math.inf
        propulsors = {}
        for w in washes:
            if w.source not in configs:
                raise ValueError(f"parameter washes: \"{w.name}\": '{w.source}' is not one of vessels {vessels}")
            try:
                propulsors[w.source] = propulsors_of(configs[w.source])
            except ValueError as exc:
                raise ValueError(f"parameter washes: \"{w.name}\": '{w.source}': {exc}") from None
        depth_field = None
        if any(b.bank is None for b in banks):
            if not gp("depth_grid"):
                raise ValueError("parameter banks: a \"<vessel>:depth\" entry needs parameter depth_grid")
            from sea_environment.bathymetry import DepthGrid
            depth_field = DepthGrid.load(gp("depth_grid")).depth_at
        self.interactions = InteractionSet(
            {n: SectionalAreaCurve.from_ship_config(c) for n, c in configs.items()}, pairs, banks, depth,
            {n: float(c.get("water_density", 1025.0)) for n, c in configs.items()}, washes=washes,
            propulsors={n: units for n, (_, units) in propulsors.items()},
            drafts={n: float(c["hull"]["draft"]) for n, c in configs.items()}, depth_field=depth_field)
        self.topics = {T.vessel_topic(n, T.ODOM): n for n in self.interactions.tracked}
        # each wash source's thrust: (vessel, kind, propulsor count) by topic
        self.thrust_topics = {T.vessel_topic(n, T.THRUSTERS if kind == "thrusters" else T.STATUS):
                              (n, kind, len(units)) for n, (kind, units) in propulsors.items()}
        self.thrust: Dict[str, list] = {}
        self.states: Dict[str, PlanarState] = {}
        self.loads = None
        self._off = {name: False for name in [p.name for p in pairs] + [b.name for b in banks]}
        self.outputs = {n: (self.create_fed_publisher(WrenchStamped, f"on_{n}/wrench", rc.LATCHED_STATE_QOS),
                            cdr.WrenchStampedEncoder(f"{n}/base_link")) for n in self.interactions.vessels}
        self.event_pub = self.create_publisher(ScenarioEvent, rc.EVENTS_TOPIC, rc.EVENTS_QOS)
        # local: the vessels' outputs, from nodes of this process without DDS (sim_plumbing.local_bus)
        self.init_stepping([StepInput(t, Odometry, decode=cdr.decode_odometry, local=True) for t in self.topics] +
                           [StepInput(t, ThrusterStatus if kind == "thrusters" else VesselStatus, local=True)
                            for t, (_, kind, _) in self.thrust_topics.items()], ready=False)
        what = [f"{p.name}: Wang (1975) between {p.a} and {p.b}" for p in pairs] + \
               [f"{b.name}: bank suction (image method{', the depth grid' if b.bank is None else ''}"
                f"{f', slope 1:{b.slope:g}' if b.slope else ''}) on {b.vessel}" for b in banks] + \
               [f"{w.name}: {w.source}'s propeller wash on {w.target}" for w in washes]
        self.get_logger().info(
            f"interactions ({'deep water' if math.isinf(depth) else f'depth {depth:g} m'}): {'; '.join(what)}; "
            "waiting for the step-0 odometry")

    def accept_input(self, spec: StepInput, msg) -> bool:
        if spec.topic in self.thrust_topics:
            vessel, kind, count = self.thrust_topics[spec.topic]
            try:
                units = thrust_units(kind, msg, count)
            except (TypeError, ZeroDivisionError):
                units = []
            if len(units) != count or not all(math.isfinite(t) and math.isfinite(a) for t, a in units):
                self.complaints(kind + " " + spec.topic, f"{spec.topic}: not {count} finite thrusts and azimuths; "
                                                         "rejected")
                return False
            if self.loads is None and self.step_of(spec, msg) == 0:
                self.thrust[vessel] = units
                self._start_if_complete()
            return True
        if not msg.is_finite():
            self.complaints("odom " + spec.topic, f"{spec.topic}: non-finite odometry rejected")
            return False
        if self.loads is None and self.step_of(spec, msg) == 0:
            self.states[self.topics[spec.topic]] = planar_state(msg)
            self._start_if_complete()
        return True

    def _start_if_complete(self) -> None:
        if len(self.states) == len(self.topics) and len(self.thrust) == len(self.thrust_topics):
            self._compute(0.5 * self.dt)   # step-0 output from the step-0 state: it acts over step 0 -> 1
            self.ready_to_step = True
            self.publish_outputs()

    def compute_step(self, inputs) -> None:
        for topic, vessel in self.topics.items():
            msg = inputs.get(topic)
            if msg is not None:
                self.states[vessel] = planar_state(msg)
        for topic, (vessel, kind, count) in self.thrust_topics.items():
            msg = inputs.get(topic)
            if msg is not None:
                self.thrust[vessel] = thrust_units(kind, msg, count)
        self._compute(1.5 * self.dt)      # from the state of step k, for the step k+1 -> k+2

    def _compute(self, lead: float) -> None:
        self.loads, off = self.interactions.loads(self.states, lead, self.thrust)
        for name, now in off.items():
            if now != self._off[name]:
                self._off[name] = now
                self.emit_event("interaction_off" if now else "interaction_on", name,
                                self._detail(name, now))

    def _detail(self, name: str, off: bool) -> str:
        pair = next((p for p in self.interactions.pairs if p.name == name), None)
        if pair:
            return (f"{pair.a} and {pair.b}: hulls "
                    f"{'overlap (Wang loads off until they part)' if off else 'apart again'}")
        bank = next(b for b in self.interactions.banks if b.name == name)
        return f"{bank.vessel}: {'at or over the bank (suction off)' if off else 'clear of the bank'}"

    def publish_outputs(self) -> None:
        if self.loads is None:
            return
        stamp_ns = self.stamp_ns()
        for vessel, (pub, encoder) in self.outputs.items():
            x, y, n = self.loads[vessel]
            pub.publish(encoder.encode(stamp_ns, (x, y, 0.0), (0.0, 0.0, n)), stamp_ns)

    def emit_event(self, kind: str, target: str, detail: str) -> None:
        ev = ScenarioEvent(step=self.step_index, source=self.get_fully_qualified_name(), kind=kind,
                           target=target, detail=detail, value=float("nan"))
        ev.header.stamp = self.stamp()
        self.event_pub.publish(ev)
        self.get_logger().info(detail)


def main(args: Optional[List[str]] = None) -> int:
    return rc.run_node(InteractionNode, "interaction_node", args)


if __name__ == "__main__":
    sys.exit(main())
