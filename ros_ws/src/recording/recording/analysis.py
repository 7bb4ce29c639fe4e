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
  yaw.png              heading of every vessel, deg true
  speed_yaw_rate.png   speed over ground (kn) and rate of turn (deg/min) of every vessel
  motions.png          speed, roll and pitch histories of every vessel (the planing-hull figure;
                       roll / pitch panels only where they are more than round-off)
  orders_<vessel>.png  helm ordered / actual, engine order and rpm, thrust, girting ratio (not for
                       a vessel whose orders are all zero: an unpowered barge)
  towline_tension.png  tension at end a and end b of every rope, kN, with the breaking load,
                       and the towline angle at the ends made fast on a vessel
  rope_heights.png     heights z of selected rope elements (and the lowest element) over time
  rope_pitch.png       pitch angles of the same elements over time
  turn_<vessel>.png    a turning manoeuvre: track in approach-course axes with advance, transfer,
                       tactical diameter and the fitted steady circle
  sea_peaks.png        (a run at sea) exceedance of the tension peaks above the mean at each rope
                       end, log scale, with the fitted Weibull and the Rayleigh of the record
  sea_motion_spectra.png  (a run at sea) Welch spectra of each vessel's heave, roll, pitch, yaw
  summary.json, summary.csv (entity, quantity, value, unit), vessel_<name>.csv, rope_<name>.csv

This module is the command (its arguments, what it prints); the recording is read into arrays
by recorded_run.py, measured by measures.py, drawn by figures.py and written out by
summary_files.py. The manoeuvre measures are defined once in sim_math/turning.py and
sim_math/trials.py (zig-zag, stopping, the IMO MSC.137(76) criteria; docs/tools.md). Vessel
lengths and breaking loads come from the runner's "tugsim" metadata record, or --length /
--breaking-load.

A run at sea (the scenario's environment.waves with hs > 0, or --waves) also gets the sea
statistics (recording/sea_statistics.py; docs/tools.md "Sea statistics"): per rope end the
tension's mean, standard deviation, significant value, maximum, peak over mean, slack events
and the peaks' Weibull and Rayleigh fits; per vessel the Welch spectra of its motions, their
significant values 4 sqrt(m0) and peak periods; over the window --sea-window, else from the
end of the wave start-up ramp, else the whole run. The sea state is read from the scenario the
recording's particulars name (beside the recording, else in the scenario library) or --scenario.
Exit status: 0 done; 1 done on the readable part of a damaged file; 2 nothing to analyse.
"""
from __future__ import annotations

import argparse
import math
import os
import sys
from typing import Dict, List, Optional

from recording.figures import make_figures
from recording.mcap_io import McapFile, McapReadError, locate_recording
from recording.measures import KN, analyse_sea, analyse_trials, analyse_turns, sea_summary, summarise
from recording.sea_statistics import DEFAULT_SEGMENT, DEFAULT_SLACK_FRACTION
from recording.recorded_run import Recording
from recording.summary_files import write_csvs, write_summary_json

EXIT_OK, EXIT_DAMAGED, EXIT_NOTHING = 0, 1, 2


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
    sea = p.add_argument_group("a run at sea (sea statistics)")
    sea.add_argument("--waves", action="store_true", help="the sea statistics even when the recording's scenario "
                     "has no waves (or is not found)")
    sea.add_argument("--no-waves", action="store_true", help="no sea statistics, even for a run in waves")
    sea.add_argument("--scenario", metavar="FILE", help="the scenario of the sea state (waves, start-up ramp); "
                     "default: the one the recording's particulars name, beside the recording or in the library")
    sea.add_argument("--sea-window", type=float, nargs=2, metavar=("T0", "T1"),
                     help="window of the sea statistics (simulation s); default: from the end of the wave "
                          "start-up ramp, else the whole run")
    sea.add_argument("--slack-fraction", type=float, default=DEFAULT_SLACK_FRACTION, metavar="F",
                     help=f"a rope is slack below F times its breaking load (default {DEFAULT_SLACK_FRACTION:g})")
    sea.add_argument("--welch-segment", type=float, default=DEFAULT_SEGMENT, metavar="S",
                     help=f"Welch segment length of the motion spectra, s (default {DEFAULT_SEGMENT:g}; "
                          "the window's length when shorter)")
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
    if args.sea_window and not args.sea_window[0] < args.sea_window[1]:
        parser.error(f"--sea-window {args.sea_window[0]:g} {args.sea_window[1]:g}: T0 must be before T1")
    if not 0.0 <= args.slack_fraction < 1.0:
        parser.error(f"--slack-fraction {args.slack_fraction:g}: expected 0 <= F < 1")
    if not args.welch_segment > 0.0:
        parser.error(f"--welch-segment {args.welch_segment:g}: expected a positive number of seconds")
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
    sea = None
    try:
        waves, waves_note = sea_state(args, rec)
    except ValueError as exc:
        sys.stderr.write(f"analyze: {exc}\n")
        return EXIT_NOTHING
    if waves_note:
        say(f"analyze: {waves_note}")
    if not args.no_waves and (args.waves or (waves and waves.get("hs", 0.0) > 0.0)):
        window = args.sea_window or (None, None)
        sea = analyse_sea(rec, waves, window[0], window[1], breaking, args.slack_fraction, args.welch_segment)
        sea_summary(sea, summary)
    figures = [] if args.no_figures else make_figures(rec, out_dir, args.elements, args.snapshots, args.dpi, turns,
                                                      breaking, sea)
    summary["figures"] = figures
    files = [write_summary_json(summary, out_dir)] + write_csvs(rec, summary, out_dir)
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


def sea_state(args, rec: Recording):
    """(waves, note): the sea state of the run as a dict (hs, tp, from_deg, spectrum, ramp_time:
    the start-up ramp, s; with "scenario": the file read) from --scenario, else from the
    recording's particulars (its "waves"), else (recordings made before the particulars carried
    the sea) from the scenario they name (beside the recording, else in the scenario library);
    None without waves (or none found). The note says why none was read; ValueError for a --scenario that does not load."""
    from scenario_format.particulars import scenario_of_recording
    from scenario_format.scenario import ScenarioError, load_scenario
    path = args.scenario
    recorded = rec.particulars.get("waves")
    if path is None and isinstance(recorded, dict):   # the recording carries its sea (since issue 31)
        try:
            w = {k: float(recorded[k]) for k in ("hs", "tp", "from_deg", "ramp_time")}
        except (KeyError, TypeError, ValueError):
            return None, "the recording's particulars carry an unreadable sea state ('waves'): none read"
        return {**w, "spectrum": str(recorded.get("spectrum", "jonswap")), "scenario": rec.particulars.get("scenario")}, None
    if path is None:
        name = rec.particulars.get("scenario")
        if not name:
            return None, None
        path, why = scenario_of_recording(args.recording, name)
        if path is None:
            return None, (f"{why}: no sea state (give --scenario FILE, or --waves for the sea statistics over the "
                          "whole run)")
    try:
        sc = load_scenario(path, check_files=False)
    except ScenarioError as exc:
        if args.scenario is not None:
            raise ValueError(f"--scenario: {exc}") from None
        return None, f"the recording's scenario does not load ({exc}): no sea state"
    w = sc.environment.waves
    if w is None or w.hs == 0.0:
        return None, None
    ramp = 3.0 * w.tp if w.ramp_time is None else w.ramp_time  # as sea_environment.environment.wave_field
    return ({"hs": w.hs, "tp": w.tp, "from_deg": w.from_deg, "spectrum": w.spectrum, "ramp_time": ramp,
             "scenario": os.path.abspath(path)}, None)


def report(say, recording: str, f: McapFile, summary: dict) -> None:
    """The summary's main numbers, one line per vessel, turn and rope."""
    say(f"analyze: {os.path.abspath(recording)}: {f.message_count} messages"
        + (" (DAMAGED FILE: readable part only)" if f.problems else ""))
    for name, v in summary["vessels"].items():
        say(f"  vessel {name}: {v['samples']} states, {v['t_start']:.1f} .. {v['t_end']:.1f} s, distance "
            f"{v['distance_run']:.1f} m, max speed over ground {v['speed_max'] / KN:.2f} kn")
        if "ukc_min" in v:
            say(f"    least under-keel clearance {v['ukc_min']:.2f} m at {v['ukc_min_at']:.1f} s, largest squat "
                f"{v['squat_max']:.2f} m")
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
    if "sea" in summary:
        report_sea(say, summary)


