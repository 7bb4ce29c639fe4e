"""The summary run_scenario prints after a run, for people: tensions in kN with their share of
the towline's breaking load (MBL), speeds in knots, headings in deg true, positions as latitude /
longitude (WGS-84, from the scenario's map origin, sim_contract.geo) and as metres east / north
of that origin. Numbers stay SI inside; these are the words at the human edge.

What only a developer reads (the StepDones the executor held back) goes to the run's log folder
(runner_notes.txt), not to the summary.
"""
from __future__ import annotations

import math
import os
from typing import List, Optional

import numpy as np

from scenario_runner import conductor as cd
from sim_contract import geo
from sim_math.rotations import yaw_from_quaternion

RUNNER_NOTES = "runner_notes.txt"  # in the log folder


def summary(sc, stats: cd.RunStats, mon) -> str:
    """The text printed after a run of scenario `sc` (its run statistics, the Monitor's tensions,
    partings and final odometry)."""
    sim_time = stats.steps_done / sc.exchange_rate
    lines = [f"scenario '{sc.name}': {sim_time:.1f} s simulated in {stats.wall_time:.1f} s wall "
             f"({sim_time / max(stats.wall_time, 1e-9):.1f}x real time, {stats.steps_done} steps at "
             f"{sc.exchange_rate:g} Hz, {sc.mode})"]
    lines += _run_lines(sc, stats)
    loads = _breaking_loads(sc)
    for rope, values in mon.tension.items():
        if values:
            lines.append("  " + tension_line(rope, np.asarray(values), loads.get(rope), mon.broken[rope]))
    origin = geo.Origin(sc.origin.latitude, sc.origin.longitude, sc.origin.height)
    for vessel, od in sorted(mon.odom.items()):
        lines.append("  " + vessel_line(vessel, od, origin))
    return "\n".join(lines)


def _run_lines(sc, stats: cd.RunStats) -> List[str]:
    """How the run went: timing, CPU, refusals, strangers, checks, events that never fired."""
    lines = []
    if stats.round_trips:
        lines.append(f"  step round trip: p50 {1e3 * cd.percentile(stats.round_trips, 50):.2f} ms, "
                     f"p99 {1e3 * cd.percentile(stats.round_trips, 99):.2f} ms")
    if stats.steps_done and math.isfinite(stats.cpu_time):
        lines.append(f"  CPU per step, all processes: {1e3 * stats.cpu_time / stats.steps_done:.2f} ms"
                     + (" (of this runner and the nodes it started; external nodes not counted)"
                        if stats.external else ""))
    if stats.compute_times:
        lines.append("  compute per step: " + ", ".join(
            f"{n} {1e3 * float(np.mean(t)):.3f} ms" for n, t in sorted(stats.compute_times.items()) if t))
    if stats.refused or any(stats.node_refused.values()):
        lines.append("  refused protocol messages (logged, not used): " + ", ".join(
            [f"runner: {n} StepDone ({why})" for why, n in sorted(stats.refused.items())] +
            [f"{node}: {n}" for node, n in sorted(stats.node_refused.items()) if n]))
    if stats.late_wire_copies:
        lines.append(f"  StepDone wire copies too late to check against the channels (over {cd.ANSWERS_KEPT} steps "
                     f"behind; not used): {stats.late_wire_copies}")
    if stats.strangers:
        lines.append("  strangers on the step protocol's topics (their messages refused): " + "; ".join(
            f"{who} from step {k}" for who, k in sorted(stats.strangers.items())))
    if stats.outputs_checked:
        lines.append(f"  step count checked: {stats.steps_done} steps, as recorded of every node "
                     f"({stats.outputs_checked} per-step output topics)")
    if stats.never_fired:
        lines.append(f"  never triggered (their condition did not hold before the end): {', '.join(stats.never_fired)}")
    if sc.mode == "realtime":
        which = (" (steps " + ", ".join(f"{k} by {1e3 * late:.1f} ms" for k, late in stats.overrun_steps[:5])
                 + (", ..." if stats.overruns > 5 else "") + ")") if stats.overrun_steps else ""
        lines.append(f"  realtime: {stats.overruns} overrun step(s){which}; lateness p99 "
                     f"{1e3 * cd.percentile(stats.lateness, 99):.2f} ms; step 0 (before the clock) took "
                     f"{1e3 * stats.first_step:.1f} ms")
    return lines


