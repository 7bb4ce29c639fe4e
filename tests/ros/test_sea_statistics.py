"""The sea statistics of `analyze` (recording/sea_statistics.py, ROS-free) against independent truth.

- a narrow-band Gaussian record (400 random-phase cosines of equal amplitude, frequencies
  spread evenly over +-5 % of 1/8 Hz, 20 000 s at 4 Hz): its peaks between mean up-crossings
  follow the Rayleigh of the record's sigma (Kolmogorov-Smirnov D < 0.05 with ~2 500 peaks;
  the peaks of a finite-band record are not independent, so D is larger than the 1/sqrt(n)
  of independent draws); the mean of the highest third of the amplitudes is 2.0022 sigma
  (Longuet-Higgins 1952: 3 int_{a*}^inf a p(a) da, a* = sigma sqrt(2 ln 3), here computed by
  scipy.integrate.quad from the Rayleigh density, not from the module's constant) within 3 %;
  the mean up-crossing rate equals Rice's sqrt(m2 / m0) / 2 pi of the components' moments
  within 1 %; the standard deviation equals sqrt(sum a_i^2 / 2) within 3 %.
- a Weibull sample (shape 1.7, scale 3.0, 5 000 draws) gives back its shape and scale within 4 %.
- a Welch spectrum of A sin(2 pi t / T) has m0 = A^2 / 2 within 1 %, 4 sqrt(m0) = 2 sqrt(2) A
  and its peak at T (within one frequency bin); zeros give m0 = 0, significant 0, no peak period.
- slack events on a constructed record with three known slack intervals: count 3, the entry and
  exit times at the threshold crossings (1e-9), the time slack, the snatch after the last.
"""
import math

import numpy as np
import pytest
from scipy import integrate, stats

from recording import sea_statistics as ss


@pytest.fixture(scope="module")
def narrow_band():
    rng = np.random.default_rng(7)
    n = 400
    omega = 2 * math.pi / 8.0 * np.linspace(0.95, 1.05, n)
    amp = np.full(n, 0.5)
    phase = rng.uniform(0.0, 2 * math.pi, n)
    t = np.arange(0.0, 20000.0, 0.25)
    x = np.zeros_like(t)
    for a, w, p in zip(amp, omega, phase):
        x += a * np.cos(w * t + p)
    m0, m2 = np.sum(amp ** 2 / 2), np.sum(amp ** 2 / 2 * omega ** 2)
    return t, x, m0, m2


def test_narrow_band_peaks_are_rayleigh(narrow_band):
    t, x, m0, m2 = narrow_band
    tension = 50e3 + 1e3 * x  # a towline's tension: mean 50 kN
    st = ss.tension_statistics(t, tension, slack_threshold=1.0)
    sigma = st["tension_std"]
    assert sigma == pytest.approx(1e3 * math.sqrt(m0), rel=0.03)
    a13_theory = 3 * integrate.quad(lambda a: a * (a * math.exp(-a * a / 2)), math.sqrt(2 * math.log(3)),
                                    math.inf)[0]
    assert a13_theory == pytest.approx(2.0022, abs=1e-4)
    print(f"narrow band: {st['peaks']} peaks, Rayleigh KS D {st['rayleigh_ks']:.4f}, a1/3 / sigma "
          f"{st['amplitude_significant_over_std']:.4f} (theory {a13_theory:.4f}), Weibull shape "
          f"{st['weibull_shape']:.3f}, up-crossing rate {st['upcrossings'] / t[-1]:.5f} Hz "
          f"(Rice {math.sqrt(m2 / m0) / (2 * math.pi):.5f} Hz)")
    assert st["peaks"] > 2000
    assert st["rayleigh_ks"] < 0.05
    assert st["amplitude_significant_over_std"] == pytest.approx(a13_theory, rel=0.03)
    assert st["tension_significant"] == pytest.approx(st["tension_mean"] + st["amplitude_significant"], rel=1e-12)
    assert st["upcrossings"] / t[-1] == pytest.approx(math.sqrt(m2 / m0) / (2 * math.pi), rel=0.01)
    assert st["weibull_shape"] == pytest.approx(2.0, rel=0.15)  # a Rayleigh is the Weibull of shape 2
    assert st["slack_events"] == 0 and st["slack_time"] == 0.0


