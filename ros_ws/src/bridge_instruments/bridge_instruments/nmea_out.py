"""NMEA 0183 and AIS out: a running simulation as an ECDIS sees it.

    ros2 run bridge_instruments nmea_out --ros-args -p scenario:=default_demo.yaml \
        -p "outputs:=['tug@127.0.0.1:10110']"

(a string array parameter is written in YAML's flow style, quoted for the shell). Parameters left
at their defaults take the values of the run's scenario file, `scenario`: its vessels, ropes,
exchange rate, origin and `nmea` settings (_settings); without it, `vessels` must be given, and
what the node then cannot send (AIS dimensions, tensions) is said in its log.

For every own vessel (`outputs`: "vessel@host:port") it sends, over UDP to that destination, one
sentence per datagram: RMC, GGA, VTG, HDT, ROT, RSA, RPM (engine and shaft), one XDR per rope
with an end on the vessel (its tension), an XDR of its pitch and roll (attitude(): the REP-103
angles of /<vessel>/status converted to the bus's bow-up / starboard-down convention), and for
every other vessel of the run an AIS VDM position report (type 1) and, the first time and every
`static_every`-th time, its static data
(type 5, length and beam from its ship file, with the `ship_overrides` of the scenario named by
the parameter `scenario` merged over it: scenario_format/particulars.py). Sentence
formats: bridge_instruments/sentences.py.

It reads the topic contract only (/<vessel>/odom, /<vessel>/status, /<rope>/end_<x>/wrench) and
sends the state of one simulation step at a time: the first step of every 1/rate s of
simulation time (the step stamped t with t mod (1/rate) < one exchange period), once every
topic of that step has arrived. So in a paced run it is real time, in a lockstep run as fast as
the simulation, and the time in RMC / GGA names the step (UTC = utc_start + t).

A destination that cannot be resolved or refuses a datagram (no route, permission, ...) is
reported once per kind (and counted); the node and the simulation go on.
"""
from __future__ import annotations

import collections
import math
import re
import socket
import sys
from typing import Dict, List, Optional, Tuple

from rclpy.node import Node
from rclpy.serialization import deserialize_message
from nav_msgs.msg import Odometry
from geometry_msgs.msg import WrenchStamped
from tug_msgs.msg import VesselStatus

from sim_math.rotations import matrix_from_quaternion, rpy_from_quaternion
from sim_plumbing import cdr
from sim_plumbing import ros_common as rc
from bridge_instruments import sentences as S
from sim_contract import geo
from sim_contract import topics as T
from sim_contract.equipment import NMEA_UDP_PORT, check_mmsi, parse_utc
from sim_contract.node_params import NMEA_OUT
from scenario_format.particulars import hull_dimensions, scenario_path, scenario_ships
from scenario_format.scenario import ScenarioError, load_scenario

_HOST = re.compile(r"^(?=.{1,253}$)[A-Za-z0-9]([A-Za-z0-9-]{0,61}[A-Za-z0-9])?(\.[A-Za-z0-9]([A-Za-z0-9-]{0,61}"
                   r"[A-Za-z0-9])?)*\.?$|^[0-9A-Fa-f:.]+$")
_KEEP_STEPS = 16  # stamps held while waiting for every topic of a due step


def parse_output(text: str) -> Tuple[str, str, int]:
    """'vessel@host:port' (port default 10110; IPv6 hosts in brackets) -> (vessel, host, port);
    ValueError naming what is wrong."""
    vessel, sep, dest = text.partition("@")
    if not sep or not vessel:
        raise ValueError(f"output {text!r}: expected 'vessel@host:port'")
    host, port = dest, NMEA_UDP_PORT
    m = re.fullmatch(r"\[([^\]]*)\](?::(.*))?|([^:]*)(?::(.*))?", dest)
    if m:
        host = m.group(1) if m.group(1) is not None else m.group(3)
        p = m.group(2) if m.group(1) is not None else m.group(4)
        if p is not None:
            if not p.isdigit():
                raise ValueError(f"output {text!r}: port {p!r} is not a number")
            port = int(p)
    return vessel, host, port


def check_destination(host: str, port: int) -> Optional[str]:
    """Why host:port cannot be a UDP destination (None if it can be tried)."""
    if not 1 <= port <= 65535:
        return f"port {port} is outside 1-65535"
    if not host or not _HOST.match(host):
        return f"host {host!r} is not a host name or address"
    return None


def _pairs(items: List[str], what: str) -> Dict[str, str]:
    out = {}
    for item in items:
        if not item:
            continue
        key, sep, value = item.partition("=")
        if not sep or not key:
            raise ValueError(f"{what} {item!r}: expected 'name=value'")
        out[key] = value
    return out


