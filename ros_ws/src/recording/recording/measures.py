"""The numbers of a recording: the manoeuvres sailed and their measures, the IMO criteria, the
towline angle and the summary `analyze` writes (no figures: this module does not need matplotlib).

The manoeuvre is found from the orders given (a turn: the first helm order; a zig-zag: helm
orders alternating side at one angle; a stop: the first astern order from ahead) and measured
with the definitions written once in sim_math/turning.py and sim_math/trials.py (ITTC terms,
IMO MSC.137(76) criteria; docs/tools.md). Values are SI and ENU (rad, m, m/s); the speeds in
knots and compass courses are added for people.
"""
from __future__ import annotations

import math
import os
from typing import Dict, List, Optional, Tuple

import numpy as np

from sim_math import trials
from sim_math.turning import turning_measures
from recording import sea_statistics
from recording.recorded_run import Recording, status_column

KN = 1852.0 / 3600.0  # m/s per knot


# ---------------------------------------------------------------------------------------
# The manoeuvre sailed, from the orders given
# ---------------------------------------------------------------------------------------
def find_zigzag(rec: Recording, name: str):
    """(order times, order angles) of a zig-zag: from the first helm order of at least 5 deg,
    the helm orders that alternate side at the same angle (within 0.5 deg); None unless
    there is at least one reversal."""
    t, d = rec.steering_orders(name)
    keep_t, keep_d = [], []
    for ti, di in zip(t, d):
        if not keep_t:
            if abs(di) >= math.radians(5.0):
                keep_t, keep_d = [float(ti)], [float(di)]
            continue
        if abs(di - keep_d[-1]) < 1e-9:
            continue  # the same order repeated
        if abs(abs(di) - abs(keep_d[0])) <= math.radians(0.5) and di * keep_d[-1] < 0:
            keep_t.append(float(ti))
            keep_d.append(float(di))
        else:
            break  # midships or another angle: the zig-zag is over
    return (keep_t, keep_d) if len(keep_t) >= 2 else None


def find_stop(rec: Recording, name: str, min_speed: float = 0.3):
    """Time of the first astern order (engine order <= -0.5) given from ahead (engine order
    >= 0 before it) while making headway above min_speed; None if there is none."""
    t, e = rec.engine_orders(name)
    v = rec.vessels[name]
    for i in range(t.size):
        # the order before the first one on the command topic is not on it: headway tells
        ahead_before = e[i - 1] >= 0.0 if i else True
        if e[i] <= -0.5 and ahead_before and np.interp(t[i], v["t"], v["u"]) > min_speed:
            return float(t[i])
    return None


def find_turn(rec: Recording, name: str, min_steering_deg: float = 1.0):
    """(t0, t1) of the first turn: from the first helm order of at least min_steering_deg
    to the next change of the helm order (or the end of the data); None if there is none."""
    t, d = rec.steering_orders(name)
    prev = 0.0
    for i in range(t.size):
        if abs(d[i]) >= math.radians(min_steering_deg) and abs(d[i] - prev) > 1e-9:
            later = np.nonzero(np.abs(d[i + 1:] - d[i]) > 1e-9)[0]
            t1 = float(t[i + 1 + later[0]]) if later.size else float(rec.vessels[name]["t"][-1])
            return float(t[i]), t1
        prev = d[i]
    return None


