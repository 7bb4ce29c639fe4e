"""The vessel node: one executable for every ship file.

    ros2 run tug_dynamics vessel_node --ros-args -r __ns:=/tug -p ship_file:=harbour_tug.yaml

Subscribes ``command`` (tug_msgs/VesselCommand), ``thruster_command`` (tug_msgs/ThrusterCommand:
per-thruster orders, for ships with azimuth thrusters), every topic named in ``rope_end_topics``
(tug_msgs/RopeEndCoupling: a rope end's force with its stiffness and damping, followed along the
attachment's motion inside the step) and in ``wrench_topics`` (geometry_msgs/WrenchStamped, held
over the step; frame_id "<vessel>/<attachment>" or "<vessel>/base_link").
Publishes ``odom`` (nav_msgs/Odometry), ``attachments`` (tug_msgs/AttachmentArray) and
``status`` (tug_msgs/VesselStatus) once per exchange step, and ``thrusters``
(tug_msgs/ThrusterStatus) with them on a ship with azimuth thrusters; the frames on ``/tf``
(tf2_msgs/TFMessage, map -> <vessel>/base_link, every step, the odometry's pose) and
``/tf_static`` (<vessel>/base_link -> <vessel>/<attachment>, once, latched); and its scene on
``markers`` (visualization_msgs/MarkerArray: hull, deck, attachment points, thrust and rope end
force arrows; sim_plumbing.scene) at ``marker_rate``. The physics lives in the ship model
(tug_dynamics.ship_file.load_ship); this node only converts messages.
"""
from __future__ import annotations

import copy
import math
import operator
import os
import sys
from typing import List, Optional

import numpy as np
import yaml
from geometry_msgs.msg import WrenchStamped
from visualization_msgs.msg import MarkerArray
from nav_msgs.msg import Odometry
from tf2_msgs.msg import TFMessage
from tug_msgs.msg import (AttachmentArray, HullContact, RopeEndCoupling, ScenarioEvent, ThrusterCommand, ThrusterStatus,
                           VesselCommand, VesselStatus)

from sim_plumbing import cdr
from sim_math.rotations import quaternion_from_rpy
from sim_contract import topics as T
from sim_contract.node_params import VESSEL_NODE
from sim_math.data_files import resolve as resolve_data_file
from sim_plumbing import ros_common as rc
from sim_math.hull_plan import HullDimensions
from sim_plumbing.scene import VesselScene
from sea_environment.environment import Environment
from tug_dynamics.environment_loads import EnvironmentStatus, VesselInEnvironment
from tug_dynamics.prescribed import MotionLaw, PrescribedMotion
from tug_dynamics.seakeeping import VesselInWaves, waves_refused
from sim_plumbing.ros_common import ModelDiverged
from sim_plumbing.stepping import REJECTED_ORDER, SteppedNode, StepInput
from tug_dynamics.vessel import (BodyPoints, Command, CommandRejected, ExternalWrench, ThrusterOrder, Vessel,
                                 VesselState, check_command, rotation_body_to_world)

# the status record's float fields in message order (every model's StatusRecord has them all)
_STATUS_FLOATS_A = operator.attrgetter(*cdr.VESSEL_STATUS_FLOATS_A)
_STATUS_FLOATS_B = operator.attrgetter(*cdr.VESSEL_STATUS_FLOATS_B)
_STATUS_FLOATS_ENV = operator.attrgetter(*cdr.VESSEL_STATUS_FLOATS_ENV)
_STILL_DEEP = EnvironmentStatus()   # what status reports without an environment


