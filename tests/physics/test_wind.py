"""Wind (sea_environment.wind) against independent truths: the Kolmogorov -5/3 law the NPD
spectrum must follow at high frequency, Parseval's identity and a Welch estimate (scipy) of a
long gust record against the spectrum it was drawn from, and plain geometry for directions and
apparent wind."""
import math

import numpy as np
import pytest
from scipy.signal import welch

from sea_environment import wind

KN = 1852.0 / 3600.0


@pytest.mark.parametrize("u10", [5.0, 15.0, 30.0])
def test_npd_spectrum_has_the_inertial_range_slope(u10):
    """Far above the spectral peak turbulence follows Kolmogorov's f^(-5/3): the NPD form
    approaches it slowly (n = 0.468), so the log-log slope is taken between 1 and 10 kHz, where
    it must be -5/3 within 1 %, and it steepens monotonically towards it from 0.01 Hz on."""
    slopes = []
    for lo in (0.01, 0.1, 1.0, 10.0):
        s2 = wind.npd_spectrum([lo, 10 * lo], u10, 30.0)
        slopes.append(math.log10(s2[1] / s2[0]))
    assert all(a > b for a, b in zip(slopes, slopes[1:]))
    f = np.array([1e3, 1e4])
    s = wind.npd_spectrum(f, u10, 30.0)
    slope = math.log(s[1] / s[0]) / math.log(f[1] / f[0])
    assert slope == pytest.approx(-5.0 / 3.0, rel=0.01)


def test_gust_record_has_the_spectrum_it_was_drawn_from():
    """A 4-hour record at 0.25 s: its variance is the spectrum's integral over the harmonics
    (Parseval, exact) and a Welch estimate (Hann, 4096 samples, 50 % overlap) matches S(f) in
    third-octave bands from 0.005 to 0.5 Hz within 20 %."""
    u10, z, dt = 20.0, 25.0, 0.25
    rec = wind.GustRecord(u10, z, period=4 * 3600.0, dt=dt, seed=7)
    g = rec.gust
    k = np.arange(1, g.size // 2)
    fk = k / rec.period
    assert np.var(g) == pytest.approx(np.sum(wind.npd_spectrum(fk, u10, z) / rec.period), rel=1e-9)
    f, p = welch(g, fs=1.0 / dt, nperseg=4096)
    edges = 0.005 * 2.0 ** (np.arange(0, 24) / 3.0)
    edges = edges[edges <= 0.5]
    for lo, hi in zip(edges[:-1], edges[1:]):
        band = (f >= lo) & (f < hi)
        if band.sum() < 2:
            continue
        est, model = p[band].mean(), wind.npd_spectrum(f[band], u10, z).mean()
        assert est == pytest.approx(model, rel=0.20), f"{lo:.4f}-{hi:.4f} Hz"


def test_gust_record_is_reproducible_from_its_seed_and_has_the_mean_wind():
    a = wind.GustRecord(12.0, 10.0, period=600.0, dt=0.5, seed=3)
    b = wind.GustRecord(12.0, 10.0, period=600.0, dt=0.5, seed=3)
    c = wind.GustRecord(12.0, 10.0, period=600.0, dt=0.5, seed=4)
    ts = np.arange(0.0, 1200.0, 0.37)
    sa = np.array([a.speed(t) for t in ts])
    assert np.array_equal(sa, [b.speed(t) for t in ts]) and not np.allclose(sa, [c.speed(t) for t in ts])
    assert a.mean == pytest.approx(12.0)  # the 1-hour mean at 10 m is U0 by definition
    assert np.mean(a.gust) == pytest.approx(0.0, abs=1e-9)
    assert a.speed(37.0) == pytest.approx(a.speed(37.0 + a.period))  # periodic
    assert a.speed(1.0) == pytest.approx(a.mean + a.gust[2])  # on the samples: exactly them
    still = wind.GustRecord(0.0)
    assert still.speed(123.0) == 0.0


def test_mean_wind_grows_logarithmically_with_height():
    u = [wind.mean_speed_at(15.0, z) for z in (5.0, 10.0, 20.0, 40.0)]
    assert u[1] == pytest.approx(15.0)
    assert u[2] - u[1] == pytest.approx(u[3] - u[2], rel=1e-12)  # equal steps per doubling: log law
    assert u[0] < u[1] < u[2]
    with pytest.raises(ValueError, match="height"):
        wind.mean_speed_at(15.0, 0.0)


@pytest.mark.parametrize("from_deg,east,north", [(0.0, 0.0, -1.0), (90.0, -1.0, 0.0), (180.0, 0.0, 1.0),
                                                 (270.0, 1.0, 0.0), (45.0, -math.sqrt(0.5), -math.sqrt(0.5))])
def test_wind_from_a_compass_direction_blows_the_other_way(from_deg, east, north):
    ve, vn = wind.wind_velocity_enu(10.0, from_deg)
    assert (ve, vn) == pytest.approx((10 * KN * east, 10 * KN * north), abs=1e-12)


def test_bad_wind_input_is_refused():
    for args in [(-1.0, 0.0), (math.nan, 0.0), (5.0, math.inf)]:
        with pytest.raises(ValueError, match="wind"):
            wind.wind_velocity_enu(*args)
    with pytest.raises(ValueError, match="wind"):
        wind.GustRecord(math.nan)


@pytest.mark.parametrize("wind_enu,vel,yaw,speed,angle", [
    ((-8.0, 0.0), (0.0, 0.0), math.pi / 2, 8.0, -math.pi / 2),          # heading north, wind from east: starboard beam
    ((0.0, 0.0), (5.0, 0.0), 0.0, 5.0, 0.0),                            # steaming east in still air: from ahead
    ((5.0, 0.0), (0.0, 5.0), math.pi / 2, math.sqrt(50.0), math.pi / 4),  # north at 5, west wind 5: port bow
    ((0.0, -3.0), (0.0, 0.0), math.pi / 2, 3.0, 0.0),                   # heading into a north wind
])
def test_apparent_wind(wind_enu, vel, yaw, speed, angle):
    s, a = wind.apparent_wind(wind_enu, vel, yaw)
    assert s == pytest.approx(speed) and a == pytest.approx(angle, abs=1e-12)
