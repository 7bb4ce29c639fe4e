"""The IMO standard manoeuvring trials other than the turning circle (sim_math.turning), measured
from a sampled track, and the criteria of IMO Resolution MSC.137(76), Standards for Ship
Manoeuvrability (2002), with the definitions of MSC/Circ.1053 (explanatory notes). Pure numpy,
no ROS: used by ``analyze`` and the tests alike.

Angles in radians in the REP-103 sense (heading = yaw, counter-clockwise from east, unwrapped);
lengths in metres, speeds in m/s, times in s.

- Zig-zag delta/psi (10/10, 20/20): helm delta to one side at t0; when the heading has changed
  by psi the helm is reversed (first execute, t1); when it has changed by psi to the other side
  it is reversed again (t2), and so on. Heading deviation h(t) = psi(t) - psi(t0), and s = the
  sign of the first helm order's turn (+1 port). First overshoot = max of s h over [t1, t2]
  minus the check angle psi; second overshoot = max of -s h over [t2, t3] minus psi. The check
  angle is the deviation at which each reversal was executed, as measured (|h(t1)|, |h(t2)|):
  the trial's own psi, plus whatever the helmsman (or the state-triggered event) overshot.
  A zig-zag is judged by the criteria only if it was one: every reversal executed at a
  deviation within 1 deg of delta (``heading_triggered``); a zig-zag timed by the clock is
  measured but not judged.
- Initial turning: with delta = 10 deg, the distance along the track from t0 until the heading
  has changed by 10 deg (MSC.137(76) 5.3.2; the first leg of the 10/10 zig-zag).
- Stopping (crash stop): full astern ordered at t0 from an ahead approach; the ship has stopped
  when its headway u (body x over ground) first reaches 0 (linear interpolation). Track reach =
  distance along the track from t0 to then; head reach and lateral deviation along and across
  the approach course.

Criteria (MSC.137(76) 5.4, L = length between perpendiculars, V = approach speed):
  turning: advance <= 4.5 L, tactical diameter <= 5 L; initial turning: <= 2.5 L;
  zig-zag 10/10 first overshoot <= 10 deg if L/V < 10 s, <= 20 deg if L/V >= 30 s, else
  5 + (L/V)/2 deg; second overshoot <= 25 deg, 40 deg, else 17.5 + 0.75 (L/V) deg;
  zig-zag 20/20 first overshoot <= 25 deg; stopping: track reach <= 15 L (an Administration may
  allow up to 20 L for a large ship: not applied here).
"""
from __future__ import annotations

import math
from typing import Dict, List, Optional, Sequence

import numpy as np


def _cross_time(t: np.ndarray, f: np.ndarray, level: float, start: int = 0) -> float:
    """First time at or after index start where f rises through level (linear interpolation);
    NaN if it never does."""
    above = np.nonzero(f[start:] >= level)[0]
    if not above.size:
        return math.nan
    j = start + int(above[0])
    if j == 0 or f[j - 1] >= level:
        return float(t[j])
    return float(t[j - 1] + (level - f[j - 1]) * (t[j] - t[j - 1]) / (f[j] - f[j - 1]))


