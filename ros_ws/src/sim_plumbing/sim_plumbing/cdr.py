"""The per-step messages of the step protocol written and read as CDR bytes (no ROS import).

Why: every exchange step each node publishes 3-5 messages and takes 1-3. Building them as
rclpy message objects, converting them field by field on publish and back on take, costs more
CPU than the physics and, with every node in its own process, was the largest single share of
a step (measured: the vessel node's outputs alone were a fifth of the CPU of a whole step).
Nodes therefore publish serialized messages and take the hot topics raw. The bytes are what
rmw_fastrtps sends for ROS 2 Jazzy and every encoder and decoder here is checked against
rclpy's own (de)serializer (tests/ros/test_cdr.py); any ROS 2 tool sees ordinary messages.

CDR rules (XCDR1, little endian): a 4-byte encapsulation header 00 01 00 00; every primitive
aligned to its size counted from the end of that header; a string is a uint32 length that
counts the terminating NUL, then the bytes; a sequence is a uint32 count, then the elements.
"""
from __future__ import annotations

import math
import struct
from typing import Callable, Dict, List, NamedTuple, Optional, Sequence, Tuple, TypeVar

import numpy as np

ENCAPSULATION = b"\x00\x01\x00\x00"  # CDR, little endian, no options
T = TypeVar("T")
_HEADER = len(ENCAPSULATION)
_STAMP = struct.Struct("<iI")
_U32 = struct.Struct("<I")
_U64 = struct.Struct("<Q")
_F64 = struct.Struct("<d")
_V3 = struct.Struct("<3d")
_V6 = struct.Struct("<6d")
_V10 = struct.Struct("<10d")


def stamp_parts(stamp_ns: int) -> Tuple[int, int]:
    """builtin_interfaces/Time (sec, nanosec) of a time in nanoseconds (>= 0)."""
    return stamp_ns // 1_000_000_000, stamp_ns % 1_000_000_000


class CdrWriter:
    """Writes a message field by field (for messages whose layout changes from call to call)."""

    def __init__(self):
        self.parts: List[bytes] = [ENCAPSULATION]
        self.size = 0  # bytes after the encapsulation header

    def align(self, n: int) -> None:
        pad = (-self.size) % n
        if pad:
            self.parts.append(b"\x00" * pad)
            self.size += pad

    def raw(self, data: bytes, align: int) -> None:
        self.align(align)
        self.parts.append(data)
        self.size += len(data)

    def uint32(self, v: int) -> None:
        self.raw(_U32.pack(v), 4)

    def stamp(self, stamp_ns: int) -> None:
        self.raw(_STAMP.pack(*stamp_parts(stamp_ns)), 4)

    def string(self, s: str) -> None:
        b = s.encode() + b"\x00"
        self.uint32(len(b))
        self.parts.append(b)
        self.size += len(b)

    def float64s(self, a) -> None:
        """Consecutive float64 values (a struct of doubles, or the body of a sequence)."""
        a = np.asarray(a)
        if a.size:
            self.raw(np.ascontiguousarray(a, dtype="<f8").tobytes(), 8)

    def float64_seq(self, a) -> None:
        a = np.asarray(a, float).ravel()
        self.uint32(a.size)
        self.float64s(a)

    def getvalue(self) -> bytes:
        return b"".join(self.parts)


class Template:
    """A message whose strings and sequence lengths never change (per publisher): its bytes
    are laid out once; each publish copies them and packs the changing fields into slots."""

    def __init__(self):
        self._body = bytearray()
        self.slots: List[Tuple[int, struct.Struct]] = []

    def align(self, n: int) -> None:
        self._body += b"\x00" * ((-len(self._body)) % n)

    def const(self, st: struct.Struct, align: int, *values) -> None:
        self.align(align)
        self._body += st.pack(*values)

    def string(self, s: str) -> None:
        b = s.encode() + b"\x00"
        self.const(_U32, 4, len(b))
        self._body += b

    def slot(self, st: struct.Struct, align: int) -> int:
        """Reserve a changing field group (aligned to `align`, packed without inner padding)."""
        self.align(align)
        self.slots.append((_HEADER + len(self._body), st))
        self._body += b"\x00" * st.size
        return len(self.slots) - 1

    def seal(self) -> None:
        self.data = bytes(ENCAPSULATION + self._body)

    def pack(self, *groups: Sequence) -> bytes:
        """The message with slot i holding groups[i] (a tuple of its values)."""
        buf = bytearray(self.data)
        for (offset, st), values in zip(self.slots, groups):
            st.pack_into(buf, offset, *values)
        return bytes(buf)


