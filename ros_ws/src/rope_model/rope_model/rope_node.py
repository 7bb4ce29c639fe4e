"""The rope node: one executable for every rope file.

    ros2 run rope_model rope_node --ros-args -r __ns:=/towline -p rope_file:=table1.yaml \
        -p end_a:=tug/towing_hook -p end_b:=barge/bow_bollard

Each end is "<vessel>/<attachment>" (pinned to that attachment point, taken from
/<vessel>/attachments each step), "fixed" (held at end_X_position) or "free". The chain is
laid out between the ends' step-0 positions (straight, slack or wound on end a's winch) and,
with equilibrium:=true, settled to static equilibrium for those positions and the ends' step-0
velocities before step 0 (RopeChain.settle; nothing of it is published).

Publishes ``state`` (tug_msgs/RopeState), for each end pinned to a vessel ``end_<a|b>/coupling``
(tug_msgs/RopeEndCoupling: the force the vessel takes over the coming step, with its stiffness and
damping, world axes; rope_model.end_coupling) and ``end_<a|b>/wrench`` (geometry_msgs/WrenchStamped:
the mean force over the last step in frame "<vessel>/<attachment>", i.e. acting at the attachment
point with the vessel's body axes; for RViz, instruments and analysis) and ``markers`` (visualization_msgs/MarkerArray, a line strip coloured
by tension). Subscribes ``winch`` (tug_msgs/WinchCommand) for a rope wound on a winch.
"""
from __future__ import annotations

import copy
import math
import os
import sys
from typing import Dict, List, Optional

import numpy as np
from geometry_msgs.msg import WrenchStamped
from tug_msgs.msg import AttachmentArray, RopeEndCoupling, RopeState, ScenarioEvent, WinchCommand
from visualization_msgs.msg import MarkerArray

from rope_model.models import ModelFailure, make_model, rope_file_model
from sea_environment.environment import Environment
from rope_model.state_cdr import rope_state_cdr
from rope_model.winch import Winch
from sim_contract import topics as T
from sim_plumbing import cdr
from sim_math.rotations import matrix_from_quaternion
from sim_contract.node_params import ROPE_NODE
from sim_math.data_files import resolve as resolve_data_file
from sim_plumbing import ros_common as rc
from sim_plumbing.ros_common import ModelDiverged
from sim_plumbing.stepping import SteppedNode, StepInput

LAYOUTS = ("straight", "slack", "winch")


class RopeEnd:
    def __init__(self, label: str, spec: str, position: List[float]):
        self.label = label  # "a" or "b"
        self.spec = spec
        if spec in ("fixed", "free"):
            self.mode, self.vessel, self.attachment = spec, "", ""
        elif spec.count("/") == 1 and all(spec.split("/")):
            self.mode = "pinned"
            self.vessel, self.attachment = spec.split("/")
        else:
            raise ValueError(f"parameter end_{label}:={spec!r}: expected '<vessel>/<attachment>', 'fixed' or 'free'")
        self.position = np.array(position, float) if len(position) == 3 else None
        if self.mode != "pinned" and self.position is None:
            raise ValueError(f"parameter end_{label}_position: end {label} is '{spec}', give its position [x, y, z] m")
        self.velocity = np.zeros(3)
        self.orientation = None  # attachment frame orientation, quaternion (x, y, z, w)

    @property
    def frame(self) -> str:
        return f"{self.vessel}/{self.attachment}"


