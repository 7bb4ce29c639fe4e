"""Statistics of a run at sea (ROS-free: numpy and scipy only): a towline's tension record
(mean, standard deviation, peaks, significant value, slack events, the peaks' distribution
against a fitted Weibull and the Rayleigh of the record) and a vessel's motion spectra (Welch).

Definitions (docs/tools.md, "Sea statistics"):

- a **peak** is the largest value between two successive up-crossings of the record's mean
  (one peak per zero-mean up-crossing cycle; DNV-RP-C205 3.3, Ochi 1998 ch. 3); its
  **amplitude** is the peak minus the mean. The cycles before the first and after the last
  up-crossing are incomplete and not counted.
- the **significant value** is the mean of the highest third of the peaks (H1/3 applied to the
  tension peaks); for a narrow-band Gaussian record the amplitudes are Rayleigh distributed,
  P(A > a) = exp(-a^2 / (2 sigma^2)), and the mean of their highest third is
  RAYLEIGH_A13 sigma = 2.0022 sigma (Longuet-Higgins 1952).
- the **Weibull** fitted to the amplitudes is scipy.stats.weibull_min with its location fixed
  at 0 (the mean) and shape k and scale fitted by maximum likelihood; the **Rayleigh** is the
  Weibull of shape 2 and scale sqrt(2) sigma, sigma the record's standard deviation (nothing
  fitted). The goodness of each is the Kolmogorov-Smirnov statistic D (largest distance
  between the empirical and the model distribution of the amplitudes).
- the **mean up-crossing rate** (crossings of the mean per second) is compared by Rice (1944)
  with sqrt(m2 / m0) / (2 pi) for the spectral moments m_n = int omega^n S(omega) d omega.
- a **slack event** is an entry of the tension below a threshold (from at or above it); the
  event ends when the tension is back at or above the threshold. A record that starts slack
  does not count that first stretch as an event (it is reported as slack at the start).
- **motion spectra**: scipy.signal.welch (Hann window, segments of `segment` seconds, half
  overlapping, linear trend removed per segment, one-sided density) of the record resampled on
  a uniform grid; m0 = int S(f) df (the variance), significant value 4 sqrt(m0) (as Hs: a
  double amplitude, crest to trough), peak period 1 / f at the spectrum's maximum, mean
  zero-crossing period Tz = sqrt(m0 / m2) (moments in Hz).

Every function takes plain arrays and returns plain dicts of floats (None where a value does
not exist, e.g. the peak period of a record of zeros: never NaN).
"""
from __future__ import annotations

import math
import warnings
from typing import Dict, Optional, Sequence

import numpy as np

# mean of the highest third of Rayleigh amplitudes over sigma: 3 int_{a*}^inf a p(a) da with
# a* = sigma sqrt(2 ln 3) = sqrt(2 ln 3) + 3 sqrt(pi / 2) erfc(sqrt(ln 3))
RAYLEIGH_A13 = math.sqrt(2.0 * math.log(3.0)) + 3.0 * math.sqrt(math.pi / 2.0) * math.erfc(math.sqrt(math.log(3.0)))

DEFAULT_SEGMENT = 120.0  # s, Welch segment length
DEFAULT_SLACK_FRACTION = 0.01  # of the breaking load


def _f(x) -> Optional[float]:
    """A float, or None for NaN / infinity (JSON-clean)."""
    x = float(x)
    return x if math.isfinite(x) else None


def mean_upcrossings(x: np.ndarray, level: float) -> np.ndarray:
    """Indices i where x crosses `level` upwards between samples i-1 and i (x[i-1] < level <= x[i])."""
    x = np.asarray(x, float)
    return np.nonzero((x[:-1] < level) & (x[1:] >= level))[0] + 1


def peaks_between_upcrossings(x: np.ndarray, level: Optional[float] = None) -> np.ndarray:
    """The largest value of x in each complete cycle between successive up-crossings of
    `level` (default: the mean of x)."""
    x = np.asarray(x, float)
    level = float(np.mean(x)) if level is None else level
    up = mean_upcrossings(x, level)
    if up.size < 2:
        return np.zeros(0)
    return np.maximum.reduceat(x[up[0]:up[-1]], up[:-1] - up[0])