def _header_template(t: Template, frame_id: str) -> None:
    t.slot(_STAMP, 4)
    t.string(frame_id)


class OdometryEncoder:
    """nav_msgs/Odometry with zero covariances."""

    _POSE = struct.Struct("<7d")

    def __init__(self, frame_id: str, child_frame_id: str):
        t = self.t = Template()
        _header_template(t, frame_id)
        t.string(child_frame_id)
        t.slot(self._POSE, 8)                         # pose.pose: position, orientation (x y z w)
        t.const(struct.Struct("<36d"), 8, *([0.0] * 36))  # pose.covariance
        t.slot(_V6, 8)                                # twist.twist: linear, angular
        t.const(struct.Struct("<36d"), 8, *([0.0] * 36))
        t.seal()

    def encode(self, stamp_ns: int, position, quaternion_xyzw, linear, angular) -> bytes:
        return self.t.pack(stamp_parts(stamp_ns), (*position, *quaternion_xyzw), (*linear, *angular))


class AttachmentArrayEncoder:
    """tug_msgs/AttachmentArray of a fixed set of attachment points."""

    def __init__(self, frame_id: str, vessel: str, names: Sequence[str]):
        t = self.t = Template()
        _header_template(t, frame_id)
        t.slot(_U64, 8)  # step
        t.string(vessel)
        t.const(_U32, 4, len(names))
        for name in names:
            t.string(name)
            t.slot(_V10, 8)  # position, velocity, orientation (x y z w)
        t.seal()
        self.n = len(names)

    def encode(self, stamp_ns: int, step: int, positions, velocities, quaternion_xyzw) -> bytes:
        """positions, velocities: (n, 3) in the order of the names; one orientation for all."""
        q = tuple(quaternion_xyzw)
        points = [(*p, *v, *q) for p, v in zip(np.asarray(positions).tolist(), np.asarray(velocities).tolist())]
        return self.t.pack(stamp_parts(stamp_ns), (step,), *points)


VESSEL_STATUS_FLOATS_A = ("engine_order", "steering_angle_ordered", "steering_angle", "shaft_speed", "thrust")
VESSEL_STATUS_FLOATS_B = ("speed_through_water", "heel", "trim", "rise", "girting_ratio", "girting_threshold")
# the environment block (tug_dynamics.environment_loads.EnvironmentStatus), then `grounded`
VESSEL_STATUS_FLOATS_ENV = ("apparent_wind_speed", "apparent_wind_angle", "water_depth", "squat",
                            "under_keel_clearance")
# the sea block (tug_dynamics.seakeeping.SeaStatus), after `grounded`
VESSEL_STATUS_FLOATS_SEA = ("wave_elevation", "wave_significant_height", "wave_encounter_period",
                            "wave_encounter_angle", "heave", "roll", "pitch")
CALM_SEA = (0.0,) * len(VESSEL_STATUS_FLOATS_SEA)


