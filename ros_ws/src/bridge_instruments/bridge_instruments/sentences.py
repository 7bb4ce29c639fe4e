"""NMEA 0183 sentences of one own vessel and AIS VDM messages of the others (ROS-free).

Sentences are assembled and check-summed by pynmea2 (its sentence classes and `render()`), AIS
payloads encoded and armoured by pyais; this module only puts the numbers into the fields in
the formats of NMEA 0183 (v4.11 field layouts) and ITU-R M.1371:

own vessel (one sentence per datagram, in this order; the time of GGA / RMC is the
simulation time of the state they report, UTC = utc_start + t):
  $GPRMC  time, A, lat, N/S, lon, E/W, SOG kn, COG deg true, date, , , mode A, nav status S (safe)
  $GPGGA  time, lat, lon, fix quality 1, 12 satellites, HDOP 0.8, 0.0 M, 0.0 M (antenna at the
          still-water surface over the map origin's height), no DGPS
  $GPVTG  COG deg true, T, (no magnetic), M, SOG kn, N, SOG km/h, K, mode A
  $IIHDT  heading deg true, T (talker: `heading_talker`, default II)
  $IIROT  rate of turn deg/min (negative: bow turns to port), A (talker: `heading_talker`)
  $IIRSA  rudder angle (negative: bow turns to port, i.e. REP-103 positive steering is negative
          here), A; no second rudder: empty, V
  $IIRPM  E (engine) 1 and S (shaft) 1, rpm (negative: turning astern), pitch empty (fixed
          pitch), A (talker: `engine_talker`, default II)
  $IIXDR  N (force), tension N, N (newton), the rope's name: one per rope with an end on the vessel
  $IIXDR  A, pitch, D, PTCH, A, roll, D, ROLL: the vessel's attitude (angular displacement, degrees,
          to 0.1 deg) in the convention of motion sensors on the bus (Airmar PB200 / LB150 manuals,
          XDR "B" sentence: pitch positive when the bow moves up, roll positive to starboard, i.e.
          starboard side down; OpenCPN's dashboard reads PTCH / ROLL as they come). The simulation's
          REP-103 angles (pitch positive bow DOWN, roll positive starboard down) are converted at
          this edge only (nmea_out.attitude): pitch changes sign, roll keeps it. The angles are the
          totals the odometry carries: manoeuvring heel / trim plus the wave-frequency roll / pitch.
other vessels:
  !AIVDM  type 1 position report (every time) and type 5 static and voyage data (every
          `static_every`-th time and the first), channel A.

The heading and engine talkers are choices (Talkers): a gyro's HE and the engine room's ER are
the standard ones, but gpsd (3.22, Debian 12) drops every sentence of a talker its lexer does
not know, HE and ER among them, and then reports no heading; it reads II (integrated
instrumentation), as it reads GP, HC, IN and TI.
"""
from __future__ import annotations

import datetime as _dt
import re
from typing import List, NamedTuple, Optional, Sequence, Tuple

import pyais
import pynmea2

# one sentence: at most 82 characters including '$' and <CR><LF> (NMEA 0183 5.3)
MAX_SENTENCE = 82


class OwnShip(NamedTuple):
    """What the own-vessel sentences carry, in their units (deg true, kn, deg/min, rpm, N)."""
    t: float  # s of simulation time
    latitude: float  # deg
    longitude: float  # deg
    sog_kn: float
    cog_deg: float
    heading_deg: float
    rot_deg_min: float  # + to starboard
    rudder_deg: float  # + bow to starboard (NMEA RSA)
    shaft_rpm: float  # - astern
    engine_rpm: float
    tensions: Tuple[Tuple[str, float], ...] = ()  # (rope name, N)
    pitch_deg: Optional[float] = None  # + bow up (NMEA XDR PTCH); None: no attitude sentence
    roll_deg: Optional[float] = None  # + starboard side down (NMEA XDR ROLL)


class Talkers(NamedTuple):
    """Talker IDs of the own-vessel sentences whose sender a bridge names differently."""
    heading: str = "II"  # HDT, ROT (a gyro: HE)
    engine: str = "II"  # RPM (the engine room: ER)


def check_talker(talker: str) -> Optional[str]:
    """Why `talker` cannot be an NMEA 0183 talker ID (None if it can): two upper-case letters or
    digits, not starting with P (proprietary sentences)."""
    if not re.fullmatch(r"[A-Z][A-Z0-9]", talker or ""):
        return f"{talker!r} is not two upper-case letters or digits (e.g. II, HE, GP)"
    if talker.startswith("P"):
        return f"{talker!r} starts with P, which marks a proprietary sentence"
    return None


class Target(NamedTuple):
    """An AIS target: another vessel of the run."""
    mmsi: int
    latitude: float
    longitude: float
    sog_kn: float
    cog_deg: float
    heading_deg: float
    rot_deg_min: float
    status: int = 0  # AIS navigational status: 0 under way using engine, 1 at anchor, ...


class Particulars(NamedTuple):
    """AIS static data of a target (type 5)."""
    mmsi: int
    name: str
    length: float  # m
    beam: float  # m
    draught: float  # m
    ship_type: int = 0  # ITU-R M.1371 Table 53: 0 not available, 31 towing, 52 tug, ...
    callsign: str = ""


def utc_at(utc_start: _dt.datetime, t: float) -> _dt.datetime:
    """UTC of simulation time t, to the hundredth of a second NMEA carries."""
    return utc_start + _dt.timedelta(milliseconds=10 * round(t * 100.0))




def _time(d: _dt.datetime) -> str:
    return f"{d.hour:02d}{d.minute:02d}{d.second:02d}.{d.microsecond // 10000:02d}"


