"""The nodes of a run and the topics they exchange, from a validated scenario: each node's
spec (package, executable, namespace, parameters mapped through its table in
sim_contract.node_params), the topic contract of the scenario (sim_contract.topics), which
topics the recorder is fed, and which nodes another machine runs (--external)."""
from __future__ import annotations

import dataclasses
import json
import math
import os
from typing import Dict, List, Sequence, Tuple

from scenario_format.scenario import (Scenario, depth_grid_path, environment_parameter, has_thrusters, heading_rad,
                                     installed_executable, interaction_depth, resolve)
from sim_contract import topics as T
from sim_contract.node_params import NODE_TABLES
from sim_math import data_files
from sim_plumbing import ros_common as rc


class RunError(RuntimeError):
    """The run could not go on (a node died, stopped answering or reported a failure)."""


# Topics the runner itself publishes (/clock, /sim/step) or takes raw (/sim/step_done): it hands
# their bytes to the recorder, which then needs no subscription of its own for them.
FED_TOPICS = ("/clock", rc.SIM_STEP_TOPIC, rc.STEP_DONE_TOPIC)


def _node_outputs(sc: Scenario) -> List[str]:
    """The per-step outputs of the simulation nodes: the contract's state topics
    (LATCHED_STATE_QOS) and the vessels' frames (/tf, /tf_static), published through
    SteppedNode.create_fed_publisher."""
    return [t for t, _type, qos in contract_topics(sc)
            if qos is rc.LATCHED_STATE_QOS or t in (rc.TF_TOPIC, rc.TF_STATIC_TOPIC)]


def _published_by(topic: str, names) -> bool:
    """Whether one of these nodes ("/<namespace>/<node>") publishes this output: a namespaced
    topic its namespace's node, /tf and /tf_static every vessel node."""
    if topic in (rc.TF_TOPIC, rc.TF_STATIC_TOPIC):
        return any(n.endswith("/vessel") for n in names)
    return any(topic.startswith(n.rsplit("/", 1)[0] + "/") for n in names)


def fed_topics(sc: Scenario, external: Sequence[str] = ()) -> Tuple[str, ...]:
    """Topics the recorder gets without a subscription: the runner's own (FED_TOPICS) and the
    per-step outputs of the nodes it starts, through their feed (sim_plumbing/record_feed.py).
    Outputs of external nodes (names "/<namespace>/<node>", started by somebody else) are
    subscribed: /tf too as soon as one vessel node is external."""
    return FED_TOPICS + tuple(t for t in _node_outputs(sc) if not _published_by(t, external))


def external_outputs(sc: Scenario, external: Sequence[str]) -> Tuple[Tuple[str, ...], Tuple[str, ...]]:
    """(the outputs of these external nodes, recorded by subscription at their own stamp; those
    of them published every exchange step, which the runner waits for before the next step, so
    that the recording loses none of them as the nodes' feed would not)."""
    outputs = tuple(t for t in _node_outputs(sc) if _published_by(t, external))
    names = ({f"/{v.name}" for v in sc.vessels} | {f"/{r.name}" for r in sc.ropes}
             | {f"/{c.name}" for c in sc.contacts} | ({f"/{T.INTERACTIONS}"} if sc.interactions else set()))
    per_step = ("odom", "attachments", "status", "thrusters", "state", "wrench")  # the contract's "every step"
    every_step = tuple(t for t in outputs if t.split("/")[-1] in per_step and "/" + t.split("/")[1] in names)
    return outputs, every_step


def per_step_outputs(sc: Scenario, names: Sequence[str]) -> Dict[str, str]:
    """topic -> the node that publishes it, for the per-step state outputs (the contract's "every
    step": odometry, attachments, status, thrusters, rope state, end wrenches) of these nodes: the
    topics a stranger must not publish, and whose count is checked against the steps run."""
    out = {}
    for topic in external_outputs(sc, names)[1]:
        owner = [n for n in names if _published_by(topic, [n])]
        if len(owner) == 1:
            out[topic] = owner[0]
    return out


