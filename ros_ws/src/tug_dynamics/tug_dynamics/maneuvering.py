"""Displacement-ship manoeuvring model (surge, sway, yaw, optional roll), ROS-free.

Papers: Yun & Kim, "Study on the Maneuverability of Barge by Captive Model Test" (the barge);
S. D. Yoon, "A Study on the Control of Ship Maneuvering by the Simulation of Anchor Dredging"
(the S-175 low-speed model and its anchor).

Force components, one kernel function each, summed in the body frame (REP-103: x fwd, y port,
z up) by _deriv:
  hull       _hull_polynomial: Yun & Kim Eq 2 (captive-model derivatives), or
             _hull_lowspeed: S. D. Yoon Eq 3 (reconstructed; README "Reading decisions"), or
             _hull_crossflow: linear (ideal-fluid lift) terms continued as sin(b) cos(b) plus the
             cross-flow drag strip integral (Oltmann & Sharma 1984; Hooft 1994), valid at any
             drift angle 0..180 deg (escort / indirect towing; README "ASD tug")
  propeller  _propeller_thrust: S. D. Yoon Eq 4, K_T(J) quadratic, wake w_P(beta, r), thrust
             deduction; shaft-speed lag Eq 9 (_engine_rate)
  rudder     _rudder_force, _rudder_inflow: S. D. Yoon Eq 7-8 (Fujii normal force, Kijima flow
             straightening); steering gear Eq 10 (_steering_gear_rate)
  thruster   _thruster_forces: azimuth thrusters (ASD tug): S. D. Yoon Eq 4 along the thruster's
             axis with the axial inflow, hull thrust deduction t(azimuth), thruster-thruster
             interaction of the ABS DP guide (_thruster_interaction); rpm lag Eq 9 style and
             slew-rate-limited azimuth (_azimuth_rate) per thruster
  anchor     _anchor_dredging: S. D. Yoon Eq 5-6; let-go / heave-up timing in the class
  towline    _simple_towline: Yun & Kim Eq 3 (constant magnitude, gamma ramp)
  external   _wrench_in_body: any number of vessel.ExternalWrench (world force at a body point)
  roll       _roll_moment: GM restoring and damping (harbour tug)
  body       _rigid_body_coriolis, _solve_accelerations: Yun & Kim Eq 1 / S. D. Yoon Eq 1
  current    uniform world current; hydrodynamics use the velocity through the water.

The papers use y to starboard and starboard-positive rudder. Every component whose
paper form is not odd-symmetric converts at its boundary (comment names the equation).
The time integration is RK4 in a numba kernel (cache=True) with a fixed sub-step.
"""
from __future__ import annotations

import dataclasses
import math
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np
from numba import njit

from sea_environment.sampler import (E0, E_CURRENT_X, E_CURRENT_Y, E_DEPTH, E_GROUND_FX, E_GROUND_FY, E_WIND_FX, E_WIND_FY, E_WIND_X, E_WIND_Z,
                                     N_SAMPLE, P_TIME, EnvironmentSampler, sample)
from sea_environment.shallow_water import (N_SW, SW_CROSSFLOW, SW_GAMMA, SW_JZ, SW_MX, SW_MY, SW_NONLINEAR,
                                           SW_NR, SW_NV, SW_ONE_MINUS_T, SW_ONE_MINUS_W, SW_RESISTANCE, SW_XVR,
                                           SW_XVV, SW_YR, SW_YV, shallow_water_factors)
from sim_math.integration import rk4_stage, rk4_update

from .vessel import (ANCHOR_HEAVE_UP, ANCHOR_LET_GO, CPL_C, CPL_K, CPL_ON, CPL_P, CPL_V, NCPL, SPRING_SUBSTEP,
                     AnchorState,
                     Command, CommandRejected, ExternalWrench, StatusRecord, ThrusterOrder, ThrusterStatus, Vessel,
                     VesselState, check_command, check_current, coupling_row)

# ---- state vector layout -------------------------------------------------
S_X, S_Y, S_PSI, S_U, S_V, S_R, S_PHI, S_P, S_N, S_DELTA = range(10)
NSTATE = 10
# azimuth thruster k (if the file has thrusters): shaft speed (rps) at S_THR0 + 2k, azimuth (rad,
# 0 = thrust ahead, + turns the thrust to port) at S_THR0 + 2k + 1; the state vector is
# NSTATE + 2 n_thrusters long (ships without thrusters keep NSTATE)
S_THR0 = NSTATE

# ---- hull parameter vector ------------------------------------------------
(H_FORM, H_RHO, H_L, H_T, H_M, H_XG, H_ZG, H_MX, H_MY, H_MMG_CORIOLIS, H_ROLL, H_GMW, H_KP, H_ZH,
 H_TOW_ON, H_TOW_F, H_TOW_X, H_TOW_DRIFT, H_TOW_RATE, H_TOW_MAX, H_ANC_LW, H_ANC_LA, H_ANC_UEPS,
 H_ANC_RON, H_ANC_VUCAP, H_NPROP, H_NRUD, H_MAXRATE, H_TE, H_TN, H_ANC_UREF, H_NTHR) = range(32)
H_C0 = 32           # hull coefficients start here (16 slots)
# shallow water (sea_environment.shallow_water.shallow_water_factors): the 16 hull coefficients'
# deep-water values, the factor (SW_*) each takes (-1: none), the hull's beam, block coefficient
# and the depth the factors are set for, its deep-water beam-on cross-flow C_D, the factors in force, the deep (u, v, r, p) mass matrix
# and the deep added masses m_x, m_y, J_z
H_SW_DEEP = H_C0 + 16
H_SW_KIND = H_SW_DEEP + 16
H_SW_BEAM, H_SW_BLOCK, H_SW_DEPTH, H_SW_CD0 = H_SW_KIND + 16, H_SW_KIND + 17, H_SW_KIND + 18, H_SW_KIND + 19
H_SWF = H_SW_KIND + 20
H_M0 = H_SWF + N_SW
H_ADD0 = H_M0 + 16
NHULL = H_ADD0 + 3

FORM_NONE, FORM_POLY, FORM_LOWSPEED, FORM_CROSSFLOW = 0, 1, 2, 3

# ---- propeller rows ---------------------------------------------------------
(P_X, P_Y, P_Z, P_D, P_PITCH, P_C1, P_C2, P_C3, P_WP0, P_T, P_AST, P_XPN) = range(12)
NPROP = 12
# ---- rudder rows ------------------------------------------------------------
(R_X, R_Y, R_Z, R_AREA, R_FALPHA, R_ETA, R_AH, R_XH, R_TR, R_WR0, R_LR, R_PROP, R_KAPPA0) = range(13)
NRUD = 13

# ---- azimuth thruster rows ---------------------------------------------------
(T_X, T_Y, T_Z, T_D, T_C1, T_C2, T_C3, T_AST, T_W, T_TN, T_RATE, T_TAZ, T_FULL, T_AMIN, T_AMAX,
 T_NTD, T_INTER) = range(17)   # T_INTER: 1 = thruster-thruster interaction (ABS), 0 = none
T_TD0 = 17          # thrust deduction table: T_NTD azimuths (rad, increasing in [-pi, pi]), then values
MAX_TD = 12
NTHR = T_TD0 + 2 * MAX_TD
MAX_THRUSTERS = 4

# ---- control vector ------------------------------------------------------------
C_NCMD, C_DCMD, C_ANC_F, C_ANC_SIDE, C_CUR_X, C_CUR_Y, C_GAMMA = range(7)
NCTRL = 7
C_THR0 = NCTRL      # thruster k: ordered shaft speed (rps) at C_THR0 + 2k, ordered azimuth (rad) + 1

# ---- output (diagnostics of the last derivative evaluation) ------------------
O_THRUST, O_ANC_X, O_HEEL_EXT, O_UR, O_VR = range(5)
# each force component's (X, Y, N) at O_TERM0 + 3 * TERM_*: the terms _deriv_c sums, so a steady
# state's balance can be checked term by term (Vessel.force_terms); coriolis: the rigid-body and
# added-mass Coriolis / centripetal terms moved to the right-hand side
FORCE_TERMS = ("hull", "propeller", "rudder", "thruster", "anchor", "towline", "external", "coriolis")
(TERM_HULL, TERM_PROPELLER, TERM_RUDDER, TERM_THRUSTER, TERM_ANCHOR, TERM_TOWLINE, TERM_EXTERNAL,
 TERM_CORIOLIS) = range(len(FORCE_TERMS))
O_TERM0 = 5
NOUT = O_TERM0 + 3 * len(FORCE_TERMS)
O_THR0 = NOUT       # thruster k: delivered force along its axis (N) at O_THR0 + 2k, open-water thrust + 1


@njit(cache=True)
def _interp_resistance(u, rv, rf):
    """X(u) from a table of (speed >= 0, resistance >= 0); quadratic outside; odd in u."""
    a = abs(u)
    k = rv.shape[0]
    if k == 0:
        return 0.0
    if a >= rv[k - 1]:
        val = rf[k - 1] * (a / rv[k - 1]) ** 2
    elif a <= rv[0]:
        val = rf[0] * (a / rv[0]) ** 2 if rv[0] > 0.0 else rf[0]
    else:
        i = 0
        while rv[i + 1] < a:
            i += 1
        f = (a - rv[i]) / (rv[i + 1] - rv[i])
        val = rf[i] + f * (rf[i + 1] - rf[i])
    return -val if u > 0.0 else val


# ---- force components -----------------------------------------------------------------------
# Each returns its contribution in the body frame (y port); _deriv sums them in a fixed order.

@njit(cache=True, inline="always")
def _current_in_body(ctrl, cpsi, spsi, cphi):
    """The uniform world current in body axes (horizontal; sway part projected by the heel)."""
    uc = cpsi * ctrl[C_CUR_X] + spsi * ctrl[C_CUR_Y]
    vc = (-spsi * ctrl[C_CUR_X] + cpsi * ctrl[C_CUR_Y]) * cphi
    return uc, vc