def significant(values: np.ndarray) -> Optional[float]:
    """Mean of the highest third of `values` (at least one value); None for none."""
    v = np.sort(np.asarray(values, float))[::-1]
    if not v.size:
        return None
    return float(v[:max(1, int(round(v.size / 3.0)))].mean())


def fit_weibull(amplitudes: np.ndarray) -> Dict[str, Optional[float]]:
    """Weibull (scipy.stats.weibull_min) of the amplitudes, location fixed at 0, shape and
    scale by maximum likelihood, and its Kolmogorov-Smirnov D; None values for fewer than 3
    positive amplitudes."""
    from scipy import stats
    a = np.asarray(amplitudes, float)
    a = a[a > 0.0]
    if a.size < 3 or np.ptp(a) <= 1e-9 * a.max():  # all alike (a regular record's peaks): no distribution
        return {"weibull_shape": None, "weibull_scale": None, "weibull_ks": None}
    with warnings.catch_warnings():  # nearly alike: scipy's start guess warns, the fit is still made
        warnings.simplefilter("ignore", RuntimeWarning)
        shape, _loc, scale = stats.weibull_min.fit(a, floc=0.0)
    d = stats.kstest(a, "weibull_min", args=(shape, 0.0, scale)).statistic
    return {"weibull_shape": _f(shape), "weibull_scale": _f(scale), "weibull_ks": _f(d)}


def rayleigh_ks(amplitudes: np.ndarray, sigma: float) -> Optional[float]:
    """Kolmogorov-Smirnov D of the amplitudes against the Rayleigh of sigma."""
    from scipy import stats
    a = np.asarray(amplitudes, float)
    if not a.size or not sigma > 0.0:
        return None
    return _f(stats.kstest(a, "rayleigh", args=(0.0, sigma)).statistic)


def slack_events(t: np.ndarray, x: np.ndarray, threshold: float) -> Dict[str, object]:
    """Entries below `threshold` (see the module docstring): count, total time slack (each
    sample below counts the time to the next sample), whether the record starts slack, the
    largest tension after leaving slack until the next entry (the snatch) and the intervals
    (t entered, t left or None) with times linearly interpolated at the threshold."""
    t, x = np.asarray(t, float), np.asarray(x, float)
    below = x < threshold
    if not x.size:
        return {"slack_events": 0, "slack_time": 0.0, "slack_at_start": False, "snatch_max": None, "_intervals": []}
    dt = np.diff(t, append=t[-1])
    enter = np.nonzero(~below[:-1] & below[1:])[0] + 1
    leave = np.nonzero(below[:-1] & ~below[1:])[0] + 1

    def at(i):  # time of the threshold crossing between samples i-1 and i
        x0, x1 = x[i - 1], x[i]
        return float(t[i - 1] + (t[i] - t[i - 1]) * (threshold - x0) / (x1 - x0)) if x1 != x0 else float(t[i])
    intervals = []
    for i in enter:
        after = leave[leave > i]
        intervals.append((at(i), at(after[0]) if after.size else None))
    snatches = []
    for j in leave:
        nxt = enter[enter > j]
        seg = x[j:nxt[0]] if nxt.size else x[j:]
        if seg.size:
            snatches.append(seg.max())
    return {"slack_events": int(enter.size), "slack_time": float(dt[below].sum()), "slack_at_start": bool(below[0]),
            "snatch_max": _f(max(snatches)) if snatches else None, "_intervals": intervals}


def tension_statistics(t: np.ndarray, tension: np.ndarray, slack_threshold: float) -> Dict[str, object]:
    """The statistics of one end's tension record over its window (see the module docstring);
    keys starting with "_" hold arrays for the figures (peak amplitudes, sorted)."""
    t, x = np.asarray(t, float), np.asarray(tension, float)
    ok = np.isfinite(x)
    t, x = t[ok], x[ok]
    out: Dict[str, object] = {"samples": int(x.size), "slack_threshold": _f(slack_threshold)}
    if not x.size:
        return out
    mean, std = float(x.mean()), float(x.std())
    up = mean_upcrossings(x, mean) if std > 0.0 else np.zeros(0, int)
    peaks = peaks_between_upcrossings(x, mean) if std > 0.0 else np.zeros(0)
    amp = np.sort(peaks - mean)
    duration = float(t[-1] - t[0]) if t.size > 1 else 0.0
    out.update(tension_mean=mean, tension_std=std, tension_max=float(x.max()), tension_min=float(x.min()),
               peak_over_mean=_f(x.max() / mean) if mean > 0.0 else None,
               upcrossings=int(up.size), upcrossing_period=_f(duration / up.size) if up.size else None,
               peaks=int(peaks.size), tension_significant=significant(peaks),
               amplitude_significant=significant(amp), amplitude_significant_over_std=
               _f(significant(amp) / std) if amp.size and std > 0.0 else None)
    out.update(fit_weibull(amp))
    out["rayleigh_ks"] = rayleigh_ks(amp, std)
    out.update(slack_events(t, x, slack_threshold))
    out["_amplitudes"] = amp
    out["_sigma"] = std
    return out


