"""Wind: the mean wind at a height and its gusts, after the NPD (Frøya) wind model as given in
ISO 19901-1:2015, Petroleum and natural gas industries - Specific requirements for offshore
structures - Part 1: Metocean design and operating considerations, A.7.5 (also DNV-RP-C205
2.3.5). Pure numpy, no ROS.

Inside everything is SI and REP-103: the wind is the air's velocity over ground, world ENU
(east, north), m/s. A person gives a speed in knots and the direction the wind comes FROM in
degrees true (0 = from north, clockwise); `wind_velocity_enu` converts at that edge.

- Mean profile (ISO 19901-1 Eq A.7-1 with the 1-hour mean, t = t0): U(z) = U0 (1 + C ln(z/10)),
  C = 5.73e-2 sqrt(1 + 0.148 U0), U0 the 1-hour mean at 10 m above the sea.
- Gust spectrum of the longitudinal component (Eq A.7-3):
  S(f) = 320 (U0/10)^2 (z/10)^0.45 / (1 + f~^n)^(5/(3n)),  f~ = 172 f (z/10)^(2/3) (U0/10)^(-3/4),
  n = 0.468; S in (m/s)^2/Hz, f in Hz. Stated for U0 up to about 40 m/s and 0.00167 <= f <= 0.5 Hz.
- Gust record: a sum of harmonics at f_k = k / T (k = 1 .. up to the Nyquist frequency of the
  sampling step) with amplitudes sqrt(2 S(f_k) / T) and phases drawn from numpy's PCG64 with the
  given seed (the standard random-phase method), evaluated by an inverse FFT over one record of
  length T and repeated periodically: the same seed gives the same record on every machine.
  The gusts vary the wind's speed along its mean direction (the longitudinal component the
  spectrum describes); lateral gusts are not modelled.
"""
from __future__ import annotations

import math
from typing import Tuple

import numpy as np
from numba import njit

KNOT = 1852.0 / 3600.0  # m/s
NPD_N = 0.468


def wind_velocity_enu(speed_kn: float, from_deg_true: float) -> Tuple[float, float]:
    """The air's velocity (east, north) m/s for a wind of speed_kn knots blowing FROM
    from_deg_true (compass, 0 = north, clockwise): a north wind (from 0) blows towards the south."""
    if not (math.isfinite(speed_kn) and math.isfinite(from_deg_true)) or speed_kn < 0.0:
        raise ValueError(f"wind: speed {speed_kn!r} kn must be finite and >= 0, direction {from_deg_true!r} finite")
    u = speed_kn * KNOT
    th = math.radians(from_deg_true)
    return -u * math.sin(th), -u * math.cos(th)


def mean_speed_at(u10: float, z: float) -> float:
    """1-hour mean wind speed at height z (m above the sea) for the 1-hour mean u10 at 10 m."""
    if z <= 0.0:
        raise ValueError(f"wind: height {z!r} m must be above the sea (> 0)")
    c = 5.73e-2 * math.sqrt(1.0 + 0.148 * u10)
    return u10 * (1.0 + c * math.log(z / 10.0))


def npd_spectrum(f, u10: float, z: float = 10.0):
    """NPD / ISO 19901-1 gust spectrum S(f), (m/s)^2/Hz, at height z for the 1-hour mean u10."""
    f = np.asarray(f, float)
    ft = 172.0 * f * (z / 10.0) ** (2.0 / 3.0) * (u10 / 10.0) ** -0.75
    return 320.0 * (u10 / 10.0) ** 2 * (z / 10.0) ** 0.45 / (1.0 + ft ** NPD_N) ** (5.0 / (3.0 * NPD_N))


class GustRecord:
    """Wind speed along the mean direction at one height: the mean (mean_speed_at) plus a gust
    record from the NPD spectrum, periodic with period `period` s, sampled every `dt` s and
    interpolated linearly between samples. u10 = 0 gives still air."""

    def __init__(self, u10: float, z: float = 10.0, period: float = 3600.0, dt: float = 0.25, seed: int = 0):
        if not (math.isfinite(u10) and u10 >= 0.0):
            raise ValueError(f"wind: 1-hour mean speed {u10!r} m/s must be finite and >= 0")
        if not (period > 0.0 and dt > 0.0 and period >= 4 * dt):
            raise ValueError(f"wind: gust record period {period!r} s and step {dt!r} s (period >= 4 steps)")
        self.u10, self.z, self.dt, self.seed = float(u10), float(z), float(dt), int(seed)
        n = int(round(period / dt))
        self.period = n * dt
        self.mean = mean_speed_at(u10, z) if u10 > 0.0 else 0.0
        self.gust = self._record(n) if u10 > 0.0 else np.zeros(n)

    def _record(self, n: int) -> np.ndarray:
        k = np.arange(1, n // 2 + (n % 2))            # positive frequencies below Nyquist
        f = k / self.period
        amp = np.sqrt(2.0 * npd_spectrum(f, self.u10, self.z) / self.period)
        phase = np.random.default_rng(self.seed).uniform(0.0, 2.0 * math.pi, k.size)
        spec = np.zeros(n // 2 + 1, complex)
        spec[k] = 0.5 * n * amp * np.exp(1j * phase)  # irfft: sum_k amp cos(2 pi f_k t + phase)
        return np.fft.irfft(spec, n)

    def speed(self, t: float) -> float:
        """Wind speed (m/s, along the mean direction) at simulation time t (s)."""
        return gust_speed(self.mean, self.gust, self.dt, self.period, t)


@njit(cache=True)
def gust_speed(mean, gust, dt, period, t):
    """GustRecord.speed as a kernel (the vessel's environment sampler calls it every step): the
    record, periodic in `period`, interpolated linearly between its samples `dt` apart."""
    x = (t % period) / dt
    i = int(x)
    w = x - i
    n = gust.size
    return mean + (1.0 - w) * gust[i % n] + w * gust[(i + 1) % n]


def apparent_wind(wind_enu, velocity_enu, yaw: float) -> Tuple[float, float]:
    """(speed m/s, angle rad) of the wind a vessel feels: the air's velocity relative to the
    vessel, the angle being where it comes FROM relative to the bow, + to port (REP-103 body y),
    in (-pi, pi]: 0 = from dead ahead, +pi/2 = on the port beam."""
    return apparent_wind_xy(float(wind_enu[0]), float(wind_enu[1]), float(velocity_enu[0]),
                            float(velocity_enu[1]), float(yaw))


@njit(cache=True)
def apparent_wind_xy(wx, wy, vx, vy, yaw):
    """apparent_wind on scalars, as a kernel."""
    rx = wx - vx
    ry = wy - vy
    c, s = math.cos(yaw), math.sin(yaw)
    bx, by = c * rx + s * ry, -s * rx + c * ry       # world -> body (rotation by -yaw)
    return math.hypot(bx, by), math.atan2(-by, -bx)  # it comes from the opposite of where it goes
