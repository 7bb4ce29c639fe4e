"""Displacement-ship manoeuvring model (surge, sway, yaw, optional roll), ROS-free.

Force components, summed in the body frame (REP-103: x fwd, y port, z up):
  hull       seed 002 polynomial form (Eq 2, captive-model derivatives) or
             seed 003 low-speed form (Eq 3, reconstructed; see README "Reading decisions")
  propeller  seed 003 Eq 4: K_T(J) quadratic, wake w_P(beta, r), thrust deduction, rpm lag Eq 9
  rudder     seed 003 Eq 7-8 (Fujii normal force, Kijima flow straightening), gear Eq 10
  anchor     seed 003 Eq 5-6 dredging, let-go / heave-up timing
  towline    seed 002 Eq 3 simple towline (constant magnitude, gamma ramp)
  external   any number of vessel.ExternalWrench (world force at a body point)
  current    uniform world current; hydrodynamics use the relative velocity.

The papers use y to starboard and starboard-positive rudder. Every component whose
paper form is not odd-symmetric converts at its boundary (comment names the equation).
The time integration is RK4 in a numba kernel (cache=True) with a fixed sub-step.
"""
from __future__ import annotations

import math
from typing import Dict, List, Optional, Sequence

import numpy as np
from numba import njit

from .vessel import (ANCHOR_HEAVE_UP, ANCHOR_LET_GO, Command, ExternalWrench,
                     Vessel, VesselState, check_command)

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


