"""Turn a recording into the papers' figures (PNG) and a summary (JSON + CSV).

    ros2 run recording analyze output/default_demo.mcap [-o output/default_demo_analysis]

Reads any MCAP recording that has the topic contract's topics (this project's recorder, a
replay recorded again, rosbag2): /<vessel>/odom, /<vessel>/status, /<vessel>/command,
/<rope>/state, /<rope>/end_a|end_b/wrench, /scenario/events; vessels and ropes are found by
topic name and type. A rosbag2 bag directory is read through its .mcap file; a sqlite3 bag
(.db3 file or directory) is refused with the command that converts it (exit status 2). Time
is the messages' header stamp (simulation time), so a re-recorded replay gives the same
results as the original; duplicated stamps (a looped replay) are kept once. A truncated or
corrupt file is reported (path, byte offset, what is wrong) and its readable part is analysed.

Writes to the output directory (default: <recording without .mcap>_analysis/):
  tracks.png           XY tracks (map frame, x east, y north) of every vessel and rope element
                       (snapshots of each rope and the paths of selected elements)
  yaw.png              yaw (heading) angle of every vessel, unwrapped, deg
  speed_yaw_rate.png   speed over ground and yaw rate of every vessel
  motions.png          speed, roll and pitch histories of every vessel (the planing-hull figure;
                       roll / pitch panels only where they are more than round-off)
  orders_<vessel>.png  helm ordered / actual, engine order and rpm, thrust, girting ratio
  towline_tension.png  tension at end a and end b of every rope, kN, with the breaking load,
                       and the towline angle at the ends made fast on a vessel
  rope_heights.png     heights z of selected rope elements (and the lowest element) over time
  rope_pitch.png       pitch angles of the same elements over time
  turn_<vessel>.png    a turning manoeuvre: track in approach-course axes with advance, transfer,
                       tactical diameter and the fitted steady circle
  summary.json, summary.csv (entity, quantity, value, unit), vessel_<name>.csv, rope_<name>.csv

The manoeuvre measures are defined once in sim_math/turning.py and sim_math/trials.py (zig-zag,
stopping, the IMO MSC.137(76) criteria; docs/tools.md). Vessel lengths and breaking loads come
from the runner's "tugsim" metadata record, or --length / --breaking-load.
Exit status: 0 done; 1 done on the readable part of a damaged file; 2 nothing to analyse.
"""
from __future__ import annotations

import argparse
import csv
import json
import math
import os
import re
import sys
from typing import Dict, List, Optional

import numpy as np

from recording.mcap_io import McapFile, McapReadError, locate_recording
from recording.measures import KN, analyse_trials, analyse_turns, summarise, towline_angle
from recording.recorded_run import Recording, status_column

EXIT_OK, EXIT_DAMAGED, EXIT_NOTHING = 0, 1, 2


# ---------------------------------------------------------------------------------------
# Figures
# ---------------------------------------------------------------------------------------
def _element_picks(n: int, k: int) -> List[int]:
    if n <= 0:
        return []
    return sorted(set(int(round(f * (n - 1))) for f in np.linspace(0.0, 1.0, min(k, n))))


def _rope_element_series(rope: dict, k: int, key: str):
    """Values of elements at fixed fractions along the rope (index by the current element count)."""
    fracs = np.linspace(0.0, 1.0, k)
    out = np.full((len(rope["t"]), k), np.nan)
    for j, arr in enumerate(rope["pos"] if key == "z" else rope["pitch"]):
        n = len(arr)
        if not n:
            continue
        idx = np.round(fracs * (n - 1)).astype(int)
        out[j] = arr[idx, 2] if key == "z" else arr[idx]
    return fracs, out


class _Figures:
    """Saves figures as PNG files in out_dir and keeps their paths."""

    def __init__(self, plt, out_dir: str, dpi: int):
        self.plt, self.out_dir, self.dpi = plt, out_dir, dpi
        self.files: List[str] = []

    def save(self, fig, name: str) -> None:
        path = os.path.join(self.out_dir, name)
        fig.tight_layout()
        fig.savefig(path, dpi=self.dpi)
        self.plt.close(fig)
        self.files.append(path)


