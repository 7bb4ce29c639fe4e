"""Extreme-value statistics of a study's runs (ROS-free): per configuration the measures'
statistics over the seeds, and a Gumbel fit of one measure's per-run maxima with its most
probable maximum (MPM) for a stated duration.

Each run's peak is the maximum of a record of `record` s; over a duration D = n records the
maximum of n independent Gumbel(loc, scale) maxima is Gumbel(loc + scale ln n, scale) (the
Gumbel is max-stable), whose mode, the MPM, is loc + scale ln(D / record). The fit is scipy's
maximum likelihood (scipy.stats.gumbel_r.fit); the confidence intervals are the asymptotic normal
ones of that estimator, from the inverse of the Gumbel's Fisher information per sample,
scale^2 / n * [[1 + 6 (1 - g)^2 / pi^2, 6 (1 - g) / pi^2], [6 (1 - g) / pi^2, 6 / pi^2]]
(g: Euler's constant; rows loc, scale), carried to the MPM by the delta method.
"""
from __future__ import annotations

import math
from typing import Dict, List, Sequence

import numpy as np

EULER_GAMMA = 0.5772156649015329


def gumbel_covariance(scale: float, n: int) -> np.ndarray:
    """Asymptotic covariance of the maximum-likelihood (loc, scale) of n Gumbel samples."""
    a = 6.0 / math.pi ** 2
    one = 1.0 - EULER_GAMMA
    return scale ** 2 / n * np.array([[1.0 + a * one ** 2, a * one], [a * one, a]])


def gumbel_fit(maxima: Sequence[float], duration: float, record: float, confidence: float = 0.95) -> Dict[str, float]:
    """The Gumbel fit of per-run maxima (each over `record` s) and the most probable maximum in
    `duration` s, with confidence intervals: {samples, loc, scale, loc_low, loc_high, scale_low,
    scale_high, mpm, mpm_low, mpm_high, records}. NaN values for fewer than 3 finite samples or
    samples all equal (no spread to fit)."""
    from scipy import stats
    x = np.asarray([v for v in maxima if v is not None and math.isfinite(v)], float)
    keys = ("loc", "scale", "loc_low", "loc_high", "scale_low", "scale_high", "mpm", "mpm_low", "mpm_high")
    out = {"samples": int(x.size), "records": duration / record, **{k: math.nan for k in keys}}
    if x.size < 3 or np.ptp(x) <= 1e-12 * max(1.0, float(np.abs(x).max())):
        return out
    loc, scale = stats.gumbel_r.fit(x)
    z = stats.norm.ppf(0.5 + confidence / 2.0)
    cov = gumbel_covariance(scale, x.size)
    ln_n = math.log(duration / record)
    gradient = np.array([1.0, ln_n])
    mpm, mpm_sd = loc + scale * ln_n, math.sqrt(gradient @ cov @ gradient)
    loc_sd, scale_sd = math.sqrt(cov[0, 0]), math.sqrt(cov[1, 1])
    out.update(loc=loc, scale=scale, loc_low=loc - z * loc_sd, loc_high=loc + z * loc_sd,
               scale_low=scale - z * scale_sd, scale_high=scale + z * scale_sd,
               mpm=mpm, mpm_low=mpm - z * mpm_sd, mpm_high=mpm + z * mpm_sd)
    return {k: float(v) if isinstance(v, (float, np.floating)) else v for k, v in out.items()}


def configuration_statistics(table, axis_keys: List[str], measures: List[str], extremes=None,
                             record: float = math.nan):
    """One row per configuration (the axes' values): runs, failed, and per measure its count,
    mean, std, min and max over the seeds (the successful runs); with `extremes` (the study's
    Extremes) also the Gumbel fit of that measure, columns <measure>_gumbel_<key>."""
    import pandas as pd
    rows = []
    for configuration, group in table.groupby("configuration", sort=True):
        row = {"configuration": int(configuration)}
        row.update({key: group[key].iloc[0] for key in axis_keys})
        ok = group[group["status"] == "ok"]
        row.update(runs=int(len(group)), failed=int((group["status"] != "ok").sum()))
        for m in measures:
            values = ok[m].astype(float)
            values = values[np.isfinite(values)]
            row.update({f"{m}_count": int(values.size), f"{m}_mean": values.mean() if values.size else math.nan,
                        f"{m}_std": values.std(ddof=1) if values.size > 1 else math.nan,
                        f"{m}_min": values.min() if values.size else math.nan,
                        f"{m}_max": values.max() if values.size else math.nan})
        if extremes is not None:
            fit = gumbel_fit(ok[extremes.measure].astype(float).tolist(), extremes.duration,
                             extremes.record or record, extremes.confidence)
            row.update({f"{extremes.measure}_gumbel_{k}": v for k, v in fit.items()})
        rows.append(row)
    return pd.DataFrame(rows)