@njit(cache=True)
def _deriv(s, hp, props, ruds, rv, rf, minv, ctrl, wf, wp, wm, out):
    """Time derivative of the state vector s (see S_* indices)."""
    ds = np.zeros(NSTATE)
    psi = s[S_PSI]
    u = s[S_U]
    v = s[S_V]
    r = s[S_R]
    phi = s[S_PHI]
    p = s[S_P]
    n = s[S_N]
    delta = s[S_DELTA]
    cpsi = math.cos(psi)
    spsi = math.sin(psi)
    cphi = math.cos(phi)
    sphi = math.sin(phi)
    rho = hp[H_RHO]
    L = hp[H_L]
    T = hp[H_T]
    m = hp[H_M]
    xg = hp[H_XG]
    zg = hp[H_ZG]

    # current in body axes (horizontal, roll projection neglected); relative velocity
    uc = cpsi * ctrl[C_CUR_X] + spsi * ctrl[C_CUR_Y]
    vc = (-spsi * ctrl[C_CUR_X] + cpsi * ctrl[C_CUR_Y]) * cphi
    ur = u - uc
    vr = v - vc
    U2 = ur * ur + vr * vr
    U = math.sqrt(U2)
    Ue = U if U > 1e-9 else 1e-9
    rl = r * L

    X = 0.0
    Y = 0.0
    N = 0.0
    K = 0.0
    c = hp[H_C0:H_C0 + 16]
    form = int(hp[H_FORM])
    # ---------------- hull ----------------
    XH = 0.0
    YH = 0.0
    NH = 0.0
    if form == FORM_POLY:
        # seed 002 Eq 2 in the prime system of Eq 4 (F / 0.5 rho U^2 L^2, v'=v/U, r'=rL/U),
        # expanded dimensionally so U -> 0 stays finite. All terms are odd in (v, r), so
        # the paper's y-starboard signs carry over to y-port unchanged.
        q = 0.5 * rho * L * L
        XH = q * (c[0] * vr * vr + c[1] * rl * rl + c[2] * vr * rl)
        YH = q * (c[3] * vr * U + c[4] * vr * abs(vr) + c[5] * rl * U + c[6] * rl * abs(rl)
                  + c[7] * vr * rl * rl / Ue + c[8] * rl * vr * vr / Ue)
        NH = q * L * (c[9] * vr * U + c[10] * vr * abs(vr) + c[11] * rl * U + c[12] * rl * abs(rl)
                      + c[13] * vr * rl * rl / Ue + c[14] * rl * vr * vr / Ue)
        XH += _interp_resistance(ur, rv, rf)
    elif form == FORM_LOWSPEED:
        # seed 003 Eq 3 (reconstructed), forces / 0.5 rho L d V^2, V = sqrt(u^2+v^2).
        # Y'v and N'r multiply |u|: hull lift and yaw damping oppose sway / yaw also astern
        # (the paper covers ahead motion only; the Munk moment N'v u v changes sign, as it should).
        q = 0.5 * rho * L * T
        XH = q * (c[0] * ur * abs(ur) + c[1] * vr * rl)
        YH = q * (c[2] * abs(ur) * vr + c[3] * ur * rl + c[4] * vr * abs(vr) + c[5] * vr * abs(rl)
                  + c[6] * rl * abs(rl))
        NH = q * L * (c[7] * ur * vr + c[8] * abs(ur) * rl + c[9] * vr * vr * rl / Ue
                      + c[10] * vr * rl * rl / Ue + c[11] * rl * abs(rl))
        XH += _interp_resistance(ur, rv, rf)
    X += XH
    Y += YH
    N += NH
    K += -hp[H_ZH] * YH      # hull lateral force acts at z_H (below the waterline)

    # ---------------- propellers (seed 003 Eq 4) ----------------
    thrust_total = 0.0
    nprop = int(hp[H_NPROP])
    ua_list = np.zeros(4)
    wp_list = np.zeros(4)
    for k in range(nprop):
        pr = props[k]
        D = pr[P_D]
        xp = pr[P_X]
        up = ur - pr[P_Y] * r                      # surge speed at the propeller
        vp = vr + xp * r                           # lateral speed at the propeller
        # w_P = w_P0 exp(-4 (beta - x_P' r')^2): the local drift angle at the propeller
        bl = math.atan2(vp, abs(up) + 1e-9)
        wpk = pr[P_WP0] * math.exp(-4.0 * bl * bl)
        ua = up * (1.0 - wpk)
        # K_T = C1 + C2 J + C3 J^2 written as rho D^4 [C1 n|n| + C2 |n| ua / D + C3 ua|ua| / D^2]:
        # identical for n > 0, ua >= 0; finite at n = 0 (locked-propeller drag opposes motion);
        # astern (n < 0) the bollard and J terms are scaled by the astern factor and act astern.
        if n >= 0.0:
            a1 = pr[P_C1]
            a2 = pr[P_C2]
        else:
            a1 = pr[P_C1] * pr[P_AST]
            a2 = pr[P_C2] * pr[P_AST]
        thr = rho * D ** 4 * (a1 * n * abs(n) + a2 * abs(n) * ua / D + pr[P_C3] * ua * abs(ua) / (D * D))
        thrust_total += thr
        fx = (1.0 - pr[P_T]) * thr
        X += fx
        N += -pr[P_Y] * fx
        ua_list[k] = ua
        wp_list[k] = wpk
    out[O_THRUST] = thrust_total

    # ---------------- rudders (seed 003 Eq 7-8) ----------------
    nrud = int(hp[H_NRUD])
    for k in range(nrud):
        rd = ruds[k]
        j = int(rd[R_PROP])
        # paper frame (y starboard, starboard rudder positive): flip v, r, delta (Eq 7-8)
        dp = -delta
        vpp = -vr
        rpp = -r
        eta = rd[R_ETA]
        if j >= 0:
            pr = props[j]
            wpk = wp_list[j]
            ua = ua_list[j]
            wr = wpk * rd[R_WR0] / pr[P_WP0] if pr[P_WP0] > 0.0 else rd[R_WR0]
            eps = (1.0 - wr) / (1.0 - wpk)
            kap = rd[R_KAPPA0] / eps
            nP = n * pr[P_PITCH]
            s_ = 1.0 - ua / nP if n > 1e-9 else -1.0
            if s_ >= 0.0:
                # propeller race (slip s in [0, 1]; moving astern with the engine ahead: s = 1)
                if s_ > 1.0:
                    s_ = 1.0
                arg = 1.0 - 2.0 * (1.0 - eta * kap) * s_ + (1.0 - eta * kap * (2.0 - kap)) * s_ * s_
                uR = eps * nP * math.sqrt(arg if arg > 0.0 else 0.0)
            else:
                # windmilling, stopped or astern: no race, the wake flow (continuous at s = 0)
                s_ = 0.0
                uR = eps * ua
        else:
            s_ = 0.0
            uR = (1.0 - rd[R_WR0]) * ur
        sc = s_ if s_ > 0.0 else 0.0
        # Eq 8: gamma = C_p C_s;  C_p as printed ((1+s)^2, see README)
        cp = 1.0 / math.sqrt(1.0 + 0.6 * eta * (2.0 - 1.4 * sc) * sc / ((1.0 + sc) ** 2))
        # beta - l_R r': inflow angle of the local lateral flow at x = l_R L, bounded form
        betaR = math.atan2(-(vpp + rd[R_LR] * L * rpp), abs(ur) + 1e-9)
        ab = abs(betaR)
        cs = 0.45 * ab if ab <= 1.111 else 0.5
        gb = cp * cs * betaR
        if gb > 1.5:
            gb = 1.5
        if gb < -1.5:
            gb = -1.5
        vR = uR * math.tan(gb)
        VR2 = uR * uR + vR * vR
        alpha = dp - gb
        sgn = 1.0 if uR >= 0.0 else -1.0           # reverse flow: the normal force reverses
        FN = 0.5 * rho * rd[R_AREA] * rd[R_FALPHA] * VR2 * math.sin(alpha) * sgn
        XR = -(1.0 - rd[R_TR]) * FN * math.sin(dp)
        YRp = -(1.0 + rd[R_AH]) * FN * math.cos(dp)
        NRp = -(rd[R_X] + rd[R_AH] * rd[R_XH]) * FN * math.cos(dp)
        YR = -YRp                                   # back to y-port (Eq 7)
        NR = -NRp - rd[R_Y] * XR
        X += XR
        Y += YR
        N += NR
        K += -rd[R_Z] * YR

    # ---------------- anchor (seed 003 Eq 5-6), ground-referenced ----------------
    fa = ctrl[C_ANC_F]
    out[O_ANC_X] = 0.0
    if fa > 0.0:
        lw = hp[H_ANC_LW] * fa
        ueps = hp[H_ANC_UEPS]
        sat = u / ueps
        if sat > 1.0:
            sat = 1.0
        if sat < -1.0:
            sat = -1.0
        XA = -lw * sat
        Vg = math.sqrt(u * u + v * v)
        Vg = Vg if Vg > ueps else ueps
        rp = r * L / Vg
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
        # Eq 5 while turning (w != 0): lateral force toward the turning centre, moment with the
        # turn (the paper's reading); Eq 6 straight (w = 0).
        X += XA
        Y += vu * lw * w
        N += lw * hp[H_ANC_LA] * w
        out[O_ANC_X] = XA

    # ---------------- seed 002 Eq 3 simple towline ----------------
    if hp[H_TOW_ON] > 0.0:
        th = ctrl[C_GAMMA] + hp[H_TOW_DRIFT] * math.atan2(vr, abs(ur) + 1e-9)
        F0 = hp[H_TOW_F]
        XT = F0 * math.cos(th)
        YT = F0 * math.sin(th)
        X += XT
        Y += YT
        N += hp[H_TOW_X] * YT                    # N_TL = Y_TL L/2 (towpoint at the bow)

    # ---------------- external wrenches (world force at body point) ----------------
    kheel = 0.0
    for k in range(wf.shape[0]):
        fxw = wf[k, 0]
        fyw = wf[k, 1]
        fzw = wf[k, 2]
        # body = Rx(phi)^T Rz(psi)^T world
        f1 = cpsi * fxw + spsi * fyw
        f2h = -spsi * fxw + cpsi * fyw
        f2 = cphi * f2h + sphi * fzw
        f3 = -sphi * f2h + cphi * fzw
        m1w = wm[k, 0]
        m2w = wm[k, 1]
        m3w = wm[k, 2]
        m1 = cpsi * m1w + spsi * m2w
        m2h = -spsi * m1w + cpsi * m2w
        m3 = -sphi * m2h + cphi * m3w
        rx = wp[k, 0]
        ry = wp[k, 1]
        rz = wp[k, 2]
        kx = ry * f3 - rz * f2 + m1
        X += f1
        Y += f2
        K += kx
        N += rx * f2 - ry * f1 + m3
        kheel += kx + hp[H_ZH] * f2             # heeling couple against the hull's lateral resistance
    out[O_HEEL_EXT] = kheel
    out[O_UR] = ur
    out[O_VR] = vr

    # ---------------- rigid body + added mass (MMG form, about the reference point) ----------
    # Relative velocities in the Coriolis terms: exact for a uniform current (Fossen 2011, 10.3).
    mx = hp[H_MX]
    my = hp[H_MY]
    if hp[H_MMG_CORIOLIS] > 0.0:
        X += (m + my) * vr * r + m * xg * r * r
        Y += -(m + mx) * ur * r
    else:
        X += m * (vr * r + xg * r * r)
        Y += -m * ur * r
    N += -m * xg * ur * r
    if hp[H_ROLL] > 0.0:
        K += m * zg * ur * r - hp[H_GMW] * sphi - hp[H_KP] * p
    rhs0 = X
    rhs1 = Y
    rhs2 = N
    rhs3 = K
    du = minv[0, 0] * rhs0 + minv[0, 1] * rhs1 + minv[0, 2] * rhs2 + minv[0, 3] * rhs3
    dv = minv[1, 0] * rhs0 + minv[1, 1] * rhs1 + minv[1, 2] * rhs2 + minv[1, 3] * rhs3
    dr = minv[2, 0] * rhs0 + minv[2, 1] * rhs1 + minv[2, 2] * rhs2 + minv[2, 3] * rhs3
    dp_ = minv[3, 0] * rhs0 + minv[3, 1] * rhs1 + minv[3, 2] * rhs2 + minv[3, 3] * rhs3
    # the current turns with the body: d(nu_c)/dt = -omega x nu_c
    ds[S_U] = du + r * vc
    ds[S_V] = dv - r * uc
    ds[S_R] = dr
    if hp[H_ROLL] > 0.0:
        ds[S_P] = dp_
        ds[S_PHI] = p
    # kinematics (4-DOF, pitch = 0)
    ds[S_X] = u * cpsi - v * cphi * spsi
    ds[S_Y] = u * spsi + v * cphi * cpsi
    ds[S_PSI] = r * cphi

    # engine Eq 9 and steering gear Eq 10
    ds[S_N] = (ctrl[C_NCMD] - n) / hp[H_TN]
    err = ctrl[C_DCMD] - delta
    te = hp[H_TE]
    rate = hp[H_MAXRATE]
    if abs(err) <= te * rate:
        ds[S_DELTA] = err / te
    else:
        ds[S_DELTA] = rate if err > 0.0 else -rate
    return ds