# ---------------------------------------------------------------------------------------
# Measures of the manoeuvres
# ---------------------------------------------------------------------------------------
def analyse_turns(rec: Recording, turn_start: Optional[float], turn_end: Optional[float],
                  steady_from_deg: float) -> Dict[str, dict]:
    """Turning measures per vessel (sim_math.turning): from turn_start (to turn_end or the end)
    when given, else the first turn of the helm orders (find_turn); a vessel that sailed a
    zig-zag is measured by analyse_trials instead. A turn is kept when the heading changed by
    10 deg or more, or when turn_start was given."""
    turns = {}
    for name, v in rec.vessels.items():
        if turn_start is not None:
            span = (turn_start, turn_end if turn_end is not None else float(v["t"][-1]))
        elif find_zigzag(rec, name):
            continue  # measured as a zig-zag (analyse_trials), not as a turn
        else:
            span = find_turn(rec, name)
            if span and turn_end is not None:
                span = (span[0], turn_end)
        if span is None or len(v["t"]) < 3:
            continue
        m = turning_measures(v["t"], v["x"], v["y"], v["yaw"], v["u"], v["v"], v["r"], span[0], span[1],
                             steady_from_deg)
        ot, od = rec.steering_orders(name)
        m["helm_angle"] = float(od[ot <= span[0] + 1e-9][-1]) if np.any(ot <= span[0] + 1e-9) else math.nan
        _for_people(m)
        if "_along" in m:
            m["_psi0"] = float(np.interp(span[0], v["t"], v["yaw_unwrapped"]))
            m["_x0"], m["_y0"] = float(np.interp(span[0], v["t"], v["x"])), float(np.interp(span[0], v["t"], v["y"]))
        if m.get("heading_change", 0.0) and abs(m["heading_change"]) >= math.radians(10) or turn_start is not None:
            turns[name] = m
    return turns


def _for_people(m: dict) -> None:
    """Adds the approach speed in knots and heading as a compass course (deg true) to a
    manoeuvre's measures (SI and ENU stay the reference values)."""
    if math.isfinite(m.get("approach_speed", math.nan)):
        m["approach_speed_kn"] = m["approach_speed"] / KN
    if math.isfinite(m.get("approach_heading", math.nan)):
        m["approach_heading_deg_true"] = trials.compass_deg(m["approach_heading"])


def analyse_trials(rec: Recording) -> Dict[str, dict]:
    """Zig-zag and stopping (crash stop) measures per vessel, sim_math.trials definitions; the
    zig-zag from the alternating helm orders (find_zigzag), the stop from the first
    astern order given from ahead (find_stop)."""
    out: Dict[str, dict] = {}
    for name, v in rec.vessels.items():
        res = {}
        zz = find_zigzag(rec, name)
        if zz and len(v["t"]) > 2:
            z = trials.zigzag_measures(v["t"], v["yaw_unwrapped"], zz[0], zz[1], v["x"], v["y"], v["speed"])
            z["approach_heading"] = float(np.interp(zz[0][0], v["t"], v["yaw"]))
            _for_people(z)
            res["zigzag"] = z
        t_stop = find_stop(rec, name)
        if t_stop is not None and len(v["t"]) > 2:
            st = trials.stopping_measures(v["t"], v["x"], v["y"], v["yaw_unwrapped"], v["u"], v["speed"], t_stop)
            et, eo = rec.engine_orders(name)
            st["engine_order"] = float(eo[et <= t_stop + 1e-9][-1])
            st["approach_heading"] = float(np.interp(t_stop, v["t"], v["yaw"]))
            _for_people(st)
            res["stopping"] = st
        if res:
            out[name] = res
    return out


def imo_table(length: float, vs: dict) -> List[dict]:
    """MSC.137(76) criteria rows for one vessel's summary: the turning criteria for a hard-over
    turn (helm >= 30 deg), the zig-zag and initial turning criteria for a 10/10 or 20/20
    zig-zag, the stopping criterion for a full-astern stop; angles shown in deg."""
    turn = vs.get("turn")
    if turn is not None and not abs(turn.get("helm_angle") or 0.0) >= math.radians(30.0):
        turn = None
    stop = vs.get("stopping")
    if stop is not None and not stop.get("engine_order", 0.0) <= -0.99:
        stop = None
    rows = trials.imo_criteria(length, turn=turn, zigzag=vs.get("zigzag"), stop=stop)
    for r in rows:
        if r["unit"] == "rad":
            r["value"], r["limit"], r["unit"] = math.degrees(r["value"]), math.degrees(r["limit"]), "deg"
    return rows