@njit(cache=True, inline="always")
def _hull_polynomial(c, rho, L, ur, vr, rl, U, Ue, rv, rf):
    """Yun & Kim (barge captive-model tests) Eq 2 in the prime system of their Eq 4
    (F / 0.5 rho U^2 L^2, v' = v/U, r' = rL/U), expanded dimensionally so U -> 0 stays finite.
    All terms are odd in (v, r), so the paper's y-starboard signs carry over to y-port.
    c: X'vv X'rr X'vr, Y'v Y'v|v| Y'r Y'r|r| Y'vrr Y'rvv, N'v N'v|v| N'r N'r|r| N'vrr N'rvv."""
    q = 0.5 * rho * L * L
    XH = q * (c[0] * vr * vr + c[1] * rl * rl + c[2] * vr * rl)
    YH = q * (c[3] * vr * U + c[4] * vr * abs(vr) + c[5] * rl * U + c[6] * rl * abs(rl)
              + c[7] * vr * rl * rl / Ue + c[8] * rl * vr * vr / Ue)
    NH = q * L * (c[9] * vr * U + c[10] * vr * abs(vr) + c[11] * rl * U + c[12] * rl * abs(rl)
                  + c[13] * vr * rl * rl / Ue + c[14] * rl * vr * vr / Ue)
    XH += _interp_resistance(ur, rv, rf)
    return XH, YH, NH


@njit(cache=True, inline="always")
def _hull_lowspeed(c, rho, L, T, ur, vr, rl, Ue, rv, rf):
    """S. D. Yoon (anchor dredging) Eq 3 (reconstructed, README "Reading decisions"): forces
    / 0.5 rho L d V^2, V = sqrt(u^2 + v^2). Y'v and N'r multiply |u|: hull lift and yaw damping
    oppose sway and yaw also astern (the paper covers ahead motion only; the Munk moment
    N'v u v changes sign, as it should).
    c: X'uu X'vr, Y'v Y'r Y'vv Y'vr Y'rr, N'v N'r N'vvr N'vrr N'rr, dC_D.

    Beam-on drag (README "Beam-on drag"): the captive-model Y'vv v|v| gives the hull a beam-on C_D
    of -Y'vv only; dC_D = -(C_D + Y'vv) raises it to the file's beam_on_drag C_D at 90 deg drift,
    weighted by sin^2(drift) = v^2 / V^2 (nil at the turn's small drift angles, whole at 90 deg)."""
    q = 0.5 * rho * L * T
    XH = q * (c[0] * ur * abs(ur) + c[1] * vr * rl)
    YH = q * (c[2] * abs(ur) * vr + c[3] * ur * rl + c[4] * vr * abs(vr) + c[5] * vr * abs(rl)
              + c[6] * rl * abs(rl) + c[12] * vr * abs(vr) * (vr / Ue) ** 2)
    NH = q * L * (c[7] * ur * vr + c[8] * abs(ur) * rl + c[9] * vr * vr * rl / Ue
                  + c[10] * vr * rl * rl / Ue + c[11] * rl * abs(rl))
    XH += _interp_resistance(ur, rv, rf)
    return XH, YH, NH


@njit(cache=True, inline="always")
def _wabsw_moments(v, r, a, b):
    """Exact integrals I0 = int_a^b w|w| dx and I1 = int_a^b x w|w| dx of the cross-flow velocity
    w(x) = v + x r (a < b). On a piece where w keeps its sign s, w|w| = s (v + x r)^2, integrated
    as a polynomial (no cancellation as r -> 0); the piece boundary is w's zero x0 = -v / r."""
    I0 = 0.0
    I1 = 0.0
    x0 = -v / r if r != 0.0 else a - 1.0
    for piece in range(2):
        if piece == 0:
            p, q = a, (x0 if a < x0 < b else b)
        else:
            if not (a < x0 < b):
                break
            p, q = x0, b
        xm = 0.5 * (p + q)
        wm = v + xm * r
        sg = 1.0 if wm > 0.0 else (-1.0 if wm < 0.0 else 0.0)
        d1 = q - p
        d2 = q * q - p * p
        d3 = q * q * q - p * p * p
        d4 = q * q * q * q - p * p * p * p
        I0 += sg * (v * v * d1 + v * r * d2 + r * r * d3 / 3.0)
        I1 += sg * (0.5 * v * v * d2 + 2.0 * v * r * d3 / 3.0 + 0.25 * r * r * d4)
    return I0, I1


@njit(cache=True, inline="always")
def _hull_crossflow(c, rho, L, T, ur, vr, r, rv, rf):
    """Hull forces valid at any drift angle: Oltmann & Sharma (1984) split into an ideal-fluid
    (lift) part and a cross-flow drag part, the latter as Hooft's (1994) strip integral.

      X = q (X'uu u|u| + X'vr v rL) - R(u)                       (R: the resistance table)
      Y = q (Y'v |u| v + Y'r u rL)     - 0.5 rho C_D T int w|w| dx
      N = q L (N'v u v + N'r |u| rL)   - 0.5 rho C_D T int x w|w| dx,   w(x) = v + x r
    q = 0.5 rho L T, the integral over the hull's lateral plane x_aft..x_fore, C_D = -Y'vv.

    The linear (lift / Munk) terms are the low-aspect-ratio lift of hull and skeg: with
    u = U cos(b), v = U sin(b) they are U^2 sin(b) cos(b) (slender-body / Jones form), zero at
    90 deg; the cross-flow drag is U^2 sin(b)|sin(b)| at r = 0 and takes the whole (v, r) field
    exactly, with no expansion in v or r.
    c: X'uu X'vr Y'v Y'r N'v N'r Y'vv x_aft x_fore."""
    q = 0.5 * rho * L * T
    rl = r * L
    I0, I1 = _wabsw_moments(vr, r, c[7], c[8])
    kd = 0.5 * rho * (-c[6]) * T
    XH = q * (c[0] * ur * abs(ur) + c[1] * vr * rl)
    YH = q * (c[2] * abs(ur) * vr + c[3] * ur * rl) - kd * I0
    NH = q * L * (c[4] * ur * vr + c[5] * abs(ur) * rl) - kd * I1
    XH += _interp_resistance(ur, rv, rf)
    return XH, YH, NH


@njit(cache=True, inline="always")
def _hull_forces(hp, rv, rf, ur, vr, r):
    """Hull forces X_H, Y_H, N_H of the file's hull form at the velocity through the water."""
    form = int(hp[H_FORM])
    if form == FORM_NONE:
        return 0.0, 0.0, 0.0
    L = hp[H_L]
    U = math.sqrt(ur * ur + vr * vr)
    Ue = U if U > 1e-9 else 1e-9
    rl = r * L
    c = hp[H_C0:H_C0 + 16]
    if form == FORM_POLY:
        XH, YH, NH = _hull_polynomial(c, hp[H_RHO], L, ur, vr, rl, U, Ue, rv, rf)
    elif form == FORM_CROSSFLOW:
        XH, YH, NH = _hull_crossflow(c, hp[H_RHO], L, hp[H_T], ur, vr, r, rv, rf)
    else:
        XH, YH, NH = _hull_lowspeed(c, hp[H_RHO], L, hp[H_T], ur, vr, rl, Ue, rv, rf)
    # shallow water's extra resistance (README "Shallow water" (S4)) on the resistance table
    return XH + (hp[H_SWF + SW_RESISTANCE] - 1.0) * _interp_resistance(ur, rv, rf), YH, NH


@njit(cache=True, inline="always")
def _propeller_thrust(props, k, rho, n, ur, vr, r, one_minus_w):
    """S. D. Yoon Eq 4 (with Eq 8's wake): thrust of propeller row k at shaft speed n (rps);
    one_minus_w: the shallow-water factor on 1 - w_P0 (README "Shallow water" (S6)).

    Returns (thrust, advance speed u_A, wake fraction w_P); the rudder behind it needs both."""
    D = props[k, P_D]
    up = ur - props[k, P_Y] * r                # surge speed at the propeller
    vp = vr + props[k, P_X] * r                # lateral speed at the propeller
    # w_P = w_P0 exp(-4 (beta - x_P' r')^2): the local drift angle at the propeller
    beta_p = math.atan2(vp, abs(up) + 1e-9)
    wake = (1.0 - (1.0 - props[k, P_WP0]) * one_minus_w) * math.exp(-4.0 * beta_p * beta_p)
    ua = up * (1.0 - wake)
    # K_T = C1 + C2 J + C3 J^2 written as rho D^4 [C1 n|n| + C2 |n| ua / D + C3 ua|ua| / D^2]:
    # identical for n > 0, ua >= 0; finite at n = 0 (locked-propeller drag opposes motion);
    # astern (n < 0) the bollard and J terms are scaled by the astern factor and act astern.
    if n >= 0.0:
        a1 = props[k, P_C1]
        a2 = props[k, P_C2]
    else:
        a1 = props[k, P_C1] * props[k, P_AST]
        a2 = props[k, P_C2] * props[k, P_AST]
    thrust = rho * D ** 4 * (a1 * n * abs(n) + a2 * abs(n) * ua / D + props[k, P_C3] * ua * abs(ua) / (D * D))
    return thrust, ua, wake


@njit(cache=True, inline="always")
def _rudder_inflow(wake_r0, kappa0, eta, wake_p0, pitch, wake_p, ua, n):
    """S. D. Yoon Eq 8 inflow behind a propeller: longitudinal speed u_R at the rudder and the
    propeller slip s (eta = D / H, kappa = kappa0 / eps, w_R = w_P w_R0 / w_P0).

    Turning ahead with slip s in [0, 1]: the propeller race (Kijima et al. 1990,
    u_R = eps n P sqrt(...)); windmilling, stopped or astern: the wake flow, continuous at s = 0.
    Scalars only: array arguments of an inlined function with branches cost reference counts."""
    wake_r = wake_p * wake_r0 / wake_p0 if wake_p0 > 0.0 else wake_r0
    eps = (1.0 - wake_r) / (1.0 - wake_p)
    kap = kappa0 / eps
    nP = n * pitch
    slip = 1.0 - ua / nP if n > 1e-9 else -1.0
    if slip < 0.0:
        return eps * ua, 0.0
    if slip > 1.0:
        slip = 1.0     # moving astern with the engine ahead
    arg = 1.0 - 2.0 * (1.0 - eta * kap) * slip + (1.0 - eta * kap * (2.0 - kap)) * slip * slip
    return eps * nP * math.sqrt(arg if arg > 0.0 else 0.0), slip