@njit(cache=True)
def _integrate(s, dt, hmax, hp, props, ruds, rv, rf, minv, ctrl, wf, wp, wm, out):
    """RK4 over dt in equal sub-steps <= hmax; the towline angle follows seed 002 Eq 3."""
    nsub = int(math.ceil(dt / hmax - 1e-9))
    if nsub < 1:
        nsub = 1
    h = dt / nsub
    for _ in range(nsub):
        k1 = _deriv(s, hp, props, ruds, rv, rf, minv, ctrl, wf, wp, wm, out)
        k2 = _deriv(s + 0.5 * h * k1, hp, props, ruds, rv, rf, minv, ctrl, wf, wp, wm, out)
        k3 = _deriv(s + 0.5 * h * k2, hp, props, ruds, rv, rf, minv, ctrl, wf, wp, wm, out)
        k4 = _deriv(s + h * k3, hp, props, ruds, rv, rf, minv, ctrl, wf, wp, wm, out)
        s += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        if hp[H_TOW_ON] > 0.0:
            g = ctrl[C_GAMMA]
            gm = hp[H_TOW_MAX]
            step = hp[H_TOW_RATE] * h
            if abs(gm - g) <= step:
                g = gm
            else:
                g += step if gm > g else -step
            ctrl[C_GAMMA] = g
    _deriv(s, hp, props, ruds, rv, rf, minv, ctrl, wf, wp, wm, out)   # diagnostics at the end
    return s