def resolve_external(specs: List["NodeSpec"], wanted: Sequence[str]) -> List[str]:
    """Node names ("/tug/vessel") of `--external` items: "all", a node name or a namespace
    ("tug", "/tug"). ValueError naming the item that matches no node of the scenario."""
    names = [s.name for s in specs]
    out: List[str] = []
    for item in wanted:
        item = item.strip()
        if not item:
            continue
        if item == "all":
            found = names
        else:
            ns = "/" + item.strip("/")
            found = [n for n in names if n == ns or n.rsplit("/", 1)[0] == ns]
        if not found:
            raise ValueError(f"--external {item!r}: no such node; the scenario's nodes are {', '.join(names)} "
                             "(a name, its namespace, or all)")
        out += [n for n in found if n not in out]
    return out


@dataclasses.dataclass
class NodeSpec:
    namespace: str  # e.g. /tug
    node_name: str  # e.g. vessel
    package: str
    executable: str
    params: Dict[str, object]  # parameter name -> value (bool, int, float, str or list of str/float)

    @property
    def name(self) -> str:
        return f"{self.namespace}/{self.node_name}"

    def ros_args(self) -> List[str]:
        """The same parameters as `--ros-args` for a process started like `ros2 run`."""
        args = ["-r", f"__ns:={self.namespace}", "-r", f"__node:={self.node_name}"]
        for key, value in self.params.items():
            args += ["-p", f"{key}:={yaml_value(value)}"]
        return args

    def parameter_overrides(self):
        from rclpy.parameter import Parameter
        return [Parameter(k, value=v) for k, v in self.params.items()]


def executable_path(package: str, executable: str) -> str:
    """Where `ros2 run package executable` finds the executable; RunError if nowhere."""
    path = installed_executable(package, executable)
    if path is None:
        raise RunError(f"executable {package}/{executable} not found on AMENT_PREFIX_PATH (is the workspace "
                       "sourced?)")
    return path


def yaml_value(value) -> str:
    # rcl parses -p values as YAML: strings are quoted so that none turns into a number or map.
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(value)
    if isinstance(value, (list, tuple)):
        return "[" + ",".join(yaml_value(v) for v in value) + "]"
    return json.dumps(str(value))


def _data_file(package: str, subdir: str, name: str, scenario_path: str, portable: bool) -> str:
    path = resolve(package, subdir, name, scenario_path)
    return data_files.shipped_name(package, subdir, path) if portable else path


