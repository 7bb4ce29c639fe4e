"""The summary files `analyze` writes: summary.json, summary.csv (rows entity, quantity, value,
unit; the unit of each quantity is here) and the time series behind the figures,
vessel_<name>.csv and rope_<name>.csv.
"""
from __future__ import annotations

import csv
import json
import os
import re
from typing import List

import numpy as np

from recording.recorded_run import Recording

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


# the sea statistics (measures.analyse_sea): a rope end's sea_end_a / sea_end_b and a vessel's
# sea_<motion>, whose spectral values are in the motion's own unit (its "unit" entry)
SEA_UNITS = {"slack_threshold": "N", "amplitude_significant": "N", "weibull_scale": "N", "snatch_max": "N",
             "upcrossing_period": "s", "slack_time": "s", "window_start": "s", "window_end": "s",
             "peak_period": "s", "tz": "s", "segment": "s", "peak_over_mean": "1",
             "amplitude_significant_over_std": "1", "weibull_shape": "1", "weibull_ks": "1", "rayleigh_ks": "1"}


def _sea_unit(key: str, values: dict) -> str:
    """The unit of a quantity of one sea statistics entry."""
    unit = values.get("unit", "")
    if key == "m0":
        return f"{unit}^2" if unit else ""
    if key in ("significant", "unit"):
        return unit if key == "significant" else ""
    return SEA_UNITS.get(key, _units(key))


def _units(key: str) -> str:
    """The unit of a summary quantity, from its key."""
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


def write_summary_json(summary: dict, out_dir: str) -> str:
    """summary.json in out_dir (NaN and infinity are not JSON: summarise gives None); its path."""
    path = os.path.join(out_dir, "summary.json")
    with open(path, "w") as fh:
        json.dump(summary, fh, indent=1, allow_nan=False)
    return path


def write_csvs(rec: Recording, summary: dict, out_dir: str) -> List[str]:
    """summary.csv (the summary's numbers, one row each) and the time series of every vessel and
    rope in out_dir; their paths."""
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
                                unit = _sea_unit(tk, val) if k.startswith("sea_") else _units(tk)
                                w.writerow([entity, key, "" if item is None else item, unit])
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