class VesselStatusEncoder:
    """tug_msgs/VesselStatus; field order of the .msg file. The vessel's hull contacts are fixed
    when it starts: their names and the arrays' lengths are laid out once."""

    _A = struct.Struct("<5dB")
    _B = struct.Struct("<6d?")
    _C = struct.Struct("<II")
    _D = struct.Struct("<5d?")
    _E = struct.Struct(f"<{len(VESSEL_STATUS_FLOATS_SEA)}d")

    def __init__(self, frame_id: str, vessel: str, contact_names: Sequence[str] = ()):
        t = self.t = Template()
        _header_template(t, frame_id)
        t.slot(_U64, 8)      # step
        t.string(vessel)
        t.slot(self._A, 8)   # 5 doubles, anchor_state
        t.slot(self._B, 8)   # 6 doubles, girting_warning
        t.slot(self._C, 4)   # commands_rejected, commands_clamped
        t.slot(self._D, 8)   # environment: 5 doubles, grounded
        t.slot(self._E, 8)   # the sea: 7 doubles
        n = self.n_contacts = len(contact_names)
        t.const(_U32, 4, n)
        for name in contact_names:
            t.string(name)
        for _ in ("contact_forces", "contact_points"):
            t.const(_U32, 4, n)
            if n:   # an empty sequence has no elements to align
                t.slot(struct.Struct(f"<{3 * n}d"), 8)
        t.seal()

    def encode(self, stamp_ns: int, step: int, floats_a: Sequence[float], anchor_state: int,
               floats_b: Sequence[float], girting_warning: bool, rejected: int, clamped: int,
               floats_env: Sequence[float] = (0.0, 0.0, math.inf, 0.0, math.inf), grounded: bool = False,
               contact_forces: Sequence[float] = (), contact_points: Sequence[float] = (),
               floats_sea: Sequence[float] = CALM_SEA) -> bytes:
        """contact_forces / contact_points: 3 doubles per contact, flattened, in the names' order."""
        groups = [stamp_parts(stamp_ns), (step,), (*floats_a, anchor_state), (*floats_b, girting_warning),
                  (rejected, clamped), (*floats_env, grounded), tuple(floats_sea)]
        if self.n_contacts:
            groups += [tuple(contact_forces), tuple(contact_points)]
        return self.t.pack(*groups)


class HullContactEncoder:
    """tug_msgs/HullContact of one contact (names fixed)."""

    _STATE = struct.Struct("<?")
    _VALUES = struct.Struct("<4d")
    _VECTORS = struct.Struct("<12d")

    def __init__(self, frame_id: str, contact: str, fender_vessel: str, fender: str, hull_vessel: str):
        t = self.t = Template()
        _header_template(t, frame_id)
        t.slot(_U64, 8)
        for s in (contact, fender_vessel, fender, hull_vessel):
            t.string(s)
        t.slot(self._STATE, 1)
        t.slot(self._VALUES, 8)    # penetration, gap, normal_force, friction_force
        t.slot(self._VECTORS, 8)   # force_on_hull, point, hull_point_body, fender_point_body
        t.seal()

    def encode(self, stamp_ns: int, step: int, in_contact: bool, values: Sequence[float],
               vectors: Sequence[float]) -> bytes:
        return self.t.pack(stamp_parts(stamp_ns), (step,), (in_contact,), tuple(values), tuple(vectors))


class RopeEndCouplingEncoder:
    """tug_msgs/RopeEndCoupling of one rope end (names fixed)."""

    _VALUES = struct.Struct("<27d")   # force, reference_position, reference_velocity, stiffness, damping

    def __init__(self, frame_id: str, vessel: str, attachment: str):
        t = self.t = Template()
        _header_template(t, frame_id)
        t.slot(_U64, 8)
        t.string(vessel)
        t.string(attachment)
        t.slot(self._VALUES, 8)
        t.seal()

    def encode(self, stamp_ns: int, step: int, force, reference_position, reference_velocity, stiffness,
               damping) -> bytes:
        values = np.concatenate((force, reference_position, reference_velocity, np.ravel(stiffness),
                                 np.ravel(damping))).tolist()
        return self.t.pack(stamp_parts(stamp_ns), (step,), tuple(values))