@njit(cache=True, inline="always")
def _rudder_force(ruds, k, uR, slip, rho, L, ur, vr, r, delta, gamma_factor):
    """S. D. Yoon Eq 7-8: X_R, Y_R, N_R of rudder k in the inflow u_R at propeller slip s
    (Fujii normal force, flow straightening gamma = C_p C_s, times gamma_factor: shallow water,
    README "Shallow water" (S7)). The paper's frame has y to
    starboard and starboard rudder positive: v, r and delta are flipped going in and Y, N
    coming out."""
    delta_p = -delta                            # paper frame (suffix _p): y starboard
    v_p = -vr
    r_p = -r
    eta = ruds[k, R_ETA]
    sc = slip if slip > 0.0 else 0.0
    # Eq 8: gamma = C_p C_s;  C_p as printed ((1+s)^2, see README)
    c_p = 1.0 / math.sqrt(1.0 + 0.6 * eta * (2.0 - 1.4 * sc) * sc / ((1.0 + sc) ** 2))
    # beta - l_R r': inflow angle of the local lateral flow at x = l_R L, bounded form;
    # gamma_beta = gamma (beta - l_R r'), the flow-straightened angle
    betaR = math.atan2(-(v_p + ruds[k, R_LR] * L * r_p), abs(ur) + 1e-9)
    abs_beta = abs(betaR)
    c_s = 0.45 * abs_beta if abs_beta <= 1.111 else 0.5
    gamma_beta = c_p * c_s * gamma_factor * betaR
    if gamma_beta > 1.5:
        gamma_beta = 1.5
    if gamma_beta < -1.5:
        gamma_beta = -1.5
    vR = uR * math.tan(gamma_beta)
    VR2 = uR * uR + vR * vR
    alpha = delta_p - gamma_beta
    sgn = 1.0 if uR >= 0.0 else -1.0           # reverse flow: the normal force reverses
    FN = 0.5 * rho * ruds[k, R_AREA] * ruds[k, R_FALPHA] * VR2 * math.sin(alpha) * sgn
    XR = -(1.0 - ruds[k, R_TR]) * FN * math.sin(delta_p)
    YR_p = -(1.0 + ruds[k, R_AH]) * FN * math.cos(delta_p)
    NR_p = -(ruds[k, R_X] + ruds[k, R_AH] * ruds[k, R_XH]) * FN * math.cos(delta_p)
    YR = -YR_p                                  # back to y-port (Eq 7)
    NR = -NR_p - ruds[k, R_Y] * XR
    return XR, YR, NR


@njit(cache=True, inline="always")
def _anchor_dredging(hp, ctrl, u, v, r):
    """S. D. Yoon Eq 5-6: a dredging anchor, ground-referenced (it drags over the bottom).

    X_A = -lambda_a W (against the headway). Eq 5 while turning (weight |w| -> 1): the text's
    Y_A = X_A v/u, a resistance to the sway (centripetal in a steady turn, where the ship slides
    outward), and N_A = lambda_a W l_a with the turn; Eq 6 straight (w = 0). README "Anchor
    readings (issue 36)"."""
    lw = hp[H_ANC_LW] * ctrl[C_ANC_F]
    ueps = hp[H_ANC_UEPS]
    sat = u / ueps
    if sat > 1.0:
        sat = 1.0
    if sat < -1.0:
        sat = -1.0
    XA = -lw * sat
    Vg = math.sqrt(u * u + v * v)
    Vg = Vg if Vg > ueps else ueps
    rp = r * hp[H_L] / Vg
    side = ctrl[C_ANC_SIDE]
    w = rp / hp[H_ANC_RON]
    if side != 0.0:
        w = side * w
        w = 0.0 if w < 0.0 else (1.0 if w > 1.0 else w)
        w = side * w
    else:
        w = -1.0 if w < -1.0 else (1.0 if w > 1.0 else w)
    # a dredging anchor does nothing without headway: fade Eq 5's turning terms below u_ref
    fade = abs(u) / hp[H_ANC_UREF]
    w *= fade if fade < 1.0 else 1.0
    vu = v / (abs(u) if abs(u) > ueps else ueps)
    cap = hp[H_ANC_VUCAP]
    vu = cap if vu > cap else (-cap if vu < -cap else vu)
    return XA, -lw * vu * abs(w), lw * hp[H_ANC_LA] * w


@njit(cache=True, inline="always")
def _record_term(out, term, X, Y, N):
    """One force component's (X, Y, N) into out (O_TERM0 + 3 term)."""
    i = O_TERM0 + 3 * term
    out[i] = X
    out[i + 1] = Y
    out[i + 2] = N


@njit(cache=True, inline="always")
def _propellers_and_rudders(hp, props, ruds, rho, n, delta, ur, vr, r, X, Y, N, K, out):
    """Adds every propeller's (Eq 4) and rudder's (Eq 7-8) force to the running sums X, Y, N, K in
    the model's fixed order and records the two terms; sets out[O_THRUST]."""
    thrust_total = 0.0
    XP = 0.0
    NP = 0.0
    prop_advance = np.zeros(4)
    prop_wake = np.zeros(4)
    for k in range(int(hp[H_NPROP])):
        thrust, ua, wake = _propeller_thrust(props, k, rho, n, ur, vr, r, hp[H_SWF + SW_ONE_MINUS_W])
        prop_advance[k] = ua
        prop_wake[k] = wake
        thrust_total += thrust
        fx = (1.0 - props[k, P_T]) * hp[H_SWF + SW_ONE_MINUS_T] * thrust
        X += fx
        N += -props[k, P_Y] * fx
        XP += fx
        NP += -props[k, P_Y] * fx
    out[O_THRUST] = thrust_total
    _record_term(out, TERM_PROPELLER, XP, 0.0, NP)
    XRs = 0.0
    YRs = 0.0
    NRs = 0.0
    for k in range(int(hp[H_NRUD])):
        j = int(ruds[k, R_PROP])
        if j < 0:                              # no propeller ahead of it: the hull's wake
            uR, slip = (1.0 - ruds[k, R_WR0]) * ur, 0.0
        else:
            wake_p0 = 1.0 - (1.0 - props[j, P_WP0]) * hp[H_SWF + SW_ONE_MINUS_W]
            uR, slip = _rudder_inflow(ruds[k, R_WR0], ruds[k, R_KAPPA0], ruds[k, R_ETA], wake_p0,
                                      props[j, P_PITCH], prop_wake[j], prop_advance[j], n)
        XR, YR, NR = _rudder_force(ruds, k, uR, slip, rho, hp[H_L], ur, vr, r, delta, hp[H_SWF + SW_GAMMA])
        X += XR
        Y += YR
        N += NR
        K += -ruds[k, R_Z] * YR
        XRs += XR
        YRs += YR
        NRs += NR
    _record_term(out, TERM_RUDDER, XRs, YRs, NRs)
    return X, Y, N, K


@njit(cache=True, inline="always")
def _simple_towline(hp, ctrl, ur, vr):
    """Yun & Kim Eq 3: constant magnitude X(u_c) at the angle gamma + beta, N_TL = Y_TL L/2
    (towpoint at the bow)."""
    th = ctrl[C_GAMMA] + hp[H_TOW_DRIFT] * math.atan2(vr, abs(ur) + 1e-9)
    F0 = hp[H_TOW_F]
    XT = F0 * math.cos(th)
    YT = F0 * math.sin(th)
    return XT, YT, hp[H_TOW_X] * YT


@njit(cache=True, inline="always")
def _towline_angle_ramp(gamma, gamma_max, max_change):
    """Yun & Kim Eq 3: gamma_{i+1} = gamma_i + gamma-dot dt, up to gamma_max."""
    if abs(gamma_max - gamma) <= max_change:
        return gamma_max
    return gamma + (max_change if gamma_max > gamma else -max_change)


@njit(cache=True, inline="always")
def _wrench_in_body(force, point, moment, cpsi, spsi, cphi, sphi):
    """One external wrench (world force at a body point, world moment): its X, Y, K, N."""
    # body = Rx(phi)^T Rz(psi)^T world
    f1 = cpsi * force[0] + spsi * force[1]
    f2h = -spsi * force[0] + cpsi * force[1]
    f2 = cphi * f2h + sphi * force[2]
    f3 = -sphi * f2h + cphi * force[2]
    m1 = cpsi * moment[0] + spsi * moment[1]
    m2h = -spsi * moment[0] + cpsi * moment[1]
    m3 = -sphi * m2h + cphi * moment[2]
    kx = point[1] * f3 - point[2] * f2 + m1
    return f1, f2, kx, point[0] * f2 - point[1] * f1 + m3


@njit(cache=True, inline="always")
def _point_motion(point, x, y, u, v, r, p, cpsi, spsi, cphi, sphi):
    """World position and velocity of a body point at the state (R = Rz(psi) Rx(phi), body angular
    velocity (p, 0, r), the reference point at z = 0), as 6 floats."""
    rx, ry, rz = point[0], point[1], point[2]
    a, b, c = rx, cphi * ry - sphi * rz, sphi * ry + cphi * rz
    b0, b1, b2 = u - r * ry, v + r * rx - p * rz, p * ry
    h1, h2 = cphi * b1 - sphi * b2, sphi * b1 + cphi * b2
    return (x + cpsi * a - spsi * b, y + spsi * a + cpsi * b, c,
            cpsi * b0 - spsi * h1, spsi * b0 + cpsi * h1, h2)


@njit(cache=True, inline="always")
def _coupled_force(force, cpl, point, x, y, u, v, r, p, cpsi, spsi, cphi, sphi):
    """force + K (p_pt - p_ref) + C (v_pt - v_ref), world, as 3 floats (force itself for a row that
    is not coupled): an exchanged force followed along the point's own motion inside the step (the
    other side's one-step lag removed; docs/step-protocol.md)."""
    if cpl[CPL_ON] <= 0.0:
        return force[0], force[1], force[2]
    px, py, pz, vx, vy, vz = _point_motion(point, x, y, u, v, r, p, cpsi, spsi, cphi, sphi)
    dp0, dp1, dp2 = px - cpl[CPL_P], py - cpl[CPL_P + 1], pz - cpl[CPL_P + 2]
    dv0, dv1, dv2 = vx - cpl[CPL_V], vy - cpl[CPL_V + 1], vz - cpl[CPL_V + 2]
    k, c = CPL_K, CPL_C
    return (force[0] + cpl[k] * dp0 + cpl[k + 1] * dp1 + cpl[k + 2] * dp2
            + cpl[c] * dv0 + cpl[c + 1] * dv1 + cpl[c + 2] * dv2,
            force[1] + cpl[k + 3] * dp0 + cpl[k + 4] * dp1 + cpl[k + 5] * dp2
            + cpl[c + 3] * dv0 + cpl[c + 4] * dv1 + cpl[c + 5] * dv2,
            force[2] + cpl[k + 6] * dp0 + cpl[k + 7] * dp1 + cpl[k + 8] * dp2
            + cpl[c + 6] * dv0 + cpl[c + 7] * dv1 + cpl[c + 8] * dv2)


