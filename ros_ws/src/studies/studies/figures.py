"""Figures of a study (matplotlib, PNG): each measure against the first axis, one line per value
of the second axis (further axes: one line per combination); with seeds the runs as dots and
the mean over the seeds as the line; with extremes the Gumbel MPM and its confidence band."""
from __future__ import annotations

import math
import os
from typing import List

import numpy as np


def _label(key: str) -> str:
    return key.split(".")[-1].replace("_", " ")


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


def measure_figures(table, statistics, axis_keys: List[str], measures: List[str], folder: str, extremes=None,
                    dpi: int = 110) -> List[str]:
    """One PNG per measure in folder; their paths. Nothing without an axis (a pure Monte Carlo
    study: a histogram per measure instead)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    os.makedirs(folder, exist_ok=True)
    ok = table[table["status"] == "ok"]
    paths = []
    for m in measures:
        fig, ax = plt.subplots(figsize=(7, 4.5))
        if not axis_keys:
            values = ok[m].astype(float)
            ax.hist(values[np.isfinite(values)], bins=max(5, int(math.sqrt(len(values) or 1))))
            ax.set_xlabel(m)
            ax.set_ylabel("runs")
        else:
            x = axis_keys[0]
            for label, rows in _lines(ok, axis_keys):
                stats = rows.groupby(x, sort=True)[m].mean()
                line, = ax.plot(stats.index, stats.values, "o-", label=label or None)
                if len(rows) > len(stats):  # seeds: every run as a dot
                    ax.plot(rows[x], rows[m], ".", color=line.get_color(), alpha=0.4)
            if extremes is not None and extremes.measure == m and len(axis_keys) == 1:
                mpm = statistics.sort_values(x)
                ax.plot(mpm[x], mpm[f"{m}_gumbel_mpm"], "k--", label=f"MPM in {extremes.duration:g} s (Gumbel)")
                ax.fill_between(mpm[x], mpm[f"{m}_gumbel_mpm_low"], mpm[f"{m}_gumbel_mpm_high"], color="k", alpha=0.1)
            ax.set_xlabel(x)
            ax.set_ylabel(m)
            if ax.get_legend_handles_labels()[0]:
                ax.legend(fontsize=8)
        ax.grid(True, alpha=0.3)
        fig.tight_layout()
        path = os.path.join(folder, f"{m}.png")
        fig.savefig(path, dpi=dpi)
        plt.close(fig)
        paths.append(path)
    return paths
