"""Shallow water: the change of a ship's manoeuvring derivatives with the depth, and its squat.
Numba kernels (the vessel's environment sampler calls them every step), callable from Python; no ROS.

Derivatives: the MARAD shallow-water factors of Ankudinov et al. (MARAD systematic series,
around 1990), as restated by Taimuri et al. (2020, Ocean Engineering, doi
10.1016/j.oceaneng.2020.108103) and as coded in DMI / FORCE SimFlex's hull rules of thumb; the
original papers were not available here, the two restatements agree on every term used below
except Y'v's (noted). With F = h/T - 1 and b = Cb B (1 + B/L)^2 / T:

    K0 = 1 + 0.0775/F^2 - 0.011/F^3 + 0.000068/F^5
    K1 = -0.0643/F + 0.0724/F^2 - 0.0113/F^3 + 0.0000767/F^5
    K2 = 0.0342/F                   (B/T <= 4)     0.137 T/(B F)   (B/T > 4)
    N'v:  f_nv = K0 + K1 b + K2 b^2
    N'r:  f_nr = K0 + 1/2 K1 b + 1/3 K2 b^2
    Y'r:  f_yr = K0 + 2/5 K1 b + 24/105 K2 b^2
    Y'v:  f_yv = 1.5 f_nv - 0.5     (DMI's form; Taimuri's restatement has 1.5 f_nr - 0.5)
    added masses: g_v = K0 + 2/3 K1 b + 8/15 K2 b^2

The factors multiply the ship file's deep-water derivatives. They tend to 1 as the water deepens
(within 5 % at h/T = 4, 2 % at h/T = 6) and grow steeply below h/T = 1.5; the regression is
stated down to h/T = 1.1 and is held at that value below it (closer still, the ship is nearly
aground: the node reports the under-keel clearance).

Squat: ICORELS (1980), as recommended by PIANC (2014) for the bow squat of ships in open
shallow water: S = 2.4 (V/L^2) Fnh^2 / sqrt(1 - Fnh^2), Fnh = U / sqrt(g h), V the displaced
volume; stated for Fnh up to about 0.7 (beyond that this returns the value at 0.7).
"""
from __future__ import annotations

import math
from typing import Tuple

from numba import njit

G = 9.80665
FNH_MAX = 0.7
MIN_DEPTH_RATIO = 1.1   # h/T: the shallowest the MARAD regression covers


@njit(cache=True)
def ankudinov_factors(length: float, beam: float, draft: float, block: float,
                      depth: float) -> Tuple[float, float, float, float, float]:
    """(f_yv, f_yr, f_nv, f_nr, g_v): shallow / deep ratios of Y'v, Y'r, N'v, N'r and of the
    added masses at water depth `depth` (m); all 1 in deep water (math.inf)."""
    if not math.isfinite(depth):
        return 1.0, 1.0, 1.0, 1.0, 1.0
    f = max(depth / draft, MIN_DEPTH_RATIO) - 1.0
    k0 = 1.0 + 0.0775 / f ** 2 - 0.011 / f ** 3 + 0.000068 / f ** 5
    k1 = -0.0643 / f + 0.0724 / f ** 2 - 0.0113 / f ** 3 + 0.0000767 / f ** 5
    k2 = 0.0342 / f if beam / draft <= 4.0 else 0.137 * draft / (beam * f)
    b = block * beam * (1.0 + beam / length) ** 2 / draft
    f_nv = k0 + k1 * b + k2 * b * b
    f_nr = k0 + 0.5 * k1 * b + k2 * b * b / 3.0
    f_yr = k0 + 0.4 * k1 * b + 24.0 / 105.0 * k2 * b * b
    g_v = k0 + 2.0 / 3.0 * k1 * b + 8.0 / 15.0 * k2 * b * b
    return 1.5 * f_nv - 0.5, f_yr, f_nv, f_nr, g_v


@njit(cache=True)
def squat(speed: float, depth: float, length: float, volume: float) -> float:
    """ICORELS bow squat (m) at speed through the water `speed` (m/s) in depth h (m)."""
    if not math.isfinite(depth) or speed == 0.0:
        return 0.0
    fnh = min(abs(speed) / math.sqrt(G * depth), FNH_MAX)
    return 2.4 * volume / (length * length) * fnh * fnh / math.sqrt(1.0 - fnh * fnh)