@njit(cache=True, inline="always")
def _rigid_body_coriolis(hp, ur, vr, r):
    """Rigid-body and added-mass Coriolis terms about the reference point, moved to the right.

    MMG form (S. D. Yoon Eq 1) for the low-speed hull, Yun & Kim Eq 1 (x_G r^2, README) for the
    polynomial hull. Relative velocities: exact for a uniform current (Fossen 2011, 10.3)."""
    m = hp[H_M]
    xg = hp[H_XG]
    if hp[H_MMG_CORIOLIS] > 0.0:
        Xc = (m + hp[H_MY]) * vr * r + m * xg * r * r
        Yc = -(m + hp[H_MX]) * ur * r
    else:
        Xc = m * (vr * r + xg * r * r)
        Yc = -m * ur * r
    return Xc, Yc, -m * xg * ur * r


@njit(cache=True, inline="always")
def _roll_moment(hp, ur, r, sphi, p):
    """Roll: Coriolis coupling of the turn, restoring -m g GM sin(phi), linear damping."""
    return hp[H_M] * hp[H_ZG] * ur * r - hp[H_GMW] * sphi - hp[H_KP] * p


@njit(cache=True, inline="always")
def _solve_accelerations(minv, X, Y, N, K):
    """(u-dot, v-dot, r-dot, p-dot) = M^-1 (X, Y, N, K): rigid body + added mass."""
    du = minv[0, 0] * X + minv[0, 1] * Y + minv[0, 2] * N + minv[0, 3] * K
    dv = minv[1, 0] * X + minv[1, 1] * Y + minv[1, 2] * N + minv[1, 3] * K
    dr = minv[2, 0] * X + minv[2, 1] * Y + minv[2, 2] * N + minv[2, 3] * K
    dp = minv[3, 0] * X + minv[3, 1] * Y + minv[3, 2] * N + minv[3, 3] * K
    return du, dv, dr, dp


@njit(cache=True, inline="always")
def _engine_rate(hp, ctrl, n):
    """S. D. Yoon Eq 9: first-order shaft-speed lag n' = (n* - n) / T_n."""
    return (ctrl[C_NCMD] - n) / hp[H_TN]


@njit(cache=True, inline="always")
def _steering_gear_rate(hp, ctrl, delta):
    """S. D. Yoon Eq 10: lag T_e while the error is small, else the gear's rate limit."""
    err = ctrl[C_DCMD] - delta
    te = hp[H_TE]
    rate = hp[H_MAXRATE]
    if abs(err) <= te * rate:
        return err / te
    return rate if err > 0.0 else -rate


# ---- azimuth thrusters ------------------------------------------------------------------------

@njit(cache=True, inline="always")
def _wrap(a):
    """An angle in (-pi, pi]."""
    return math.atan2(math.sin(a), math.cos(a))


@njit(cache=True)
def _hull_deduction(thrs, k, azimuth):
    """Thrust deduction t(azimuth) of thruster k: linear in the table, periodic over 360 deg
    (one value: constant). The hull's extra resistance from the thruster's suction and jet (jet
    along the hull astern, onto the skeg sideways), acting along the thrust."""
    m = int(thrs[k, T_NTD])
    if m == 1:
        return thrs[k, T_TD0 + MAX_TD]
    a = _wrap(azimuth)
    a0 = thrs[k, T_TD0]
    am = thrs[k, T_TD0 + m - 1]
    if a < a0 or a >= am:              # the wrap-around segment, last -> first + 2 pi
        span = a0 + 2.0 * math.pi - am
        da = a - am if a >= am else a + 2.0 * math.pi - am
        f = da / span if span > 0.0 else 0.0
        return thrs[k, T_TD0 + MAX_TD + m - 1] + f * (thrs[k, T_TD0 + MAX_TD] - thrs[k, T_TD0 + MAX_TD + m - 1])
    i = 0
    while thrs[k, T_TD0 + i + 1] <= a:
        i += 1
    f = (a - thrs[k, T_TD0 + i]) / (thrs[k, T_TD0 + i + 1] - thrs[k, T_TD0 + i])
    return thrs[k, T_TD0 + MAX_TD + i] + f * (thrs[k, T_TD0 + MAX_TD + i + 1] - thrs[k, T_TD0 + MAX_TD + i])


@njit(cache=True, inline="always")
def _thruster_open_water(thrs, k, rho, n, ua):
    """S. D. Yoon Eq 4 along the thruster's axis: T = rho n^2 D^4 K_T(J), K_T = C1 + C2 J + C3 J^2,
    J = u_A / (n D), u_A the inflow along the thrust direction; rho D^4 (C1 n^2 + C2 n u_A / D +
    C3 u_A^2 / D^2) for n > 0, u_A >= 0. The quadratic is open-water data (J >= 0): beyond its zero
    the propeller freewheels and its small drag is neglected (T = 0, not the quadratic's negative
    tail); with inflow from behind (J < 0) the linear part C1 + C2 J; a stopped unit gives no
    force. Reversed rotation (a reversible unit): the same with the inflow reversed, C1 and C2
    scaled by the astern factor, thrust negative."""
    D = thrs[k, T_D]
    if n == 0.0:
        return 0.0
    sg = 1.0
    a1 = thrs[k, T_C1]
    a2 = thrs[k, T_C2]
    if n < 0.0:
        sg = -1.0
        n = -n
        ua = -ua
        a1 *= thrs[k, T_AST]
        a2 *= thrs[k, T_AST]
    t = a1 * n * n + a2 * n * ua / D
    if ua > 0.0:
        t += thrs[k, T_C3] * ua * ua / (D * D)
    if t < 0.0:
        t = 0.0
    return sg * rho * D ** 4 * t


@njit(cache=True, inline="always")
def _thruster_interaction(dist_over_d, phi_deg):
    """ABS Guide for Dynamic Positioning Systems (2013), Appendix 1 (after Dang & Laheij 2004):
    thrust ratio T / T0 of a thruster in the jet of another at distance x (x/D, D the upstream
    thruster's diameter): t = 1 - 0.75^((x/D)^(2/3)) in line; with the jet turned phi deg off the
    line joining them t_phi = t + (1 - t) phi^3 / (130 / t^3 + phi^3)."""
    t = 1.0 - 0.75 ** (dist_over_d ** (2.0 / 3.0))
    if t <= 0.0:
        return 0.0
    p3 = phi_deg * phi_deg * phi_deg
    return t + (1.0 - t) * p3 / (130.0 / (t * t * t) + p3)


@njit(cache=True, inline="always")
def _azimuth_rate(thrs, k, ordered, azimuth):
    """The azimuth follows its order at the slew-rate limit (shortest way round on a 360 deg
    unit; a unit with a limited range turns within it), settling with a first-order lag
    T_az inside rate x T_az of the order (S. D. Yoon Eq 10 form, as the steering gear)."""
    err = ordered - azimuth
    if thrs[k, T_FULL] > 0.0:
        err = _wrap(err)
    rate = thrs[k, T_RATE]
    taz = thrs[k, T_TAZ]
    if abs(err) <= taz * rate:
        return err / taz
    return rate if err > 0.0 else -rate


@njit(cache=True)
def _thruster_forces(s, thrs, ctrl, rho, ur, vr, r, out, ds):
    """X, Y, N, K of every azimuth thruster; writes their shaft and azimuth rates into ds and the
    delivered and open-water thrust into out (O_THR0 + 2k, + 1).

    Thrust acts along the azimuth (0 = ahead, + to port); the inflow is the water's velocity at
    the thruster, its component along the thruster's axis the advance speed (times 1 - w)."""
    nthr = thrs.shape[0]
    T0 = np.empty(nthr)
    ca = np.empty(nthr)
    sa = np.empty(nthr)
    for k in range(nthr):
        n = s[S_THR0 + 2 * k]
        a = s[S_THR0 + 2 * k + 1]
        ca[k] = math.cos(a)
        sa[k] = math.sin(a)
        ut = ur - thrs[k, T_Y] * r             # water velocity at the thruster (body, y port)
        vt = vr + thrs[k, T_X] * r
        ua = (ut * ca[k] + vt * sa[k]) * (1.0 - thrs[k, T_W])
        T0[k] = _thruster_open_water(thrs, k, rho, n, ua)
        ds[S_THR0 + 2 * k] = (ctrl[C_THR0 + 2 * k] - n) / thrs[k, T_TN]        # Eq 9 lag
        ds[S_THR0 + 2 * k + 1] = _azimuth_rate(thrs, k, ctrl[C_THR0 + 2 * k + 1], a)
    X = 0.0
    Y = 0.0
    N = 0.0
    K = 0.0
    for k in range(nthr):
        f = 1.0 - _hull_deduction(thrs, k, s[S_THR0 + 2 * k + 1])
        nk = abs(s[S_THR0 + 2 * k])
        for i in range(nthr):
            if i == k or T0[i] == 0.0 or thrs[k, T_INTER] == 0.0:
                continue
            # the jet of i leaves against its thrust; is k in it?
            sg = 1.0 if T0[i] > 0.0 else -1.0
            jx = -sg * ca[i]
            jy = -sg * sa[i]
            dx = thrs[k, T_X] - thrs[i, T_X]
            dy = thrs[k, T_Y] - thrs[i, T_Y]
            dist = math.sqrt(dx * dx + dy * dy)
            if dist <= 0.0:
                continue
            c = (dx * jx + dy * jy) / dist
            c = 1.0 if c > 1.0 else (-1.0 if c < -1.0 else c)
            tr = _thruster_interaction(dist / thrs[i, T_D], math.degrees(math.acos(c)))
            # ABS's ratio is for equally loaded units: a slower jet (rpm ratio) takes less
            ni = abs(s[S_THR0 + 2 * i])
            wgt = 1.0 if ni >= nk else ni / nk
            f *= 1.0 - (1.0 - tr) * wgt
        F = f * T0[k]
        fx = F * ca[k]
        fy = F * sa[k]
        X += fx
        Y += fy
        N += thrs[k, T_X] * fy - thrs[k, T_Y] * fx
        K += -thrs[k, T_Z] * fy
        out[O_THR0 + 2 * k] = F
        out[O_THR0 + 2 * k + 1] = T0[k]
    return X, Y, N, K