class ThrusterStatusEncoder:
    """tug_msgs/ThrusterStatus of a fixed list of thrusters: one float64 sequence per field, each
    as long as the names."""

    FIELDS = ("azimuth", "azimuth_ordered", "rpm", "rpm_ordered", "thrust", "open_water_thrust")

    def __init__(self, frame_id: str, vessel: str, names: Sequence[str]):
        t = self.t = Template()
        _header_template(t, frame_id)
        t.slot(_U64, 8)  # step
        t.string(vessel)
        t.const(_U32, 4, len(names))
        for name in names:
            t.string(name)
        self.n = len(names)
        values = struct.Struct(f"<{self.n}d")
        for _ in self.FIELDS:
            t.const(_U32, 4, self.n)
            if self.n:  # an empty sequence has no elements to align
                t.slot(values, 8)
        t.seal()

    def encode(self, stamp_ns: int, step: int, columns: Sequence[Sequence[float]]) -> bytes:
        """columns: one sequence of n values per field of FIELDS, in that order."""
        if not self.n:
            return self.t.pack(stamp_parts(stamp_ns), (step,))
        return self.t.pack(stamp_parts(stamp_ns), (step,), *columns)


class WrenchStampedEncoder:
    def __init__(self, frame_id: str):
        t = self.t = Template()
        _header_template(t, frame_id)
        t.slot(_V6, 8)  # force, torque
        t.seal()

    def encode(self, stamp_ns: int, force, torque=(0.0, 0.0, 0.0)) -> bytes:
        return self.t.pack(stamp_parts(stamp_ns), (*force, *torque))


class StepDoneEncoder:
    """tug_msgs/StepDone of one node in one run; a failure (with its error text) goes
    through CdrWriter."""

    # step, compute_time, ok, (padding to 4), refused_messages: CDR's own layout of these fields
    _STEP = struct.Struct("<Qd?3xI")

    def __init__(self, node: str, run_id: str):
        self.node = node
        self.run_id = run_id
        t = self.t = Template()
        _header_template(t, "")
        t.string(run_id)
        t.string(node)
        t.slot(self._STEP, 8)
        t.string("")           # error
        t.seal()

    def encode(self, stamp_ns: int, step: int, compute_time: float, error: str = "", refused: int = 0) -> bytes:
        if not error:
            return self.t.pack(stamp_parts(stamp_ns), (step, compute_time, True, refused))
        w = CdrWriter()
        w.stamp(stamp_ns)
        w.string("")
        w.string(self.run_id)
        w.string(self.node)
        w.raw(self._STEP.pack(step, compute_time, False, refused), 8)
        w.string(error)
        return w.getvalue()


def sim_step_cdr(stamp_ns: int, step: int, period: float, ordered: Sequence[str], run_id: str) -> bytes:
    """tug_msgs/SimStep of a run (header stamped and timed at step * period)."""
    w = CdrWriter()
    w.stamp(stamp_ns)
    w.string("")
    w.string(run_id)
    w.raw(_U64.pack(step), 8)
    w.stamp(stamp_ns)
    w.raw(_F64.pack(period), 8)
    w.uint32(len(ordered))
    for name in ordered:
        w.string(name)
    return w.getvalue()


class TFMessageEncoder:
    """tf2_msgs/TFMessage of a fixed list of (parent frame, child frame) transforms: stamps,
    translations and rotations change per message, the frame names never."""

    _TRANSFORM = struct.Struct("<7d")  # translation x y z, rotation x y z w

    def __init__(self, frames: Sequence[Tuple[str, str]]):
        t = self.t = Template()
        t.const(_U32, 4, len(frames))
        for parent, child in frames:
            _header_template(t, parent)
            t.string(child)
            t.slot(self._TRANSFORM, 8)
        t.seal()
        self.n = len(frames)

    def encode(self, stamp_ns: int, transforms: Sequence[Tuple[Sequence[float], Sequence[float]]]) -> bytes:
        """transforms: (translation (3,), rotation quaternion x y z w) per frame pair, in order."""
        stamp = stamp_parts(stamp_ns)
        groups = []
        for translation, rotation in transforms:
            groups.append(stamp)
            groups.append((*translation, *rotation))
        return self.t.pack(*groups)