def node_specs(sc: Scenario, scenario_path: str, run_id: str = "", portable: bool = False) -> List[NodeSpec]:
    """The nodes a scenario needs, with their parameters (run_id: the run they belong to;
    portable: a ship or rope file the packages ship by its bare name, which a node on another
    machine finds in its own installation, not by this checkout's path)."""
    # No use_sim_time: a stepped node takes the time of each step from its trigger, and /clock
    # would cost one more delivery per node per step (issue 34; an outside autopilot keeps it).
    common = {"exchange_rate": float(sc.exchange_rate), "lockstep": True, "run_id": run_id}
    if sc.environment.is_uniform:
        common.update(current_east=float(sc.environment.current[0]), current_north=float(sc.environment.current[1]))
    else:
        common["environment"] = environment_parameter(sc, scenario_path)
    specs = []
    for v in sc.vessels:
        params = {"ship_file": _data_file("tug_dynamics", "ships", v.ship_file, scenario_path, portable),
                  "initial_x": float(v.initial.x), "initial_y": float(v.initial.y), "initial_yaw": heading_rad(v),
                  "initial_speed": float(v.initial.speed), "initial_engine_order": float(v.initial.engine_order),
                  "initial_steering_angle": math.radians(v.initial.steering_deg)}
        rope_ends = [T.end_coupling_topic(r.name, end) for r in sc.ropes for end in ("a", "b")
                     if getattr(r, f"end_{end}").split("/")[0] == v.name]
        if rope_ends:
            params["rope_end_topics"] = rope_ends
        contacts = [T.contact_topic(c.name) for c in sc.contacts if v.name in (c.hull, c.fender.split("/")[0])]
        if contacts:
            params["contact_topics"] = contacts
        if any(v.name in i.felt_by for i in sc.interactions):
            params["wrench_topics"] = [T.interaction_wrench_topic(v.name)]
        if v.ship_overrides:
            params["ship_overrides"] = json.dumps(v.ship_overrides)
        if v.motion is not None:
            m = v.motion
            params.update(motion=m.type, motion_speed=float(m.speed), motion_amplitude=float(m.amplitude),
                          motion_period=float(m.period), motion_acceleration=float(m.acceleration),
                          motion_heading=m.heading, motion_turn_rate=math.radians(m.turn_rate_deg),
                          motion_turn_start=float(m.turn_start), motion_turn_duration=float(m.turn_duration))
        specs.append(NodeSpec(f"/{v.name}", "vessel", "tug_dynamics", "vessel_node", {**params, **common}))
    for r in sc.ropes:
        params = {"rope_file": _data_file("rope_model", "ropes", r.rope_file, scenario_path, portable),
                  "end_a": r.end_a, "end_b": r.end_b, "layout": r.layout, "equilibrium": r.equilibrium}
        for end in ("a", "b"):
            pos = getattr(r, f"end_{end}_position")
            if pos is not None:
                params[f"end_{end}_position"] = [float(c) for c in pos]
        if r.deployed_length:
            params["deployed_length"] = float(r.deployed_length)
        if r.n_elements:
            params["n_elements"] = int(r.n_elements)
        specs.append(NodeSpec(f"/{r.name}", "rope", "rope_model", "rope_node", {**params, **common}))
    ships = {v.name: v for v in sc.vessels}
    for c in sc.contacts:
        fender_vessel, fender = c.fender.split("/")
        params = {"fender_vessel": fender_vessel, "fender": fender, "hull_vessel": c.hull,
                  "radius": float(c.radius), "stiffness": float(c.stiffness), "damping": float(c.damping),
                  "friction": float(c.friction)}
        for side, v in (("fender", ships[fender_vessel]), ("hull", ships[c.hull])):
            params[f"{side}_ship_file"] = _data_file("tug_dynamics", "ships", v.ship_file, scenario_path, portable)
            if v.ship_overrides:
                params[f"{side}_ship_overrides"] = json.dumps(v.ship_overrides)
        specs.append(NodeSpec(f"/{c.name}", "contact", "hull_contact", "contact_node", {
            **params, "exchange_rate": float(sc.exchange_rate), "lockstep": True, "run_id": run_id}))
    specs += _interaction_specs(sc, scenario_path, run_id, portable)
    for a in sc.autopilots:
        # YAML 90 is an int; ROS would refuse it for a double parameter: numbers go as floats.
        params = {k: (list(v) if isinstance(v, tuple) else
                      float(v) if isinstance(v, int) and not isinstance(v, bool) else v)
                  for k, v in a.params.items()}
        params.update(vessel=a.vessel, exchange_rate=float(sc.exchange_rate), lockstep=True, run_id=run_id)
        if a.package != "scenario_runner":   # somebody else's autopilot may read the ROS clock
            params["use_sim_time"] = True
        specs.append(NodeSpec(f"/{a.name}", "autopilot", a.package, a.executable, params))
    for spec in specs:  # the mapping sets only parameters the node's table holds (a rename fails here)
        if spec.executable in NODE_TABLES:
            NODE_TABLES[spec.executable].check_names(set(spec.params) - {"use_sim_time"})
    return specs


def interaction_vessels(sc: Scenario) -> List[str]:
    """The vessels in an interaction, in the order the scenario first names them."""
    return list(dict.fromkeys(name for i in sc.interactions for name in i.between))


def interaction_felt(sc: Scenario) -> List[str]:
    """The vessels an interaction puts a load on (each has its on_<vessel>/wrench)."""
    return list(dict.fromkeys(name for i in sc.interactions for name in i.felt_by))