# ---- equations of motion ---------------------------------------------------------------------

@njit(cache=True)
def _deriv(s, hp, props, ruds, rv, rf, minv, ctrl, wrench_force, wrench_point, wrench_moment, out):
    """_deriv_t of a ship without azimuth thrusters (the form the tests call)."""
    return _deriv_t(s, hp, props, ruds, np.zeros((0, NTHR)), rv, rf, minv, ctrl, wrench_force, wrench_point,
                    wrench_moment, out)


@njit(cache=True)
def _deriv_t(s, hp, props, ruds, thrs, rv, rf, minv, ctrl, wrench_force, wrench_point, wrench_moment, out):
    """_deriv_c with constant wrenches (no coupling rows; the form the tests and benchmarks call)."""
    return _deriv_c(s, hp, props, ruds, thrs, rv, rf, minv, ctrl, wrench_force, wrench_point, wrench_moment,
                    np.zeros((wrench_force.shape[0], NCPL)), out)


@njit(cache=True)
def _deriv_c(s, hp, props, ruds, thrs, rv, rf, minv, ctrl, wrench_force, wrench_point, wrench_moment, wrench_cpl,
             out):
    """Time derivative of the state vector s (S_* indices); writes diagnostics to out (O_*).

    X, Y, N, K sum the components in a fixed order (the order is part of the numbers)."""
    ds = np.zeros(s.shape[0])
    u, v, r, p = s[S_U], s[S_V], s[S_R], s[S_P]
    n, delta = s[S_N], s[S_DELTA]
    cpsi, spsi = math.cos(s[S_PSI]), math.sin(s[S_PSI])
    cphi, sphi = math.cos(s[S_PHI]), math.sin(s[S_PHI])
    rho = hp[H_RHO]
    uc, vc = _current_in_body(ctrl, cpsi, spsi, cphi)
    ur = u - uc                                 # velocity through the water
    vr = v - vc
    X = 0.0
    Y = 0.0
    N = 0.0
    K = 0.0

    XH, YH, NH = _hull_forces(hp, rv, rf, ur, vr, r)
    X += XH
    Y += YH
    N += NH
    K += -hp[H_ZH] * YH      # hull lateral force acts at z_H (below the waterline)
    _record_term(out, TERM_HULL, XH, YH, NH)
    X, Y, N, K = _propellers_and_rudders(hp, props, ruds, rho, n, delta, ur, vr, r, X, Y, N, K, out)

    XT, YT, NT = 0.0, 0.0, 0.0
    if thrs.shape[0] > 0:
        XT, YT, NT, KT = _thruster_forces(s, thrs, ctrl, rho, ur, vr, r, out, ds)
        X += XT
        Y += YT
        N += NT
        K += KT
        # status thrust: along body x, propellers and thrusters
        for k in range(thrs.shape[0]):
            out[O_THRUST] += out[O_THR0 + 2 * k] * math.cos(s[S_THR0 + 2 * k + 1])
    _record_term(out, TERM_THRUSTER, XT, YT, NT)

    XA, YA, NA = 0.0, 0.0, 0.0
    if ctrl[C_ANC_F] > 0.0:
        XA, YA, NA = _anchor_dredging(hp, ctrl, u, v, r)
        X += XA
        Y += YA
        N += NA
    out[O_ANC_X] = XA
    _record_term(out, TERM_ANCHOR, XA, YA, NA)

    XT, YT, NT = 0.0, 0.0, 0.0
    if hp[H_TOW_ON] > 0.0:
        XT, YT, NT = _simple_towline(hp, ctrl, ur, vr)
        X += XT
        Y += YT
        N += NT
    _record_term(out, TERM_TOWLINE, XT, YT, NT)

    heel_external = 0.0
    Xe, Ye, Ne = X, Y, N
    for k in range(wrench_force.shape[0]):
        force = _coupled_force(wrench_force[k], wrench_cpl[k], wrench_point[k], s[S_X], s[S_Y], u, v, r, p,
                               cpsi, spsi, cphi, sphi)
        Xw, Yw, Kw, Nw = _wrench_in_body(force, wrench_point[k], wrench_moment[k], cpsi, spsi, cphi, sphi)
        X += Xw
        Y += Yw
        K += Kw
        N += Nw
        heel_external += Kw + hp[H_ZH] * Yw     # heeling couple against the hull's lateral resistance
    _record_term(out, TERM_EXTERNAL, X - Xe, Y - Ye, N - Ne)
    out[O_HEEL_EXT] = heel_external
    out[O_UR] = ur
    out[O_VR] = vr

    Xc, Yc, Nc = _rigid_body_coriolis(hp, ur, vr, r)
    X += Xc
    Y += Yc
    N += Nc
    _record_term(out, TERM_CORIOLIS, Xc, Yc, Nc)
    roll = hp[H_ROLL] > 0.0
    if roll:
        K += _roll_moment(hp, ur, r, sphi, p)
    du, dv, dr, dp = _solve_accelerations(minv, X, Y, N, K)

    # the current turns with the body: d(nu_c)/dt = -omega x nu_c
    ds[S_U] = du + r * vc
    ds[S_V] = dv - r * uc
    ds[S_R] = dr
    if roll:
        ds[S_P] = dp
        ds[S_PHI] = p
    # kinematics (4-DOF, pitch = 0)
    ds[S_X] = u * cpsi - v * cphi * spsi
    ds[S_Y] = u * spsi + v * cphi * cpsi
    ds[S_PSI] = r * cphi
    ds[S_N] = _engine_rate(hp, ctrl, n)
    ds[S_DELTA] = _steering_gear_rate(hp, ctrl, delta)
    return ds


@njit(cache=True)
def _integrate(s, dt, hmax, hp, props, ruds, thrs, rv, rf, minv, ctrl, wrench_force, wrench_point, wrench_moment,
               wrench_cpl, out):
    """RK4 over dt in equal sub-steps <= hmax; the towline angle ramps between sub-steps and the
    azimuths of 360 deg thrusters are wrapped to (-pi, pi] after each. Coupled wrench rows
    (wrench_cpl) are evaluated at every stage. Returns the work done by each wrench's force on its
    point over dt (J; RK4's weights on the stage powers)."""
    nsub = int(math.ceil(dt / hmax - 1e-9))
    if nsub < 1:
        nsub = 1
    h = dt / nsub
    stage = np.empty_like(s)
    work = np.zeros(wrench_force.shape[0])
    for _ in range(nsub):
        _add_wrench_work(s, wrench_force, wrench_point, wrench_cpl, work, h / 6.0)
        k1 = _deriv_c(s, hp, props, ruds, thrs, rv, rf, minv, ctrl, wrench_force, wrench_point, wrench_moment,
                      wrench_cpl, out)
        x2 = rk4_stage(s, 0.5 * h, k1, stage)
        _add_wrench_work(x2, wrench_force, wrench_point, wrench_cpl, work, h / 3.0)
        k2 = _deriv_c(x2, hp, props, ruds, thrs, rv, rf, minv, ctrl, wrench_force, wrench_point, wrench_moment,
                      wrench_cpl, out)
        x3 = rk4_stage(s, 0.5 * h, k2, stage)
        _add_wrench_work(x3, wrench_force, wrench_point, wrench_cpl, work, h / 3.0)
        k3 = _deriv_c(x3, hp, props, ruds, thrs, rv, rf, minv, ctrl, wrench_force, wrench_point, wrench_moment,
                      wrench_cpl, out)
        x4 = rk4_stage(s, h, k3, stage)
        _add_wrench_work(x4, wrench_force, wrench_point, wrench_cpl, work, h / 6.0)
        k4 = _deriv_c(x4, hp, props, ruds, thrs, rv, rf, minv, ctrl, wrench_force, wrench_point, wrench_moment,
                      wrench_cpl, out)
        rk4_update(s, h, k1, k2, k3, k4)
        if hp[H_TOW_ON] > 0.0:
            ctrl[C_GAMMA] = _towline_angle_ramp(ctrl[C_GAMMA], hp[H_TOW_MAX], hp[H_TOW_RATE] * h)
        for k in range(thrs.shape[0]):
            if thrs[k, T_FULL] > 0.0:
                s[S_THR0 + 2 * k + 1] = _wrap(s[S_THR0 + 2 * k + 1])
    _deriv_c(s, hp, props, ruds, thrs, rv, rf, minv, ctrl, wrench_force, wrench_point, wrench_moment, wrench_cpl,
             out)   # diagnostics
    return work


@njit(cache=True)
def _add_wrench_work(s, wrench_force, wrench_point, wrench_cpl, work, weight):
    """work += weight x the power (W) of each wrench's force on its point's world velocity at s:
    RK4's weights on the stage powers give the work over a sub-step."""
    u, v, r, p = s[S_U], s[S_V], s[S_R], s[S_P]
    cpsi, spsi = math.cos(s[S_PSI]), math.sin(s[S_PSI])
    cphi, sphi = math.cos(s[S_PHI]), math.sin(s[S_PHI])
    for k in range(wrench_force.shape[0]):
        point = wrench_point[k]
        f0, f1, f2 = _coupled_force(wrench_force[k], wrench_cpl[k], point, s[S_X], s[S_Y], u, v, r, p,
                                    cpsi, spsi, cphi, sphi)
        _x, _y, _z, vx, vy, vz = _point_motion(point, s[S_X], s[S_Y], u, v, r, p, cpsi, spsi, cphi, sphi)
        work[k] += weight * (f0 * vx + f1 * vy + f2 * vz)