# visualization_msgs/Marker types and actions used here
MARKER_ARROW, MARKER_SPHERE_LIST, MARKER_LINE_STRIP, MARKER_TRIANGLE_LIST, MARKER_TEXT = 0, 7, 4, 11, 9
MARKER_ADD = 0
_IDENTITY_POSE = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0)


class MarkerSpec(NamedTuple):
    """One visualization_msgs/Marker (action ADD, lifetime 0). points (N, 3), colors (N, 4)
    per point or empty; scale: the type's meaning (line width; arrow shaft, head, head length;
    sphere diameters; text height)."""
    ns: str
    marker_id: int
    marker_type: int
    scale: Tuple[float, float, float]
    color: Tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)
    points: object = ()
    colors: object = ()
    pose: Tuple[float, ...] = _IDENTITY_POSE  # position x y z, orientation x y z w
    text: str = ""
    frame_locked: bool = False


def _write_marker(w: CdrWriter, stamp_ns: int, frame_id: str, m: MarkerSpec) -> None:
    pts = np.ascontiguousarray(m.points, dtype="<f8").reshape(-1, 3)
    cols = np.ascontiguousarray(m.colors, dtype="<f4").reshape(-1, 4)
    w.stamp(stamp_ns)
    w.string(frame_id)
    w.string(m.ns)
    w.raw(struct.pack("<iii", m.marker_id, m.marker_type, MARKER_ADD), 4)
    w.float64s(np.array([*m.pose, *m.scale], float))  # pose, scale
    w.raw(struct.pack("<4f", *m.color), 4)
    w.raw(struct.pack("<iI?", 0, 0, m.frame_locked), 4)  # lifetime, frame_locked
    w.uint32(len(pts))
    w.float64s(pts)
    w.uint32(len(cols))
    if len(cols):
        w.raw(cols.tobytes(), 4)
    w.string("")  # texture_resource
    w.stamp(0)  # texture: header, format, data
    w.string("")
    w.string("")
    w.uint32(0)
    w.uint32(0)  # uv_coordinates
    w.string(m.text)
    w.string("")  # mesh_resource
    w.string("")  # mesh_file: filename, data
    w.uint32(0)
    w.raw(b"\x00", 1)  # mesh_use_embedded_materials


def marker_array_cdr(stamp_ns: int, frame_id: str, markers: Sequence[MarkerSpec]) -> bytes:
    """visualization_msgs/MarkerArray of these markers, all in one frame and stamp."""
    return MarkerArrayTemplate(frame_id, ()).encode(stamp_ns, markers)


class MarkerArrayTemplate:
    """visualization_msgs/MarkerArray whose first markers never change but for the stamp (a
    vessel's hull, deck, points and name): their bytes are laid out once, each call copies them,
    sets the count and the stamps, and writes the changing markers (arrows) after them. An S-175's
    24 kB of markers with its three arrows: 216 -> 132 us a call (the arrows are most of the rest)."""

    def __init__(self, frame_id: str, fixed: Sequence[MarkerSpec]):
        self.frame_id = frame_id
        self.n_fixed = len(fixed)
        w = CdrWriter()
        w.uint32(0)
        self._stamps: List[int] = []  # offsets in the body (after the encapsulation) of each stamp
        for m in fixed:
            w.align(4)
            self._stamps.append(w.size)
            _write_marker(w, 0, frame_id, m)
        self._body = w.getvalue()[_HEADER:]

    def encode(self, stamp_ns: int, changing: Sequence[MarkerSpec]) -> bytes:
        body = bytearray(self._body)
        _U32.pack_into(body, 0, self.n_fixed + len(changing))
        parts = stamp_parts(stamp_ns)
        for at in self._stamps:
            _STAMP.pack_into(body, at, *parts)
        w = CdrWriter()
        w.parts.append(body)
        w.size = len(body)
        for m in changing:
            _write_marker(w, stamp_ns, self.frame_id, m)
        return w.getvalue()


