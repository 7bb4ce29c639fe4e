"""Displacement-ship manoeuvring model (surge, sway, yaw, optional roll), ROS-free.

Papers: Yun & Kim, "Study on the Maneuverability of Barge by Captive Model Test" (the barge);
S. D. Yoon, "A Study on the Control of Ship Maneuvering by the Simulation of Anchor Dredging"
(the S-175 low-speed model and its anchor).

Force components, one kernel function each, summed in the body frame (REP-103: x fwd, y port,
z up) by _deriv:
  hull       _hull_polynomial: Yun & Kim Eq 2 (captive-model derivatives), or
             _hull_lowspeed: S. D. Yoon Eq 3 (reconstructed; README "Reading decisions")
  propeller  _propeller_thrust: S. D. Yoon Eq 4, K_T(J) quadratic, wake w_P(beta, r), thrust
             deduction; shaft-speed lag Eq 9 (_engine_rate)
  rudder     _rudder_force, _rudder_inflow: S. D. Yoon Eq 7-8 (Fujii normal force, Kijima flow
             straightening); steering gear Eq 10 (_steering_gear_rate)
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
from typing import Dict, List, Optional, Sequence

import numpy as np
from numba import njit

from sim_math.integration import rk4_stage, rk4_update

from .vessel import (ANCHOR_HEAVE_UP, ANCHOR_LET_GO, AnchorState, Command, ExternalWrench, StatusRecord,
                     Vessel, VesselState, check_command, check_current)

# ---- state vector layout -------------------------------------------------
S_X, S_Y, S_PSI, S_U, S_V, S_R, S_PHI, S_P, S_N, S_DELTA = range(10)
NSTATE = 10

# ---- hull parameter vector ------------------------------------------------
(H_FORM, H_RHO, H_L, H_T, H_M, H_XG, H_ZG, H_MX, H_MY, H_MMG_CORIOLIS, H_ROLL, H_GMW, H_KP, H_ZH,
 H_TOW_ON, H_TOW_F, H_TOW_X, H_TOW_DRIFT, H_TOW_RATE, H_TOW_MAX, H_ANC_LW, H_ANC_LA, H_ANC_UEPS,
 H_ANC_RON, H_ANC_VUCAP, H_NPROP, H_NRUD, H_MAXRATE, H_TE, H_TN, H_ANC_UREF) = range(31)
H_C0 = 32           # hull coefficients start here (16 slots)
NHULL = H_C0 + 16

FORM_NONE, FORM_POLY, FORM_LOWSPEED = 0, 1, 2

# ---- propeller rows ---------------------------------------------------------
(P_X, P_Y, P_Z, P_D, P_PITCH, P_C1, P_C2, P_C3, P_WP0, P_T, P_AST, P_XPN) = range(12)
NPROP = 12
# ---- rudder rows ------------------------------------------------------------
(R_X, R_Y, R_Z, R_AREA, R_FALPHA, R_ETA, R_AH, R_XH, R_TR, R_WR0, R_LR, R_PROP, R_KAPPA0) = range(13)
NRUD = 13

# ---- control vector ------------------------------------------------------------
C_NCMD, C_DCMD, C_ANC_F, C_ANC_SIDE, C_CUR_X, C_CUR_Y, C_GAMMA = range(7)
NCTRL = 7

# ---- output (diagnostics of the last derivative evaluation) ------------------
O_THRUST, O_ANC_X, O_HEEL_EXT, O_UR, O_VR = range(5)
NOUT = 5


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
    c: X'uu X'vr, Y'v Y'r Y'vv Y'vr Y'rr, N'v N'r N'vvr N'vrr N'rr."""
    q = 0.5 * rho * L * T
    XH = q * (c[0] * ur * abs(ur) + c[1] * vr * rl)
    YH = q * (c[2] * abs(ur) * vr + c[3] * ur * rl + c[4] * vr * abs(vr) + c[5] * vr * abs(rl)
              + c[6] * rl * abs(rl))
    NH = q * L * (c[7] * ur * vr + c[8] * abs(ur) * rl + c[9] * vr * vr * rl / Ue
                  + c[10] * vr * rl * rl / Ue + c[11] * rl * abs(rl))
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
        return _hull_polynomial(c, hp[H_RHO], L, ur, vr, rl, U, Ue, rv, rf)
    return _hull_lowspeed(c, hp[H_RHO], L, hp[H_T], ur, vr, rl, Ue, rv, rf)