def attitude(status) -> Tuple[float, float]:
    """(pitch, roll) in degrees as the XDR attitude sentence carries them (sentences.attitude_xdr:
    pitch + bow up, roll + starboard side down) from a tug_msgs/VesselStatus: the totals, trim +
    pitch and heel + roll (manoeuvring plus wave-frequency). REP-103 has pitch + bow DOWN, so it
    changes sign here, at the edge, and nowhere else; roll + starboard down is the same in both."""
    return -math.degrees(status.trim + status.pitch), math.degrees(status.heel + status.roll)


class Destination:
    """One UDP destination; reports each kind of failure once, counts all."""

    def __init__(self, vessel: str, host: str, port: int, logger):
        self.vessel, self.host, self.port, self.logger = vessel, host, port, logger
        self.address = None
        self.sock: Optional[socket.socket] = None
        self.sent = 0
        self.failed = 0
        self.reported: set = set()
        why = check_destination(host, port)
        if why is None:
            try:
                family, _type, _proto, _name, addr = socket.getaddrinfo(host, port, type=socket.SOCK_DGRAM)[0]
                self.sock = socket.socket(family, socket.SOCK_DGRAM)
                self.sock.setblocking(False)
                self.address = addr
            except OSError as exc:
                why = f"cannot resolve {host!r}: {exc}"
        if why is not None:
            self.report("invalid", f"NMEA destination {self.name} for '{vessel}' is invalid ({why}): its "
                                   "sentences are not sent; the simulation goes on")

    @property
    def name(self) -> str:
        return f"{self.host}:{self.port}"

    def report(self, kind: str, text: str) -> None:
        if kind not in self.reported:
            self.reported.add(kind)
            self.logger.error(text)

    def send(self, lines: List[str]) -> None:
        if self.sock is None:
            self.failed += len(lines)
            return
        for line in lines:
            try:
                self.sock.sendto((line + "\r\n").encode("ascii"), self.address)
                self.sent += 1
            except OSError as exc:
                self.failed += 1
                self.report(f"errno {exc.errno}", f"NMEA destination {self.name} for '{self.vessel}' refuses "
                                                  f"datagrams ({exc.strerror or exc}); reported once, counted; the "
                                                  "simulation goes on")

    def close(self) -> None:
        if self.sock is not None:
            self.sock.close()


def _stamp_ns(data: bytes) -> Optional[int]:
    """The header stamp of a serialized message whose first field is a std_msgs/Header."""
    if len(data) < 12 or data[1] not in (0, 1):
        return None
    order = "little" if data[1] == 1 else "big"
    sec = int.from_bytes(data[4:8], order, signed=True)
    nsec = int.from_bytes(data[8:12], order)
    return sec * 1_000_000_000 + nsec