def _breaking_loads(sc) -> dict:
    """Rope -> breaking load (N or None) of the scenario's rope files; {} when they cannot be read
    (the summary then gives the tensions alone)."""
    from scenario_format.particulars import breaking_loads, particulars
    try:
        return breaking_loads(particulars(sc._path or "scenario.yaml", sc))
    except (OSError, ValueError, KeyError):
        return {}


def tension_line(rope: str, tension: np.ndarray, breaking_load: Optional[float], parted: bool) -> str:
    """"towline: tension peak 46.8 kN (30 % of MBL 157 kN), mean 20.1 kN" (N in), PARTED if it parted."""
    peak = float(tension.max())
    share = f" ({100.0 * peak / breaking_load:.0f} % of MBL {breaking_load / 1e3:.0f} kN)" if breaking_load else ""
    return (f"{rope}: tension peak {peak / 1e3:.1f} kN{share}, mean {float(tension.mean()) / 1e3:.1f} kN"
            + (", PARTED" if parted else ""))


def vessel_line(vessel: str, od, origin: geo.Origin) -> str:
    """A vessel's final state from its odometry (nav_msgs/Odometry): position as latitude /
    longitude and metres east / north of the map origin, heading deg true, speed over ground kn."""
    p, q, tw = od.pose.pose.position, od.pose.pose.orientation, od.twist.twist
    lat, lon, _ = geo.enu_to_geodetic(p.x, p.y, origin)
    heading = geo.compass_deg(yaw_from_quaternion(q.x, q.y, q.z, q.w))
    return (f"{vessel}: final position {latitude_longitude(lat, lon)} ({metres_of_origin(p.x, p.y)}), "
            f"heading {heading:.1f} deg true, speed {geo.knots(math.hypot(tw.linear.x, tw.linear.y)):.2f} kn")


def latitude_longitude(lat: float, lon: float) -> str:
    """WGS-84 degrees as a chart gives them: "51°58.800'N 4°03.000'E"."""
    def dm(value: float, pos: str, neg: str) -> str:
        minutes = round(abs(value) * 60.0, 3)
        return f"{int(minutes // 60)}°{minutes % 60:06.3f}'{pos if value >= 0 else neg}"
    return f"{dm(lat, 'N', 'S')} {dm(lon, 'E', 'W')}"


def metres_of_origin(x: float, y: float) -> str:
    """A map point in words: "120.0 m E, 35.5 m S of origin"."""
    return f"{abs(x):.1f} m {'E' if x >= 0 else 'W'}, {abs(y):.1f} m {'N' if y >= 0 else 'S'} of origin"


def runner_notes(stats: cd.RunStats) -> List[str]:
    """What only a developer of the runner reads."""
    return [f"runner: {stats.rescued} StepDone(s) the executor held back, taken directly "
            "(rclpy EventsExecutor; see sim_plumbing.ros_common.take_missed)"] if stats.rescued else []


def write_runner_notes(log_dir: str, stats: cd.RunStats) -> Optional[str]:
    """runner_notes written to <log_dir>/runner_notes.txt (when there are any); its path."""
    notes = runner_notes(stats)
    if not notes:
        return None
    path = os.path.join(log_dir, RUNNER_NOTES)
    try:
        os.makedirs(log_dir, exist_ok=True)
        with open(path, "w") as f:
            f.write("\n".join(notes) + "\n")
    except OSError:
        return None
    return path
