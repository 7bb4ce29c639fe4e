"""A recording read into arrays: the `Recording` of one MCAP file, as `analyze` uses it.

Decodes the topic contract's topics (/<vessel>/odom, /<vessel>/status, /<vessel>/command,
/<rope>/state, /<rope>/end_a|end_b/wrench, /scenario/events; vessels and ropes found by topic
name and type) into time-sorted arrays per vessel and rope on one time origin: the header stamps
(simulation time) unless no message has one, duplicated stamps (a looped replay) kept once. Also
the orders each vessel was given and the run's particulars from the file's metadata. What is
wrong with the file or its messages is kept in `file.problems` and `decoder.notes`, never raised.
"""
from __future__ import annotations

import math
import re
from typing import Callable, Dict, List, NamedTuple, Optional, Tuple

import numpy as np

from sim_math.rotations import rpy_from_quaternion
from recording.mcap_io import Decoder, McapFile
from scenario_format.particulars import particulars_from_metadata

EPOCH_LIKE = 1e8  # s: stamps beyond ~3 years are wall-clock (epoch) times, shown relative to the first


def _stamp_ns(msg) -> int:
    st = msg.header.stamp
    return int(st.sec) * 1_000_000_000 + int(st.nanosec)


class _Series:
    """Samples of one topic: (stamp, log time, values) -> time-sorted arrays, duplicates dropped."""

    def __init__(self):
        self.stamps: List[int] = []
        self.logs: List[int] = []
        self.rows: List[object] = []

    def add(self, stamp: int, log: int, row) -> None:
        self.stamps.append(stamp)
        self.logs.append(log)
        self.rows.append(row)

    def any_stamp(self) -> bool:
        return any(s != 0 for s in self.stamps)

    def order(self, use_stamps: bool):
        """Indices in time order (header stamps, or log times for a file without stamps), the
        last of equal times."""
        if not self.rows:
            return np.zeros(0, int), np.zeros(0)
        t = np.asarray(self.stamps if use_stamps else self.logs, np.int64)
        idx = np.argsort(t, kind="stable")
        ts = t[idx]
        keep = np.ones(ts.size, bool)
        keep[:-1] = ts[1:] != ts[:-1]  # of equal stamps keep the last received
        return idx[keep], ts[keep] * 1e-9


# VesselStatus fields kept per sample, in column order (read by name with status_column)
STATUS_FIELDS = ("engine_order", "steering_angle_ordered", "steering_angle", "shaft_speed", "thrust",
                 "speed_through_water", "heel", "trim", "rise", "girting_ratio", "girting_threshold",
                 "water_depth", "squat", "under_keel_clearance")


def status_column(status: dict, field: str) -> np.ndarray:
    """One VesselStatus field over time from a vessel's "status" table."""
    return status["data"][:, STATUS_FIELDS.index(field)]


class _Handler(NamedTuple):
    take: Callable[[object, int], None]  # (decoded message, log time ns)
    fields: Tuple[str, ...]  # the message fields take() reads