def test_weibull_parameters_are_recovered():
    sample = stats.weibull_min.rvs(1.7, scale=3.0, size=5000, random_state=np.random.default_rng(3))
    fit = ss.fit_weibull(sample)
    print(f"Weibull sample: shape {fit['weibull_shape']:.4f} (1.7), scale {fit['weibull_scale']:.4f} (3.0), "
          f"KS D {fit['weibull_ks']:.4f}")
    assert fit["weibull_shape"] == pytest.approx(1.7, rel=0.04)
    assert fit["weibull_scale"] == pytest.approx(3.0, rel=0.04)
    assert fit["weibull_ks"] < 0.03


def test_fit_of_too_few_amplitudes_gives_none():
    assert ss.fit_weibull(np.array([1.0, 2.0])) == {"weibull_shape": None, "weibull_scale": None, "weibull_ks": None}


@pytest.mark.parametrize("amplitude,period", [(2.0, 8.0), (0.05, 12.5)])
def test_welch_spectrum_of_a_sine(amplitude, period):
    t = np.arange(0.0, 1800.0, 0.05)
    sp = ss.motion_spectrum(t, amplitude * np.sin(2 * math.pi * t / period + 0.3), segment=200.0)
    df = sp["_f"][1] - sp["_f"][0]
    print(f"sine A {amplitude} T {period}: m0 {sp['m0']:.6g} (A^2/2 = {amplitude ** 2 / 2:.6g}), Tp {sp['peak_period']:.3f} s")
    assert sp["m0"] == pytest.approx(amplitude ** 2 / 2, rel=0.01)
    assert sp["significant"] == pytest.approx(2 * math.sqrt(2) * amplitude, rel=0.005)
    assert abs(1 / sp["peak_period"] - 1 / period) <= df
    assert sp["tz"] == pytest.approx(period, rel=0.02)
    assert sp["segment"] == pytest.approx(200.0)


def test_welch_spectrum_of_zeros_is_zero():
    t = np.arange(0.0, 300.0, 0.1)
    for x in (np.zeros_like(t), np.full_like(t, 3.0), 0.2 * t):  # zeros, a constant, a steady drift
        sp = ss.motion_spectrum(t, x, segment=60.0)
        assert sp["m0"] == 0.0 and sp["significant"] == 0.0
        assert sp["peak_period"] is None and sp["tz"] is None
        assert np.all(np.isfinite(sp["_S"]))
    assert ss.motion_spectrum(t[:2], t[:2])["m0"] is None  # too short: nothing, no error


def test_zero_tension_record_has_no_nan():
    t = np.arange(0.0, 100.0, 0.1)
    st = ss.tension_statistics(t, np.zeros_like(t), slack_threshold=10.0)
    assert st["tension_std"] == 0.0 and st["peaks"] == 0 and st["tension_significant"] is None
    assert st["peak_over_mean"] is None and st["rayleigh_ks"] is None and st["weibull_shape"] is None
    assert st["slack_at_start"] and st["slack_events"] == 0 and st["slack_time"] == pytest.approx(100.0 - 0.1)


def test_slack_events_of_a_constructed_record():
    """Tension 100 N with dips to 0 N: linear ramps down 100 -> 0 over 1 s, slack, ramps back up
    over 1 s; threshold 10 N is crossed 0.9 s into each ramp down and 0.1 s into each ramp up."""
    t = np.arange(0.0, 60.0 + 1e-9, 0.1)
    x = np.full_like(t, 100.0)
    dips = [(10.0, 13.0), (25.0, 26.5), (40.0, 44.0)]  # (ramp down starts, ramp up starts)
    for a, b in dips:
        x = np.where((t >= a) & (t < a + 1), 100.0 * (1 - (t - a)), x)
        x = np.where((t >= a + 1) & (t < b), 0.0, x)
        x = np.where((t >= b) & (t < b + 1), 100.0 * (t - b), x)
    x[(t > 46.0) & (t < 47.0)] = 180.0  # the snatch after the last slack interval
    ev = ss.slack_events(t, x, 10.0)
    assert ev["slack_events"] == 3 and not ev["slack_at_start"]
    expected = [(a + 0.9, b + 0.1) for a, b in dips]
    assert np.allclose(np.array(ev["_intervals"]), expected, atol=1e-9)
    # samples below: from the first sample after the entry to the last before the exit, each counts dt
    assert ev["slack_time"] == pytest.approx(sum(b + 0.1 - (a + 0.9) for a, b in dips), abs=3 * 0.1 + 1e-9)
    assert ev["snatch_max"] == 180.0
    # a record that ends slack: the entry counts, the interval has no end
    ev = ss.slack_events(t[t < 42.0], x[t < 42.0], 10.0)
    assert ev["slack_events"] == 3 and ev["_intervals"][-1][1] is None