def uniform(t: np.ndarray, x: np.ndarray):
    """(dt, x on a uniform grid of the median step from t[0]) by linear interpolation; None for
    fewer than 4 samples or no positive step."""
    t, x = np.asarray(t, float), np.asarray(x, float)
    if t.size < 4:
        return None
    dt = float(np.median(np.diff(t)))
    if not dt > 0.0:
        return None
    grid = t[0] + dt * np.arange(int(math.floor((t[-1] - t[0]) / dt + 1e-9)) + 1)
    return dt, np.interp(grid, t, x)


def motion_spectrum(t: np.ndarray, x: np.ndarray, segment: float = DEFAULT_SEGMENT) -> Dict[str, object]:
    """Welch spectrum of one motion record (see the module docstring): m0, significant value
    4 sqrt(m0), peak period, Tz, the segment used; "_f" and "_S" hold the spectrum (Hz, unit^2 /
    Hz). A record of zeros (or a constant, or a straight line) gives m0 = 0, significant 0 and
    no peak period."""
    from scipy import signal
    u = uniform(t, x)
    if u is None:
        return {"m0": None, "significant": None, "peak_period": None, "tz": None, "segment": None}
    dt, y = u
    n = min(y.size, max(4, int(round(segment / dt))))
    f, s = signal.welch(y, fs=1.0 / dt, window="hann", nperseg=n, noverlap=n // 2, detrend="linear",
                        scaling="density", return_onesided=True)
    s = np.where(np.isfinite(s), s, 0.0)
    df = f[1] - f[0] if f.size > 1 else 0.0
    m0, m2 = float(np.sum(s) * df), float(np.sum(s * f ** 2) * df)
    scale = float(np.max(np.abs(y))) if y.size else 0.0
    if not m0 > (1e-12 * scale) ** 2 or not m0 > 0.0:  # round-off of a straight line: nothing moves
        m0, peak_period, tz = 0.0, None, None
    else:
        k = int(np.argmax(s[1:])) + 1 if s.size > 1 else 0
        peak_period = _f(1.0 / f[k]) if f[k] > 0.0 else None
        tz = _f(math.sqrt(m0 / m2)) if m2 > 0.0 else None
    return {"m0": m0, "significant": 4.0 * math.sqrt(m0), "peak_period": peak_period, "tz": tz,
            "segment": n * dt, "_f": f, "_S": s}


def rayleigh_exceedance(a: np.ndarray, sigma: float) -> np.ndarray:
    """P(A > a) of the Rayleigh of sigma."""
    return np.exp(-np.asarray(a, float) ** 2 / (2.0 * sigma ** 2))


def weibull_exceedance(a: np.ndarray, shape: float, scale: float) -> np.ndarray:
    """P(A > a) of the Weibull (location 0)."""
    return np.exp(-(np.asarray(a, float) / scale) ** shape)


def window_mask(t: np.ndarray, start: Optional[float], end: Optional[float]) -> np.ndarray:
    """Samples with start <= t <= end (None: open)."""
    t = np.asarray(t, float)
    m = np.ones(t.shape, bool)
    if start is not None:
        m &= t >= start
    if end is not None:
        m &= t <= end
    return m


def empirical_exceedance(sorted_values: Sequence[float]) -> np.ndarray:
    """P(A > a_i) estimated as 1 - i / (n + 1) for the ascending a_i (i = 1..n, Weibull plotting position)."""
    n = len(sorted_values)
    return 1.0 - np.arange(1, n + 1) / (n + 1.0)