class Recording:
    """Everything the figures need, decoded from one MCAP file."""

    def __init__(self, path: str, vessels: Optional[List[str]] = None, ropes: Optional[List[str]] = None):
        self.path = path
        self.file = McapFile(path)
        self.decoder = Decoder()
        self._odom: Dict[str, _Series] = {}
        self._status: Dict[str, _Series] = {}
        self._command: Dict[str, _Series] = {}
        self._rope: Dict[str, _Series] = {}
        self._wrench: Dict[str, Dict[str, _Series]] = {}
        self.events: List[dict] = []
        want_v = set(vessels) if vessels else None
        want_r = set(ropes) if ropes else None
        handlers: Dict[int, object] = {}
        checked = set()  # channels decoded with the file's schema whose fields were checked
        for msg in self.file.messages():
            ch = msg.channel
            h = handlers.get(ch.id)
            if h is None:
                h = handlers[ch.id] = self._handler(ch.topic, ch.type_name, want_v, want_r)
            if h is False:
                continue
            m = self.decoder.decode(msg)
            if m is None:
                continue
            if ch.id in self.decoder.from_schema and ch.id not in checked:
                checked.add(ch.id)  # on the channel's first message: every message has the same fields
                if not self._has_fields(ch, m, h.fields):
                    handlers[ch.id] = False
                    continue
            h.take(m, msg.log_time)
        self._finish()
        self.particulars = self._read_particulars()

    # -- reading --------------------------------------------------------------------------
    def _read_particulars(self) -> dict:
        """The run's particulars from the recording (scenario_format.particulars: vessel lengths, rope
        ends and breaking loads); {} for a recording without them (rosbag2, older files)."""
        try:
            return particulars_from_metadata(self.file.metadata)
        except ValueError as exc:
            self.decoder.notes.append(f"{exc}; lengths and breaking loads only from --length / --breaking-load")
            return {}

    def _has_fields(self, ch, msg, fields) -> bool:
        """A channel decoded with the file's own schema (its type does not import here) may be
        of an older version of the type: one without a field the analysis reads is left out,
        with a note."""
        missing = [f for f in fields if not hasattr(msg, f)]
        if missing:
            self.decoder.notes.append(f"{ch.topic}: its {ch.type_name} (the file's own schema) has no field "
                                      f"{', '.join(missing)}; not analysed")
        return not missing

    def _handler(self, topic: str, tname: str, want_v, want_r):
        """A _Handler for a topic of the contract (take(msg, log time) and the fields it reads),
        or False for a topic not analysed."""
        short = tname.replace("/msg/", "/")
        m = re.fullmatch(r"/(.+)/(odom|status|command)", topic)
        if m and (want_v is None or m.group(1) in want_v):
            name, kind = m.groups()
            if kind == "odom" and short == "nav_msgs/Odometry":
                s = self._odom.setdefault(name, _Series())
                return _Handler(lambda msg, log, s=s: s.add(_stamp_ns(msg), log, self._odom_row(msg)),
                                ("header", "pose", "twist"))
            if kind == "status" and short == "tug_msgs/VesselStatus":
                s = self._status.setdefault(name, _Series())
                return _Handler(lambda msg, log, s=s: s.add(_stamp_ns(msg), log, [
                    getattr(msg, f) for f in STATUS_FIELDS]), ("header",) + STATUS_FIELDS)
            if kind == "command" and short == "tug_msgs/VesselCommand":
                s = self._command.setdefault(name, _Series())
                return _Handler(lambda msg, log, s=s: s.add(_stamp_ns(msg), log, [msg.engine_order,
                                                                                   msg.steering_angle]),
                                ("header", "engine_order", "steering_angle"))
        m = re.fullmatch(r"/(.+)/state", topic)
        if m and short == "tug_msgs/RopeState" and (want_r is None or m.group(1) in want_r):
            s = self._rope.setdefault(m.group(1), _Series())
            return _Handler(lambda msg, log, s=s: s.add(_stamp_ns(msg), log, self._rope_row(msg)),
                            ("header", "element_poses", "end_a_force", "end_b_force", "connection_tensions",
                             "broken", "stretched_length", "unstretched_length"))
        m = re.fullmatch(r"/(.+)/end_([ab])/wrench", topic)
        if m and short == "geometry_msgs/WrenchStamped" and (want_r is None or m.group(1) in want_r):
            s = self._wrench.setdefault(m.group(1), {}).setdefault(m.group(2), _Series())
            return _Handler(lambda msg, log, s=s: s.add(_stamp_ns(msg), log, [math.hypot(
                msg.wrench.force.x, msg.wrench.force.y, msg.wrench.force.z)]), ("header", "wrench"))
        if topic == "/scenario/events" and short == "tug_msgs/ScenarioEvent":
            return _Handler(lambda msg, log: self.events.append({
                "stamp_ns": _stamp_ns(msg), "step": int(msg.step), "source": msg.source, "kind": msg.kind,
                "target": msg.target, "detail": msg.detail,
                "value": None if not math.isfinite(msg.value) else float(msg.value)}),
                ("header", "step", "source", "kind", "target", "detail", "value"))
        return False

    @staticmethod
    def _odom_row(msg):
        p, q = msg.pose.pose.position, msg.pose.pose.orientation
        lin, ang = msg.twist.twist.linear, msg.twist.twist.angular
        return [p.x, p.y, p.z, q.x, q.y, q.z, q.w, lin.x, lin.y, lin.z, ang.x, ang.y, ang.z]

    @staticmethod
    def _rope_row(msg):
        poses = msg.element_poses
        n = len(poses)
        pos = np.empty((n, 3))
        quat = np.empty((n, 4))
        for i, pose in enumerate(poses):
            pp, qq = pose.position, pose.orientation
            pos[i] = (pp.x, pp.y, pp.z)
            quat[i] = (qq.x, qq.y, qq.z, qq.w)
        fa, fb = msg.end_a_force, msg.end_b_force
        tens = np.asarray(msg.connection_tensions, float)
        # hypot: a damaged message's huge components give inf, not an OverflowError
        return {"pos": pos, "quat": quat, "tension_a": math.hypot(fa.x, fa.y, fa.z),
                "tension_b": math.hypot(fb.x, fb.y, fb.z), "broken": bool(msg.broken),
                "max_tension": float(tens.max()) if tens.size else math.nan,
                "stretched": float(msg.stretched_length), "unstretched": float(msg.unstretched_length)}

    def _finish(self) -> None:
        """Arrays per vessel / rope on a common time origin."""
        firsts = []
        built = {}
        every = [s for table in (self._odom, self._status, self._command, self._rope) for s in table.values()]
        every += [s for ends in self._wrench.values() for s in ends.values()]
        # header stamps (simulation time) unless no message of the file has one
        self.time_source = "header stamps" if any(s.any_stamp() for s in every) else "log times"
        use = self.time_source == "header stamps"
        for kind, table in (("odom", self._odom), ("status", self._status), ("command", self._command),
                            ("rope", self._rope)):
            for name, s in table.items():
                idx, t = s.order(use)
                built[(kind, name)] = (idx, t, s)
                if t.size:
                    firsts.append(t[0])
        for name, ends in self._wrench.items():
            for end, s in ends.items():
                idx, t = s.order(use)
                built[("wrench_" + end, name)] = (idx, t, s)
                if t.size:
                    firsts.append(t[0])
        self.t_ref = min(firsts) if firsts and min(firsts) > EPOCH_LIKE else 0.0
        self.vessels: Dict[str, Dict[str, np.ndarray]] = {}
        self.ropes: Dict[str, Dict[str, object]] = {}
        for (kind, name), (idx, t, s) in built.items():
            if not idx.size:
                continue
            t = t - self.t_ref
            if kind == "odom":
                a = np.asarray([s.rows[i] for i in idx], float)
                roll, pitch, yaw = rpy_from_quaternion(a[:, 3], a[:, 4], a[:, 5], a[:, 6])
                v = self.vessels.setdefault(name, {})
                v.update(t=t, x=a[:, 0], y=a[:, 1], z=a[:, 2], roll=roll, pitch=pitch, yaw=yaw,
                         u=a[:, 7], v=a[:, 8], w=a[:, 9], p=a[:, 10], q=a[:, 11], r=a[:, 12])
                v["speed"] = np.hypot(v["u"], v["v"])
                v["yaw_unwrapped"] = np.unwrap(yaw)
            elif kind in ("status", "command"):
                a = np.asarray([s.rows[i] for i in idx], float)
                self.vessels.setdefault(name, {})[kind] = {"t": t, "data": a}
            elif kind == "rope":
                rows = [s.rows[i] for i in idx]
                rope = self.ropes.setdefault(name, {})
                rope.update(t=t, pos=[r["pos"] for r in rows],
                            pitch=[rpy_from_quaternion(*r["quat"].T)[1] if len(r["quat"]) else np.zeros(0)
                                   for r in rows],
                            tension_a=np.array([r["tension_a"] for r in rows]),
                            tension_b=np.array([r["tension_b"] for r in rows]),
                            max_tension=np.array([r["max_tension"] for r in rows]),
                            broken=np.array([r["broken"] for r in rows]),
                            stretched=np.array([r["stretched"] for r in rows]),
                            unstretched=np.array([r["unstretched"] for r in rows]))
                rope["min_z"] = np.array([p[:, 2].min() if len(p) else math.nan for p in rope["pos"]])
            else:
                a = np.asarray([s.rows[i][0] for i in idx], float)
                self.ropes.setdefault(name, {})[kind] = {"t": t, "tension": a}
        self.vessels = {k: v for k, v in self.vessels.items() if "t" in v}  # vessels need odom
        for name, v in self.vessels.items():
            self._check_order_stamps(name, v)
        for ev in self.events:
            ev["time"] = ev["stamp_ns"] * 1e-9 - self.t_ref
        self.events.sort(key=lambda e: e["stamp_ns"])

    def _check_order_stamps(self, name: str, v: dict) -> None:
        """Orders stamped outside the recording's time (an outside tool's wall-clock stamps in a
        run on simulation time, as send_command wrote before it read /clock) cannot be placed:
        the orders are then read from the commanded values the vessel reports in its status,
        and a note says so (never silently dropped)."""
        cmd = v.get("command")
        if cmd is None or not cmd["t"].size or "status" not in v:
            return
        lo, hi = v["t"][0] - 1.0, v["t"][-1] + 1.0
        stray = int(np.count_nonzero((cmd["t"] < lo) | (cmd["t"] > hi)))
        if stray:
            del v["command"]
            self.decoder.notes.append(
                f"/{name}/command: {stray} of {cmd['t'].size} orders are stamped outside the recording's time "
                f"({lo + 1.0:.2f} .. {hi - 1.0:.2f} s; wall-clock stamps of an outside tool?); the orders of {name} "
                f"are taken from the commanded engine order and steering angle in /{name}/status instead")

    # -- the orders given -----------------------------------------------------------------
    def _orders(self, name: str, command_column: int, status_field: str):
        """(times, values) of one order given to a vessel: from its command topic (order stamps),
        else from its status topic (the time of the last state before the held order changed)."""
        v = self.vessels[name]
        if "command" in v and v["command"]["t"].size:
            return v["command"]["t"], v["command"]["data"][:, command_column]
        if "status" in v and v["status"]["t"].size:
            t, d = v["status"]["t"], status_column(v["status"], status_field)
            change = np.nonzero(np.abs(np.diff(d)) > 1e-9)[0]
            return np.concatenate([[t[0]], t[change]]), np.concatenate([[d[0]], d[change + 1]])
        return np.zeros(0), np.zeros(0)

    def steering_orders(self, name: str):
        """(times, steering angles) of the helm orders given to a vessel (_orders)."""
        return self._orders(name, 1, "steering_angle_ordered")

    def engine_orders(self, name: str):
        """(times, engine orders) given to a vessel (_orders)."""
        return self._orders(name, 0, "engine_order")