class RopeNode(SteppedNode):
    LIVE_PARAMETERS = ROPE_NODE.live  # no effect on the physics

    def __init__(self, node_name: str = "rope", **kwargs):
        super().__init__(node_name, **kwargs)
        rc.declare_table(self, ROPE_NODE)
        gp = self.get_parameter

        rope_file = gp("rope_file").value
        path = resolve_data_file("rope_model", "ropes", rope_file)
        if not os.path.isfile(path):
            raise FileNotFoundError(f"rope file '{path}' not found (parameter rope_file:={rope_file})")
        rope_file_model(path)  # validates the model key early
        self.rope_path = path
        self.ends = [RopeEnd("a", gp("end_a").value, list(gp("end_a_position").value)),
                     RopeEnd("b", gp("end_b").value, list(gp("end_b_position").value))]
        self.layout = gp("layout").value
        if self.layout not in LAYOUTS:
            raise ValueError(f"parameter layout:={self.layout!r}: expected one of {LAYOUTS}")
        if self.layout == "winch" and self.ends[0].mode == "free":
            raise ValueError("parameter layout:=winch needs end a on a vessel or fixed (the winch is at end a)")
        self.equilibrium = bool(gp("equilibrium").value)
        self.deployed_length = gp("deployed_length").value or None
        self.n_elements = gp("n_elements").value or None
        self.max_substep = gp("max_substep").value
        self.current = (gp("current_east").value, gp("current_north").value, 0.0)
        self.env = None
        if gp("environment").value:
            if any(self.current):
                raise ValueError("parameters current_east / current_north and environment both give a current: "
                                 "use environment.current")
            self.env, _ = Environment.from_parameter(gp("environment").value)
        self.rope_name = self.get_namespace().strip("/").split("/")[-1] or "rope"
        self.rope = None  # a rope_model.models adapter, built once the ends' positions are known
        self.rejected = 0  # winch orders refused (NaN, inf)
        self.clamped = 0   # winch orders clamped to the winch's limits

        self.state_pub = self.create_fed_publisher(RopeState, T.STATE, rc.LATCHED_STATE_QOS)
        self.marker_pub = self.create_fed_publisher(MarkerArray, T.MARKERS, rc.LATCHED_STATE_QOS)
        self.event_pub = self.create_publisher(ScenarioEvent, rc.EVENTS_TOPIC, rc.EVENTS_QOS)
        self.wrench_outputs: Dict[str, tuple] = {}  # end label -> (publisher, encoder)
        self.coupling_outputs: Dict[str, tuple] = {}
        for end in self.ends:
            if end.mode == "pinned":
                self.wrench_outputs[end.label] = (
                    self.create_fed_publisher(WrenchStamped, f"end_{end.label}/wrench", rc.LATCHED_STATE_QOS),
                    cdr.WrenchStampedEncoder(end.frame))
                self.coupling_outputs[end.label] = (
                    self.create_fed_publisher(RopeEndCoupling, f"end_{end.label}/coupling", rc.LATCHED_STATE_QOS),
                    cdr.RopeEndCouplingEncoder(rc.WORLD_FRAME, end.vessel, end.attachment))
        self._drives: Dict[str, tuple] = {}     # pinned end -> (start, velocity) of the rope's last step
        self._couplings: Dict[str, object] = {}  # pinned end -> end_coupling.EndCoupling to publish
        self.vessel_topics = {}
        for end in self.ends:
            if end.mode == "pinned":
                self.vessel_topics.setdefault(T.vessel_topic(end.vessel, T.ATTACHMENTS), end.vessel)
        inputs = [StepInput(t, AttachmentArray, decode=cdr.decode_attachment_array) for t in self.vessel_topics]
        if self.layout == "winch":
            inputs.append(StepInput(T.WINCH, WinchCommand, kind="order", decode=cdr.decode_winch_command))
        self.init_stepping(inputs, ready=False)
        # markers on every n-th step: RViz needs no more than ~10 Hz and they cost a third of a step
        self.marker_every = max(1, round(1e9 / self.period_ns / gp("marker_rate").value))
        if not self.vessel_topics:
            self._build()
        self.get_logger().info(
            f"rope '{self.rope_name}' from {path}: ends {self.ends[0].spec} - {self.ends[1].spec}, "
            f"layout {self.layout}, {'lockstep' if self.lockstep else 'free-running'}"
            + ("" if self.rope else "; waiting for the vessels' attachments"))

    # -- inputs --------------------------------------------------------------------------
    def on_live_parameters(self, changes) -> None:
        self.marker_every = max(1, round(1e9 / self.period_ns / changes["marker_rate"]))

    WINCH_MODES = Winch.MODES  # indexed by WinchCommand.SPEED, HOLD, CONSTANT_TENSION

    @staticmethod
    def _winch_tensions(msg) -> dict:
        """The order's tensions as set_winch keywords: 0 (or absent) = keep the current (None)."""
        return {k: (getattr(msg, k, 0.0) or None) for k in ("set_tension", "recover_tension", "brake_load")}

    def _winch_order_fault(self, msg):
        """Why a WinchCommand is refused (None: acceptable): a non-finite rate, an unknown mode,
        a non-finite or negative tension, a recover tension above the set tension."""
        if not math.isfinite(msg.payout_rate):
            return f"payout_rate={msg.payout_rate!r}"
        mode = getattr(msg, "mode", 0)
        if not 0 <= mode < len(self.WINCH_MODES):
            return f"mode={mode!r} (expected 0 SPEED, 1 HOLD or 2 CONSTANT_TENSION)"
        for k in ("set_tension", "recover_tension", "brake_load"):
            v = getattr(msg, k, 0.0)
            if not (math.isfinite(v) and v >= 0.0):
                return f"{k}={v!r} (expected a finite tension >= 0 N, 0 = keep)"
        rope = getattr(self.rope, "rope", None)  # the element chain: check against its present settings
        if rope is not None and getattr(rope, "winch", False):
            t = self._winch_tensions(msg)
            ts = t["set_tension"] if t["set_tension"] is not None else rope.set_tension
            tr = t["recover_tension"] if t["recover_tension"] is not None else rope.recover_tension
            if tr > ts:
                return f"recover_tension {tr:g} N above set_tension {ts:g} N"
        return None

    def step_of(self, spec, msg) -> int:
        if spec.msg_type is AttachmentArray:
            return msg.step
        return super().step_of(spec, msg)

    def accept_input(self, spec: StepInput, msg) -> bool:
        if spec.msg_type is WinchCommand:
            why = self._winch_order_fault(msg)
            if why is not None:
                self.rejected += 1
                detail = f"winch command rejected, keeping the last valid one: {why}"
                if self.complaints("winch rejected", detail):
                    self.emit_event("command_rejected", detail)
                return False
            return True
        for end in self.ends:
            if end.mode == "pinned" and T.vessel_topic(end.vessel, T.ATTACHMENTS) == spec.topic:
                point = msg.points.get(end.attachment)
                if point is None:
                    self.complaints("attachments " + spec.topic,
                                    f"{spec.topic} has no attachment '{end.attachment}' for end {end.label} "
                                    f"(it has {list(msg.points)})")
                    return False
                if not all(math.isfinite(v) for v in point.position + point.velocity + point.orientation):
                    self.complaints("attachments " + spec.topic,
                                    f"{spec.topic}: non-finite kinematics for '{end.attachment}' rejected")
                    return False
        if self.rope is None and msg.step == 0:
            self._take_attachments(msg)
            if all(e.position is not None for e in self.ends):
                try:
                    self._build()
                except ValueError as exc:  # e.g. a straight layout already beyond the breaking load
                    raise ModelDiverged(f"rope '{self.rope_name}' cannot be laid out between its ends' "
                                        f"step-0 positions: {exc}") from exc
        return True

    def _take_attachments(self, msg: cdr.AttachmentsIn) -> None:
        for end in self.ends:
            if end.mode == "pinned" and end.vessel == msg.vessel:
                point = msg.points[end.attachment]
                end.position = np.array(point.position)
                end.velocity = np.array(point.velocity)
                end.orientation = point.orientation

    def _build(self) -> None:
        a = self.ends[0]
        heading = 0.0
        if a.orientation is not None:
            x, y, z, w = a.orientation
            heading = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
        current = self.current
        if self.env is not None:   # laid out and settled in the current at its middle at t = 0
            mid = 0.5 * (np.asarray(a.position, float) + np.asarray(self.ends[1].position, float))
            cx, cy = self.env.current.velocity_xy(0.0, float(mid[0]), float(mid[1]))
            current = (cx, cy, 0.0)
        self.rope = make_model(self.rope_path, self.layout, a.position, self.ends[1].position,
                               end_a=a.mode, end_b=self.ends[1].mode, current=current,
                               n_elements=self.n_elements, deployed_length=self.deployed_length,
                               max_substep=self.max_substep, velocity_a=a.velocity, heading=heading,
                               equilibrium=self.equilibrium, velocity_b=self.ends[1].velocity,
                               **({"seabed": lambda c: self.env.depth_at(c[:, 0], c[:, 1])}
                                  if self.env is not None and not self.env.depth.is_deep else {}))
        if self.env is not None:   # from here on every step samples it at the elements, from t = 0
            self.rope.attach_environment(self.env)
        for end in self.ends:
            if end.mode == "pinned":
                self.rope.set_end(end.label, end.position, end.velocity)
                self._drives[end.label] = (np.array(end.position, float), np.array(end.velocity, float))
        self._couplings = self.rope.couplings(self._drives, self.dt, averaged=False)
        self._warm_up()
        self.ready_to_step = True
        self.publish_outputs()
        out = self.rope.outputs()
        settled = ("" if self.rope.settle_time is None else
                   f", settled to equilibrium in {self.rope.settle_time:.0f} s (end tensions "
                   + ", ".join(f"{np.linalg.norm(self.rope.end_force(e, averaged=False)) / 1e3:.2f}" for e in "ab")
                   + " kN)")
        self.get_logger().info(f"rope laid out ({self.rope.name}): {len(out['positions'])} elements/nodes, "
                               f"{out['unstretched_length']:.2f} m deployed{settled}")

    def _warm_up(self) -> None:
        """One step of a copy of the rope, thrown away: the first step's one-off work (loading
        the compiled kernels the settling did not use, e.g. the one that samples the environment:
        17 ms in the berthing run) is done now, before the run's clock starts, not in step 0 of a
        paced run. The rope itself is untouched. A failure here is left to the real step to raise."""
        scratch = copy.deepcopy(self.rope)
        try:
            drives = {label: scratch.drive_end(label, p, v, self.dt) for label, (p, v) in self._drives.items()}
            scratch.step(self.dt)
            scratch.couplings(drives, self.dt, averaged=True)
        except Exception:  # noqa: BLE001 - the real step meets the same fault and reports it
            pass

    # -- stepping -------------------------------------------------------------------------
    def compute_step(self, inputs) -> None:
        for topic in self.vessel_topics:
            msg = inputs.get(topic)
            if msg is not None:
                self._take_attachments(msg)
        for end in self.ends:
            if end.mode == "pinned":   # continuously: from where the last step left it to the vessel's path
                self._drives[end.label] = self.rope.drive_end(end.label, end.position, end.velocity, self.dt)
        order = inputs.get(T.WINCH)
        if order is not None:
            # clamped to the winch's limits like any order; the notes say how
            try:
                notes = self.rope.set_winch(self.WINCH_MODES[getattr(order, "mode", 0)],
                                            payout_rate=order.payout_rate, **self._winch_tensions(order))
            except ValueError as exc:  # a fault accept_input could not see (refused whole)
                self.rejected += 1
                detail = f"winch command rejected, keeping the last valid one: {exc}"
                if self.complaints("winch rejected", detail):
                    self.emit_event("command_rejected", detail)
                notes = ()
            for note in notes or ():
                self.clamped += 1
                if self.complaints("winch clamped", f"winch command clamped: {note}", "warning"):
                    self.emit_event("command_clamped", note)
        try:
            self.rope.step(self.dt)
        except ModelFailure as exc:
            k = self.step_index
            detail = f"rope '{self.rope_name}' failed at step {k} -> {k + 1} (t = {k * self.dt:.3f} s): {exc}"
            self.emit_event("rope_failed", detail)
            raise ModelDiverged(detail) from exc
        for detail, tension in self.rope.new_events():
            self.emit_event("rope_parted", detail, tension)
        self._couplings = self.rope.couplings(self._drives, self.dt, averaged=True)

    def publish_outputs(self) -> None:
        if self.rope is None:
            return
        stamp_ns = self.stamp_ns()
        out = self.rope.outputs()
        line = np.asarray(out["line"])
        forces = {end: self.rope.end_force(end, averaged=self.step_index > 0) for end in ("a", "b")}
        # written as CDR bytes from the arrays: building Pose/Twist objects per element would
        # cost more than the rope's physics (see state_cdr.py)
        self.state_pub.publish(rope_state_cdr(
            stamp_ns=stamp_ns, frame_id=rc.WORLD_FRAME, step=self.step_index,
            rope=self.rope_name, model=self.rope.name, positions=out["positions"],
            quaternions=out["quaternions"], velocities=out["velocities"],
            angular_velocities=out["angular_velocities"], lengths=out["lengths"], tensions=out["tensions"],
            piece_starts=out["piece_starts"], unstretched_length=float(out["unstretched_length"]),
            stretched_length=float(np.linalg.norm(np.diff(line, axis=0), axis=1).sum()),
            mass=float(out["mass"]), end_a_force=forces["a"], end_b_force=forces["b"], broken=bool(out["broken"]),
            kinetic_energy=out["kinetic_energy"], potential_energy=out["potential_energy"]),
            stamp_ns)

        for end in self.ends:
            if end.mode != "pinned":
                continue
            # Attachment frame axes are the vessel's body axes: rotate the world force into them.
            rot = matrix_from_quaternion(*end.orientation)
            f_body = rot.T @ forces[end.label]
            publisher, encoder = self.wrench_outputs[end.label]
            publisher.publish(encoder.encode(stamp_ns, f_body.tolist()), stamp_ns)
            c = self._couplings[end.label]
            publisher, encoder = self.coupling_outputs[end.label]
            publisher.publish(encoder.encode(stamp_ns, self.step_index, c.force, c.reference_position,
                                             c.reference_velocity, c.stiffness, c.damping), stamp_ns)

        if rc.marker_step(self.get_fully_qualified_name(), self.step_index, self.marker_every):
            self.marker_pub.publish(self._markers(line, out["tensions"], stamp_ns), stamp_ns)

    def _markers(self, joints: np.ndarray, tensions: np.ndarray, stamp_ns: int) -> bytes:
        n = min(len(joints), len(tensions))
        # green (slack) -> yellow (half the breaking load) -> red (breaking load)
        s = np.clip(np.asarray(tensions[:n], float) / self.rope.breaking_load, 0.0, 1.0)
        colors = np.column_stack((np.minimum(1.0, 2 * s), np.minimum(1.0, 2 * (1 - s)), np.zeros(n), np.ones(n)))
        return cdr.line_strip_marker_array_cdr(stamp_ns, rc.WORLD_FRAME, self.rope_name, 0,
                                               max(0.1, 2.0 * self.rope.radius), joints[:n], colors)

    def emit_event(self, kind: str, detail: str, value: float = float("nan")) -> None:
        ev = ScenarioEvent(step=self.step_index, source=self.get_fully_qualified_name(), kind=kind,
                           target=self.rope_name, detail=detail, value=float(value))
        ev.header.stamp = self.stamp()
        self.event_pub.publish(ev)
        if kind not in ("command_rejected", "command_clamped"):  # those were logged rate-limited
            self.get_logger().warning(detail)


def main(args: Optional[List[str]] = None) -> int:
    return rc.run_node(RopeNode, "rope_node", args, failures=ModelFailure)


if __name__ == "__main__":
    sys.exit(main())