def towline_angle(rec: Recording, rope_name: str, end: str) -> Optional[Tuple[str, np.ndarray, np.ndarray]]:
    """(vessel, times, angle) of a rope's end on a vessel: the horizontal direction in which the
    line leaves the vessel (from the end element to its neighbour) relative to the vessel's
    heading, rad in (-pi, pi]: 0 = leading ahead, +-pi = straight astern, + to port. None when
    the end is not on a recorded vessel or the rope has fewer than two elements."""
    spec = rec.particulars.get("ropes", {}).get(rope_name, {}).get(f"end_{end}", "")
    vessel = spec.split("/")[0] if "/" in spec else None
    rope = rec.ropes.get(rope_name, {})
    if vessel not in rec.vessels or "pos" not in rope:
        return None
    v = rec.vessels[vessel]
    t, ang = [], []
    for tk, p in zip(rope["t"], rope["pos"]):
        if len(p) < 2:
            continue
        d = p[1] - p[0] if end == "a" else p[-2] - p[-1]
        yaw = np.interp(tk, v["t"], v["yaw_unwrapped"])
        t.append(tk)
        ang.append(math.atan2(d[1], d[0]) - yaw)
    if not t:
        return None
    a = np.asarray(ang)
    return vessel, np.asarray(t), np.arctan2(np.sin(a), np.cos(a))


# ---------------------------------------------------------------------------------------
# Summary
# ---------------------------------------------------------------------------------------
def _clean(value):
    if isinstance(value, dict):
        return {k: _clean(v) for k, v in value.items() if not k.startswith("_")}
    if isinstance(value, (list, tuple)):
        return [_clean(v) for v in value]
    if isinstance(value, (np.floating, float)):
        return float(value) if math.isfinite(value) else None
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, np.bool_):
        return bool(value)
    return value