@njit(cache=True)
def _integrate_in_environment(s, dt, hmax, hp, props, ruds, thrs, rv, rf, minv, ctrl, wrench_force, wrench_point,
                              wrench_moment, wrench_cpl, out, env):
    """_integrate in the environment (env: a EnvironmentSampler's data) as sampled at the
    start state: its wind and the bottom's friction are the last two wrench rows (filled here);
    then the environment is sampled at the new state, its time advanced by dt, and its current and
    the shallow-water factors at its depth (_apply_depth) set for the next step. One compiled call: the same as
    Python calls cost twice the step (bench_vessels)."""
    e = env[E0:E0 + N_SAMPLE]
    k = wrench_force.shape[0] - 2
    wrench_force[k, 0], wrench_force[k, 1], wrench_force[k, 2] = e[E_WIND_FX], e[E_WIND_FY], 0.0
    wrench_point[k, 0], wrench_point[k, 1], wrench_point[k, 2] = e[E_WIND_X], 0.0, e[E_WIND_Z]
    wrench_force[k + 1, 0], wrench_force[k + 1, 1], wrench_force[k + 1, 2] = e[E_GROUND_FX], e[E_GROUND_FY], 0.0
    for i in range(3):
        wrench_point[k + 1, i] = 0.0
        wrench_moment[k, i] = 0.0
        wrench_moment[k + 1, i] = 0.0
    work = _integrate(s, dt, hmax, hp, props, ruds, thrs, rv, rf, minv, ctrl, wrench_force, wrench_point,
                      wrench_moment, wrench_cpl, out)
    env[P_TIME] += dt
    sample(env, s[S_X], s[S_Y], s[S_PSI], s[S_U], s[S_V])
    _apply_environment(e, ctrl, hp, minv)
    return work


@njit(cache=True)
def _apply_environment(e, ctrl, hp, minv):
    """The sampled current into ctrl, and the shallow-water factors at the sampled depth
    (_apply_depth)."""
    ctrl[C_CUR_X], ctrl[C_CUR_Y] = e[E_CURRENT_X], e[E_CURRENT_Y]
    _apply_depth(hp, minv, e[E_DEPTH])