def line_strip_marker_array_cdr(stamp_ns: int, frame_id: str, ns: str, marker_id: int, width: float,
                                points, colors_rgba) -> bytes:
    """visualization_msgs/MarkerArray holding one LINE_STRIP marker (action ADD, identity pose,
    scale.x = width, lifetime 0) through points (N, 3) with per-point colors (N, 4)."""
    return marker_array_cdr(stamp_ns, frame_id, [MarkerSpec(ns, marker_id, MARKER_LINE_STRIP, (width, 0.0, 0.0),
                                                             points=points, colors=colors_rgba)])


def clock_cdr(stamp_ns: int) -> bytes:
    """rosgraph_msgs/Clock."""
    return ENCAPSULATION + _STAMP.pack(*stamp_parts(stamp_ns))


# -- reading ------------------------------------------------------------------------------
class CdrError(ValueError):
    pass


class CdrReader:
    def __init__(self, data: bytes):
        if len(data) < _HEADER or data[0] != 0 or data[1] != 1:
            raise CdrError(f"not little-endian CDR (encapsulation {bytes(data[:4])!r})")
        self.data = data
        self.pos = _HEADER

    def unpack(self, st: struct.Struct, align: int) -> tuple:
        self.pos += (-(self.pos - _HEADER)) % align
        end = self.pos + st.size
        if end > len(self.data):
            raise CdrError(f"message ends at byte {len(self.data)}, field needs {end}")
        values = st.unpack_from(self.data, self.pos)
        self.pos = end
        return values

    def stamp_ns(self) -> int:
        sec, nanosec = self.unpack(_STAMP, 4)
        return sec * 1_000_000_000 + nanosec

    def uint32(self) -> int:
        return self.unpack(_U32, 4)[0]

    def string(self) -> str:
        n = self.uint32()
        end = self.pos + n
        if n == 0 or end > len(self.data):
            raise CdrError(f"string of length {n} at byte {self.pos} does not fit")
        try:
            s = bytes(self.data[self.pos:end - 1]).decode()
        except UnicodeDecodeError as exc:
            raise CdrError(f"string at byte {self.pos} is not UTF-8: {exc}") from None
        self.pos = end
        return s


def decode_or_report(decode: Callable[[bytes], T], data: bytes, report: Callable[[str], None]) -> Optional[T]:
    """decode(data); None, after report(why), for bytes that are not such a message (the
    caller drops them and goes on)."""
    try:
        return decode(data)
    except CdrError as exc:
        report(str(exc))
        return None


class WrenchIn(NamedTuple):
    """A geometry_msgs/WrenchStamped as taken."""
    stamp_ns: int
    frame_id: str
    force: Tuple[float, float, float]
    torque: Tuple[float, float, float]

    def is_finite(self) -> bool:
        return all(math.isfinite(v) for v in self.force + self.torque)


def decode_wrench_stamped(data: bytes) -> WrenchIn:
    r = CdrReader(data)
    stamp = r.stamp_ns()
    frame = r.string()
    v = r.unpack(_V6, 8)
    return WrenchIn(stamp, frame, v[:3], v[3:])


class TriggerIn(NamedTuple):
    """A tug_msgs/SimStep as taken."""
    stamp_ns: int
    run_id: str
    step: int
    ordered: Tuple[str, ...]


def decode_sim_step(data: bytes) -> TriggerIn:
    r = CdrReader(data)
    stamp = r.stamp_ns()
    r.string()  # frame_id
    run_id = r.string()
    step = r.unpack(_U64, 8)[0]
    r.stamp_ns()  # time (= header stamp)
    r.unpack(_F64, 8)  # period
    n = r.uint32()
    if n > len(data):  # every string takes at least 5 bytes: a count beyond the message is garbage
        raise CdrError(f"sequence of {n} names in a {len(data)}-byte message")
    ordered = tuple(r.string() for _ in range(n))
    return TriggerIn(stamp, run_id, step, ordered)