def summarise(rec: Recording, turns: Dict[str, dict], manoeuvres: Optional[Dict[str, dict]] = None,
              lengths: Optional[Dict[str, Optional[float]]] = None,
              breaking: Optional[Dict[str, Optional[float]]] = None) -> dict:
    """The summary (JSON): per vessel its track figures, the turn, zig-zag and stopping measures
    and, with its length known, the MSC.137(76) criteria; per rope its tensions (and the peak
    over the breaking load when that is known)."""
    lengths, breaking = lengths or {}, breaking or {}
    vessels = {}
    for name, v in rec.vessels.items():
        d = np.hypot(np.diff(v["x"]), np.diff(v["y"])).sum() if len(v["t"]) > 1 else 0.0
        vs = {"samples": int(len(v["t"])), "t_start": v["t"][0], "t_end": v["t"][-1],
              "x_start": v["x"][0], "y_start": v["y"][0], "x_end": v["x"][-1], "y_end": v["y"][-1],
              "yaw_start": v["yaw"][0], "yaw_end": v["yaw"][-1],
              "heading_change": v["yaw_unwrapped"][-1] - v["yaw_unwrapped"][0], "distance_run": d,
              "speed_max": v["speed"].max(), "speed_mean": v["speed"].mean(), "speed_end": v["speed"][-1],
              "yaw_rate_max_abs": np.abs(v["r"]).max(), "roll_max_abs": np.abs(v["roll"]).max(),
              "pitch_max": v["pitch"].max(), "pitch_min": v["pitch"].min()}
        if "status" in v:
            vs["girting_ratio_max"] = status_column(v["status"], "girting_ratio").max()
            vs["rise_max"] = status_column(v["status"], "rise").max()
            # in shallow water (a finite depth under the hull at some time): the least under-keel
            # clearance (depth - draft - squat, as the vessel reported it) and the largest squat
            ukc = status_column(v["status"], "under_keel_clearance")
            shallow = np.isfinite(ukc)
            if shallow.any():
                vs["ukc_min"] = float(ukc[shallow].min())
                vs["ukc_min_at"] = float(v["status"]["t"][shallow][np.argmin(ukc[shallow])])
                vs["squat_max"] = float(status_column(v["status"], "squat")[shallow].max())
        if name in turns:
            vs["turn"] = turns[name]
        vs.update((manoeuvres or {}).get(name, {}))
        L = lengths.get(name)
        if L:
            vs["length"] = L
            vs["imo"] = imo_table(L, vs)
        vessels[name] = vs
    ropes = {}
    for name, r in rec.ropes.items():
        rs: Dict[str, object] = {}
        if "t" in r:
            broken = np.nonzero(r["broken"])[0]
            rs.update(samples=int(len(r["t"])), tension_a_max=r["tension_a"].max(), tension_a_mean=r["tension_a"].mean(),
                      tension_b_max=r["tension_b"].max(), tension_b_mean=r["tension_b"].mean(),
                      tension_max_anywhere=np.nanmax(r["max_tension"]) if np.isfinite(r["max_tension"]).any() else None,
                      min_element_height=np.nanmin(r["min_z"]) if np.isfinite(r["min_z"]).any() else None,
                      max_abs_element_pitch=max((float(np.abs(p).max()) for p in r["pitch"] if len(p)), default=None),
                      elements_start=len(r["pos"][0]), elements_end=len(r["pos"][-1]),
                      stretched_length_end=r["stretched"][-1], unstretched_length_end=r["unstretched"][-1],
                      broken=bool(broken.size), broken_at=float(r["t"][broken[0]]) if broken.size else None)
        for end in ("a", "b"):
            if f"wrench_{end}" in r:
                rs[f"wrench_{end}_max"] = r[f"wrench_{end}"]["tension"].max()
        if breaking.get(name) and "t" in r:
            rs["breaking_load"] = breaking[name]
            rs["peak_over_breaking_load"] = max(r["tension_a"].max(), r["tension_b"].max(),
                                                np.nanmax(r["max_tension"]) if np.isfinite(r["max_tension"]).any()
                                                else 0.0) / breaking[name]
        ropes[name] = rs
    f = rec.file
    return _clean({
        "recording": os.path.abspath(rec.path),
        "file": {"bytes": f.size, "complete": f.complete, "messages_read": f.message_count,
                 "problems": [str(p) for p in f.problems], "log_time_start": (f.start_time or 0) * 1e-9,
                 "log_time_end": (f.end_time or 0) * 1e-9, "undecodable_messages": rec.decoder.errors,
                 "notes": sorted(set(rec.decoder.notes))},
        "time_reference": rec.t_ref, "time_source": rec.time_source,
        "vessels": vessels, "ropes": ropes,
        "events": [{k: v for k, v in e.items() if k != "stamp_ns"} for e in rec.events],
    })


# ---------------------------------------------------------------------------------------
# A run at sea: tension statistics and motion spectra (recording/sea_statistics.py)
# ---------------------------------------------------------------------------------------
# the motions of a vessel whose spectra are taken: (key in the summary, record, unit)
MOTIONS = (("heave", "z", "m"), ("roll", "roll", "rad"), ("pitch", "pitch", "rad"), ("yaw", "yaw_unwrapped", "rad"),
           ("surge_velocity", "u", "m/s"), ("sway_velocity", "v", "m/s"))