def _interaction_specs(sc: Scenario, scenario_path: str, run_id: str, portable: bool = False) -> List[NodeSpec]:
    """One interaction node for all the run's pairs and banks (tug_dynamics.interaction_set)."""
    if not sc.interactions:
        return []
    ships = {v.name: v for v in sc.vessels}
    vessels = interaction_vessels(sc)
    params = {"vessels": vessels,
              "ship_files": [_data_file("tug_dynamics", "ships", ships[n].ship_file, scenario_path, portable)
                             for n in vessels],
              "ship_overrides": [json.dumps(ships[n].ship_overrides) if ships[n].ship_overrides else ""
                                 for n in vessels],
              "pairs": [f"{i.entry_name}={','.join(i.between)}" for i in sc.interactions
                        if not i.bank and "wang" in i.loads] or [""],
              "washes": [f"{i.entry_name}_wash={','.join(i.between)},{i.wash_impingement!r}" for i in sc.interactions
                         if not i.bank and "wash" in i.loads] or [""],
              "banks": [f"{i.entry_name}={i.between[0]}:" + ("depth" if i.bank == "depth" else (
                            (f"{i.bank_slope!r}:" if i.bank_slope else "")
                            + ",".join(repr(float(c)) for point in i.bank for c in point)))
                        for i in sc.interactions if i.bank] or [""],
              "depth": interaction_depth(sc)}
    if any(i.bank == "depth" for i in sc.interactions):
        params["depth_grid"] = depth_grid_path(sc.environment.depth, scenario_path)
    return [NodeSpec(f"/{T.INTERACTIONS}", "interaction", "hull_contact", "interaction_node", {
        **params, "exchange_rate": float(sc.exchange_rate), "lockstep": True, "run_id": run_id})]


def instrument_specs(sc: Scenario, scenario_path: str) -> List[NodeSpec]:
    """Processes that connect the run to bridge equipment (not step participants): the NMEA 0183 /
    AIS out node when the scenario has `nmea`."""
    if sc.nmea is None:
        return []
    n = sc.nmea
    params = {"vessels": [v.name for v in sc.vessels],
              "outputs": [f"{o.vessel}@[{o.host}]:{o.port}" if ":" in o.host else f"{o.vessel}@{o.host}:{o.port}"
                          for o in n.outputs],
              "ropes": [f"{r.name}={r.end_a},{r.end_b}" for r in sc.ropes] or [""],
              "ship_files": [f"{v.name}={resolve('tug_dynamics', 'ships', v.ship_file, scenario_path)}"
                             for v in sc.vessels],
              "mmsi": [f"{k}={m}" for k, m in n.mmsi.items()] or [""],
              "gear_ratios": [f"{k}={g!r}" for k, g in n.gear_ratios.items()] or [""],
              "rate": float(n.rate), "exchange_rate": float(sc.exchange_rate), "utc_start": n.utc_start,
              "static_every": int(n.static_every), "origin_latitude": float(sc.origin.latitude),
              "origin_longitude": float(sc.origin.longitude), "origin_height": float(sc.origin.height),
              "scenario": os.path.abspath(scenario_path)}   # AIS dimensions with the ship_overrides
    NODE_TABLES["nmea_out"].check_names(params)
    return [NodeSpec("/bridge", "nmea_out", "bridge_instruments", "nmea_out", params)]


def contract_topics(sc: Scenario) -> List[tuple]:
    """(topic, type, offered QoS) of every topic of the topic contract for this scenario
    (sim_contract.topics; /tf and /tf_static when there are vessels to broadcast their frames)."""
    named = [(t.name, t) for t in T.GLOBAL_TOPICS if sc.vessels or t.name not in (T.TF, T.TF_STATIC)]
    for v in sc.vessels:
        named += [(T.vessel_topic(v.name, t.name), t) for t in T.VESSEL_TOPICS]
        if has_thrusters(sc, v):   # azimuth thrusters: their orders and status (tug_dynamics README, ASD tug)
            named += [(T.vessel_topic(v.name, t.name), t) for t in T.THRUSTER_TOPICS]
    for r in sc.ropes:
        named += [(T.rope_topic(r.name, t.name), t) for t in T.ROPE_TOPICS]
        named += [(topic(r.name, e), t) for e in ("a", "b") if "/" in getattr(r, f"end_{e}")
                  for topic, t in ((T.end_wrench_topic, T.END_WRENCH), (T.end_coupling_topic, T.END_COUPLING))]
        if r.layout == "winch":
            named.append((T.rope_topic(r.name, T.WINCH), T.WINCH_TOPIC))
    named += [(T.contact_topic(c.name), t) for c in sc.contacts for t in T.CONTACT_TOPICS]
    named += [(T.interaction_wrench_topic(v), t) for v in interaction_felt(sc) for t in T.INTERACTION_TOPICS]
    return [(name, rc.message_class(t.type), rc.QOS_BY_KIND[t.qos]) for name, t in named]