class VesselNode(SteppedNode):
    LIVE_PARAMETERS = VESSEL_NODE.live  # the scene only: no effect on the physics

    def __init__(self, node_name: str = "vessel", **kwargs):
        super().__init__(node_name, **kwargs)
        rc.declare_table(self, VESSEL_NODE)

        ship_file = self.get_parameter("ship_file").value
        if not ship_file:
            raise ValueError("parameter 'ship_file' is required (a path or a file in share/tug_dynamics/ships)")
        path = resolve_data_file("tug_dynamics", "ships", ship_file)
        if not os.path.isfile(path):
            raise FileNotFoundError(f"ship file '{path}' not found (parameter ship_file:={ship_file})")
        ns_name = self.get_namespace().strip("/").split("/")[-1]
        self.vessel_name = self.get_parameter("vessel_name").value or ns_name or "vessel"
        initial = VesselState.at_rest(self.get_parameter("initial_x").value, self.get_parameter("initial_y").value,
                                      self.get_parameter("initial_yaw").value)
        initial.linear_velocity_body[0] = self.get_parameter("initial_speed").value

        from tug_dynamics.ship_file import load_ship, ship_config
        overrides_text = self.get_parameter("ship_overrides").value
        overrides = yaml.safe_load(overrides_text) if overrides_text else None
        if overrides is not None and not isinstance(overrides, dict):
            raise ValueError(f"parameter ship_overrides:={overrides_text!r}: expected a YAML mapping")
        self.model: Vessel = load_ship(path, name=self.vessel_name, initial_state=initial, overrides=overrides)
        initial_command = Command(self.get_parameter("initial_engine_order").value,
                                  self.get_parameter("initial_steering_angle").value)
        # 0, 0 keeps the model's own start (at rest: stopped; a planing hull given an initial
        # speed starts in its steady run at the throttle for that speed).
        if initial_command.engine_order or initial_command.steering_angle:
            for note in self.model.settle_command(initial_command):
                self.get_logger().warning(f"initial command clamped: {note}")
        motion = self.get_parameter("motion").value
        if motion:
            law = MotionLaw(motion, speed=self.get_parameter("motion_speed").value,
                            amplitude=self.get_parameter("motion_amplitude").value,
                            period=self.get_parameter("motion_period").value,
                            acceleration=self.get_parameter("motion_acceleration").value,
                            heading=self.get_parameter("motion_heading").value,
                            turn_rate=self.get_parameter("motion_turn_rate").value,
                            turn_start=self.get_parameter("motion_turn_start").value,
                            turn_duration=self.get_parameter("motion_turn_duration").value)
            self.model = PrescribedMotion(self.model, law)
        current = np.array([self.get_parameter("current_east").value, self.get_parameter("current_north").value, 0.0])
        if np.any(current):   # 0, 0 keeps the ship file's own current
            self.model.set_current(current)
        # attached to the model: from here on its steps feel the environment
        env = self._environment(self.get_parameter("environment").value, current)
        self.surroundings = (VesselInEnvironment(self.model, env[0], rho_water=env[1])
                             if env is not None and env[0].acts_on_hulls else None)
        # the sea (wave-frequency motion superposed, drift force on the manoeuvring model)
        self.sea = self._sea(env[0] if env else None, path)
        self._wave = None   # the sea's part of the last published state (seakeeping.WaveStep)
        self._feels_drift = not isinstance(self.model, PrescribedMotion)   # a prescribed track takes no force
        self._was_grounded = False

        self.rejected = 0
        self.clamped = 0
        self.body_frame = f"{self.vessel_name}/base_link"
        self.wrench_topics = [t for t in self.get_parameter("wrench_topics").value if t]
        self.contact_topics = [t for t in self.get_parameter("contact_topics").value if t]
        self.rope_end_topics = [t for t in self.get_parameter("rope_end_topics").value if t]
        # contact topic -> (force on this vessel, world; point, body) of the step being computed
        self._contacts = {t: (np.zeros(3), np.zeros(3)) for t in self.contact_topics}

        self.odom_pub = self.create_fed_publisher(Odometry, T.ODOM, rc.LATCHED_STATE_QOS)
        self.tf_pub = self.create_fed_publisher(TFMessage, rc.TF_TOPIC, rc.TF_QOS)
        self.tf_static_pub = self.create_fed_publisher(TFMessage, rc.TF_STATIC_TOPIC, rc.TF_STATIC_QOS)
        self.marker_pub = self.create_fed_publisher(MarkerArray, T.MARKERS, rc.LATCHED_STATE_QOS)
        ship_cfg = ship_config(path, overrides)[1]  # checked by load_ship above
        self.scene = VesselScene(self.vessel_name, HullDimensions.from_ship_config(ship_cfg), self.model.attachments)
        self._rope_forces = {}  # wrench topic -> (attachment point, force in body axes) of the last step
        self.attach_pub = self.create_fed_publisher(AttachmentArray, T.ATTACHMENTS, rc.LATCHED_STATE_QOS)
        self.status_pub = self.create_fed_publisher(VesselStatus, T.STATUS, rc.LATCHED_STATE_QOS)
        # per-thruster state, on ships with azimuth thrusters only (a prescribed motion's base
        # ship reports its thrusters too, though it takes no orders)
        self._thruster_names = tuple(t.name for t in getattr(self.model.status(), "thrusters", ()))
        self.thrusters_pub = (self.create_fed_publisher(ThrusterStatus, T.THRUSTERS, rc.LATCHED_STATE_QOS)
                              if self._thruster_names else None)
        self.event_pub = self.create_publisher(ScenarioEvent, rc.EVENTS_TOPIC, rc.EVENTS_QOS)
        self._wrench_points = {}  # frame_id -> attachment point (body), for accepted frames
        # commands raw: bytes that are not a VesselCommand are refused and counted, never crash the node
        self.init_stepping([StepInput(T.COMMAND, VesselCommand, kind="order", decode=cdr.decode_vessel_command),
                            StepInput(T.THRUSTER_COMMAND, ThrusterCommand, kind="order",
                                      decode=cdr.decode_thruster_command)] +
                           [StepInput(t, WrenchStamped, decode=cdr.decode_wrench_stamped, local=True)
                            for t in self.wrench_topics] +
                           [StepInput(t, RopeEndCoupling, decode=cdr.decode_rope_end_coupling)
                            for t in self.rope_end_topics] +
                           [StepInput(t, HullContact, decode=cdr.decode_hull_contact) for t in self.contact_topics])
        self.on_live_parameters({n: self.get_parameter(n).value for n in self.LIVE_PARAMETERS})
        # The first call of a numba kernel loads it from the cache (about 0.4 s): pay that
        # now, on a copy, not in the first step of a paced run.
        copy.deepcopy(self.model).step(self.dt, [])
        self._make_encoders()
        self.publish_outputs()
        self.get_logger().info(
            f"vessel '{self.vessel_name}' from {path}: {type(self.model).__name__}, "
            f"attachments {sorted(self.model.attachments)}, {1e9 / self.period_ns:g} Hz, "
            f"{'lockstep' if self.lockstep else 'free-running'}")

    def _environment(self, text: str, current: np.ndarray):
        """(Environment, water density), or None when the parameter is empty (the uniform current
        of current_east / current_north or the ship file then applies, as before)."""
        if not text:
            return None
        if np.any(current):
            raise ValueError("parameters current_east / current_north and environment both give a current: "
                             "use environment.current")
        return Environment.from_parameter(text)

    def _sea(self, env: Optional[Environment], ship_path: str) -> Optional[VesselInWaves]:
        """The vessel's response to the run's waves, or None on a calm sea."""
        if env is None or env.waves is None:
            return None
        base = self.model.base if isinstance(self.model, PrescribedMotion) else self.model
        refused = waves_refused(base, ship_path)
        if refused:
            raise ValueError(refused)
        return VesselInWaves.for_ship(ship_path, env.waves)

    # -- inputs --------------------------------------------------------------------------
    def accept_input(self, spec: StepInput, msg) -> bool:
        if spec.msg_type in (VesselCommand, ThrusterCommand) and isinstance(self.model, PrescribedMotion):
            # refused aloud: an order the motion law would silently override
            self._reject_command(CommandRejected(f"'{self.vessel_name}' follows a prescribed motion: orders "
                                                 "have no effect"))
            return False
        if spec.msg_type is VesselCommand:
            try:
                check_command(Command(msg.engine_order, msg.steering_angle, msg.anchor))
            except CommandRejected as exc:
                self._reject_command(exc)
                return False
            return True
        if spec.msg_type is ThrusterCommand:
            try:
                self._thruster_orders(msg)
            except CommandRejected as exc:
                self._reject_thruster_command(exc)
                return False
            return True
        if spec.msg_type is HullContact:
            return self._contact_fault(spec.topic, msg) is None
        if spec.msg_type is RopeEndCoupling:
            return self._rope_end_fault(spec.topic, msg) is None
        return self._wrench_point(spec.topic, msg) is not None

    def _rope_end_fault(self, topic: str, msg: cdr.RopeEndCouplingIn) -> Optional[str]:
        """Why a RopeEndCoupling cannot act on this vessel (None: it can): not finite, another
        vessel's, an attachment this ship does not have, or a stiffness that is not a spring's
        (dF/dx must be symmetric with no positive eigenvalue: it may never push the vessel on)."""
        why = None
        if not msg.is_finite():
            why = "non-finite value"
        elif msg.vessel != self.vessel_name:
            why = f"it is pinned to vessel '{msg.vessel}', not this vessel '{self.vessel_name}'"
        elif msg.attachment not in self.model.attachments:
            why = f"attachment '{msg.attachment}' is not one of {sorted(self.model.attachments)}"
        else:
            k = np.array(msg.stiffness).reshape(3, 3)
            if np.abs(k - k.T).max() > 1e-6 * max(1.0, np.abs(k).max()) or np.linalg.eigvalsh(k)[-1] > 1e-9 * max(
                    1.0, np.abs(k).max()):
                why = "its stiffness is not a restoring spring's (symmetric, negative semi-definite)"
        if why is not None:
            self.complaints("rope end " + topic, f"rope end on {topic} rejected: {why}")
        return why

    def _contact_fault(self, topic: str, msg: cdr.HullContactIn) -> Optional[str]:
        """Why a HullContact cannot act on this vessel (None: it can): not finite, or a contact
        between two other vessels."""
        why = None
        if not msg.is_finite():
            why = "non-finite value"
        elif self.vessel_name not in (msg.fender_vessel, msg.hull_vessel):
            why = (f"it couples '{msg.fender_vessel}' and '{msg.hull_vessel}', not this vessel "
                   f"'{self.vessel_name}'")
        if why is not None:
            self.complaints("contact " + topic, f"contact on {topic} rejected: {why}")
        return why

    def _reject_command(self, exc: CommandRejected) -> None:
        self.rejected += 1
        # rate-limited: a flood of bad orders must not cost a log line and an event each
        if self.complaints("command rejected", f"command rejected, keeping the last valid one: {exc}"):
            self.emit_event("command_rejected", str(exc))

    def _reject_thruster_command(self, exc: CommandRejected) -> None:
        self.rejected += 1
        if self.complaints("thruster command rejected",
                           f"thruster command rejected, keeping the last valid orders: {exc}"):
            self.emit_event("command_rejected", f"{T.THRUSTER_COMMAND}: {exc}")

    def _thruster_orders(self, msg: cdr.ThrusterCommandIn) -> List[ThrusterOrder]:
        """The orders of a ThrusterCommand, checked as far as the message goes (lengths, names,
        finite values); CommandRejected naming what is wrong. The model checks them again as it
        takes them (and clamps)."""
        names = self._thruster_names
        if not names or type(self.model).set_thruster_command is Vessel.set_thruster_command:
            raise CommandRejected(f"vessel '{self.vessel_name}' ({type(self.model).__name__}) has no azimuth "
                                  "thrusters that take orders; thruster orders refused")
        n = len(msg.azimuth)
        if len(msg.rpm) != n or (msg.thrusters and len(msg.thrusters) != n):
            raise CommandRejected(f"lengths differ: {len(msg.thrusters)} thrusters, {n} azimuth, "
                                  f"{len(msg.rpm)} rpm (thrusters may be empty: by index)")
        if n == 0:
            raise CommandRejected("no orders in it (azimuth and rpm are empty)")
        if msg.thrusters:
            unknown = [t for t in msg.thrusters if t not in names]
            if unknown:
                raise CommandRejected(f"thruster(s) {unknown} do not exist; vessel '{self.vessel_name}' "
                                      f"has {list(names)}")
            twice = sorted({t for t in msg.thrusters if msg.thrusters.count(t) > 1})
            if twice:
                raise CommandRejected(f"thruster(s) {twice} ordered twice in one command")
            keys = list(msg.thrusters)
        else:
            if n > len(names):
                raise CommandRejected(f"{n} orders by index, vessel '{self.vessel_name}' has {len(names)} "
                                      f"thrusters {list(names)}")
            keys = list(range(n))
        for key, azimuth, rpm in zip(keys, msg.azimuth, msg.rpm):
            if not (math.isfinite(azimuth) and math.isfinite(rpm)):
                label = key if isinstance(key, str) else f"{key} ({names[key]})"
                raise CommandRejected(f"thruster {label}: azimuth={azimuth!r}, rpm={rpm!r}: not finite")
        return [ThrusterOrder(key, azimuth, rpm) for key, azimuth, rpm in zip(keys, msg.azimuth, msg.rpm)]

    def _on_trigger(self, msg: cdr.TriggerIn) -> None:
        # SimStep.ordered announces the scenario runner's orders, which are VesselCommands on
        # `command`: a step waits for those only. A thruster order (from a console, a test, a
        # driver outside the runner's timeline) is never awaited: its slot of an announced step
        # starts empty (an order stamped for the step still fills it), as stepping.py does for
        # a rejected order.
        if self.namespace_name in msg.ordered:
            self._buffer[T.THRUSTER_COMMAND].setdefault(msg.step, REJECTED_ORDER)
        super()._on_trigger(msg)

    def _wrench_point(self, topic: str, msg: cdr.WrenchIn) -> Optional[np.ndarray]:
        if not msg.is_finite():
            self.complaints("wrench " + topic, f"wrench on {topic} rejected: non-finite value {msg.force + msg.torque}")
            return None
        frame = msg.frame_id
        point = self._wrench_points.get(frame)
        if point is not None:
            return point
        prefix = self.vessel_name + "/"
        point_name = frame[len(prefix):] if frame.startswith(prefix) else None
        if point_name == "base_link":
            point = np.zeros(3)
        elif point_name in self.model.attachments:
            point = np.asarray(self.model.attachments[point_name], float)
        else:
            self.complaints("wrench " + topic, f"wrench on {topic} rejected: frame '{frame}' is neither "
                            f"'{self.body_frame}' nor an attachment frame of this vessel "
                            f"({sorted(self.model.attachments)})")
            return None
        self._wrench_points[frame] = point
        return point

    # -- stepping -------------------------------------------------------------------------
    def compute_step(self, inputs) -> None:
        order = inputs.get(T.COMMAND)
        if order is not None:
            cmd = Command(engine_order=order.engine_order, steering_angle=order.steering_angle, anchor=order.anchor)
            try:
                notes = self.model.set_command(cmd)   # the model holds the (clamped) command
            except CommandRejected as exc:
                notes = []
                self._reject_command(exc)
            for note in notes:
                self.clamped += 1
                self.complaints("command clamped", f"command clamped: {note}", "warning")
        thruster_order = inputs.get(T.THRUSTER_COMMAND)
        if thruster_order is not None:   # after `command`: of two orders for one step, this one holds
            try:
                notes = self.model.set_thruster_command(self._thruster_orders(thruster_order))
            except CommandRejected as exc:
                notes = []
                self._reject_thruster_command(exc)
            for note in notes:
                self.clamped += 1
                self.complaints("thruster command clamped", f"thruster command clamped: {note}", "warning")
        # Wrench frames have body-parallel axes: rotate to world with the state of this step.
        rot = rotation_body_to_world(self.model.state.rpy)
        wrenches = []
        for topic in self.wrench_topics:
            msg = inputs.get(topic)
            if msg is None:
                continue
            point = self._wrench_points[msg.frame_id]
            wrenches.append(ExternalWrench(force_world=rot @ np.array(msg.force), point_body=point,
                                           moment_world=rot @ np.array(msg.torque)))
            self._rope_forces[topic] = (point, msg.force)
        for topic in self.rope_end_topics:
            msg = inputs.get(topic)
            if msg is None:
                continue
            point = np.asarray(self.model.attachments[msg.attachment], float)
            force = np.array(msg.force)
            ref_p, ref_v = np.array(msg.reference_position), np.array(msg.reference_velocity)
            if self._wave is not None:   # the rope saw the point's total motion; the model steps its low-frequency one
                i = self._names.index(msg.attachment)
                ref_p, ref_v = ref_p - self._wave.offsets[0][i], ref_v - self._wave.offsets[1][i]
            wrenches.append(ExternalWrench(force_world=force, point_body=point,
                                           stiffness=np.array(msg.stiffness).reshape(3, 3),
                                           damping=np.array(msg.damping).reshape(3, 3),
                                           reference_position=ref_p, reference_velocity=ref_v))
            self._rope_forces[topic] = (point, rot.T @ force)
        for topic in self.contact_topics:
            msg = inputs.get(topic)
            if msg is None:
                continue
            on_hull = np.array(msg.force_on_hull)
            force, point = ((on_hull, np.array(msg.hull_point_body)) if msg.hull_vessel == self.vessel_name
                            else (-on_hull, np.array(msg.fender_point_body)))
            self._contacts[topic] = (force, point)
            wrenches.append(ExternalWrench(force_world=force, point_body=point))
        if self._wave is not None and self._feels_drift:
            wrenches.append(self._wave.drift)
        self.model.step(self.dt, wrenches)
        self._check_finite()

    def _check_finite(self) -> None:
        """A state gone NaN or infinite is numerics (e.g. a time constant far below the step), not
        physics: stop, naming the vessel and the step, before anything is published."""
        s = self.model.state
        values = np.concatenate((s.position, s.rpy, s.linear_velocity_body, s.angular_velocity_body))
        if not np.all(np.isfinite(values)):
            raise ModelDiverged(
                f"vessel '{self.vessel_name}' diverged at step {self.step_index} -> {self.step_index + 1} "
                f"(t = {self.step_index * self.dt:.3f} s): state not finite (position {s.position.tolist()}, "
                f"velocity {s.linear_velocity_body.tolist()}); check the ship file's masses and time constants")

    def _make_encoders(self) -> None:
        """Output messages as CDR templates, laid out once (building message objects every
        step cost more than the physics, see sim_plumbing/cdr.py)."""
        self._names = sorted(self.model.attachments)
        self._points = BodyPoints([self.model.attachments[n] for n in self._names])
        self._points_body = self._points.body
        self._odom_cdr = cdr.OdometryEncoder(rc.WORLD_FRAME, self.body_frame)
        self._attach_cdr = cdr.AttachmentArrayEncoder(rc.WORLD_FRAME, self.vessel_name, self._names)
        self._status_cdr = cdr.VesselStatusEncoder(self.body_frame, self.vessel_name,
                                                   [t.strip("/").split("/")[0] for t in self.contact_topics])
        self._thrusters_cdr = cdr.ThrusterStatusEncoder(self.body_frame, self.vessel_name, self._thruster_names)
        self._tf_cdr = cdr.TFMessageEncoder([(rc.WORLD_FRAME, self.body_frame)])
        # the attachment frames: fixed in the body, axes of the body; published once, latched
        frames = [(self.body_frame, f"{self.vessel_name}/{n}") for n in self._names]
        self.tf_static_pub.publish(cdr.TFMessageEncoder(frames).encode(
            self.stamp_ns(), [(p.tolist(), (0.0, 0.0, 0.0, 1.0)) for p in self._points_body]), self.stamp_ns())

    def on_live_parameters(self, changes) -> None:
        if "marker_rate" in changes:
            self.marker_every = max(1, round(1e9 / self.period_ns / changes["marker_rate"]))
        if "marker_force_scale" in changes:
            self.force_scale = float(changes["marker_force_scale"])

    def publish_outputs(self) -> None:
        stamp_ns = self.stamp_ns()
        s = self.model.state
        sea = cdr.CALM_SEA
        if self.sea is not None:   # what leaves the vessel moves with the waves too
            self._wave = self.sea.step(s, stamp_ns * 1e-9, self._points)
            s, sea = self._wave.total, self._wave.sea_floats
        q = quaternion_from_rpy(*s.rpy)
        v, w = s.linear_velocity_body, s.angular_velocity_body
        position = s.position.tolist()
        self.odom_pub.publish(self._odom_cdr.encode(stamp_ns, position, q, v.tolist(), w.tolist()), stamp_ns)
        self.tf_pub.publish(self._tf_cdr.encode(stamp_ns, [(position, q)]), stamp_ns)  # the odometry's pose

        if self._wave is not None:   # with their wave-frequency part (a rope end's coupling reference moves by it)
            positions, velocities = self._wave.positions, self._wave.velocities
        else:
            positions, velocities = self._points.world(s)   # every attachment point at once
        self.attach_pub.publish(self._attach_cdr.encode(stamp_ns, self.step_index, positions, velocities, q),
                                stamp_ns)

        st = self.model.status()
        env = _STILL_DEEP
        if self.surroundings is not None:
            env = self.surroundings.status     # of the state being published; it acts over the next step
            if env.grounded != self._was_grounded:
                self._was_grounded = env.grounded
                self._report_grounding(env)
        self.status_pub.publish(self._status_cdr.encode(
            stamp_ns, self.step_index, _STATUS_FLOATS_A(st), int(st.anchor_state), _STATUS_FLOATS_B(st),
            st.girting_warning, self.rejected, self.clamped, _STATUS_FLOATS_ENV(env), env.grounded,
            *self._contact_status(), floats_sea=sea), stamp_ns)
        if self.thrusters_pub is not None:
            units = st.thrusters
            self.thrusters_pub.publish(self._thrusters_cdr.encode(stamp_ns, self.step_index, [
                [getattr(u, field) for u in units] for field in cdr.ThrusterStatusEncoder.FIELDS]), stamp_ns)
        if rc.marker_step(self.get_fully_qualified_name(), self.step_index, self.marker_every):
            rot_t = rotation_body_to_world(self.model.state.rpy).T   # hull contacts as force arrows too
            arrows = list(self._rope_forces.values()) + [(p, rot_t @ f) for f, p in self._contacts.values()]
            self.marker_pub.publish(self.scene.markers(stamp_ns, st.thrust, arrows, self.force_scale), stamp_ns)

    def _contact_status(self):
        """Contact forces (body axes) and points (body), flattened, in contact_topics' order."""
        if not self.contact_topics:
            return (), ()
        rot_t = rotation_body_to_world(self.model.state.rpy).T
        forces, points = [], []
        for force, point in self._contacts.values():
            forces += (rot_t @ force).tolist()
            points += point.tolist()
        return forces, points

    def _report_grounding(self, st) -> None:
        what = "grounded" if st.grounded else "refloated"
        self.emit_event(what, f"under-keel clearance {st.under_keel_clearance:.2f} m (depth {st.water_depth:.2f} m, "
                              f"draft {self.model.draft:.2f} m, squat {st.squat:.2f} m)", st.under_keel_clearance)
        log = self.get_logger().warning if st.grounded else self.get_logger().info
        log(f"vessel '{self.vessel_name}' {'ran aground' if st.grounded else 'is afloat again'} at step "
            f"{self.step_index}: under-keel clearance {st.under_keel_clearance:.2f} m")

    def emit_event(self, kind: str, detail: str, value: float = float("nan")) -> None:
        ev = ScenarioEvent(step=self.step_index, source=self.get_fully_qualified_name(), kind=kind,
                           target=self.vessel_name, detail=detail, value=value)
        ev.header.stamp = self.stamp()
        self.event_pub.publish(ev)


def main(args: Optional[List[str]] = None) -> int:
    return rc.run_node(VesselNode, "vessel_node", args)


if __name__ == "__main__":
    sys.exit(main())