def analyse_sea(rec: Recording, waves: Optional[dict] = None, start: Optional[float] = None,
                end: Optional[float] = None, breaking: Optional[Dict[str, Optional[float]]] = None,
                slack_fraction: float = sea_statistics.DEFAULT_SLACK_FRACTION,
                segment: float = sea_statistics.DEFAULT_SEGMENT) -> dict:
    """The sea statistics of a recording over one window: per rope end its tension statistics
    (sea_statistics.tension_statistics; the slack threshold slack_fraction of the breaking load,
    none without one), per vessel the Welch spectra of its motions (MOTIONS). The window is
    [start, end] when given, else from the end of the wave start-up ramp (waves["ramp_time"])
    when the sea state is known, else the whole run; a rope's window ends where it parted.
    Keys starting with "_" hold the arrays of the figures."""
    breaking = breaking or {}
    notes: List[str] = []
    ends = [float(v["t"][-1]) for v in rec.vessels.values()] + [float(r["t"][-1]) for r in rec.ropes.values()
                                                                  if "t" in r and len(r["t"])]
    t_last = max(ends) if ends else None
    if start is not None:
        source = "--sea-window"
    elif waves and waves.get("ramp_time"):
        start, source = float(waves["ramp_time"]), "after the wave start-up ramp"
        if t_last is not None and start >= t_last:
            notes.append(f"the recording ends ({t_last:.1f} s) before the wave start-up ramp does ({start:.1f} s): "
                         f"the whole run is analysed")
            start, source = None, "whole run (shorter than the start-up ramp)"
    else:
        source = "whole run"
    out = {"window_start": start, "window_end": end if end is not None else t_last, "window_source": source, "waves": waves,
           "slack_fraction": slack_fraction, "welch": {"segment": segment, "window": "hann", "overlap": 0.5,
                                                       "detrend": "linear"},
           "vessels": {}, "ropes": {}, "notes": notes}
    for name, r in rec.ropes.items():
        if "t" in r and len(r["t"]):
            series = {e: (r["t"], r[f"tension_{e}"]) for e in ("a", "b")}
        else:
            series = {e: (r[f"wrench_{e}"]["t"], r[f"wrench_{e}"]["tension"]) for e in ("a", "b") if f"wrench_{e}" in r}
        stop = end
        if "broken" in r and np.any(r["broken"]):
            parted = float(r["t"][np.argmax(r["broken"])])
            stop = parted if stop is None else min(stop, parted)
            notes.append(f"rope {name} parted at {parted:.1f} s: its statistics end there")
        load = breaking.get(name)
        threshold = slack_fraction * load if load else math.nan
        if not load:
            notes.append(f"rope {name}: no breaking load (give --breaking-load {name}=N): slack events not counted")
        rs = {}
        for e, (t, x) in series.items():
            m = sea_statistics.window_mask(t, start, stop)
            st = sea_statistics.tension_statistics(t[m], x[m], threshold)
            if not load:
                st.update(slack_threshold=None, slack_events=None, slack_time=None, slack_at_start=None, snatch_max=None)
            st["window_start"], st["window_end"] = (float(t[m][0]), float(t[m][-1])) if m.any() else (None, None)
            rs[f"end_{e}"] = st
        out["ropes"][name] = rs
    for name, v in rec.vessels.items():
        m = sea_statistics.window_mask(v["t"], start, end)
        vs = {}
        for key, col, unit in MOTIONS:
            sp = sea_statistics.motion_spectrum(v["t"][m], v[col][m], segment)
            sp["unit"] = unit
            vs[key] = sp
        out["vessels"][name] = vs
    return out


def sea_summary(sea: dict, summary: dict) -> None:
    """Puts the sea statistics into a summary: per rope sea_end_a / sea_end_b, per vessel
    sea_<motion>, and the window and settings as summary["sea"] (JSON-clean)."""
    for name, ends in sea["ropes"].items():
        rs = summary["ropes"].setdefault(name, {})
        for e, st in ends.items():
            rs[f"sea_{e}"] = _clean(st)
    for name, motions in sea["vessels"].items():
        vs = summary["vessels"].setdefault(name, {})
        for key, sp in motions.items():
            vs[f"sea_{key}"] = _clean(sp)
    summary["sea"] = _clean({k: v for k, v in sea.items() if k not in ("ropes", "vessels")})
