"""What a live-view client may send, checked (no ROS import).

Anything arriving over the WebSocket is untrusted. Only the vessels' ``command``
(tug_msgs/VesselCommand: engine order, steering and the anchor order, which is part of the
command) and the ropes' ``winch`` (tug_msgs/WinchCommand) topics take client messages, in CDR
(as Foxglove's publish panel sends for a ROS 2 server) or JSON (a mapping of exactly the
message's order fields). A message is refused (InputRefused, with the reason) when it is too
large, not the type, has a non-finite value or an unknown anchor order; out-of-range values are
clamped (the notes say which). JSON is scanned before it is parsed: nesting deeper than
MAX_JSON_DEPTH or a number longer than MAX_NUMBER_CHARS is refused (a 2000-deep array would end
the parser in RecursionError, a 400-digit integer float() in OverflowError); and check() turns
whatever else a malformed message may raise into InputRefused, so no input ends in a traceback.
The accepted order is written anew (sim_plumbing.cdr), stamped with the simulation time the live
view gives (the run's own clock, see live_view_node), so nothing but checked numbers leaves the
server.
"""
from __future__ import annotations

import json
import math
import struct
from typing import Callable, Dict, List, NamedTuple, Tuple

from sim_plumbing import cdr

MAX_MESSAGE_BYTES = 4096
MAX_JSON_DEPTH = 4  # an order is a flat object; its optional header nests {"stamp": {...}}
MAX_NUMBER_CHARS = 40  # characters of one JSON number (a double needs at most 24)
# Generic bounds (the vessel and rope nodes clamp again to the ship's and rope's own limits)
ENGINE_LIMIT = 1.0
STEERING_LIMIT = math.pi / 2  # rad
PAYOUT_LIMIT = 10.0  # m/s
ANCHOR_ORDERS = (0, 1, 2)  # no change, let go, heave up (tug_msgs/VesselCommand)

VESSEL_COMMAND = "tug_msgs/msg/VesselCommand"
WINCH_COMMAND = "tug_msgs/msg/WinchCommand"
ENCODINGS = ("cdr", "json")


class InputRefused(ValueError):
    """A client message that is not used (the reason in args[0])."""


class Order(NamedTuple):
    data: bytes  # the CDR message to publish
    notes: Tuple[str, ...]  # what was clamped


def _finite(name: str, value) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InputRefused(f"{name}={value!r} is not a number")
    try:
        value = float(value)
    except OverflowError:  # an integer beyond the doubles
        raise InputRefused(f"{name}={str(value)[:40]}...: too large a number") from None
    if not math.isfinite(value):
        raise InputRefused(f"{name}={value!r} is not a finite number")
    return value


def _clamp(name: str, value: float, limit: float, notes: List[str]) -> float:
    if abs(value) > limit:
        notes.append(f"{name} {value:g} clamped to {math.copysign(limit, value):g}")
        return math.copysign(limit, value)
    return value


def _json_shape(text: str) -> None:
    """Refuse JSON nested deeper than MAX_JSON_DEPTH or with a number longer than
    MAX_NUMBER_CHARS, before the parser sees it (one pass, strings skipped)."""
    depth = run = 0
    in_string = escaped = False
    for c in text:
        if in_string:
            if escaped:
                escaped = False
            elif c == "\\":
                escaped = True
            elif c == '"':
                in_string = False
            continue
        if c in "0123456789+-.eE":
            run += 1
            if run > MAX_NUMBER_CHARS:
                raise InputRefused(f"a number of more than {MAX_NUMBER_CHARS} characters")
            continue
        run = 0
        if c == '"':
            in_string = True
        elif c in "[{":
            depth += 1
            if depth > MAX_JSON_DEPTH:
                raise InputRefused(f"JSON nested more than {MAX_JSON_DEPTH} deep (an order is a flat object)")
        elif c in "]}":
            depth -= 1


def _json_fields(data: bytes, fields: Tuple[str, ...]) -> Dict[str, object]:
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise InputRefused(f"not JSON (not UTF-8: {exc})") from None
    _json_shape(text)
    try:
        obj = json.loads(text)
    except (ValueError, RecursionError) as exc:
        raise InputRefused(f"not JSON: {str(exc)[:200]}") from None
    if not isinstance(obj, dict):
        raise InputRefused(f"expected a JSON object with {', '.join(fields)}")
    unknown = sorted(set(obj) - set(fields) - {"header"})
    if unknown:
        raise InputRefused(f"unknown field(s) {unknown}; expected {', '.join(fields)}")
    return obj


