"""Figures of a study (matplotlib, PNG): each measure against the first axis, one line per value
of the second axis (further axes: one line per combination); with seeds the runs as dots and
the mean over the seeds as the line; with extremes the Gumbel MPM and its confidence band."""
from __future__ import annotations

import math
import os
from typing import Dict, List

import numpy as np


KNOT = 1852.0 / 3600.0


def _label(key: str) -> str:
    return key.split(".")[-1].replace("_", " ")


def display_unit(key: str):
    """(unit, factor) a figure shows a value of this scenario or summary key in (SI inside, the
    units a towing study is read in on the axes): tensions and loads in kN, speeds in knots,
    lengths in m, periods in s; a ratio or a count without one."""
    tail = key.split(".")[-1].split("]")[-1]
    if "over" in tail or tail.endswith(("_events", "ratio")) or "order" in tail or tail in ("seed", "broken"):
        return "", 1.0
    if "tension" in tail or "load" in tail or tail.startswith("wrench") or "snatch" in tail:
        return "kN", 1e-3
    if "speed" in tail:
        return "kn", 1.0 / KNOT
    if tail in ("tp", "period") or tail.endswith(("_at", "time", "duration")):
        return "s", 1.0
    if tail in ("hs", "depth", "distance_run", "advance", "transfer", "tactical_diameter", "steady_diameter",
                "ukc_min", "squat_max", "min_element_height") or tail.endswith(("length", "_height", "_x", "_y")):
        return "m", 1.0
    return "", 1.0


def _axis_label(name: str, key: str) -> str:
    unit = display_unit(key)[0]
    return f"{name} ({unit})" if unit else name


def _lines(table, axis_keys: List[str]):
    """(label, rows) per combination of the axes after the first."""
    rest = axis_keys[1:]
    if not rest:
        yield "", table
        return
    for values, rows in table.groupby(rest, sort=True):
        values = values if isinstance(values, tuple) else (values,)
        yield ", ".join(f"{_label(k)} {v:g}" if isinstance(v, (int, float)) else f"{_label(k)} {v}"
                        for k, v in zip(rest, values)), rows


def _gumbel_overlay(ax, row, m: str, factor: float, n: int, bin_width: float, duration: float) -> None:
    """On a histogram of n runs' maxima (display units: value x factor): the fitted Gumbel density
    as expected runs per bin, and the most probable maximum in `duration` s with its band."""
    from scipy.stats import gumbel_r
    loc, scale = row[f"{m}_gumbel_loc"], row[f"{m}_gumbel_scale"]
    if not (np.isfinite(loc) and np.isfinite(scale) and scale > 0.0):
        return
    mpm, low, high = row[f"{m}_gumbel_mpm"], row[f"{m}_gumbel_mpm_low"], row[f"{m}_gumbel_mpm_high"]
    x = np.linspace(loc - 3.0 * scale, max(loc + 5.0 * scale, high), 300)
    ax.plot(x * factor, n * bin_width / factor * gumbel_r.pdf(x, loc, scale), "k-",
            label=f"Gumbel fit (loc {loc * factor:.4g}, scale {scale * factor:.3g})")
    ax.axvline(mpm * factor, color="C3", ls="--", label=f"MPM in {duration:g} s: {mpm * factor:.4g}")
    ax.axvspan(low * factor, high * factor, color="C3", alpha=0.12)


def measure_figures(table, statistics, axis_keys: List[str], measures: Dict[str, str], folder: str, extremes=None,
                    dpi: int = 110) -> List[str]:
    """One PNG per measure (name -> summary key) in folder; their paths. Nothing without an axis
    (a pure Monte Carlo study: a histogram per measure instead). Values in display_unit's units."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    os.makedirs(folder, exist_ok=True)
    ok = table[table["status"] == "ok"]
    paths = []
    for m, key in measures.items():
        fy = display_unit(key)[1]
        fig, ax = plt.subplots(figsize=(7, 4.5))
        if not axis_keys:
            values = ok[m].astype(float) * fy
            values = values[np.isfinite(values)]
            _, edges, _ = ax.hist(values, bins=max(5, int(math.sqrt(len(values) or 1))), label="runs")
            if extremes is not None and extremes.measure == m and statistics is not None and len(statistics):
                _gumbel_overlay(ax, statistics.iloc[0], m, fy, len(values), edges[1] - edges[0], extremes.duration)
                ax.legend(fontsize=8)
            ax.set_xlabel(_axis_label(m, key))
            ax.set_ylabel("runs")
        else:
            x = axis_keys[0]
            fx = display_unit(x)[1]
            for label, rows in _lines(ok, axis_keys):
                stats = rows.groupby(x, sort=True)[m].mean()
                line, = ax.plot(stats.index * fx, stats.values * fy, "o-", label=label or None)
                if len(rows) > len(stats):  # seeds: every run as a dot
                    ax.plot(rows[x] * fx, rows[m] * fy, ".", color=line.get_color(), alpha=0.4)
            if extremes is not None and extremes.measure == m and len(axis_keys) == 1:
                mpm = statistics.sort_values(x)
                ax.plot(mpm[x] * fx, mpm[f"{m}_gumbel_mpm"] * fy, "k--",
                        label=f"MPM in {extremes.duration:g} s (Gumbel)")
                ax.fill_between(mpm[x] * fx, mpm[f"{m}_gumbel_mpm_low"] * fy, mpm[f"{m}_gumbel_mpm_high"] * fy,
                                color="k", alpha=0.1)
            ax.set_xlabel(_axis_label(x, x))
            ax.set_ylabel(_axis_label(m, key))
            if ax.get_legend_handles_labels()[0]:
                ax.legend(fontsize=8)
        ax.grid(True, alpha=0.3)
        fig.tight_layout()
        path = os.path.join(folder, f"{m}.png")
        fig.savefig(path, dpi=dpi)
        plt.close(fig)
        paths.append(path)
    return paths