class PointIn(NamedTuple):
    position: Tuple[float, float, float]
    velocity: Tuple[float, float, float]
    orientation: Tuple[float, float, float, float]  # x, y, z, w


class AttachmentsIn(NamedTuple):
    """A tug_msgs/AttachmentArray as taken: points by name."""
    stamp_ns: int
    step: int
    vessel: str
    points: Dict[str, PointIn]


def decode_attachment_array(data: bytes) -> AttachmentsIn:
    r = CdrReader(data)
    stamp = r.stamp_ns()
    r.string()  # frame_id
    step = r.unpack(_U64, 8)[0]
    vessel = r.string()
    points = {}
    for _ in range(r.uint32()):
        name = r.string()
        v = r.unpack(_V10, 8)
        points[name] = PointIn(v[0:3], v[3:6], v[6:10])
    return AttachmentsIn(stamp, step, vessel, points)


class DoneIn(NamedTuple):
    """A tug_msgs/StepDone as taken."""
    stamp_ns: int
    run_id: str
    node: str
    step: int
    compute_time: float
    ok: bool
    refused: int
    error: str


def decode_step_done(data: bytes) -> DoneIn:
    r = CdrReader(data)
    stamp = r.stamp_ns()
    r.string()  # frame_id
    run_id = r.string()
    node = r.string()
    step, compute_time, ok, refused = r.unpack(StepDoneEncoder._STEP, 8)
    return DoneIn(stamp, run_id, node, step, compute_time, ok, refused, r.string())


class VesselCommandIn(NamedTuple):
    """A tug_msgs/VesselCommand as taken."""
    stamp_ns: int
    engine_order: float
    steering_angle: float
    anchor: int


_COMMAND = struct.Struct("<ddB")


def decode_vessel_command(data: bytes) -> VesselCommandIn:
    r = CdrReader(data)
    stamp = r.stamp_ns()
    r.string()  # frame_id
    engine, steering, anchor = r.unpack(_COMMAND, 8)
    return VesselCommandIn(stamp, engine, steering, anchor)


class ThrusterCommandIn(NamedTuple):
    """A tug_msgs/ThrusterCommand as taken (lengths as sent: the vessel node checks them)."""
    stamp_ns: int
    thrusters: Tuple[str, ...]
    azimuth: Tuple[float, ...]
    rpm: Tuple[float, ...]


def _sequence_count(r: CdrReader, item_size: int) -> int:
    """A sequence's element count, refused when its elements cannot fit in the rest of the message."""
    n = r.uint32()
    if n * item_size > len(r.data) - r.pos:
        raise CdrError(f"sequence of {n} elements at byte {r.pos} does not fit in a {len(r.data)}-byte message")
    return n


def _float64_sequence(r: CdrReader) -> Tuple[float, ...]:
    n = _sequence_count(r, 8)
    return r.unpack(struct.Struct(f"<{n}d"), 8) if n else ()


def decode_thruster_command(data: bytes) -> ThrusterCommandIn:
    r = CdrReader(data)
    stamp = r.stamp_ns()
    r.string()  # frame_id
    names = tuple(r.string() for _ in range(_sequence_count(r, 5)))  # a string takes >= 5 bytes
    azimuth = _float64_sequence(r)
    rpm = _float64_sequence(r)
    return ThrusterCommandIn(stamp, names, azimuth, rpm)


class WinchCommandIn(NamedTuple):
    """A tug_msgs/WinchCommand as taken (mode 0 = SPEED; tensions 0 = keep the current)."""
    stamp_ns: int
    payout_rate: float
    mode: int = 0
    set_tension: float = 0.0
    recover_tension: float = 0.0
    brake_load: float = 0.0


_WINCH_MODE = struct.Struct("<B")
_WINCH_TENSIONS = struct.Struct("<3d")