def _angle(value: float, degree_digits: int, hemispheres: str) -> Tuple[str, str]:
    """ddmm.mmmmmm / dddmm.mmmmmm and its hemisphere letter; 1e-6 minute (under 2 mm)."""
    micro = round(abs(value) * 60e6)  # micro-minutes, rounded once: never 60.000000 minutes
    deg, mins = divmod(micro, 60_000_000)
    return f"{deg:0{degree_digits}d}{mins // 1_000_000:02d}.{mins % 1_000_000:06d}", \
        hemispheres[0] if value >= 0 else hemispheres[1]


def _num(value: float, digits: int) -> str:
    text = f"{value:.{digits}f}"
    return "0." + "0" * digits if text.lstrip("-").strip("0.") == "" else text  # never "-0.00"


def _bearing(value: float, digits: int) -> str:
    """A direction in [0, 360) with `digits` decimals: 359.996 is 0.00, never 360.00."""
    return _num(round(value % 360.0, digits) % 360.0, digits)


def _render(talker: str, kind: str, fields: Sequence[str]) -> str:
    cls = pynmea2.TalkerSentence.sentence_types[kind]
    return cls(talker, kind, tuple(fields)).render(checksum=True, dollar=True, newline=False)


def own_ship_sentences(s: OwnShip, utc_start: _dt.datetime, talkers: Talkers = Talkers()) -> List[str]:
    """The sentences of one own vessel at one time, without line endings."""
    when = utc_at(utc_start, s.t)
    lat, ns = _angle(s.latitude, 2, "NS")
    lon, ew = _angle(s.longitude, 3, "EW")
    sog, cog = _num(s.sog_kn, 2), _bearing(s.cog_deg, 2)
    out = [
        _render("GP", "RMC", (_time(when), "A", lat, ns, lon, ew, sog, cog, when.strftime("%d%m%y"), "", "",
                              "A", "S")),
        _render("GP", "GGA", (_time(when), lat, ns, lon, ew, "1", "12", "0.8", "0.0", "M", "0.0", "M", "", "")),
        _render("GP", "VTG", (cog, "T", "", "M", sog, "N", _num(s.sog_kn * 1.852, 2), "K", "A")),
        _render(talkers.heading, "HDT", (_bearing(s.heading_deg, 2), "T")),
        _render(talkers.heading, "ROT", (_num(s.rot_deg_min, 2), "A")),
        _render("II", "RSA", (_num(s.rudder_deg, 2), "A", "", "V")),
        _render(talkers.engine, "RPM", ("E", "1", _num(s.engine_rpm, 1), "", "A")),
        _render(talkers.engine, "RPM", ("S", "1", _num(s.shaft_rpm, 1), "", "A")),
    ]
    out += [_render("II", "XDR", ("N", _num(tension, 1), "N", name)) for name, tension in s.tensions]
    if s.pitch_deg is not None and s.roll_deg is not None:
        out.append(attitude_xdr(s.pitch_deg, s.roll_deg))
    return out


def attitude_xdr(pitch_deg: float, roll_deg: float) -> str:
    """$IIXDR,A,<pitch>,D,PTCH,A,<roll>,D,ROLL*hh: pitch + bow up, roll + starboard side down,
    degrees to 0.1 (the module docstring names the convention)."""
    return _render("II", "XDR", ("A", _num(pitch_deg, 1), "D", "PTCH", "A", _num(roll_deg, 1), "D", "ROLL"))


def _clip(v: float, lo: float, hi: float) -> float:
    return min(hi, max(lo, v))


def position_report(tg: Target, t: float, utc_start: _dt.datetime) -> List[str]:
    """!AIVDM type 1 (class A position report) of a target; values outside AIS's ranges are
    clipped to them (speed 102.2 kn, rate of turn 708 deg/min)."""
    when = utc_at(utc_start, t)
    data = {"type": 1, "mmsi": int(tg.mmsi), "status": int(tg.status),
            "turn": _clip(tg.rot_deg_min, -708.0, 708.0), "speed": round(_clip(tg.sog_kn, 0.0, 102.2), 1),
            "accuracy": 1, "lon": tg.longitude, "lat": tg.latitude,
            "course": round(tg.cog_deg % 360.0, 1) % 360.0, "heading": int(round(tg.heading_deg)) % 360,
            "second": when.second}
    return pyais.encode_dict(data, talker_id="AI", sentence_type="VDM", radio_channel="A")


def static_report(p: Particulars, seq_id: int = 0) -> List[str]:
    """!AIVDM type 5 (two sentences) of a target: dimensions from the ship file's length and
    beam with the reference point amidships (to bow + to stern = length, to port + to starboard
    = beam, whole metres), draught, name."""
    length, beam = max(1, round(p.length)), max(1, round(p.beam))
    bow, port = min(511, length // 2 + length % 2), min(63, beam // 2 + beam % 2)
    data = {"type": 5, "mmsi": int(p.mmsi), "ais_version": 2, "imo": 0, "callsign": p.callsign[:7].upper(),
            "shipname": p.name[:20].upper(), "ship_type": int(p.ship_type), "to_bow": bow,
            "to_stern": min(511, length - bow), "to_port": port, "to_starboard": min(63, beam - port),
            "epfd": 1, "draught": round(_clip(p.draught, 0.0, 25.5), 1), "destination": "", "dte": 0}
    return pyais.encode_dict(data, talker_id="AI", sentence_type="VDM", radio_channel="A", seq_id=seq_id % 10)


def default_mmsi(index: int) -> int:
    """The MMSI of the index-th vessel of a scenario when none is given: 244 (the Netherlands,
    the default origin's country) followed by 99 and a serial: 244 99 0001, ... (fictitious)."""
    return 244_990_001 + index