def _num(value, fmt: str = ".2f", scale: float = 1.0) -> str:
    return "-" if value is None else f"{value * scale:{fmt}}"


def report_sea(say, summary: dict) -> None:
    """The sea statistics: the window, per rope end a line of tension statistics, per vessel a
    line of significant motions and peak periods."""
    sea = summary["sea"]
    w = sea.get("waves")
    state = (f"waves Hs {w['hs']:g} m, Tp {w['tp']:g} s, from {w['from_deg']:g} deg ({w['spectrum']}), start-up "
             f"ramp {w['ramp_time']:g} s" if w else "sea state not known")
    lo, hi = sea.get("window_start"), sea.get("window_end")
    say(f"  sea statistics: {state}; window {_num(lo, '.1f')} .. {_num(hi, '.1f')} s ({sea['window_source']})")
    for note in sea.get("notes", []):
        say(f"    note: {note}")
    for name, r in summary["ropes"].items():
        for e in ("a", "b"):
            st = r.get(f"sea_end_{e}")
            if not st or not st.get("samples"):
                continue
            slack = ("slack not counted (no breaking load)" if st.get("slack_events") is None else
                     f"{st['slack_events']} slack event(s) below {st['slack_threshold'] / 1e3:.1f} kN, "
                     f"{st['slack_time']:.1f} s slack" + (f", snatch {st['snatch_max'] / 1e3:.1f} kN"
                                                         if st.get("snatch_max") is not None else ""))
            say(f"    rope {name} end {e}: tension mean {_num(st['tension_mean'], '.1f', 1e-3)} kN, std "
                f"{_num(st['tension_std'], '.1f', 1e-3)} kN, significant {_num(st['tension_significant'], '.1f', 1e-3)} "
                f"kN, max {_num(st['tension_max'], '.1f', 1e-3)} kN (peak/mean {_num(st['peak_over_mean'])}), "
                f"{st['peaks']} peaks; {slack}; Weibull shape {_num(st['weibull_shape'])} scale "
                f"{_num(st['weibull_scale'], '.1f', 1e-3)} kN (KS {_num(st['weibull_ks'], '.3f')}), Rayleigh KS "
                f"{_num(st['rayleigh_ks'], '.3f')}")
    for name, v in summary["vessels"].items():
        parts = []
        for key, unit, scale in (("heave", "m", 1.0), ("roll", "deg", 180 / math.pi), ("pitch", "deg", 180 / math.pi),
                                 ("yaw", "deg", 180 / math.pi)):
            sp = v.get(f"sea_{key}")
            if sp and sp.get("m0") is not None:
                parts.append(f"{key} {_num(sp['significant'], '.2f', scale)} {unit}"
                             + (f" Tp {sp['peak_period']:.1f} s" if sp.get("peak_period") is not None else ""))
        if parts:
            say(f"    vessel {name} (significant 4 sqrt(m0)): " + ", ".join(parts))


if __name__ == "__main__":
    sys.exit(main())