def decode_winch_command(data: bytes) -> WinchCommandIn:
    """A WinchCommand; one that ends after payout_rate (the message before the winch modes)
    reads as mode SPEED with every tension 0 (keep)."""
    r = CdrReader(data)
    stamp = r.stamp_ns()
    r.string()  # frame_id
    rate = r.unpack(_F64, 8)[0]
    if r.pos >= len(data):
        return WinchCommandIn(stamp, rate)
    mode = r.unpack(_WINCH_MODE, 1)[0]
    return WinchCommandIn(stamp, rate, mode, *r.unpack(_WINCH_TENSIONS, 8))


class HullContactIn(NamedTuple):
    """A tug_msgs/HullContact as taken."""
    stamp_ns: int
    step: int
    contact: str
    fender_vessel: str
    fender: str
    hull_vessel: str
    in_contact: bool
    values: Tuple[float, float, float, float]   # penetration, gap, normal_force, friction_force
    force_on_hull: Tuple[float, float, float]
    point: Tuple[float, float, float]
    hull_point_body: Tuple[float, float, float]
    fender_point_body: Tuple[float, float, float]

    def is_finite(self) -> bool:
        return all(math.isfinite(v) for v in self.values + self.force_on_hull + self.point
                   + self.hull_point_body + self.fender_point_body)


def decode_hull_contact(data: bytes) -> HullContactIn:
    r = CdrReader(data)
    stamp = r.stamp_ns()
    r.string()  # frame_id
    step = r.unpack(_U64, 8)[0]
    names = [r.string() for _ in range(4)]
    (in_contact,) = r.unpack(HullContactEncoder._STATE, 1)
    values = r.unpack(HullContactEncoder._VALUES, 8)
    v = r.unpack(HullContactEncoder._VECTORS, 8)
    return HullContactIn(stamp, step, *names, bool(in_contact), values, v[0:3], v[3:6], v[6:9], v[9:12])


class RopeEndCouplingIn(NamedTuple):
    """A tug_msgs/RopeEndCoupling as taken (vectors and row-major matrices as tuples)."""
    stamp_ns: int
    step: int
    vessel: str
    attachment: str
    force: Tuple[float, float, float]
    reference_position: Tuple[float, float, float]
    reference_velocity: Tuple[float, float, float]
    stiffness: Tuple[float, ...]
    damping: Tuple[float, ...]

    def is_finite(self) -> bool:
        return all(math.isfinite(v) for v in self.force + self.reference_position + self.reference_velocity
                   + self.stiffness + self.damping)


def decode_rope_end_coupling(data: bytes) -> RopeEndCouplingIn:
    r = CdrReader(data)
    stamp = r.stamp_ns()
    r.string()  # frame_id
    step = r.unpack(_U64, 8)[0]
    vessel, attachment = r.string(), r.string()
    v = r.unpack(RopeEndCouplingEncoder._VALUES, 8)
    return RopeEndCouplingIn(stamp, step, vessel, attachment, v[0:3], v[3:6], v[6:9], v[9:18], v[18:27])


class OdometryIn(NamedTuple):
    """A nav_msgs/Odometry as taken (covariances skipped): pose in frame_id, twist in
    child_frame_id's axes (REP-105: the body frame)."""
    stamp_ns: int
    frame_id: str
    child_frame_id: str
    position: Tuple[float, float, float]
    orientation: Tuple[float, float, float, float]   # x, y, z, w
    linear: Tuple[float, float, float]
    angular: Tuple[float, float, float]

    def is_finite(self) -> bool:
        return all(math.isfinite(v) for v in self.position + self.orientation + self.linear + self.angular)


_POSE7 = struct.Struct("<7d")
_COV36 = struct.Struct("<36d")


def decode_odometry(data: bytes) -> OdometryIn:
    r = CdrReader(data)
    stamp = r.stamp_ns()
    frame = r.string()
    child = r.string()
    pose = r.unpack(_POSE7, 8)
    r.unpack(_COV36, 8)
    twist = r.unpack(_V6, 8)
    r.unpack(_COV36, 8)
    return OdometryIn(stamp, frame, child, pose[0:3], pose[3:7], twist[0:3], twist[3:6])