class NmeaOut(Node):
    def __init__(self, name: str = "nmea_out", **kwargs):
        super().__init__(name, **kwargs)
        rc.declare_table(self, NMEA_OUT)
        rc.refuse_fixed_parameters(self, NMEA_OUT)
        log = self.get_logger()
        cfg, ships = self._settings()
        self.vessels = [v for v in cfg["vessels"] if v]
        if not self.vessels:
            raise ValueError("parameter 'vessels': name the vessels of the run, e.g. [tug, barge] (or give "
                             "'scenario', the run's scenario file, which names them)")
        self.origin = geo.Origin(cfg["origin_latitude"], cfg["origin_longitude"], cfg["origin_height"])
        self.utc_start = parse_utc(cfg["utc_start"])
        self.tick_ns = max(1, round(1e9 / cfg["rate"]))
        self.period_ns = rc.period_ns(cfg["exchange_rate"])
        self.static_every = int(cfg["static_every"])
        self.talkers = S.Talkers(cfg["heading_talker"], cfg["engine_talker"])
        for key, talker in zip(("heading_talker", "engine_talker"), self.talkers):
            if S.check_talker(talker):
                raise ValueError(f"parameter '{key}': {S.check_talker(talker)}")
        self.outputs: Dict[str, List[Destination]] = collections.defaultdict(list)
        for item in cfg["outputs"]:
            if item:
                vessel, host, port = parse_output(item)
                if vessel not in self.vessels:
                    raise ValueError(f"parameter 'outputs': vessel {vessel!r} is not in 'vessels' {self.vessels}")
                self.outputs[vessel].append(Destination(vessel, host, port, log))
        mmsi = {k: int(v) for k, v in _pairs(cfg["mmsi"], "mmsi").items()}
        self.mmsi = {v: mmsi.get(v, S.default_mmsi(i)) for i, v in enumerate(self.vessels)}
        for v, m in self.mmsi.items():
            if check_mmsi(m):
                raise ValueError(f"parameter 'mmsi': {v}: {check_mmsi(m)}")
        self.gear = {k: float(v) for k, v in _pairs(cfg["gear_ratios"], "gear_ratios").items()}
        # rope ends on vessels: vessel -> [(rope, end)]
        self.rope_ends: Dict[str, List[Tuple[str, str]]] = collections.defaultdict(list)
        towing = set()
        for rope, ends in _pairs(cfg["ropes"], "ropes").items():
            for end, spec in zip("ab", ends.split(",")):
                vessel = spec.split("/")[0] if "/" in spec else None
                if vessel in self.vessels:
                    self.rope_ends[vessel].append((rope, end))
                    if end == "a":
                        towing.add(vessel)
        self.particulars = self._particulars(_pairs(cfg["ship_files"], "ship_files"), ships, towing)
        # latest serialized messages of due steps: stamp -> {topic: bytes}
        self.pending: Dict[int, Dict[str, bytes]] = {}
        self.needed = [T.vessel_topic(v, T.ODOM) for v in self.vessels] + [T.vessel_topic(v, T.STATUS) for v in self.vessels]
        self.needed += [T.end_wrench_topic(r, e) for v in self.vessels for r, e in self.rope_ends[v]]
        self.last_sent = -1
        self.reports = 0
        for topic in self.needed:
            self.create_subscription(_TYPES[topic.rsplit("/", 1)[1]], topic,
                                     lambda data, topic=topic: self._on_message(topic, data), rc.STATE_QOS, raw=True)
        dests = ", ".join(f"{v} -> {d.name}" for v, ds in self.outputs.items() for d in ds)
        log.info(f"NMEA 0183 / AIS out at {cfg['rate']:g} Hz of simulation time: {dests or 'no output'}; "
                 f"origin {self.origin.latitude:.6f}, {self.origin.longitude:.6f}; MMSI {self.mmsi}")
        for line in self._lacking(cfg, ships):
            log.warning(line)

    def _settings(self) -> Tuple[dict, Dict[str, Tuple[str, dict]]]:
        """(the parameters' values, with those left at their defaults taken from the scenario the
        parameter `scenario` names; its vessels' (ship file, ship_overrides)). A run's runner
        passes every value; a person who starts the node by hand names the scenario and the
        outputs, and gets the run's vessels, ropes, exchange rate, origin and `nmea` settings."""
        cfg = {p.name: self.get_parameter(p.name).value for p in NMEA_OUT}
        if not cfg["scenario"]:
            return cfg, {}
        path = scenario_path(cfg["scenario"])
        try:
            sc = load_scenario(path, check_files=False)
        except ScenarioError as exc:
            raise ValueError(f"parameter 'scenario': {exc}") from None
        ships = scenario_ships(path)
        given = {"vessels": [v.name for v in sc.vessels], "exchange_rate": float(sc.exchange_rate),
                 "ropes": [f"{r.name}={r.end_a},{r.end_b}" for r in sc.ropes],
                 "origin_latitude": float(sc.origin.latitude), "origin_longitude": float(sc.origin.longitude),
                 "origin_height": float(sc.origin.height)}
        if sc.nmea is not None:
            n = sc.nmea
            given.update(rate=float(n.rate), utc_start=n.utc_start, static_every=int(n.static_every),
                         mmsi=[f"{k}={m}" for k, m in n.mmsi.items()],
                         gear_ratios=[f"{k}={g!r}" for k, g in n.gear_ratios.items()])
        for key, value in given.items():
            if cfg[key] == NMEA_OUT[key].default and value != []:
                cfg[key] = value
        strangers = sorted(set(v for v in cfg["vessels"] if v) - set(ships))
        if strangers:
            raise ValueError(f"parameter 'scenario': {cfg['scenario']} has no vessel {', '.join(strangers)} "
                             f"(its vessels: {', '.join(ships)})")
        return cfg, ships

    def _lacking(self, cfg: dict, ships: dict) -> List[str]:
        """What a node started without the run's scenario cannot send, said in its log."""
        out = []
        if not ships:
            targets = [v for v in self.vessels if any(own != v for own in self.outputs or self.vessels)]
            no_files = [v for v in targets if not any(i.startswith(f"{v}=") for i in cfg["ship_files"])]
            if no_files:
                out.append(f"no 'scenario' (the run's scenario file) and no 'ship_files' for {', '.join(no_files)}: "
                           "their AIS static data (type 5) carry no length, beam or draught (0 m); give "
                           "-p scenario:=<the run's scenario file>")
            if not any(r for r in cfg["ropes"]):
                out.append("no 'scenario' and no 'ropes': no tension sentences ($IIXDR,N); give "
                           "-p scenario:=<the run's scenario file>")
        if not self.outputs:
            out.append("no 'outputs': nothing is sent; give e.g. -p \"outputs:=['tug@127.0.0.1:10110']\"")
        return out

    def _particulars(self, files: Dict[str, str], ships: Dict[str, Tuple[str, dict]],
                     towing: set) -> Dict[str, S.Particulars]:
        out = {}
        for v in self.vessels:
            length = beam = draft = 0.0
            path, overrides = files.get(v), {}
            if v in ships:
                path, overrides = path or ships[v][0], ships[v][1]
            if path:
                d = hull_dimensions(path, overrides)
                length, beam, draft = d.length, d.beam, d.draft
            ship_type = 31 if v in towing else (52 if "tug" in v.lower() else 0)  # 31 towing, 52 tug
            out[v] = S.Particulars(self.mmsi[v], v, length, beam, draft, ship_type)
        return out

    def _on_message(self, topic: str, data: bytes) -> None:
        stamp = _stamp_ns(data)
        if stamp is None or stamp <= self.last_sent or stamp % self.tick_ns >= self.period_ns:
            return
        slot = self.pending.setdefault(stamp, {})
        slot[topic] = data
        if len(slot) == len(self.needed):
            self._send(stamp, slot)
            self.last_sent = stamp
            for s in [s for s in self.pending if s <= stamp]:
                del self.pending[s]
        while len(self.pending) > _KEEP_STEPS:
            del self.pending[min(self.pending)]

    def _kinematics(self, v: str, slot: Dict[str, bytes]):
        od = deserialize_message(slot[T.vessel_topic(v, T.ODOM)], Odometry)
        st = deserialize_message(slot[T.vessel_topic(v, T.STATUS)], VesselStatus)
        p, q, tw = od.pose.pose.position, od.pose.pose.orientation, od.twist.twist
        roll, pitch, yaw = (float(a) for a in rpy_from_quaternion(q.x, q.y, q.z, q.w))
        # twist in the body frame: velocity over ground in the map frame (the horizontal part)
        ve, vn, _ = (float(c) for c in matrix_from_quaternion(q.x, q.y, q.z, q.w)
                     @ (tw.linear.x, tw.linear.y, tw.linear.z))
        cp, cr, sr = math.cos(pitch), math.cos(roll), math.sin(roll)
        lat, lon, _ = geo.enu_to_geodetic(p.x, p.y, self.origin)
        # yaw rate about the world vertical (r of the body frame for a level vessel)
        r = (tw.angular.y * sr + tw.angular.z * cr) / cp if abs(cp) > 1e-9 else tw.angular.z
        return dict(lat=lat, lon=lon, sog=geo.knots(math.hypot(ve, vn)), cog=geo.course_over_ground(ve, vn),
                    hdg=geo.compass_deg(yaw), rot=geo.rate_of_turn(r), status=st)

    def _send(self, stamp: int, slot: Dict[str, bytes]) -> None:
        t = stamp * 1e-9
        kin = {v: self._kinematics(v, slot) for v in self.vessels}
        static = self.reports % self.static_every == 0
        self.reports += 1
        for own, dests in self.outputs.items():
            k = kin[own]
            st = k["status"]
            shaft_rpm = st.shaft_speed * 60.0 / (2.0 * math.pi)
            tensions = []
            for rope, end in self.rope_ends[own]:
                w = cdr.decode_wrench_stamped(slot[T.end_wrench_topic(rope, end)])
                tensions.append((rope, math.sqrt(sum(c * c for c in w.force))))
            lines = S.own_ship_sentences(S.OwnShip(
                t, k["lat"], k["lon"], k["sog"], k["cog"], k["hdg"], k["rot"], -math.degrees(st.steering_angle),
                shaft_rpm, shaft_rpm * self.gear.get(own, 1.0), tuple(tensions), *attitude(st)), self.utc_start,
                self.talkers)
            for other in self.vessels:
                if other == own:
                    continue
                o = kin[other]
                anchored = o["status"].anchor_state in (VesselStatus.ANCHOR_DREDGING,)
                lines += S.position_report(S.Target(self.mmsi[other], o["lat"], o["lon"], o["sog"], o["cog"], o["hdg"],
                                                    o["rot"], 1 if anchored else 0), t, self.utc_start)
                if static:
                    lines += S.static_report(self.particulars[other], seq_id=self.reports)
            for d in dests:
                d.send(lines)

    def destroy_node(self):
        for dests in self.outputs.values():
            for d in dests:
                # stderr: the context may be shut down already (Ctrl-C), and rosout with it
                sys.stderr.write(f"nmea_out: {d.vessel} -> {d.name}: {d.sent} sentences sent, {d.failed} not sent\n")
                d.close()
        return super().destroy_node()


_TYPES = {"odom": Odometry, "status": VesselStatus, "wrench": WrenchStamped}


def main(args=None) -> int:
    return rc.run_node(lambda: NmeaOut(), "nmea_out", args)


if __name__ == "__main__":
    sys.exit(main())