ANCHOR_STATE_NAMES = {0: "none", 1: "stowed", 2: "letting_go", 3: "dredging", 4: "heaving_up"}
_NONE, _STOWED, _LETTING_GO, _DREDGING, _HEAVING = 0, 1, 2, 3, 4


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
        self.command = Command()
        self._anchor_state = _STOWED if anchor else _NONE
        self._anchor_timer = 0.0
        self._anchor_frac = 0.0
        self._anchor_side = 0.0
        self._no_wrench = (np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3)))
        self.set_state(initial_state or VesselState.at_rest())

    # ---- state ---------------------------------------------------------------
    def set_state(self, st: VesselState, shaft_rps: Optional[float] = None,
                  rudder: Optional[float] = None) -> None:
        """Set the kinematic state (and optionally the actual shaft speed and rudder angle)."""
        s = self.s
        s[S_X], s[S_Y] = st.position[0], st.position[1]
        s[S_PHI], s[S_PSI] = st.rpy[0], st.rpy[2]
        s[S_U], s[S_V] = st.linear_velocity_body[0], st.linear_velocity_body[1]
        s[S_P], s[S_R] = st.angular_velocity_body[0], st.angular_velocity_body[2]
        if shaft_rps is not None:
            s[S_N] = shaft_rps
        if rudder is not None:
            s[S_DELTA] = rudder
        self._sync_state()

    def _sync_state(self) -> None:
        s = self.s
        self.state = VesselState(np.array([s[S_X], s[S_Y], 0.0]), np.array([s[S_PHI], 0.0, s[S_PSI]]),
                                 np.array([s[S_U], s[S_V], 0.0]), np.array([s[S_P], 0.0, s[S_R]]))

    def set_current(self, current, north: Optional[float] = None) -> None:
        """Uniform current (the water's velocity over ground), world ENU, m/s.

        set_current(np.array([east, north, up])) or set_current(east, north); up is ignored.
        """
        if north is None:
            east, north = np.asarray(current, float).reshape(-1)[:2]
        else:
            east = current
        if not (math.isfinite(east) and math.isfinite(north)):
            raise ValueError(f"{self.name}: current ({east!r}, {north!r}) is not finite")
        self.ctrl[C_CUR_X], self.ctrl[C_CUR_Y] = float(east), float(north)

    @property
    def towline_angle(self) -> float:
        return float(self.ctrl[C_GAMMA])

    # ---- commands ------------------------------------------------------------------
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
            if self._anchor_state in (_STOWED, _HEAVING):
                self._anchor_state = _LETTING_GO
                self._anchor_timer = self.anchor_cfg["let_go_time"]
                self._pick_anchor_side(st)
        elif cmd.anchor == ANCHOR_HEAVE_UP:
            if self._anchor_state in (_LETTING_GO, _DREDGING):
                self._anchor_state = _HEAVING
        self.command = Command(eo, st, 0)
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
        elif st == _HEAVING:
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
        self.ctrl[C_ANC_F] = self._anchor_frac
        self.ctrl[C_ANC_SIDE] = self._anchor_side

    # ---- stepping --------------------------------------------------------------
    def step(self, dt: float, wrenches: Sequence[ExternalWrench] = ()) -> None:
        if not (dt > 0.0 and math.isfinite(dt)):
            raise ValueError(f"{self.name}: dt={dt!r} must be positive and finite")
        if wrenches:
            k = len(wrenches)
            wf = np.empty((k, 3))
            wp = np.empty((k, 3))
            wm = np.empty((k, 3))
            for i, w in enumerate(wrenches):
                wf[i] = w.force_world
                wp[i] = w.point_body
                wm[i] = w.moment_world
        else:
            wf, wp, wm = self._no_wrench
        if self.anchor_cfg is not None:
            self._update_anchor(dt)
        _integrate(self.s, dt, self.hmax, self.hp, self.props, self.ruds, self.rv, self.rf, self.minv,
                   self.ctrl, wf, wp, wm, self.out)
        self.time += dt
        self._sync_state()

    # ---- status -------------------------------------------------------------------
    def status(self) -> Dict[str, float]:
        s = self.s
        st: Dict[str, float] = {
            "engine_order": self.command.engine_order,
            "steering_angle_ordered": self.command.steering_angle,
            "steering_angle": float(s[S_DELTA]),
            "shaft_speed": float(2.0 * math.pi * s[S_N]),
            "engine_rpm": float(60.0 * s[S_N]),
            "thrust": float(self.out[O_THRUST]),
            "speed_through_water": float(math.hypot(self.out[O_UR], self.out[O_VR])),
            "heel": float(s[S_PHI]),
            "trim": 0.0,
            "rise": 0.0,
            "anchor_state": ANCHOR_STATE_NAMES[self._anchor_state],
            "anchor_force": float(-self.out[O_ANC_X]),
            "towline_angle": self.towline_angle,
        }
        rc = self.roll_cfg
        if rc is not None:
            ratio = abs(float(self.out[O_HEEL_EXT])) / rc["max_righting_moment"]
            st["girting_ratio"] = ratio
            st["girting_threshold"] = rc["girting_threshold"]
            st["girting_warning"] = bool(ratio >= rc["girting_threshold"])
        else:
            st["girting_ratio"] = 0.0
            st["girting_threshold"] = 0.0
            st["girting_warning"] = False
        return st