def make_figures(rec: Recording, out_dir: str, elements: int = 5, snapshots: int = 6, dpi: int = 110,
                 turns: Optional[Dict[str, dict]] = None,
                 breaking: Optional[Dict[str, Optional[float]]] = None) -> List[str]:
    """Every figure the recording has data for (see the module docstring); their paths."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    out = _Figures(plt, out_dir, dpi)
    if rec.vessels or rec.ropes:
        _tracks_figure(out, rec, snapshots)
    if rec.vessels:
        _yaw_figure(out, rec)
        _speed_yaw_rate_figure(out, rec)
        _motions_figure(out, rec)
    for name, v in rec.vessels.items():
        if "status" in v and len(v["status"]["t"]):
            _orders_figure(out, name, v)
    ropes = {n: r for n, r in rec.ropes.items() if "t" in r or "wrench_a" in r or "wrench_b" in r}
    if ropes:
        _tension_figure(out, rec, ropes, breaking or {})
    chains = {n: r for n, r in rec.ropes.items() if "pos" in r and len(r["t"])}
    if chains:
        _rope_element_figures(out, chains, elements)
    for name, m in (turns or {}).items():
        if "_along" in m:
            _turn_figure(out, name, m)
    return out.files


def _tracks_figure(out: _Figures, rec: Recording, snapshots: int) -> None:
    """XY tracks of the vessels (heading arrows) and rope snapshots with paths of three elements."""
    plt = out.plt
    fig, ax = plt.subplots(figsize=(8, 7))
    for name, v in rec.vessels.items():
        line, = ax.plot(v["x"], v["y"], lw=1.6, label=f"{name}")
        ax.plot(v["x"][0], v["y"][0], "o", color=line.get_color(), ms=4)
        for j in np.linspace(0, len(v["t"]) - 1, snapshots).astype(int):  # heading arrows
            ax.annotate("", xy=(v["x"][j] + 8 * math.cos(v["yaw"][j]), v["y"][j] + 8 * math.sin(v["yaw"][j])),
                        xytext=(v["x"][j], v["y"][j]), arrowprops=dict(arrowstyle="->", color=line.get_color()))
    for name, rope in rec.ropes.items():
        if "pos" not in rope or not len(rope["t"]):
            continue
        cmap = plt.get_cmap("viridis")
        js = np.linspace(0, len(rope["t"]) - 1, snapshots).astype(int)
        for c, j in enumerate(js):
            p = rope["pos"][j]
            if len(p):
                ax.plot(p[:, 0], p[:, 1], ".-", ms=2, lw=0.8, color=cmap(c / max(1, len(js) - 1)),
                        label=f"{name} elements t={rope['t'][j]:.0f} s")
        fr, _ = _rope_element_series(rope, 3, "z")
        for f in fr:
            xs = [p[int(round(f * (len(p) - 1))), 0] if len(p) else np.nan for p in rope["pos"]]
            ys = [p[int(round(f * (len(p) - 1))), 1] if len(p) else np.nan for p in rope["pos"]]
            ax.plot(xs, ys, ":", lw=0.8, color="gray")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x east (m)")
    ax.set_ylabel("y north (m)")
    ax.set_title(f"XY tracks (map frame): {os.path.basename(rec.path)}")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="best")
    out.save(fig, "tracks.png")


def _yaw_figure(out: _Figures, rec: Recording) -> None:
    fig, ax = out.plt.subplots(figsize=(8, 4))
    for name, v in rec.vessels.items():
        ax.plot(v["t"], np.degrees(v["yaw_unwrapped"]), label=name)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("yaw (deg, unwrapped, + to port)")
    ax.set_title("Yaw angles")
    ax.grid(alpha=0.3)
    ax.legend()
    out.save(fig, "yaw.png")


def _speed_yaw_rate_figure(out: _Figures, rec: Recording) -> None:
    fig, axs = out.plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    for name, v in rec.vessels.items():
        axs[0].plot(v["t"], v["speed"], label=name)
        axs[1].plot(v["t"], np.degrees(v["r"]), label=name)
    axs[0].set_ylabel("speed over ground (m/s)")
    axs[1].set_ylabel("yaw rate (deg/s)")
    axs[1].set_xlabel("time (s)")
    for a in axs:
        a.grid(alpha=0.3)
        a.legend()
    axs[0].set_title("Speed and yaw rate")
    out.save(fig, "speed_yaw_rate.png")


NOISE_DEG = 0.01  # a roll or pitch history that never spans this much is a 3-DOF model's round-off


def _motions_figure(out: _Figures, rec: Recording) -> None:
    """Speed, and roll, pitch and rise where some vessel has them (a 3-DOF model's pitch is
    round-off and gets no panel; the rise is reported by planing hulls)."""
    panels = [("speed", "speed (m/s)", {n: (v["t"], v["speed"]) for n, v in rec.vessels.items()})]
    for key, label in (("roll", "roll (deg, + stbd down)"), ("pitch", "pitch (deg, + bow down)")):
        series = {n: (v["t"], np.degrees(v[key])) for n, v in rec.vessels.items()}
        if any(np.ptp(y) > NOISE_DEG for _, y in series.values() if y.size):
            panels.append((key, label, series))
    risers = {n: (v["status"]["t"], status_column(v["status"], "rise")) for n, v in rec.vessels.items()
              if "status" in v and np.any(status_column(v["status"], "rise") != 0.0)}
    if risers:
        panels.append(("rise", "rise (m)", risers))
    fig, axs = out.plt.subplots(len(panels), 1, figsize=(8, max(3.5, 2.7 * len(panels))), sharex=True, squeeze=False)
    axs = axs[:, 0]
    for a, (_key, label, series) in zip(axs, panels):
        for name, (t, y) in series.items():
            a.plot(t, y, label=name)
        a.set_ylabel(label)
    axs[-1].set_xlabel("time (s)")
    for a in axs:
        a.grid(alpha=0.3)
        a.legend()
    axs[0].set_title("Speed" + "".join(f", {k}" for k, _, _ in panels[1:]) + " histories")
    out.save(fig, "motions.png")


def _orders_figure(out: _Figures, name: str, v: dict) -> None:
    """The orders a vessel was given and what they did: helm (or bucket) ordered and actual,
    engine order and shaft speed, thrust, and the girting ratio with its warning threshold when
    the vessel reports one."""
    st = v["status"]
    t = st["t"]
    girting = status_column(st, "girting_ratio")
    rows = 4 if np.any(girting != 0.0) else 3
    fig, axs = out.plt.subplots(rows, 1, figsize=(8, 2.5 * rows), sharex=True)
    axs[0].plot(t, np.degrees(status_column(st, "steering_angle_ordered")), "--", label="ordered")
    axs[0].plot(t, np.degrees(status_column(st, "steering_angle")), label="actual")
    axs[0].set_ylabel("rudder / nozzle (deg, + port)")
    axs[1].plot(t, status_column(st, "engine_order"), label="engine order")
    axs[1].set_ylabel("engine order (-1..1)")
    rpm = axs[1].twinx()
    rpm.plot(t, status_column(st, "shaft_speed") * 60.0 / (2.0 * math.pi), color="C3", lw=1, label="shaft")
    rpm.set_ylabel("shaft (rpm)", color="C3")
    axs[2].plot(t, status_column(st, "thrust") / 1e3, label="thrust")
    axs[2].set_ylabel("thrust (kN)")
    if rows == 4:
        axs[3].plot(t, girting, label="girting ratio")
        axs[3].plot(t, status_column(st, "girting_threshold"), "r--", lw=1, label="warning threshold")
        axs[3].set_ylabel("girting ratio")
    axs[-1].set_xlabel("time (s)")
    for a in axs:
        a.grid(alpha=0.3)
        a.legend(fontsize=7, loc="upper left")
    axs[0].set_title(f"Orders and response of {name}")
    out.save(fig, f"orders_{name}.png")


def _tension_figure(out: _Figures, rec: Recording, ropes: Dict[str, dict], breaking: Dict[str, Optional[float]]) -> None:
    """End tensions from the rope state, else from the end wrenches, with the breaking load;
    under each rope the towline angle at the ends that are made fast on a vessel."""
    angles: Dict[str, list] = {}
    for n in ropes:
        ends = ((towline_angle(rec, n, e), e) for e in ("a", "b"))
        angles[n] = [got + (e,) for got, e in ends if got]
    rows = sum(1 + bool(angles[n]) for n in ropes)
    fig, axs = out.plt.subplots(rows, 1, figsize=(8, 3.2 * rows), squeeze=False)
    axs = list(axs[:, 0])
    for name, rope in ropes.items():
        a = axs.pop(0)
        if "t" in rope:
            a.plot(rope["t"], rope["tension_a"] / 1e3, label=f"{name} end a")
            a.plot(rope["t"], rope["tension_b"] / 1e3, "--", label=f"{name} end b")
        else:
            for end in ("a", "b"):
                if f"wrench_{end}" in rope:
                    w = rope[f"wrench_{end}"]
                    a.plot(w["t"], w["tension"] / 1e3, label=f"{name} end {end} (wrench)")
        if breaking.get(name):
            a.axhline(breaking[name] / 1e3, color="r", ls=":", label=f"breaking load {breaking[name] / 1e3:.0f} kN")
        a.set_ylabel("tension (kN)")
        a.set_xlabel("time (s)")
        a.set_title(f"Towline {name}: tension at both ends")
        a.grid(alpha=0.3)
        a.legend(fontsize=7)
        if angles[name]:
            b = axs.pop(0)
            for vessel, t, ang, end in angles[name]:
                deg = np.degrees(ang)
                deg[1:][np.abs(np.diff(deg)) > 180.0] = np.nan  # no vertical line across the +-180 seam
                b.plot(t, deg, label=f"end {end} on {vessel}")
            b.set_ylabel("towline angle (deg from bow, + port)")
            b.set_xlabel("time (s)")
            b.set_ylim(-185, 185)
            b.set_yticks([-180, -90, 0, 90, 180])
            b.grid(alpha=0.3)
            b.legend(fontsize=7)
    out.save(fig, "towline_tension.png")


def _rope_element_figures(out: _Figures, chains: Dict[str, dict], elements: int) -> None:
    """Heights and pitch angles of `elements` elements spread along each rope."""
    for key, fname, ylabel, ttl in (("z", "rope_heights.png", "element height z (m)", "Rope element heights"),
                                    ("pitch", "rope_pitch.png", "element pitch (deg, + axis down to end a)",
                                     "Rope element pitch angles")):
        fig, axs = out.plt.subplots(len(chains), 1, figsize=(8, 3.8 * len(chains)), squeeze=False)
        for a, (name, rope) in zip(axs[:, 0], chains.items()):
            fracs, vals = _rope_element_series(rope, elements, key)
            for i, f in enumerate(fracs):
                y = vals[:, i] if key == "z" else np.degrees(vals[:, i])
                a.plot(rope["t"], y, lw=1, label=f"{name} element at {f:.2f} of length (end a = 0)")
            if key == "z":
                a.plot(rope["t"], rope["min_z"], "k--", lw=1, label=f"{name} lowest element")
            a.set_ylabel(ylabel)
            a.grid(alpha=0.3)
            a.legend(fontsize=7)
        axs[-1, 0].set_xlabel("time (s)")
        axs[0, 0].set_title(ttl)
        out.save(fig, fname)


def _turn_figure(out: _Figures, name: str, m: dict) -> None:
    """A turn in approach-course axes with the 90 and 180 deg points and the steady circle."""
    fig, ax = out.plt.subplots(figsize=(7, 7))
    ax.plot(m["_across"], m["_along"], lw=1.5, label=f"{name} track from execute (t0 = {m['t0']:.1f} s)")
    if math.isfinite(m.get("advance", math.nan)):
        ax.plot([m["transfer"]], [m["advance"]], "o", label=f"90 deg: advance {m['advance']:.1f} m, "
                                                             f"transfer {m['transfer']:.1f} m")
    if math.isfinite(m.get("tactical_diameter", math.nan)):
        j = int(np.argmax(m["_dpsi"] >= math.pi))
        ax.plot([m["tactical_diameter"]], [m["_along"][j]], "s",
                label=f"180 deg: tactical diameter {m['tactical_diameter']:.1f} m")
    if math.isfinite(m.get("steady_diameter", math.nan)):
        psi0, x0, y0 = m["_psi0"], m["_x0"], m["_y0"]
        c, s, side = math.cos(psi0), math.sin(psi0), m["turn_direction"]
        dx, dy = m["steady_centre_x"] - x0, m["steady_centre_y"] - y0
        ca, cx = c * dx + s * dy, side * (-s * dx + c * dy)
        ang = np.linspace(0, 2 * math.pi, 200)
        rr = m["steady_diameter"] / 2
        ax.plot(cx + rr * np.cos(ang), ca + rr * np.sin(ang), "k:", lw=1,
                label=f"steady circle: D = {m['steady_diameter']:.1f} m")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("transfer direction: across the approach course, towards the turn (m)")
    ax.set_ylabel("advance direction: along the approach course (m)")
    ax.set_title(f"Turning manoeuvre of {name}")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    out.save(fig, f"turn_{name}.png")


# ---------------------------------------------------------------------------------------
# Summary
# ---------------------------------------------------------------------------------------
TURN_UNITS = {"t0": "s", "t1": "s", "approach_speed": "m/s", "approach_heading": "rad", "turn_direction": "1",
              "heading_change": "rad", "advance": "m", "transfer": "m", "time_to_90": "s",
              "tactical_diameter": "m", "time_to_180": "s", "steady_window_from": "rad",
              "steady_window_span": "rad", "steady_diameter": "m", "steady_centre_x": "m", "steady_centre_y": "m",
              "steady_fit_rms": "m", "steady_speed": "m/s", "steady_yaw_rate": "rad/s", "steady_drift_angle": "rad",
              "steady_diameter_kinematic": "m", "speed_loss": "1", "steady_t_start": "s", "helm_angle": "rad",
              "delta": "rad", "execute_times": "s", "check_angles": "rad", "overshoots": "rad",
              "overshoot_times": "s", "initial_turning_distance": "m", "time_to_stop": "s", "track_reach": "m",
              "head_reach": "m", "lateral_deviation": "m", "engine_order": "1", "length": "m",
              "breaking_load": "N", "peak_over_breaking_load": "1"}


def _units(key: str) -> str:
    if key in TURN_UNITS:
        return TURN_UNITS[key]
    if key.endswith("_kn"):
        return "kn"
    if key.endswith("_deg_true"):
        return "deg true"
    for pat, unit in (("tension|wrench", "N"), ("speed", "m/s"), ("yaw_rate", "rad/s"), ("yaw|roll|pitch|heading", "rad"),
                      ("^t_|_at$", "s"), ("^[xy]_|distance|length|height|rise", "m")):
        if re.search(pat, key):
            return unit
    return ""


def write_csvs(rec: Recording, summary: dict, out_dir: str) -> List[str]:
    files = []
    path = os.path.join(out_dir, "summary.csv")
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["entity", "quantity", "value", "unit"])
        for kind in ("vessels", "ropes"):
            for name, vals in summary[kind].items():
                entity = f"{kind[:-1]}/{name}"
                for k, val in vals.items():
                    if k == "imo":
                        for row in val:
                            w.writerow([entity, f"imo.{row['criterion']}", "" if row["value"] is None else row["value"],
                                        row["unit"]])
                            w.writerow([entity, f"imo.{row['criterion']}.limit", row["limit"], row["unit"]])
                            w.writerow([entity, f"imo.{row['criterion']}.passed",
                                        "" if row["passed"] is None else row["passed"], ""])
                    elif isinstance(val, dict):  # turn, zigzag, stopping
                        for tk, tv in val.items():
                            if tk == "notes":
                                continue
                            for j, item in enumerate(tv if isinstance(tv, list) else [tv]):
                                key = f"{k}.{tk}" + (f"[{j}]" if isinstance(tv, list) else "")
                                w.writerow([entity, key, "" if item is None else item, _units(tk)])
                    else:
                        w.writerow([entity, k, "" if val is None else val, _units(k)])
    files.append(path)
    for name, v in rec.vessels.items():
        path = os.path.join(out_dir, f"vessel_{name}.csv")
        cols = ["t", "x", "y", "z", "roll", "pitch", "yaw", "u", "v", "w", "p", "q", "r", "speed"]
        np.savetxt(path, np.column_stack([v[c] for c in cols]), delimiter=",", header=",".join(cols),
                   comments="", fmt="%.9g")
        files.append(path)
    for name, r in rec.ropes.items():
        if "t" not in r:
            continue
        path = os.path.join(out_dir, f"rope_{name}.csv")
        cols = ["t", "tension_a", "tension_b", "max_tension", "min_z", "stretched", "unstretched", "broken"]
        np.savetxt(path, np.column_stack([np.asarray(r[c], float) for c in cols]), delimiter=",",
                   header=",".join(cols), comments="", fmt="%.9g")
        files.append(path)
    return files


def _named_values(pairs: Optional[List[str]], option: str) -> Dict[str, float]:
    """NAME=VALUE pairs of a command-line option; ValueError naming the bad one."""
    out = {}
    for item in pairs or []:
        name, sep, value = item.partition("=")
        try:
            number = float(value)
        except ValueError:
            number = math.nan
        if not sep or not name or not math.isfinite(number) or number <= 0:
            raise ValueError(f"{option} {item!r}: expected NAME=VALUE with a positive number")
        out[name] = number
    return out


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="analyze", description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog="Exit status: 0 done; 1 damaged file, its readable part analysed; "
                                       "2 nothing to analyse.")
    p.add_argument("recording", help="MCAP file, or a rosbag2 bag directory holding one (sqlite3 .db3 bags: "
                                      "convert them first, the error message says how)")
    p.add_argument("-o", "--output", help="output directory (default: <recording>_analysis next to the file)")
    p.add_argument("--vessels", nargs="+", help="only these vessels (namespaces); default: every /<name>/odom")
    p.add_argument("--ropes", nargs="+", help="only these ropes; default: every /<name>/state")
    p.add_argument("--turn-start", type=float, metavar="S", help="execute time of the turn (simulation s); "
                   "default: the first helm order of >= 1 deg found on the command or status topic")
    p.add_argument("--turn-end", type=float, metavar="S", help="end of the turn; default: next helm order or the end")
    p.add_argument("--length", nargs="+", metavar="VESSEL=M",
                   help="vessel length for the IMO criteria (default: from the run's metadata)")
    p.add_argument("--breaking-load", nargs="+", metavar="ROPE=N",
                   help="rope breaking load for the tension figure, N (default: from the run's metadata)")
    p.add_argument("--steady-from-deg", type=float, default=180.0,
                   help="heading change before which the turn is never taken as steady (default 180)")
    p.add_argument("--elements", type=int, default=5, help="rope elements per height/pitch figure (default 5)")
    p.add_argument("--snapshots", type=int, default=6, help="rope shapes drawn in the XY figure (default 6)")
    p.add_argument("--dpi", type=int, default=110)
    p.add_argument("--no-figures", action="store_true", help="only the summary files")
    p.add_argument("--quiet", action="store_true")
    return p


def main(argv: Optional[List[str]] = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        lengths = _named_values(args.length, "--length")
        breaking = _named_values(args.breaking_load, "--breaking-load")
    except ValueError as exc:
        parser.error(str(exc))
    say = (lambda s: None) if args.quiet else (lambda s: print(s, flush=True))
    try:
        rec = read_recording(args, say)
    except McapReadError as exc:
        sys.stderr.write(f"analyze: {exc}\n")
        return EXIT_NOTHING
    if not rec.vessels and not rec.ropes:
        sys.stderr.write(f"analyze: {args.recording}: no contract topics with readable messages (/<vessel>/odom "
                         f"nav_msgs/Odometry, /<rope>/state tug_msgs/RopeState); nothing to analyse\n")
        return EXIT_NOTHING
    out_dir = args.output or os.path.splitext(os.path.abspath(args.recording))[0] + "_analysis"
    os.makedirs(out_dir, exist_ok=True)
    known = rec.particulars
    lengths = {**{n: v.get("length") for n, v in known.get("vessels", {}).items()}, **lengths}
    breaking = {**{n: r.get("breaking_load") for n, r in known.get("ropes", {}).items()}, **breaking}
    turns = analyse_turns(rec, args.turn_start, args.turn_end, args.steady_from_deg)
    summary = summarise(rec, turns, analyse_trials(rec), lengths, breaking)
    figures = [] if args.no_figures else make_figures(rec, out_dir, args.elements, args.snapshots, args.dpi, turns,
                                                      breaking)
    summary["figures"] = figures
    path = os.path.join(out_dir, "summary.json")
    with open(path, "w") as fh:
        json.dump(summary, fh, indent=1, allow_nan=False)
    files = [path] + write_csvs(rec, summary, out_dir)
    report(say, args.recording, rec.file, summary)
    say(f"  wrote {len(figures)} figure(s) and {len(files)} summary file(s) to {out_dir}")
    return EXIT_DAMAGED if rec.file.problems else EXIT_OK


def read_recording(args, say) -> Recording:
    """The recording args.recording names, decoded; what is wrong with it goes to stderr
    (damage, undecodable messages, topics not analysed). McapReadError if nothing is readable."""
    path, note = locate_recording(args.recording)  # a rosbag2 directory: its .mcap; sqlite3: what to do
    if note:
        say(f"analyze: {note}")
    rec = Recording(path, args.vessels, args.ropes)
    if rec.file.problems:
        sys.stderr.write(f"analyze: the recording is damaged; analysing its readable part:\n{rec.file.report()}\n")
    for line in rec.decoder.report():
        sys.stderr.write(f"analyze: {line}\n")
    for note in sorted(set(rec.decoder.notes)):
        sys.stderr.write(f"analyze: {note}\n")
    return rec


def report(say, recording: str, f: McapFile, summary: dict) -> None:
    """The summary's main numbers, one line per vessel, turn and rope."""
    say(f"analyze: {os.path.abspath(recording)}: {f.message_count} messages"
        + (" (DAMAGED FILE: readable part only)" if f.problems else ""))
    for name, v in summary["vessels"].items():
        say(f"  vessel {name}: {v['samples']} states, {v['t_start']:.1f} .. {v['t_end']:.1f} s, distance "
            f"{v['distance_run']:.1f} m, max speed {v['speed_max']:.2f} m/s")
        t = v.get("turn")
        if t:
            fmt = lambda k, scale=1.0: "-" if t.get(k) is None else f"{t[k] * scale:.1f}"  # noqa: E731
            say(f"    turn from t0 = {t['t0']:.1f} s ({'port' if t.get('turn_direction', 1) > 0 else 'starboard'}"
                f", {fmt('approach_speed_kn')} kn on {fmt('approach_heading_deg_true')} deg true): "
                f"advance {fmt('advance')} m, transfer {fmt('transfer')} m, tactical diameter "
                f"{fmt('tactical_diameter')} m, steady diameter {fmt('steady_diameter')} m (2U/r "
                f"{fmt('steady_diameter_kinematic')} m), steady speed {fmt('steady_speed', 1 / KN)} kn, "
                f"yaw rate {fmt('steady_yaw_rate', 180 / math.pi)} deg/s"
                + (f"; {t['notes']}" if t.get("notes") else ""))
        z = v.get("zigzag")
        if z:
            deg = ", ".join(f"{math.degrees(o):.1f}" for o in z["overshoots"]) or "-"
            say(f"    zig-zag {math.degrees(z['delta']):.0f}/{math.degrees(z['delta']):.0f} from "
                f"{z.get('approach_speed_kn', math.nan):.1f} kn on {z.get('approach_heading_deg_true', math.nan):05.1f} deg "
                f"true: overshoots {deg} deg")
        st = v.get("stopping")
        if st:
            reach = "not stopped" if st["track_reach"] is None else f"track reach {st['track_reach']:.0f} m, head " \
                f"reach {st['head_reach']:.0f} m, lateral {st['lateral_deviation']:.0f} m, in {st['time_to_stop']:.0f} s"
            say(f"    stop (engine {st['engine_order']:+.2f}) from {st.get('approach_speed_kn', math.nan):.1f} kn: {reach}")
        if v.get("imo"):
            say(f"    IMO MSC.137(76), L = {v['length']:.1f} m:")
            say("      | criterion | value | limit | holds |")
            for row in v["imo"]:
                value = "-" if row["value"] is None else f"{row['value']:.2f}"
                holds = {True: "yes", False: "NO", None: "not measured"}[row["passed"]]
                say(f"      | {row['criterion']} | {value} {row['unit']} | {row['limit']:.2f} {row['unit']} | {holds} |")
    for name, r in summary["ropes"].items():
        if "tension_a_max" in r:
            say(f"  rope {name}: max tension end a {r['tension_a_max'] / 1e3:.1f} kN, end b "
                f"{r['tension_b_max'] / 1e3:.1f} kN, lowest element z {r['min_element_height']:.2f} m"
                + (f", peak {100 * r['peak_over_breaking_load']:.0f} % of the breaking load"
                   if r.get("peak_over_breaking_load") is not None else "")
                + (f", parted at {r['broken_at']:.1f} s" if r.get("broken") else ""))


if __name__ == "__main__":
    sys.exit(main())