def vessel_command(data: bytes, encoding: str, stamp_ns: int) -> Order:
    if encoding == "cdr":
        try:
            msg = cdr.decode_vessel_command(data)
        except cdr.CdrError as exc:
            raise InputRefused(f"not a VesselCommand: {exc}") from None
        engine, steering, anchor = msg.engine_order, msg.steering_angle, msg.anchor
    else:
        obj = _json_fields(data, ("engine_order", "steering_angle", "anchor"))
        engine, steering, anchor = obj.get("engine_order", 0.0), obj.get("steering_angle", 0.0), obj.get("anchor", 0)
    engine, steering = _finite("engine_order", engine), _finite("steering_angle", steering)
    if isinstance(anchor, bool) or not isinstance(anchor, int) or anchor not in ANCHOR_ORDERS:
        raise InputRefused(f"anchor={anchor!r} is not one of 0 (no change), 1 (let go), 2 (heave up)")
    notes: List[str] = []
    engine = _clamp("engine_order", engine, ENGINE_LIMIT, notes)
    steering = _clamp("steering_angle", steering, STEERING_LIMIT, notes)
    w = cdr.CdrWriter()
    w.stamp(stamp_ns)
    w.string("")
    w.raw(struct.pack("<ddB", engine, steering, anchor), 8)
    return Order(w.getvalue(), tuple(notes))


def winch_command(data: bytes, encoding: str, stamp_ns: int) -> Order:
    """A WinchCommand: payout_rate (clamped), and the winch mode (0 speed, 1 hold, 2 constant
    tension) with its set / recover tension and brake load (N, >= 0; 0 keeps the current)."""
    if encoding == "cdr":
        try:
            order = cdr.decode_winch_command(data)
        except cdr.CdrError as exc:
            raise InputRefused(f"not a WinchCommand: {exc}") from None
        rate, mode = order.payout_rate, order.mode
        tensions = (order.set_tension, order.recover_tension, order.brake_load)
    else:
        names = ("payout_rate", "mode", "set_tension", "recover_tension", "brake_load")
        fields = _json_fields(data, names)
        rate, mode = fields.get("payout_rate", 0.0), fields.get("mode", 0)
        tensions = tuple(fields.get(n, 0.0) for n in names[2:])
    notes: List[str] = []
    rate = _clamp("payout_rate", _finite("payout_rate", rate), PAYOUT_LIMIT, notes)
    if isinstance(mode, bool) or mode not in (0, 1, 2):
        raise InputRefused(f"mode={mode!r}: expected 0 (speed), 1 (hold) or 2 (constant tension)")
    checked = []
    for name, value in zip(("set_tension", "recover_tension", "brake_load"), tensions):
        value = _finite(name, value)
        if value < 0.0:
            raise InputRefused(f"{name}={value!r} N: a tension is >= 0 (0 keeps the current one)")
        checked.append(value)
    w = cdr.CdrWriter()
    w.stamp(stamp_ns)
    w.string("")
    w.raw(struct.pack("<d", rate), 8)
    w.raw(struct.pack("<B", int(mode)), 1)
    w.raw(struct.pack("<3d", *checked), 8)
    return Order(w.getvalue(), tuple(notes))


CHECKS: Dict[str, Callable[[bytes, str, int], Order]] = {VESSEL_COMMAND: vessel_command, WINCH_COMMAND: winch_command}


def schema_matches(full_type: str, schema_name: str) -> bool:
    """A client channel's schema name names the type ('pkg/msg/Type' or 'pkg/Type')."""
    pkg, _, name = full_type.split("/")
    return schema_name in (full_type, f"{pkg}/{name}")


def check(full_type: str, data: bytes, encoding: str, stamp_ns: int) -> Order:
    """The order to publish for a client message of this type, or InputRefused."""
    if len(data) > MAX_MESSAGE_BYTES:
        raise InputRefused(f"{len(data)} bytes: more than {MAX_MESSAGE_BYTES}")
    if encoding not in ENCODINGS:
        raise InputRefused(f"encoding {encoding!r}: expected one of {ENCODINGS}")
    try:
        return CHECKS[full_type](bytes(data), encoding, stamp_ns)
    except InputRefused:
        raise
    except (ValueError, TypeError, OverflowError, RecursionError, struct.error, KeyError, IndexError) as exc:
        # whatever a malformed message makes the decoding raise: refused with a status, not a traceback
        raise InputRefused(f"malformed: {type(exc).__name__}: {str(exc)[:200]}") from None