def path_length(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Cumulative distance along the track (0 at the first sample)."""
    return np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(x), np.diff(y)))])


def zigzag_measures(t, psi, order_times: Sequence[float], order_angles: Sequence[float],
                    x=None, y=None, speed=None) -> Dict[str, object]:
    """Overshoot angles of a zig-zag from the heading psi(t) (unwrapped) and the helm orders
    (times, steering angles, + to port) from its first helm order on; see the module docstring.
    With x, y and speed: the initial turning distance and approach speed as well.

    Returns delta (the helm angle), check_angles (|h| at each reversal), overshoots (first,
    second, ... as far as the data go), their times, period-free execute times, and the
    approach speed / initial turning distance when given the track."""
    t = np.asarray(t, float)
    psi = np.asarray(psi, float)
    times = [float(v) for v in order_times]
    angles = [float(v) for v in order_angles]
    if len(times) < 2:
        raise ValueError("a zig-zag needs at least the first helm order and one reversal")
    t0 = times[0]
    h = psi - float(np.interp(t0, t, psi))
    side = 1.0 if angles[0] > 0 else -1.0
    out: Dict[str, object] = {"t0": t0, "delta": abs(angles[0]), "turn_direction": side,
                              "execute_times": times[1:], "check_angles": [], "overshoots": [],
                              "overshoot_times": []}
    for k in range(1, len(times)):
        t_exec = times[k]
        t_next = times[k + 1] if k + 1 < len(times) else float(t[-1])
        sgn = side if k % 2 == 1 else -side  # the side the ship was swinging to before reversal k
        check = abs(float(np.interp(t_exec, t, h)))
        win = (t >= t_exec) & (t <= t_next)
        if not win.any():
            break
        j = int(np.argmax(sgn * h[win]))
        peak = float(sgn * h[win][j])
        if k + 1 >= len(times) and j == int(win.sum()) - 1:
            break  # still swinging at the end of the data: no peak yet
        out["check_angles"].append(check)
        out["overshoots"].append(peak - check)
        out["overshoot_times"].append(float(t[win][j]))
    out["heading_triggered"] = bool(out["check_angles"]) and all(
        abs(c - out["delta"]) <= math.radians(1.0) for c in out["check_angles"])
    if x is not None and y is not None and speed is not None:
        x, y, speed = (np.asarray(a, float) for a in (x, y, speed))
        s = path_length(x, y)
        out["approach_speed"] = float(np.interp(t0, t, speed))
        t10 = _cross_time(t, side * h, math.radians(10.0), int(np.searchsorted(t, t0)))
        out["initial_turning_distance"] = (float(np.interp(t10, t, s) - np.interp(t0, t, s))
                                           if math.isfinite(t10) else math.nan)
    return out


def stopping_measures(t, x, y, psi, u, speed, t0: float) -> Dict[str, float]:
    """Crash-stop measures from the astern order at t0: time to stop (headway u through 0),
    track reach (distance along the track), head reach and lateral deviation (along and across
    the approach course, + to port), approach speed. NaN where the ship has not stopped."""
    t, x, y, psi, u, speed = (np.asarray(a, float) for a in (t, x, y, psi, u, speed))
    i0 = int(np.searchsorted(t, t0))
    s = path_length(x, y)
    t_stop = _cross_time(t, -u, 0.0, i0)
    out = {"t0": float(t0), "approach_speed": float(np.interp(t0, t, speed)),
           "approach_heading": float(np.interp(t0, t, psi)), "time_to_stop": t_stop - t0,
           "track_reach": math.nan, "head_reach": math.nan, "lateral_deviation": math.nan}
    if math.isfinite(t_stop):
        x0, y0 = np.interp(t0, t, x), np.interp(t0, t, y)
        dx, dy = np.interp(t_stop, t, x) - x0, np.interp(t_stop, t, y) - y0
        c, sn = math.cos(out["approach_heading"]), math.sin(out["approach_heading"])
        out["track_reach"] = float(np.interp(t_stop, t, s) - np.interp(t0, t, s))
        out["head_reach"] = float(c * dx + sn * dy)
        out["lateral_deviation"] = float(-sn * dx + c * dy)
    return out


def _criterion(name: str, value: float, limit: float, unit: str) -> Dict[str, object]:
    ok = None if not math.isfinite(value) else bool(value <= limit)
    return {"criterion": name, "value": value, "limit": limit, "unit": unit, "passed": ok}


def zigzag_overshoot_limits(delta: float, length: float, speed: float) -> List[float]:
    """MSC.137(76) 5.4.3 limits (rad) of the first and second overshoot for a zig-zag of helm
    delta (rad); an empty list for a zig-zag the resolution does not judge."""
    lv = length / speed if speed > 0 else math.inf
    if abs(math.degrees(delta) - 10.0) < 0.5:
        first = 10.0 if lv < 10 else 20.0 if lv >= 30 else 5.0 + 0.5 * lv
        second = 25.0 if lv < 10 else 40.0 if lv >= 30 else 17.5 + 0.75 * lv
        return [math.radians(first), math.radians(second)]
    if abs(math.degrees(delta) - 20.0) < 0.5:
        return [math.radians(25.0)]
    return []


def imo_criteria(length: float, turn: Optional[dict] = None, zigzag: Optional[dict] = None,
                 stop: Optional[dict] = None) -> List[Dict[str, object]]:
    """The MSC.137(76) criteria the given measures can be judged against: a list of
    {criterion, value, limit, unit, passed} (values in L or rad; passed None when the
    measure is missing)."""
    rows = []
    if turn is not None:
        rows.append(_criterion("turning: advance", turn.get("advance", math.nan) / length, 4.5, "L"))
        rows.append(_criterion("turning: tactical diameter", turn.get("tactical_diameter", math.nan) / length,
                               5.0, "L"))
    if zigzag is not None and zigzag.get("heading_triggered", True):
        d = float(zigzag["delta"])
        tag = f"zig-zag {math.degrees(d):.0f}/{math.degrees(d):.0f}"
        if abs(math.degrees(d) - 10.0) < 0.5 and "initial_turning_distance" in zigzag:
            rows.append(_criterion("initial turning: distance to 10 deg", zigzag["initial_turning_distance"] / length,
                                   2.5, "L"))
        limits = zigzag_overshoot_limits(d, length, float(zigzag.get("approach_speed", math.nan)))
        for k, limit in enumerate(limits):
            over = zigzag["overshoots"][k] if k < len(zigzag["overshoots"]) else math.nan
            rows.append(_criterion(f"{tag}: {('first', 'second')[k]} overshoot", over, limit, "rad"))
    if stop is not None:
        rows.append(_criterion("stopping: track reach", stop.get("track_reach", math.nan) / length, 15.0, "L"))
    return rows


def compass_deg(yaw: float) -> float:
    """REP-103 yaw (rad, counter-clockwise from east) as a compass heading, deg true in [0, 360)
    (0 = north, clockwise): for people and NMEA only."""
    return (90.0 - math.degrees(yaw)) % 360.0