@njit(cache=True, inline="always")
def _propeller_thrust(props, k, rho, n, ur, vr, r):
    """S. D. Yoon Eq 4 (with Eq 8's wake): thrust of propeller row k at shaft speed n (rps).

    Returns (thrust, advance speed u_A, wake fraction w_P); the rudder behind it needs both."""
    D = props[k, P_D]
    up = ur - props[k, P_Y] * r                # surge speed at the propeller
    vp = vr + props[k, P_X] * r                # lateral speed at the propeller
    # w_P = w_P0 exp(-4 (beta - x_P' r')^2): the local drift angle at the propeller
    beta_p = math.atan2(vp, abs(up) + 1e-9)
    wake = props[k, P_WP0] * math.exp(-4.0 * beta_p * beta_p)
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
def _rudder_force(ruds, k, uR, slip, rho, L, ur, vr, r, delta):
    """S. D. Yoon Eq 7-8: X_R, Y_R, N_R of rudder k in the inflow u_R at propeller slip s
    (Fujii normal force, flow straightening gamma = C_p C_s). The paper's frame has y to
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
    gamma_beta = c_p * c_s * betaR
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

    Eq 5 while turning (weight w != 0): lateral force toward the turning centre, moment with the
    turn (the paper's reading); Eq 6 straight (w = 0)."""
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
    vu = abs(v) / (abs(u) if abs(u) > ueps else ueps)
    if vu > hp[H_ANC_VUCAP]:
        vu = hp[H_ANC_VUCAP]
    return XA, vu * lw * w, lw * hp[H_ANC_LA] * w


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


# ---- equations of motion ---------------------------------------------------------------------

@njit(cache=True)
def _deriv(s, hp, props, ruds, rv, rf, minv, ctrl, wrench_force, wrench_point, wrench_moment, out):
    """Time derivative of the state vector s (S_* indices); writes diagnostics to out (O_*).

    X, Y, N, K sum the components in a fixed order (the order is part of the numbers)."""
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

    thrust_total = 0.0
    prop_advance = np.zeros(4)
    prop_wake = np.zeros(4)
    for k in range(int(hp[H_NPROP])):
        thrust, ua, wake = _propeller_thrust(props, k, rho, n, ur, vr, r)
        prop_advance[k] = ua
        prop_wake[k] = wake
        thrust_total += thrust
        fx = (1.0 - props[k, P_T]) * thrust
        X += fx
        N += -props[k, P_Y] * fx
    out[O_THRUST] = thrust_total

    for k in range(int(hp[H_NRUD])):
        j = int(ruds[k, R_PROP])
        if j < 0:                              # no propeller ahead of it: the hull's wake
            uR, slip = (1.0 - ruds[k, R_WR0]) * ur, 0.0
        else:
            uR, slip = _rudder_inflow(ruds[k, R_WR0], ruds[k, R_KAPPA0], ruds[k, R_ETA], props[j, P_WP0],
                                      props[j, P_PITCH], prop_wake[j], prop_advance[j], n)
        XR, YR, NR = _rudder_force(ruds, k, uR, slip, rho, hp[H_L], ur, vr, r, delta)
        X += XR
        Y += YR
        N += NR
        K += -ruds[k, R_Z] * YR

    out[O_ANC_X] = 0.0
    if ctrl[C_ANC_F] > 0.0:
        XA, YA, NA = _anchor_dredging(hp, ctrl, u, v, r)
        X += XA
        Y += YA
        N += NA
        out[O_ANC_X] = XA

    if hp[H_TOW_ON] > 0.0:
        XT, YT, NT = _simple_towline(hp, ctrl, ur, vr)
        X += XT
        Y += YT
        N += NT

    heel_external = 0.0
    for k in range(wrench_force.shape[0]):
        Xw, Yw, Kw, Nw = _wrench_in_body(wrench_force[k], wrench_point[k], wrench_moment[k],
                                         cpsi, spsi, cphi, sphi)
        X += Xw
        Y += Yw
        K += Kw
        N += Nw
        heel_external += Kw + hp[H_ZH] * Yw     # heeling couple against the hull's lateral resistance
    out[O_HEEL_EXT] = heel_external
    out[O_UR] = ur
    out[O_VR] = vr

    Xc, Yc, Nc = _rigid_body_coriolis(hp, ur, vr, r)
    X += Xc
    Y += Yc
    N += Nc
    roll = hp[H_ROLL] > 0.0
    if roll:
        K += _roll_moment(hp, ur, r, sphi, p)
    du, dv, dr, dp = _solve_accelerations(minv, X, Y, N, K)

    ds = np.zeros(NSTATE)
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
def _integrate(s, dt, hmax, hp, props, ruds, rv, rf, minv, ctrl, wrench_force, wrench_point, wrench_moment, out):
    """RK4 over dt in equal sub-steps <= hmax; the towline angle ramps between sub-steps."""
    nsub = int(math.ceil(dt / hmax - 1e-9))
    if nsub < 1:
        nsub = 1
    h = dt / nsub
    stage = np.empty_like(s)
    for _ in range(nsub):
        k1 = _deriv(s, hp, props, ruds, rv, rf, minv, ctrl, wrench_force, wrench_point, wrench_moment, out)
        k2 = _deriv(rk4_stage(s, 0.5 * h, k1, stage), hp, props, ruds, rv, rf, minv, ctrl, wrench_force,
                    wrench_point, wrench_moment, out)
        k3 = _deriv(rk4_stage(s, 0.5 * h, k2, stage), hp, props, ruds, rv, rf, minv, ctrl, wrench_force,
                    wrench_point, wrench_moment, out)
        k4 = _deriv(rk4_stage(s, h, k3, stage), hp, props, ruds, rv, rf, minv, ctrl, wrench_force, wrench_point,
                    wrench_moment, out)
        rk4_update(s, h, k1, k2, k3, k4)
        if hp[H_TOW_ON] > 0.0:
            ctrl[C_GAMMA] = _towline_angle_ramp(ctrl[C_GAMMA], hp[H_TOW_MAX], hp[H_TOW_RATE] * h)
    _deriv(s, hp, props, ruds, rv, rf, minv, ctrl, wrench_force, wrench_point, wrench_moment, out)   # diagnostics
    return s