@njit(cache=True)
def _apply_depth(hp, minv, depth):
    """Shallow-water factors (sea_environment.shallow_water.shallow_water_factors, README
    "Shallow water") at water depth `depth` (m; inf = deep) on every hull coefficient that takes
    one (hp[H_SW_KIND:]), on the resistance, wake, thrust deduction and flow straightening
    (hp[H_SWF:], read by the kernels) and on the added masses (minv rebuilt). Nothing to do when
    the depth is the one the factors are set for."""
    if depth == hp[H_SW_DEPTH] or hp[H_FORM] == FORM_NONE or not hp[H_SW_BEAM] > 0.0:
        return     # unchanged, no hull, or no particulars (a vessel not built by load_ship)
    hp[H_SW_DEPTH] = depth
    f = shallow_water_factors(hp[H_L], hp[H_SW_BEAM], hp[H_T], hp[H_SW_BLOCK], depth, hp[H_SW_CD0])
    for i in range(N_SW):
        hp[H_SWF + i] = f[i]
    for i in range(16):
        kind = int(hp[H_SW_KIND + i])
        hp[H_C0 + i] = hp[H_SW_DEEP + i] * (f[kind] if kind >= 0 else 1.0)
    mx, my, jz = hp[H_ADD0], hp[H_ADD0 + 1], hp[H_ADD0 + 2]
    hp[H_MX], hp[H_MY] = mx * f[SW_MX], my * f[SW_MY]
    m = np.empty((4, 4))
    for i in range(16):
        m[i // 4, i % 4] = hp[H_M0 + i]
    m[0, 0] += mx * (f[SW_MX] - 1.0)
    m[1, 1] += my * (f[SW_MY] - 1.0)
    m[2, 2] += jz * (f[SW_JZ] - 1.0)
    minv[:, :] = np.linalg.inv(m)


# the shallow-water factor (SW_*) each hull coefficient takes, per form, in hp[H_C0:] order
# (README "Shallow water"): the sway cross-flow drag (Y'v|v|, -C_D) the cross-flow growth (S9), every
# other nonlinear term (S3)'s; X'rr none (not covered); -1 = none
_SW_KINDS = {
    # X'vv X'rr X'vr, Y'v Y'v|v| Y'r Y'r|r| Y'vrr Y'rvv, N'v N'v|v| N'r N'r|r| N'vrr N'rvv
    FORM_POLY: (SW_XVV, -1, SW_XVR, SW_YV, SW_CROSSFLOW, SW_YR, SW_NONLINEAR, SW_NONLINEAR, SW_NONLINEAR,
                SW_NV, SW_NONLINEAR, SW_NR, SW_NONLINEAR, SW_NONLINEAR, SW_NONLINEAR),
    # X'uu X'vr, Y'v Y'r Y'vv Y'vr Y'rr, N'v N'r N'vvr N'vrr N'rr, dC_D (beam-on drag)
    FORM_LOWSPEED: (SW_RESISTANCE, SW_XVR, SW_YV, SW_YR, SW_CROSSFLOW, SW_NONLINEAR, SW_NONLINEAR, SW_NV, SW_NR,
                    SW_NONLINEAR, SW_NONLINEAR, SW_NONLINEAR, SW_CROSSFLOW),
    # X'uu X'vr Y'v Y'r N'v N'r Y'vv(-C_D) x_aft x_fore
    FORM_CROSSFLOW: (SW_RESISTANCE, SW_XVR, SW_YV, SW_YR, SW_NV, SW_NR, SW_CROSSFLOW, -1, -1),
}


def point_mobility_matrix(minv, point_body, roll: bool) -> float:
    """vessel.Vessel.point_mobility for the (u, v, r, p) mass matrix inverse minv: a world force
    (fx, fy) at body point r gives X = fx, Y = fy, N = rx fy - ry fx, K = -rz fy (roll only with
    a roll degree of freedom); the point's horizontal acceleration is (u' - ry r',
    v' + rx r' - rz p'), i.e. G M^-1 G^T with G the point's lever. Body axes: the eigenvalues do
    not depend on the heading."""
    rx, ry, rz = (float(c) for c in point_body)
    g = np.array([[1.0, 0.0, -ry, 0.0], [0.0, 1.0, rx, -rz if roll else 0.0]])
    mob = g @ np.asarray(minv, float) @ g.T
    return float(np.linalg.eigvalsh(0.5 * (mob + mob.T))[-1])


# AnchorState members bound once: an Enum class attribute costs ~0.1 us per lookup in step()
_NO_ANCHOR, _STOWED, _LETTING_GO, _DREDGING, _HEAVING_UP = (
    AnchorState.NONE, AnchorState.STOWED, AnchorState.LETTING_GO, AnchorState.DREDGING, AnchorState.HEAVING_UP)


@dataclasses.dataclass(kw_only=True, slots=True)
class DisplacementStatus(StatusRecord):
    """StatusRecord plus the displacement model's own values."""
    engine_rpm: float        # actual shaft speed, rev/min (mean of the thrusters' on a thruster-only ship)
    anchor_force: float      # N, dredging resistance (S. D. Yoon Eq 5-6), >= 0
    towline_angle: float     # rad, Yun & Kim Eq 3 gamma
    thrusters: tuple         # one vessel.ThrusterStatus per azimuth thruster (empty without)


def anchor_holding_factor(holding_force: float, chain_out: float, chain_weight: float, height: float) -> float:
    """Share (0..1) of an anchor's holding force its chain lets it use at this depth.

    The anchor holds only while the chain pulls on it horizontally, i.e. while the chain's
    catenary from the hawse pipe (height = depth + hawse height above the bottom) still has its
    lowest point at the anchor. For a catenary with horizontal tension H and submerged weight w
    per metre, the suspended length from that point to a height h is s = sqrt(h^2 + 2 h H / w)
    (e.g. Faltinsen 1990, Sea Loads on Ships and Offshore Structures, ch. 8), so with chain_out
    metres out the largest such H is w (chain_out^2 - h^2) / (2 h). A chain shorter than the
    height does not reach the bottom: no holding."""
    if chain_out <= height:
        return 0.0
    h_max = chain_weight * (chain_out * chain_out - height * height) / (2.0 * height)
    return min(1.0, h_max / holding_force)


class ManeuveringVessel(Vessel):
    """A displacement ship built from a parsed ship file (see ship_file.load_ship).

    Parameters are plain arrays produced by ship_file; the hot path is one numba call.
    """

    def __init__(self, name: str, hp: np.ndarray, props: np.ndarray, ruds: np.ndarray,
                 res_speed: np.ndarray, res_force: np.ndarray, mass_matrix: np.ndarray,
                 limits: dict, attachments: Dict[str, np.ndarray], anchor: Optional[dict] = None,
                 roll: Optional[dict] = None, hmax: float = 0.1,
                 initial_state: Optional[VesselState] = None, current=(0.0, 0.0),
                 source: str = "", thrusters: Optional[np.ndarray] = None,
                 thruster_cfg: Sequence[dict] = ()):
        self.name = name
        self.source = source
        self.hp = np.ascontiguousarray(hp, float)
        kinds = _SW_KINDS.get(int(self.hp[H_FORM]), ())
        self.hp[H_SW_DEEP:H_SW_DEEP + 16] = self.hp[H_C0:H_C0 + 16]       # deep-water coefficients
        self.hp[H_SW_KIND:H_SW_KIND + 16] = -1.0
        self.hp[H_SW_KIND:H_SW_KIND + len(kinds)] = kinds
        self.hp[H_SWF:H_SWF + N_SW] = 1.0
        self.hp[H_SW_DEPTH] = math.inf       # (deep added masses m_x, m_y, J_z: ship_file, H_ADD0)
        self.props = np.ascontiguousarray(props, float).reshape(-1, NPROP) if len(props) else np.zeros((1, NPROP))
        self.ruds = np.ascontiguousarray(ruds, float).reshape(-1, NRUD) if len(ruds) else np.zeros((1, NRUD))
        self.rv = np.ascontiguousarray(res_speed, float)
        self.rf = np.ascontiguousarray(res_force, float)
        self.mass_matrix = np.asarray(mass_matrix, float)
        self.minv = np.ascontiguousarray(np.linalg.inv(self.mass_matrix))
        self.hp[H_M0:H_M0 + 16] = self.mass_matrix.ravel()
        self.limits = dict(limits)   # max_steering (rad), rated_rps
        self.attachments = {k: np.asarray(v, float) for k, v in attachments.items()}
        self.anchor_cfg = anchor
        self.roll_cfg = roll
        self.hmax = float(hmax)
        # azimuth thrusters: rows (T_*) and per thruster {name, rated_rps, full_360, azimuth_range
        # (rad, (lo, hi)), reversible}
        self.thrs = (np.ascontiguousarray(thrusters, float).reshape(-1, NTHR) if thrusters is not None
                     and len(thrusters) else np.zeros((0, NTHR)))
        self.thruster_cfg = [dict(c) for c in thruster_cfg]
        if len(self.thruster_cfg) != self.thrs.shape[0]:
            raise ValueError(f"{name}: {self.thrs.shape[0]} thruster rows but {len(self.thruster_cfg)} configurations")
        self.thruster_names = tuple(c["name"] for c in self.thruster_cfg)
        nthr = self.thrs.shape[0]
        self.hp[H_NTHR] = nthr
        self.ctrl = np.zeros(NCTRL + 2 * nthr)
        self.ctrl[C_CUR_X], self.ctrl[C_CUR_Y] = current
        self.out = np.zeros(NOUT + 2 * nthr)
        self.s = np.zeros(NSTATE + 2 * nthr)
        self._thruster_orders = [(0.0, 0.0)] * nthr     # held (azimuth rad, rpm fraction) per thruster
        self.time = 0.0
        self._command = Command()
        self._anchor_state = _STOWED if anchor else _NO_ANCHOR
        self._anchor_timer = 0.0
        self._anchor_frac = 0.0
        self._anchor_side = 0.0
        self._anchor_hold = 1.0   # share of the holding force the chain allows (set_depth)
        self._no_wrench = (np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3)))
        self.wrench_work = np.zeros(0)   # J, work done by each wrench of the last step on its point
        self._no_coupling = np.zeros((2, NCPL))   # the coupling rows of no wrench / the environment's two
        self._environment: Optional[EnvironmentSampler] = None   # attach_environment
        self.set_state(initial_state or VesselState.at_rest())

    # ---- state and environment ---------------------------------------------------------
    def set_state(self, state: VesselState, shaft_rps: Optional[float] = None,
                  rudder: Optional[float] = None, thrusters: Optional[Sequence[Tuple[float, float]]] = None) -> None:
        """Set the kinematic state (and optionally the actual shaft speed and rudder angle, and
        the azimuth thrusters' actual (azimuth rad, shaft speed rps), one pair per thruster)."""
        s = self.s
        if thrusters is not None:
            if len(thrusters) != self.thrs.shape[0]:
                raise ValueError(f"{self.name}: {len(thrusters)} thruster states for {self.thrs.shape[0]} thrusters")
            for k, (az, n) in enumerate(thrusters):
                s[S_THR0 + 2 * k + 1] = float(az)
                s[S_THR0 + 2 * k] = float(n)
        s[S_X], s[S_Y] = state.position[0], state.position[1]
        s[S_PHI], s[S_PSI] = state.rpy[0], state.rpy[2]
        s[S_U], s[S_V] = state.linear_velocity_body[0], state.linear_velocity_body[1]
        s[S_P], s[S_R] = state.angular_velocity_body[0], state.angular_velocity_body[2]
        if shaft_rps is not None:
            s[S_N] = shaft_rps
        if rudder is not None:
            s[S_DELTA] = rudder
        self._sync_state()
        if self._environment is not None:
            self._sample_environment()

    def _sync_state(self) -> None:
        s = self.s
        self.state = VesselState(np.array([s[S_X], s[S_Y], 0.0]), np.array([s[S_PHI], 0.0, s[S_PSI]]),
                                 np.array([s[S_U], s[S_V], 0.0]), np.array([s[S_P], 0.0, s[S_R]]))

    def set_current(self, current_world: Sequence[float]) -> None:
        """Uniform current (east, north, up) m/s, world ENU. The model moves in the horizontal
        plane only: a vertical component is refused, not ignored."""
        east, north, up = check_current(current_world)
        if up != 0.0:
            raise ValueError(f"{self.name}: a displacement ship has no heave; vertical current {float(up)!r} m/s "
                             "must be 0")
        self.ctrl[C_CUR_X], self.ctrl[C_CUR_Y] = float(east), float(north)

    def set_depth(self, depth: float) -> None:
        """Water depth under the vessel (m; math.inf = deep / not given). Every hull coefficient,
        the added masses, wake, thrust deduction, rudder flow straightening and resistance take
        their shallow-water factors (sea_environment.shallow_water.shallow_water_factors; README
        "Shallow water"); with a chain in the ship file the depth also limits the anchor's
        holding (anchor_holding_factor)."""
        depth = float(depth)
        if not depth > 0.0:
            raise ValueError(f"{self.name}: water depth {depth!r} m must be > 0")
        self._set_hull_particulars()
        _apply_depth(self.hp, self.minv, depth)
        self._set_anchor_hold(depth)

    def _set_hull_particulars(self) -> None:
        """Beam and block coefficient (load_ship sets them after construction) for the factors."""
        self.hp[H_SW_BEAM] = self.beam
        self.hp[H_SW_BLOCK] = self.volume / (self.length * self.beam * self.draft)

    def _set_anchor_hold(self, depth: float) -> None:
        self._anchor_depth = depth
        a = self.anchor_cfg
        if a is None or a.get("chain_out") is None or math.isinf(depth):
            self._anchor_hold = 1.0
        else:
            self._anchor_hold = anchor_holding_factor(a["holding_force"], a["chain_out"], a["chain_weight"],
                                                      depth + a["hawse_height"])

    def attach_environment(self, sampler: EnvironmentSampler) -> None:
        """From now on every step feels the sampler's environment (current, wind, depth and its
        factors, the bottom); sampled here on the present state at sampler.time."""
        self._environment = sampler
        self._set_hull_particulars()
        self._env_rows = (np.empty((2, 3)), np.empty((2, 3)), np.empty((2, 3)))
        self._anchor_chain = self.anchor_cfg is not None and self.anchor_cfg.get("chain_out") is not None
        self._sample_environment()

    def _sample_environment(self) -> None:
        """The attached environment at the present state (set_state keeps it so)."""
        env, s = self._environment, self.s
        env.sample(s[S_X], s[S_Y], s[S_PSI], s[S_U], s[S_V])
        _apply_environment(env.out, self.ctrl, self.hp, self.minv)
        self._set_anchor_hold(max(float(env.out[E_DEPTH]), 1e-3))

    @property
    def towline_angle(self) -> float:
        return float(self.ctrl[C_GAMMA])

    # ---- commands ------------------------------------------------------------------
    @property
    def command(self) -> Command:
        return self._command

    def set_command(self, cmd: Command) -> List[str]:
        """Engine order and steering (and the anchor). On a ship whose only propulsion is azimuth
        thrusters (an ASD tug) they map onto every thruster: rpm fraction |engine_order|, azimuth
        -steering_angle ahead (engine_order >= 0) and pi + steering_angle astern, so a positive
        steering angle pushes the stern to starboard and turns the vessel to port either way;
        steering is clamped to +-pi there. Per-thruster orders: set_thruster_command."""
        check_command(cmd)   # raises CommandRejected; the held command is untouched
        msgs = []
        eo, st = float(cmd.engine_order), float(cmd.steering_angle)
        if not -1.0 <= eo <= 1.0:
            c = min(1.0, max(-1.0, eo))
            msgs.append(f"{self.name}: engine_order {eo:g} clamped to {c:g}")
            eo = c
        smax = self.limits["max_steering"]
        if not -smax <= st <= smax:
            c = min(smax, max(-smax, st))
            msgs.append(f"{self.name}: steering_angle {st:g} rad clamped to {c:g} rad")
            st = c
        if cmd.anchor != 0 and self.anchor_cfg is None:
            msgs.append(f"{self.name}: has no anchor; anchor order {cmd.anchor} ignored")
        elif cmd.anchor == ANCHOR_LET_GO:
            if self._anchor_state in (_STOWED, _HEAVING_UP):
                self._anchor_state = _LETTING_GO
                self._anchor_timer = self.anchor_cfg["let_go_time"]
                self._pick_anchor_side(st)
        elif cmd.anchor == ANCHOR_HEAVE_UP:
            if self._anchor_state in (_LETTING_GO, _DREDGING):
                self._anchor_state = _HEAVING_UP
        self._command = Command(eo, st, 0)
        self.ctrl[C_NCMD] = eo * self.limits["rated_rps"]
        self.ctrl[C_DCMD] = st
        if self.thrs.shape[0] and self.hp[H_NPROP] == 0:
            az = -st if eo >= 0.0 else _wrap(math.pi + st)
            msgs += self._apply_thruster_orders([(k, az, abs(eo)) for k in range(self.thrs.shape[0])])
        return msgs

    def _thruster_label(self, k: int) -> str:
        return f"thruster {k} ({self.thruster_names[k]})"

    def set_thruster_command(self, orders: Sequence[ThrusterOrder]) -> List[str]:
        """Per-thruster orders (vessel.ThrusterOrder: thruster index or name, azimuth rad, rpm
        fraction). Thrusters not named keep their orders. NaN / inf, a thruster the vessel does
        not have, or one named twice: CommandRejected naming it, and no order changes. rpm outside
        [-1, 1] (a reversible unit) or [0, 1], an azimuth outside a limited unit's range: clamped,
        one message each. A 360 deg unit takes any azimuth (wrapped to (-pi, pi])."""
        nthr = self.thrs.shape[0]
        if nthr == 0:
            raise CommandRejected(f"{self.name}: has no azimuth thrusters; thruster orders refused")
        resolved = []
        seen = set()
        for o in orders:
            key = o.thruster
            if isinstance(key, str):
                if key not in self.thruster_names:
                    raise CommandRejected(f"{self.name}: thruster {key!r} does not exist; "
                                          f"thrusters are {list(self.thruster_names)}")
                k = self.thruster_names.index(key)
            elif isinstance(key, (int, np.integer)) and not isinstance(key, bool):
                k = int(key)
                if not 0 <= k < nthr:
                    raise CommandRejected(f"{self.name}: thruster {k} does not exist; thrusters are 0..{nthr - 1} "
                                          f"{list(self.thruster_names)}")
            else:
                raise CommandRejected(f"{self.name}: thruster {key!r} is neither an index nor a name")
            if k in seen:
                raise CommandRejected(f"{self.name}: {self._thruster_label(k)} ordered twice in one command")
            seen.add(k)
            for field in ("azimuth", "rpm"):
                value = getattr(o, field)
                try:
                    ok = math.isfinite(value)
                except TypeError:
                    ok = False
                if not ok:
                    raise CommandRejected(f"{self.name}: {self._thruster_label(k)} {field}={value!r} "
                                          "is not a finite number")
            resolved.append((k, float(o.azimuth), float(o.rpm)))
        return self._apply_thruster_orders(resolved)

    def _apply_thruster_orders(self, resolved) -> List[str]:
        """Clamp and hold checked (index, azimuth, rpm fraction) orders; one message per clamp."""
        msgs = []
        for k, az, rpm in resolved:
            cfg = self.thruster_cfg[k]
            lo = -1.0 if cfg["reversible"] else 0.0
            if not lo <= rpm <= 1.0:
                c = min(1.0, max(lo, rpm))
                msgs.append(f"{self.name}: {self._thruster_label(k)} rpm {rpm:g} clamped to {c:g} "
                            f"(range {lo:g} .. 1 of rated)")
                rpm = c
            if cfg["full_360"]:
                az = _wrap(az)
            else:
                a0, a1 = cfg["azimuth_range"]
                if not a0 <= az <= a1:
                    c = min(a1, max(a0, az))
                    msgs.append(f"{self.name}: {self._thruster_label(k)} azimuth {az:g} rad clamped to {c:g} rad "
                                f"(range {a0:g} .. {a1:g} rad)")
                    az = c
            self._thruster_orders[k] = (az, rpm)
            self.ctrl[C_THR0 + 2 * k] = rpm * cfg["rated_rps"]
            self.ctrl[C_THR0 + 2 * k + 1] = az
        return msgs

    @property
    def thruster_orders(self) -> List[Tuple[float, float]]:
        """The held (azimuth rad, rpm fraction) of each thruster, after clamping."""
        return list(self._thruster_orders)

    def settle_command(self, cmd: Command) -> List[str]:
        msgs = self.set_command(cmd)
        self.s[S_N] = self.ctrl[C_NCMD]      # engine at its ordered rpm (Eq 9 lag already run out)
        self.s[S_DELTA] = self.ctrl[C_DCMD]  # rudder at its ordered angle (Eq 10)
        self.settle_thrusters()
        return msgs

    def settle_thrusters(self) -> None:
        """Every thruster at its ordered rpm and azimuth (lags run out)."""
        for k in range(self.thrs.shape[0]):
            self.s[S_THR0 + 2 * k] = self.ctrl[C_THR0 + 2 * k]
            self.s[S_THR0 + 2 * k + 1] = self.ctrl[C_THR0 + 2 * k + 1]

    def _pick_anchor_side(self, steering: float) -> None:
        side = self.anchor_cfg["side"]
        if side != 0.0:
            self._anchor_side = side
        elif abs(steering) > math.radians(1.0):
            self._anchor_side = math.copysign(1.0, steering)   # the turning side's bow anchor
        else:
            self._anchor_side = 0.0                             # chosen when the ship starts turning

    def _update_anchor(self, dt: float) -> None:
        st = self._anchor_state
        if st == _LETTING_GO:
            self._anchor_timer -= dt
            if self._anchor_timer <= 0.0:
                self._anchor_state = _DREDGING
                self._anchor_frac = 1.0
        elif st == _HEAVING_UP:
            self._anchor_frac -= dt / self.anchor_cfg["heave_up_time"]
            if self._anchor_frac <= 0.0:
                self._anchor_frac = 0.0
                self._anchor_state = _STOWED
                self._anchor_side = 0.0 if self.anchor_cfg["side"] == 0.0 else self.anchor_cfg["side"]
        if self._anchor_frac > 0.0 and self._anchor_side == 0.0:
            s = self.s
            V = max(math.hypot(s[S_U], s[S_V]), self.hp[H_ANC_UEPS])
            rp = s[S_R] * self.hp[H_L] / V
            if abs(rp) >= self.hp[H_ANC_RON]:
                self._anchor_side = math.copysign(1.0, rp)
        self.ctrl[C_ANC_F] = self._anchor_frac * self._anchor_hold
        self.ctrl[C_ANC_SIDE] = self._anchor_side

    def _mobility_of(self, point_body) -> float:
        """point_mobility, kept per point (the mass matrix does not change)."""
        key = tuple(point_body)
        cache = self.__dict__.setdefault("_mobility_cache", {})
        if key not in cache:
            cache[key] = self.point_mobility(point_body)
        return cache[key]

    def point_mobility(self, point_body) -> float:
        """Largest horizontal mobility (1/kg: acceleration per newton) of a body point: the
        largest eigenvalue of G M^-1 G^T over the horizontal plane, G the point's lever on
        (u, v, r, p), M the rigid-body + added mass matrix. The inverse of the smallest mass the
        point feels; the exchange-rate bound and the sub-step of a coupled force use it."""
        return point_mobility_matrix(self.minv, point_body, self.hp[H_ROLL] > 0.0)

    # ---- stepping --------------------------------------------------------------
    def step(self, dt: float, wrenches: Sequence[ExternalWrench] = ()) -> None:
        if not (dt > 0.0 and math.isfinite(dt)):
            raise ValueError(f"{self.name}: dt={dt!r} must be positive and finite")
        env = self._environment
        hmax = self.hmax
        if wrenches:
            k = len(wrenches)
            rows = k if env is None else k + 2      # + the environment's wind and bottom friction
            force = np.empty((rows, 3))
            point = np.empty((rows, 3))
            moment = np.empty((rows, 3))
            cpl = np.zeros((rows, NCPL))
            stiffest = 0.0
            for i, w in enumerate(wrenches):
                force[i] = w.force_world
                point[i] = w.point_body
                moment[i] = w.moment_world
                if w.coupled:
                    coupling_row(w, cpl[i])
                    # |K| (Frobenius: >= its largest eigenvalue, cheap) x the point's mobility
                    stiffest = max(stiffest, math.sqrt(float((cpl[i, CPL_K:CPL_K + 9] ** 2).sum()))
                                   * self._mobility_of(point[i]))
            if stiffest > 0.0:   # the coupled spring is inside the explicit RK4 now: resolve it
                hmax = min(hmax, SPRING_SUBSTEP / math.sqrt(stiffest))
        else:
            force, point, moment = self._no_wrench if env is None else self._env_rows
            cpl = self._no_coupling[:force.shape[0]]
        if self.anchor_cfg is not None:
            if (env is not None and self._anchor_chain and self._anchor_state != _STOWED
                    and env.out[E_DEPTH] != self._anchor_depth):   # stowed, the chain's hold does not matter
                self._set_anchor_hold(max(float(env.out[E_DEPTH]), 1e-3))
            self._update_anchor(dt)
        if env is None:
            work = _integrate(self.s, dt, hmax, self.hp, self.props, self.ruds, self.thrs, self.rv, self.rf,
                              self.minv, self.ctrl, force, point, moment, cpl, self.out)
        else:
            work = _integrate_in_environment(self.s, dt, hmax, self.hp, self.props, self.ruds, self.thrs, self.rv,
                                             self.rf, self.minv, self.ctrl, force, point, moment, cpl, self.out,
                                             env.data)
        self.wrench_work = work[:len(wrenches)]
        self.time += dt
        self._sync_state()

    # ---- status -------------------------------------------------------------------
    def status(self) -> DisplacementStatus:
        s = self.s
        rc = self.roll_cfg
        if rc is not None:
            ratio = abs(float(self.out[O_HEEL_EXT])) / rc["max_righting_moment"]
            threshold = rc["girting_threshold"]
        else:
            ratio = threshold = 0.0     # no roll model: no heel, no girting
        nthr = self.thrs.shape[0]
        thr = tuple(ThrusterStatus(
            name=self.thruster_names[k],
            azimuth=float(_wrap(s[S_THR0 + 2 * k + 1])),
            azimuth_ordered=float(self.ctrl[C_THR0 + 2 * k + 1]),
            rpm=float(60.0 * s[S_THR0 + 2 * k]),
            rpm_ordered=float(60.0 * self.ctrl[C_THR0 + 2 * k]),
            thrust=float(self.out[O_THR0 + 2 * k]),
            open_water_thrust=float(self.out[O_THR0 + 2 * k + 1])) for k in range(nthr))
        shaft = float(s[S_N])
        steering = float(s[S_DELTA])
        if nthr and self.hp[H_NPROP] == 0:
            # a thruster-only ship: the thrusters' mean shaft speed, and the steering angle the
            # mean azimuth stands for (set_command's mapping inverted)
            shaft = float(np.mean(s[S_THR0:S_THR0 + 2 * nthr:2]))
            az = s[S_THR0 + 1:S_THR0 + 2 * nthr:2]
            cx, cy = float(np.mean(np.cos(az))), float(np.mean(np.sin(az)))
            steering = -math.atan2(cy, cx) if cx >= 0.0 else float(_wrap(math.atan2(cy, cx) - math.pi))
        return DisplacementStatus(
            engine_order=self._command.engine_order,
            steering_angle_ordered=self._command.steering_angle,
            steering_angle=steering,
            shaft_speed=float(2.0 * math.pi * shaft),
            thrust=float(self.out[O_THRUST]),
            anchor_state=self._anchor_state,
            speed_through_water=float(math.hypot(self.out[O_UR], self.out[O_VR])),
            heel=float(s[S_PHI]),
            trim=0.0,
            rise=0.0,
            girting_ratio=ratio,
            girting_threshold=threshold,
            girting_warning=rc is not None and bool(ratio >= threshold),
            engine_rpm=float(60.0 * shaft),
            anchor_force=float(-self.out[O_ANC_X]),
            towline_angle=self.towline_angle,
            thrusters=thr,
        )

    def force_terms(self) -> Dict[str, Tuple[float, float, float]]:
        """Each force component's body-frame (X N, Y N, N N m) at the state the last step ended on,
        as _deriv_c summed them (FORCE_TERMS: hull, propeller, rudder, thruster, anchor, towline,
        external, coriolis). Their sums are the right-hand sides of the equations of motion, so
        a steady state's terms add up to zero (tests/physics/test_anchor_turn_balance.py)."""
        return {name: (float(self.out[O_TERM0 + 3 * k]), float(self.out[O_TERM0 + 3 * k + 1]),
                       float(self.out[O_TERM0 + 3 * k + 2])) for k, name in enumerate(FORCE_TERMS)}
