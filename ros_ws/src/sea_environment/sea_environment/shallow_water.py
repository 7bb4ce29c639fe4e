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

Whole-model factors (shallow_water_factors): every term of a manoeuvring model that the
shallow-water set restated in the package README of tug_dynamics ("Shallow water") covers, as
functions of h' = T / h (draft over depth). Sources as restated, with the expressions, in the open
MMG implementation mmgdynamics (N. Paulig, `shallow_water_hdm`, github nikpau/mmgdynamics), which
names Tang et al. (2020, Ocean Engineering 196, 106679) and Furukawa et al. (2016, MASHCON 4,
doi 10.18451/978-3-939230-38-0_33); the originals were not available here. Numbered as in the
README:

  (S1) k = 2T/L, k_e(q) = k / (h'/2 + ((pi h'/2) cot(pi h'/2))^q)   (effective aspect ratio)
  (S2) Y'v ~ pi/2 k_e(2.3) + 1.4 Cb B/L,  Y'r ~ k_e(0.7),  N'v ~ k_e(1.7),
       N'r ~ 0.54 k_e(0.7) - k_e(0.7)^2      (shallow / deep ratio of each: the factor)
  (S3) N'vvr, N'vrr: x (1 + 6 h'^2.5)
  (S4) X'vv: x (1 + 27.7 h'^2 - 70.8 h'^4);  X'vr: x (1 + 1.3 h'^2);  resistance: x (1 + 0.388 h'^2)
  (S5) 1 - t_P: x 1 / (1 - 0.2 h' + 0.7295 h'^2)
  (S6) 1 - w_P: x cos(1.4 Cb h')
  (S7) gamma_R (rudder flow straightening): x (1 + 0.0161 h' + 4.4222 h'^2 - 4.9825 h'^3)
  (S8) with F = h/T - 1: m_x: x (F^1.3 + 3.77 + 1.14 B/T - 0.233 L/T - 3.43 Cb) / F^1.3,
       m_y: x (F^0.82 + 0.413 + 0.032 B/T + 0.129 (B/T)^2) / F^0.82,
       J_z: x (F^0.82 + 0.413 + 0.0192 B/T + 0.00554 (B/T)^2) / F^0.82
       (S4)'s X'vv, X'vr and (S8) are regressions on ship forms: only for L/T >= 10 and B/T <= 4
       (our bound); a barge or tug outside it keeps those deep values
  (S3') our extension: every other nonlinear hull term the set does not name (Y'vr, Y'r|r|,
       N'r|r|, N'v|v|, ...) takes (S3)'s growth too; X'rr keeps its deep value
  (S9) sway cross-flow drag (the hull's beam-on C_D and the Y'v|v| term that carries it), whose
       growth the set above does not give: the lateral current-force
       coefficient of UFC 4-159-03 (US DoD, "Design: Moorings", 2005, 4-5.1, Eq 11-13), force
       1/2 rho V^2 L T C_yc at 90 deg:
         C_yc = C0 + (C1 - C0) h'^K,  C1 = 3.2 (h' = 1), K = 2 (its "wide range of ship and barge
         tests"),  C0 = 0.22 sqrt(chi),  chi = L^2 A_m / (B V)  (= L C_m / (C_b B))
       as the factor C_yc / C0 on the ship's deep-water C0 (ufc_deep_crossflow_drag, or the
       C_D the ship file implies). UFC's worked example (FFG-7, its Table 4-6) has the side force
       grow 3.5 times from T/d = 0.096 to 0.96.

Deep-water limit (our decision): the ITTC's deep-water bound h/T = 4. Each factor f is applied as
1 + (f - 1) w with w = 1 for h/T <= 3, falling linearly to 0 at h/T = 4, so the ship is exactly the
deep-water one at h/T >= 4 (the raw factors there differ from 1 by up to a few %). Below
h/T = 1.1 (MIN_DEPTH_RATIO) the factors are held at their value there.

Squat: ICORELS (1980), as recommended by PIANC (2014) for the bow squat of ships in open
shallow water: S = 2.4 (V/L^2) Fnh^2 / sqrt(1 - Fnh^2), Fnh = U / sqrt(g h), V the displaced
volume; stated for Fnh up to about 0.7 (beyond that this returns the value at 0.7).
"""
from __future__ import annotations

import math
from typing import Tuple

import numpy as np
from numba import njit

G = 9.80665
FNH_MAX = 0.7
MIN_DEPTH_RATIO = 1.1   # h/T: the shallowest the MARAD regression covers
FULL_SHALLOW_RATIO, DEEP_RATIO = 3.0, 4.0     # h/T: factors fade to 1 between these
# a ship form (S4's X'vv, X'vr and S8 apply): L/T >= 10, B/T <= 4 (our bound: the container ships,
# tankers and bulk carriers such regressions are fitted to; the S-175 has 20.6 and 3.0)
SHIP_FORM_MIN_L_OVER_T, SHIP_FORM_MAX_B_OVER_T = 10.0, 4.0
# shallow_water_factors' tuple: index of each factor
(SW_YV, SW_YR, SW_NV, SW_NR, SW_NONLINEAR, SW_XVV, SW_XVR, SW_RESISTANCE, SW_ONE_MINUS_T, SW_ONE_MINUS_W,
 SW_GAMMA, SW_MX, SW_MY, SW_JZ, SW_CROSSFLOW) = range(15)
N_SW = 15
UFC_C1, UFC_K = 3.2, 2.0      # UFC 4-159-03 Eq 11: C_yc at T/d = 1, and the exponent


def ufc_deep_crossflow_drag(length: float, beam: float, block: float, midship: float) -> float:
    """UFC 4-159-03 Eq 12-13: deep-water beam-on current-drag coefficient C0 = 0.22 sqrt(chi),
    chi = L^2 A_m / (B V) with A_m = C_m B T and V = C_b L B T, i.e. chi = L C_m / (C_b B)
    (force 1/2 rho V^2 L T C0)."""
    return 0.22 * math.sqrt(length * midship / (block * beam))


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
def ufc_crossflow_factor(deep_drag: float, draft_over_depth: float) -> float:
    """UFC 4-159-03 Eq 11 over its deep value: C_yc / C0 = (C0 + (C1 - C0) (T/d)^K) / C0 (not
    faded: shallow_water_factors fades it with the rest)."""
    return (deep_drag + (UFC_C1 - deep_drag) * draft_over_depth ** UFC_K) / deep_drag


@njit(cache=True)
def _effective_aspect_ratio(k: float, hr: float, q: float) -> float:
    """(S1): k_e = k / (h'/2 + ((pi h'/2) cot(pi h'/2))^q), h' = T/h; k at h' = 0."""
    if hr <= 0.0:
        return k
    a = 0.5 * math.pi * hr
    return k / (0.5 * hr + (a / math.tan(a)) ** q)


@njit(cache=True)
def shallow_water_factors(length: float, beam: float, draft: float, block: float, depth: float,
                          crossflow_drag: float):
    """The N_SW shallow / deep factors (SW_* order; module docstring (S1)-(S9)) at water depth
    `depth` (m), faded to exactly 1 at h/T >= 4 (math.inf: all 1); crossflow_drag: the ship's
    deep-water beam-on C_D (on L T), the base of (S9)."""
    out = np.ones(N_SW)
    if not math.isfinite(depth):
        return out
    ratio = max(depth / draft, MIN_DEPTH_RATIO)
    if ratio >= DEEP_RATIO:
        return out
    hr = 1.0 / ratio
    k = 2.0 * draft / length
    ke23 = _effective_aspect_ratio(k, hr, 2.3)
    ke07 = _effective_aspect_ratio(k, hr, 0.7)
    ke17 = _effective_aspect_ratio(k, hr, 1.7)
    cbl = 1.4 * block * beam / length
    out[SW_YV] = (0.5 * math.pi * ke23 + cbl) / (0.5 * math.pi * k + cbl)
    out[SW_YR] = ke07 / k
    out[SW_NV] = ke17 / k
    out[SW_NR] = (0.54 * ke07 - ke07 * ke07) / (0.54 * k - k * k)
    out[SW_NONLINEAR] = 1.0 + 6.0 * hr ** 2.5
    out[SW_XVV] = 1.0 + 27.7 * hr ** 2 - 70.8 * hr ** 4
    out[SW_XVR] = 1.0 + 1.3 * hr ** 2
    out[SW_RESISTANCE] = 1.0 + 0.388 * hr ** 2
    out[SW_ONE_MINUS_T] = 1.0 / (1.0 - 0.2 * hr + 0.7295 * hr ** 2)
    out[SW_ONE_MINUS_W] = math.cos(1.4 * block * hr)
    out[SW_GAMMA] = 1.0 + 0.0161 * hr + 4.4222 * hr ** 2 - 4.9825 * hr ** 3
    if crossflow_drag > 0.0:
        out[SW_CROSSFLOW] = ufc_crossflow_factor(crossflow_drag, hr)
    f = ratio - 1.0
    bt, lt = beam / draft, length / draft
    if not (lt >= SHIP_FORM_MIN_L_OVER_T and bt <= SHIP_FORM_MAX_B_OVER_T):
        # (S4)'s X'vv, X'vr and (S8): regressions on ship forms; a barge or tug keeps its deep
        # values (S8's m_x at h/T 1.2 would be x 95 for the box barge)
        out[SW_XVV] = out[SW_XVR] = 1.0
        return _faded(out, ratio)
    out[SW_MX] = (f ** 1.3 + 3.77 + 1.14 * bt - 0.233 * lt - 3.43 * block) / f ** 1.3
    out[SW_MY] = (f ** 0.82 + 0.413 + 0.032 * bt + 0.129 * bt * bt) / f ** 0.82
    out[SW_JZ] = (f ** 0.82 + 0.413 + 0.0192 * bt + 0.00554 * bt * bt) / f ** 0.82
    return _faded(out, ratio)


@njit(cache=True)
def _faded(out, ratio):
    """1 + (f - 1) w, w = 1 at h/T <= 3 falling linearly to 0 at h/T = 4."""
    w = min(1.0, (DEEP_RATIO - ratio) / (DEEP_RATIO - FULL_SHALLOW_RATIO))
    for i in range(N_SW):
        out[i] = 1.0 + (out[i] - 1.0) * w
    return out


@njit(cache=True)
def squat(speed: float, depth: float, length: float, volume: float) -> float:
    """ICORELS bow squat (m) at speed through the water `speed` (m/s) in depth h (m)."""
    if not math.isfinite(depth) or speed == 0.0:
        return 0.0
    fnh = min(abs(speed) / math.sqrt(G * depth), FNH_MAX)
    return 2.4 * volume / (length * length) * fnh * fnh / math.sqrt(1.0 - fnh * fnh)