# AnchorState members bound once: an Enum class attribute costs ~0.1 us per lookup in step()
_NO_ANCHOR, _STOWED, _LETTING_GO, _DREDGING, _HEAVING_UP = (
    AnchorState.NONE, AnchorState.STOWED, AnchorState.LETTING_GO, AnchorState.DREDGING, AnchorState.HEAVING_UP)


@dataclasses.dataclass(kw_only=True, slots=True)
class DisplacementStatus(StatusRecord):
    """StatusRecord plus the displacement model's own values."""
    engine_rpm: float        # actual shaft speed, rev/min
    anchor_force: float      # N, dredging resistance (S. D. Yoon Eq 5-6), >= 0
    towline_angle: float     # rad, Yun & Kim Eq 3 gamma


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
                 source: str = ""):
        self.name = name
        self.source = source
        self.hp = np.ascontiguousarray(hp, float)
        self.props = np.ascontiguousarray(props, float).reshape(-1, NPROP) if len(props) else np.zeros((1, NPROP))
        self.ruds = np.ascontiguousarray(ruds, float).reshape(-1, NRUD) if len(ruds) else np.zeros((1, NRUD))
        self.rv = np.ascontiguousarray(res_speed, float)
        self.rf = np.ascontiguousarray(res_force, float)
        self.mass_matrix = np.asarray(mass_matrix, float)
        self.minv = np.ascontiguousarray(np.linalg.inv(self.mass_matrix))
        self.limits = dict(limits)   # max_steering (rad), rated_rps
        self.attachments = {k: np.asarray(v, float) for k, v in attachments.items()}
        self.anchor_cfg = anchor
        self.roll_cfg = roll
        self.hmax = float(hmax)
        self.ctrl = np.zeros(NCTRL)
        self.ctrl[C_CUR_X], self.ctrl[C_CUR_Y] = current
        self.out = np.zeros(NOUT)
        self.s = np.zeros(NSTATE)
        self.time = 0.0
        self._command = Command()
        self._anchor_state = _STOWED if anchor else _NO_ANCHOR
        self._anchor_timer = 0.0
        self._anchor_frac = 0.0
        self._anchor_side = 0.0
        self._anchor_hold = 1.0   # share of the holding force the chain allows (set_depth)
        self._no_wrench = (np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3)))
        self.set_state(initial_state or VesselState.at_rest())

    # ---- state and environment ---------------------------------------------------------
    def set_state(self, state: VesselState, shaft_rps: Optional[float] = None,
                  rudder: Optional[float] = None) -> None:
        """Set the kinematic state (and optionally the actual shaft speed and rudder angle)."""
        s = self.s
        s[S_X], s[S_Y] = state.position[0], state.position[1]
        s[S_PHI], s[S_PSI] = state.rpy[0], state.rpy[2]
        s[S_U], s[S_V] = state.linear_velocity_body[0], state.linear_velocity_body[1]
        s[S_P], s[S_R] = state.angular_velocity_body[0], state.angular_velocity_body[2]
        if shaft_rps is not None:
            s[S_N] = shaft_rps
        if rudder is not None:
            s[S_DELTA] = rudder
        self._sync_state()

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
        """Water depth under the vessel (m; math.inf = not given). It limits the anchor's holding
        when the ship file gives the chain (anchor_holding_factor); the hull's manoeuvring
        derivatives keep their deep-water values."""
        depth = float(depth)
        if not depth > 0.0:
            raise ValueError(f"{self.name}: water depth {depth!r} m must be > 0")
        a = self.anchor_cfg
        if a is None or a.get("chain_out") is None or math.isinf(depth):
            self._anchor_hold = 1.0
        else:
            self._anchor_hold = anchor_holding_factor(a["holding_force"], a["chain_out"], a["chain_weight"],
                                                      depth + a["hawse_height"])

    @property
    def towline_angle(self) -> float:
        return float(self.ctrl[C_GAMMA])

    # ---- commands ------------------------------------------------------------------
    @property
    def command(self) -> Command:
        return self._command

    def set_command(self, cmd: Command) -> List[str]:
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
        return msgs

    def settle_command(self, cmd: Command) -> List[str]:
        msgs = self.set_command(cmd)
        self.s[S_N] = self.ctrl[C_NCMD]      # engine at its ordered rpm (Eq 9 lag already run out)
        self.s[S_DELTA] = self.ctrl[C_DCMD]  # rudder at its ordered angle (Eq 10)
        return msgs

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

    # ---- stepping --------------------------------------------------------------
    def step(self, dt: float, wrenches: Sequence[ExternalWrench] = ()) -> None:
        if not (dt > 0.0 and math.isfinite(dt)):
            raise ValueError(f"{self.name}: dt={dt!r} must be positive and finite")
        if wrenches:
            k = len(wrenches)
            force = np.empty((k, 3))
            point = np.empty((k, 3))
            moment = np.empty((k, 3))
            for i, w in enumerate(wrenches):
                force[i] = w.force_world
                point[i] = w.point_body
                moment[i] = w.moment_world
        else:
            force, point, moment = self._no_wrench
        if self.anchor_cfg is not None:
            self._update_anchor(dt)
        _integrate(self.s, dt, self.hmax, self.hp, self.props, self.ruds, self.rv, self.rf, self.minv,
                   self.ctrl, force, point, moment, self.out)
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
        return DisplacementStatus(
            engine_order=self._command.engine_order,
            steering_angle_ordered=self._command.steering_angle,
            steering_angle=float(s[S_DELTA]),
            shaft_speed=float(2.0 * math.pi * s[S_N]),
            thrust=float(self.out[O_THRUST]),
            anchor_state=self._anchor_state,
            speed_through_water=float(math.hypot(self.out[O_UR], self.out[O_VR])),
            heel=float(s[S_PHI]),
            trim=0.0,
            rise=0.0,
            girting_ratio=ratio,
            girting_threshold=threshold,
            girting_warning=rc is not None and bool(ratio >= threshold),
            engine_rpm=float(60.0 * s[S_N]),
            anchor_force=float(-self.out[O_ANC_X]),
            towline_angle=self.towline_angle,
        )
