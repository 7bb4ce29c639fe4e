"""Numba kernels of the 6-DOF planing hull of Yoon & Kang, "Modeling and Simulation of the
6 DOF Motion of a High Speed Planing Hull Running in Calm Sea". ROS-free.

forces() sums one function per force group (Eq 2: F_G + F_B, F_H, F_P; external wrenches
for F_ENV): _gravity_and_hydrostatics (Eqs 3-4), _bottom_lift (Eqs 9, 14),
_horizontal_hydrodynamics and _added_mass_derivatives (Eqs 7-8, 13), _hull_side_force_roll
(Eq 7 K_v), _roll_moment and _vertical_plane (Eq 7 K, Z, M rows), _waterjet (Eqs 10-12),
_wrench_in_body; then _rigid_body_rhs and _mass_matrix (Eq 1).

All arrays SI/radians, REP-103 (body x fwd, y port, z up; world ENU). The paper's frames
are already these (its section 2.1), so its Eqs 1-14 apply unchanged except:
- Table 2 trim tau is bow-UP positive; REP-103 pitch is bow-DOWN positive: pitch = -tau.
- Eq 12's bucket angle delta turns the boat to STARBOARD when positive (its section 4.2);
  the interface's steering angle turns to PORT: delta = -steering_angle.
Parameter and polynomial slots are named below; planing.py fills them from the ship file.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from sea_environment.sampler import (E0, E_CURRENT_X, E_CURRENT_Y, E_GROUND_FX, E_GROUND_FY, E_WIND_FX,
                                     E_WIND_FY, E_WIND_X, E_WIND_Z, N_SAMPLE, P_TIME, sample)
from sim_math.integration import rk4_stage, rk4_update
from sim_math.linalg import lu_factor, lu_solve
from sim_math.rotations import matrix_entries_from_trig

from .vessel import CPL_C, CPL_K, CPL_ON, CPL_P, CPL_V, NCPL

# external wrench rows: [F_world (3), r_body (3), M_world (3)], then a coupled force's linearisation
# (vessel.coupling_row) from W_CPL
W_CPL = 9
NWRENCH = W_CPL + NCPL

# --- scalar parameter slots -------------------------------------------------------------
(P_RHO, P_G, P_MASS, P_XG, P_YG, P_ZG, P_IXX, P_IYY, P_IZZ,
 P_LREF, P_BLIFT, P_D0, P_V0, P_NEXP, P_LIFT_FADE, P_UFIT,
 P_ZWD, P_KPD, P_MQD, P_ZQ1, P_CZ0, P_CZ1, P_CQ0, P_CQ1, P_CP0, P_CP1, P_ZSIDE,
 P_FNV0, P_FNV1, P_YVV, P_NRR, P_YPHI, P_NPHI, P_KPHI,
 P_AJ, P_UDES, P_ETAREV, P_XT, P_YT, P_ZT,
 P_RTAB_U0, P_RTAB_DU, P_RAST, P_NRAMP, P_DRATE, P_DMAX, P_MAXSUB, P_NPAR) = range(48)

# --- polynomial rows (coefficients a0..a4 in U, m/s) --------------------------------------
(C_YVD, C_YRD, C_YV, C_YR, C_NVD, C_NRD, C_NV, C_NR, C_KS, C_MS, C_CL, C_CM, C_MW, C_NPOLY) = range(14)

# --- diagnostics slots --------------------------------------------------------------------
(D_THRUST, D_LIFT, D_RISE, D_DRAFT, D_UJ, D_RES, D_ND) = range(7)


@njit(cache=True, inline="always")
def poly(c, row, x):
    """Row `row` of the coefficient table c (a0..a4) at x (Eq 13, Table 5's quartics)."""
    return c[row, 0] + x * (c[row, 1] + x * (c[row, 2] + x * (c[row, 3] + x * c[row, 4])))


@njit(cache=True)
def resistance(P, rtab, u):
    """Calm-water resistance (N, positive) at forward speed u >= 0 from the Savitsky table."""
    u0 = P[P_RTAB_U0]
    du = P[P_RTAB_DU]
    n = rtab.shape[0]
    if u <= u0:
        # below the table: quadratic to zero (no Savitsky there)
        return rtab[0] * (u / u0) ** 2
    s = (u - u0) / du
    i = int(s)
    if i >= n - 1:
        u_hi = u0 + du * (n - 1)
        return rtab[n - 1] * (u / u_hi) ** 2
    f = s - i
    return rtab[i] * (1.0 - f) + rtab[i + 1] * f


@njit(cache=True)
def jet_speed(P, rtab, n_abs):
    """Eq 11: jet speed for an impeller speed fraction n_abs in [0, 1].

    The rpm sets the design running speed U0 = n U_design (linear, paper 2.5); R0 is the
    Savitsky resistance there."""
    u0 = n_abs * P[P_UDES]
    if u0 <= 0.0:
        return 0.0
    r0 = resistance(P, rtab, u0)
    return 0.5 * (u0 + math.sqrt(u0 * u0 + 4.0 * r0 / (P[P_RHO] * P[P_AJ])))


# ---- force components: each returns its contribution in the body frame ----------------------

@njit(cache=True, inline="always")
def _water_velocity_in_body(R, current, u, v, w):
    """Velocity through the water, body axes: the body velocity less the world current."""
    R00, R01, R02, R10, R11, R12, R20, R21, R22 = R
    u_rel = u - (R00 * current[0] + R10 * current[1] + R20 * current[2])
    v_rel = v - (R01 * current[0] + R11 * current[1] + R21 * current[2])
    w_rel = w - (R02 * current[0] + R12 * current[1] + R22 * current[2])
    return u_rel, v_rel, w_rel


@njit(cache=True, inline="always")
def _gravity_and_hydrostatics(P, C, z0, phi, th, sf, st, ct, cf, Up):
    """Eqs 3-4: gravity less the buoyancy lost with the rise Z0 of the origin, restoring
    moments K_S phi, M_S theta (Table 6, scaled by rho g V0 L, see planing.py).

    Returns X, Y, Z, K, M and the draft d1 = d0 - Z0 at the reference point."""
    rho = P[P_RHO]
    g = P[P_G]
    d1 = P[P_D0] - z0
    vol = P[P_V0] * (max(d1, 0.0) / P[P_D0]) ** P[P_NEXP]
    dzs = -rho * g * (P[P_V0] - vol)            # Eq 3 (negative when risen)
    rhogvl = rho * g * P[P_V0] * P[P_LREF]
    return (-dzs * st, dzs * ct * sf, dzs * ct * cf,
            poly(C, C_KS, Up) * rhogvl * phi, poly(C, C_MS, Up) * rhogvl * th, d1)


@njit(cache=True, inline="always")
def _bottom_lift(P, C, U, Up, d1, st, ct):
    """Eqs 9 and 14: bottom lift and lift moment (the caller applies them ahead, bow up only).

    Returns the lift and its X, Z, M (the roll due to sway is _hull_side_force_roll's)."""
    fade = min(max(d1 / P[P_LIFT_FADE], 0.0), 1.0)   # no lift once the hull is out
    qd = 0.5 * P[P_RHO] * U * U * fade
    B = P[P_BLIFT]
    lift = qd * B * B * poly(C, C_CL, Up)
    return lift, -lift * st, lift * ct, qd * B * B * B * poly(C, C_CM, Up)


@njit(cache=True, inline="always")
def _added_mass_derivatives(P, C, Up):
    """Eq 7's Y_vdot, Y_rdot, N_vdot, N_rdot from the Eq 13 polynomials (prime system on L)."""
    h = 0.5 * P[P_RHO]
    L = P[P_LREF]
    return (poly(C, C_YVD, Up) * h * L ** 3, poly(C, C_YRD, Up) * h * L ** 4,
            poly(C, C_NVD, Up) * h * L ** 4, poly(C, C_NRD, Up) * h * L ** 5)


@njit(cache=True, inline="always")
def _horizontal_hydrodynamics(P, C, rtab, U, Up, ahead, u_rel, v_rel, r, phi, yvd, yrd):
    """Eqs 7-8, 13: surge resistance and Munk terms, sway and yaw damping (prime system on L).

    Returns X, Y, N, the resistance term of X and the hull side force Y_v v + Y_r r."""
    h = 0.5 * P[P_RHO]
    L = P[P_LREF]
    yv = poly(C, C_YV, Up) * h * L * L * U
    yr = poly(C, C_YR, Up) * h * L ** 3 * U
    nv = poly(C, C_NV, Up) * h * L ** 3 * U
    nr = poly(C, C_NR, Up) * h * L ** 4 * U
    if ahead:
        res = -resistance(P, rtab, u_rel)
    else:
        res = P[P_RAST] * u_rel * u_rel        # astern: quadratic, opposes motion
    X = res - yvd * v_rel * r - yrd * r * r     # Eq 8: X_vr = -Y_vdot, X_rr = -Y_rdot
    yside = yv * v_rel + yr * r
    Y = (yside + P[P_YVV] * v_rel * abs(v_rel) + P[P_YPHI] * phi)
    N = (nv * v_rel + nr * r + P[P_NRR] * r * abs(r) + P[P_NPHI] * phi)
    return X, Y, N, res, yside


@njit(cache=True, inline="always")
def _hull_side_force_roll(P, U, yside):
    """Eq 7's K_v v (and the same for Y_r r): roll moment of the hull side force about the origin.

    Planing with dry sides, the side force is bottom pressure normal to the two deadrise
    panels; its line of action crosses the centreline at b / (2 sin 2 beta) above the keel,
    P_ZSIDE above the origin (planing.py). It is applied there in full from the volumetric
    Froude number P_FNV1 up, at the origin (as a displacement hull's, wetted sides) below
    P_FNV0, linearly between (PLANING.md)."""
    fn = U / math.sqrt(P[P_G] * P[P_V0] ** (1.0 / 3.0))
    w = min(max((fn - P[P_FNV0]) / (P[P_FNV1] - P[P_FNV0]), 0.0), 1.0)
    return -P[P_ZSIDE] * w * yside


@njit(cache=True, inline="always")
def _attitude_rates(p, q, r, sf, cf, st, ct):
    """phi-dot, theta-dot: roll/pitch damping acts on these, not on the part of p, q that a
    trimmed or heeled hull gets from turning (no bottom velocity there)."""
    ct_safe = ct if abs(ct) > 1e-6 else 1e-6
    return p + (sf * q + cf * r) * st / ct_safe, cf * q - sf * r


@njit(cache=True, inline="always")
def _roll_moment(P, U, phi, phidot):
    """Eq 7 K row: K_phi phi, with roll damping (estimated) on phi-dot."""
    return P[P_KPHI] * phi - (P[P_CP0] + P[P_CP1] * U) * phidot


@njit(cache=True, inline="always")
def _vertical_plane(P, C, U, Up, q, w_rel, thdot, zdot):
    """Eq 7 Z_q q and M_w w, plus heave and pitch damping (estimated).

    Returns Z_q q, the pitch moment, and the heave damping force along world z."""
    h = 0.5 * P[P_RHO]
    L = P[P_LREF]
    pitch = poly(C, C_MW, Up) * h * L ** 3 * U * w_rel - (P[P_CQ0] + P[P_CQ1] * U) * thdot
    return P[P_ZQ1] * U * q, pitch, -(P[P_CZ0] + P[P_CZ1] * U) * zdot


@njit(cache=True, inline="always")
def _waterjet(P, rtab, n_imp, delta_cmd, u_rel):
    """Eqs 10-12: waterjet thrust and bucket steering (Z_delta = 0).

    Returns the thrust, the jet speed and X, Y, K, M, N."""
    rho = P[P_RHO]
    uj = jet_speed(P, rtab, abs(n_imp))
    if n_imp >= 0.0:
        thrust = rho * P[P_AJ] * uj * (uj - u_rel)             # Eq 10
    else:
        # astern: reversing bucket, reduced efficiency; inlet momentum drag kept
        thrust = -rho * P[P_AJ] * uj * (P[P_ETAREV] * uj + u_rel)
    dl = -delta_cmd                                  # paper's delta: + turns to starboard
    xd = thrust * math.cos(dl)
    yd = thrust * math.sin(dl)
    return thrust, uj, xd, yd, -P[P_ZT] * yd, P[P_ZT] * xd, P[P_XT] * yd - P[P_YT] * xd


@njit(cache=True, inline="always")
def _wrench_in_body(wrench, R):
    """One external wrench [F_world, r_body, M_world] (9,): its X, Y, Z, K, M, N."""
    R00, R01, R02, R10, R11, R12, R20, R21, R22 = R
    bx = R00 * wrench[0] + R10 * wrench[1] + R20 * wrench[2]
    by = R01 * wrench[0] + R11 * wrench[1] + R21 * wrench[2]
    bz = R02 * wrench[0] + R12 * wrench[1] + R22 * wrench[2]
    rx, ry, rz = wrench[3], wrench[4], wrench[5]
    return (bx, by, bz,
            ry * bz - rz * by + R00 * wrench[6] + R10 * wrench[7] + R20 * wrench[8],
            rz * bx - rx * bz + R01 * wrench[6] + R11 * wrench[7] + R21 * wrench[8],
            rx * by - ry * bx + R02 * wrench[6] + R12 * wrench[7] + R22 * wrench[8])


@njit(cache=True)
def rotation_entries(x):
    """R (body -> world) of state x as matrix_entries_from_trig's tuple."""
    return matrix_entries_from_trig(math.cos(x[3]), math.sin(x[3]), math.cos(x[4]), math.sin(x[4]),
                                    math.cos(x[5]), math.sin(x[5]))


@njit(cache=True)
def point_world_motion(x, R, r):
    """World position and velocity of body point r at state x: X + R r, R (nu + omega x r)."""
    R00, R01, R02, R10, R11, R12, R20, R21, R22 = R
    rx, ry, rz = r[0], r[1], r[2]
    u, v, w, p, q, rr = x[6], x[7], x[8], x[9], x[10], x[11]
    bx, by, bz = u + q * rz - rr * ry, v + rr * rx - p * rz, w + p * ry - q * rx
    pos = np.array([x[0] + R00 * rx + R01 * ry + R02 * rz, x[1] + R10 * rx + R11 * ry + R12 * rz,
                    x[2] + R20 * rx + R21 * ry + R22 * rz])
    vel = np.array([R00 * bx + R01 * by + R02 * bz, R10 * bx + R11 * by + R12 * bz, R20 * bx + R21 * by + R22 * bz])
    return pos, vel


@njit(cache=True)
def _coupled_row(row, x, R):
    """The wrench row with its force followed along the point's motion at state x:
    F + K (p - p_ref) + C (v - v_ref) (vessel.ExternalWrench's coupling)."""
    out = row.copy()
    pos, vel = point_world_motion(x, R, row[3:6])
    c = W_CPL
    for i in range(3):
        f = row[i]
        for j in range(3):
            f += row[c + CPL_K + 3 * i + j] * (pos[j] - row[c + CPL_P + j])
            f += row[c + CPL_C + 3 * i + j] * (vel[j] - row[c + CPL_V + j])
        out[i] = f
    return out


# ---- rigid body, Eq 1 ------------------------------------------------------------------------

@njit(cache=True, inline="always")
def _inertia_about_origin(P):
    """Ixx, Iyy, Izz, Ixy, Ixz, Iyz about the origin: about-CG principal values + parallel axis."""
    m = P[P_MASS]
    xg, yg, zg = P[P_XG], P[P_YG], P[P_ZG]
    return (P[P_IXX] + m * (yg * yg + zg * zg), P[P_IYY] + m * (xg * xg + zg * zg),
            P[P_IZZ] + m * (xg * xg + yg * yg), -m * xg * yg, -m * xg * zg, -m * yg * zg)


@njit(cache=True, inline="always")
def _rigid_body_rhs(P, inertia, X, Y, Z, K, M, N, u, v, w, p, q, r, b):
    """Eq 1 in vector form about the origin, CG at rg: b = forces less the velocity terms."""
    m = P[P_MASS]
    xg, yg, zg = P[P_XG], P[P_YG], P[P_ZG]
    Ixx, Iyy, Izz, Ixy, Ixz, Iyz = inertia
    # omega x v
    wv0 = q * w - r * v
    wv1 = r * u - p * w
    wv2 = p * v - q * u
    # omega x (omega x rg)
    cen0 = p * (p * xg + q * yg + r * zg) - xg * (p * p + q * q + r * r)
    cen1 = q * (p * xg + q * yg + r * zg) - yg * (p * p + q * q + r * r)
    cen2 = r * (p * xg + q * yg + r * zg) - zg * (p * p + q * q + r * r)
    # I omega, omega x I omega
    Iw0 = Ixx * p + Ixy * q + Ixz * r
    Iw1 = Ixy * p + Iyy * q + Iyz * r
    Iw2 = Ixz * p + Iyz * q + Izz * r
    b[0] = X - m * (wv0 + cen0)
    b[1] = Y - m * (wv1 + cen1)
    b[2] = Z - m * (wv2 + cen2)
    b[3] = K - (q * Iw2 - r * Iw1) - m * (yg * wv2 - zg * wv1)
    b[4] = M - (r * Iw0 - p * Iw2) - m * (zg * wv0 - xg * wv2)
    b[5] = N - (p * Iw1 - q * Iw0) - m * (xg * wv1 - yg * wv0)


@njit(cache=True, inline="always")
def _mass_matrix(P, inertia, yvd, yrd, nvd, nrd, A):
    """Rigid-body mass matrix about the origin plus the added mass (Eq 7's acceleration terms
    moved to the left; X_udot = 0 by Eq 8)."""
    m = P[P_MASS]
    xg, yg, zg = P[P_XG], P[P_YG], P[P_ZG]
    Ixx, Iyy, Izz, Ixy, Ixz, Iyz = inertia
    A[:, :] = 0.0
    A[0, 0] = m
    A[1, 1] = m
    A[2, 2] = m
    # -m S(rg) block and m S(rg) block
    A[0, 4] = m * zg
    A[0, 5] = -m * yg
    A[1, 3] = -m * zg
    A[1, 5] = m * xg
    A[2, 3] = m * yg
    A[2, 4] = -m * xg
    A[3, 1] = -m * zg
    A[3, 2] = m * yg
    A[4, 0] = m * zg
    A[4, 2] = -m * xg
    A[5, 0] = -m * yg
    A[5, 1] = m * xg
    A[3, 3] = Ixx
    A[3, 4] = Ixy
    A[3, 5] = Ixz
    A[4, 3] = Ixy
    A[4, 4] = Iyy
    A[4, 5] = Iyz
    A[5, 3] = Ixz
    A[5, 4] = Iyz
    A[5, 5] = Izz
    A[1, 1] -= yvd
    A[1, 5] -= yrd
    A[5, 1] -= nvd
    A[5, 5] -= nrd
    A[2, 2] -= P[P_ZWD]
    A[3, 3] -= P[P_KPD]
    A[4, 4] -= P[P_MQD]


@njit(cache=True)
def forces(x, P, C, rtab, n_imp, delta_cmd, wrenches, current, diag, b, A):
    """Generalised mass matrix A (6x6) and right-hand side b (6) of A nu_dot = b at state x.

    x = [X, Y, Z, phi, theta, psi, u, v, w, p, q, r]; n_imp: impeller speed fraction (-1..1);
    delta_cmd: bucket angle, interface sign (+ = port). wrenches: (k, 9) external wrenches
    [F_world, r_body, M_world]; current: (3,) water current, world. Returns the heave rate of the origin.
    X..N sum the components in a fixed order (the order is part of the numbers).
    """
    phi, th = x[3], x[4]
    u, v, w, p, q, r = x[6], x[7], x[8], x[9], x[10], x[11]
    cf, sf = math.cos(phi), math.sin(phi)
    ct, st = math.cos(th), math.sin(th)
    R = matrix_entries_from_trig(cf, sf, ct, st, math.cos(x[5]), math.sin(x[5]))
    u_rel, v_rel, w_rel = _water_velocity_in_body(R, current, u, v, w)
    U = math.sqrt(u_rel * u_rel + v_rel * v_rel)   # resultant speed (paper 3.4)
    ahead = u_rel > 0.0
    # Eq 13 coefficients: at the resultant speed ahead, at rest astern (paper 4.1)
    Up = min(U, P[P_UFIT]) if ahead else 0.0

    z0 = x[2]
    fx, fy, fz, mk, mm, d1 = _gravity_and_hydrostatics(P, C, z0, phi, th, sf, st, ct, cf, Up)
    mn = 0.0
    lift = 0.0
    if ahead and th < 0.0:                          # Eq 9: only ahead and bow up
        lift, Xl, Zl, Ml = _bottom_lift(P, C, U, Up, d1, st, ct)
        fx += Xl
        fz += Zl
        mm += Ml

    yvd, yrd, nvd, nrd = _added_mass_derivatives(P, C, Up)
    Xh, Yh, Nh, res, yside = _horizontal_hydrodynamics(P, C, rtab, U, Up, ahead, u_rel, v_rel, r, phi, yvd, yrd)
    fx += Xh
    fy += Yh
    mn += Nh
    if ahead:                                       # astern: derivatives at rest (4.1), no lever
        mk += _hull_side_force_roll(P, U, yside)
    phidot, thdot = _attitude_rates(p, q, r, sf, cf, st, ct)
    mk += _roll_moment(P, U, phi, phidot)

    R20, R21, R22 = R[6], R[7], R[8]
    zdot = R20 * u + R21 * v + R22 * w           # world heave rate of the origin
    Zq, Mv, cz = _vertical_plane(P, C, U, Up, q, w_rel, thdot, zdot)
    fz += Zq
    mm += Mv
    fx += cz * R20
    fy += cz * R21
    fz += cz * R22

    thrust, uj, Xj, Yj, Kj, Mj, Nj = _waterjet(P, rtab, n_imp, delta_cmd, u_rel)
    fx += Xj
    fy += Yj
    mk += Kj
    mm += Mj
    mn += Nj

    for k in range(wrenches.shape[0]):
        row = wrenches[k]
        if row[W_CPL + CPL_ON] > 0.0:
            row = _coupled_row(row, x, R)
        Xw, Yw, Zw, Kw, Mw, Nw = _wrench_in_body(row, R)
        fx += Xw
        fy += Yw
        fz += Zw
        mk += Kw
        mm += Mw
        mn += Nw

    inertia = _inertia_about_origin(P)
    _rigid_body_rhs(P, inertia, fx, fy, fz, mk, mm, mn, u, v, w, p, q, r, b)
    _mass_matrix(P, inertia, yvd, yrd, nvd, nrd, A)
    diag[D_THRUST] = thrust
    diag[D_LIFT] = lift
    diag[D_RISE] = z0
    diag[D_DRAFT] = d1
    diag[D_UJ] = uj
    diag[D_RES] = res
    return zdot


@njit(cache=True)
def rhs(x, P, C, rtab, n_imp, delta_cmd, wrenches, current, diag):
    """Time derivative of x = [X, Y, Z, phi, theta, psi, u, v, w, p, q, r]."""
    b = np.empty(6)
    A = np.empty((6, 6))
    zdot = forces(x, P, C, rtab, n_imp, delta_cmd, wrenches, current, diag, b, A)
    # Eq 1: the accelerations A^-1 b; A and b are this call's own, solved in place
    piv = np.empty(6, np.int64)
    if lu_factor(A, piv):
        lu_solve(A, piv, b)
    else:  # singular or not finite: a non-finite state, which PlaningHull.step refuses
        b[:] = np.nan
    acc = b
    phi, th, psi = x[3], x[4], x[5]
    u, v, w, p, q, r = x[6], x[7], x[8], x[9], x[10], x[11]
    cf, sf = math.cos(phi), math.sin(phi)
    ct, st = math.cos(th), math.sin(th)
    cp, sp = math.cos(psi), math.sin(psi)
    dx = np.empty(12)
    dx[0] = cp * ct * u + (cp * st * sf - sp * cf) * v + (cp * st * cf + sp * sf) * w
    dx[1] = sp * ct * u + (sp * st * sf + cp * cf) * v + (sp * st * cf - cp * sf) * w
    dx[2] = zdot
    ct_safe = ct if abs(ct) > 1e-6 else 1e-6
    tt = st / ct_safe
    dx[3] = p + (sf * q + cf * r) * tt
    dx[4] = cf * q - sf * r
    dx[5] = (sf * q + cf * r) / ct_safe
    for i in range(6):
        dx[6 + i] = acc[i]
    return dx


@njit(cache=True)
def _approach(value, target, max_change):
    """value moved toward target by at most max_change (a rate-limited actuator)."""
    if target > value + max_change:
        return value + max_change
    if target < value - max_change:
        return value - max_change
    return target


@njit(cache=True)
def integrate(x, act, cmd, P, C, rtab, wrenches, current, dt, diag, hmax):
    """Advance x (12) and actuators act = [impeller fraction, bucket angle] by dt (RK4, sub-steps
    <= hmax, at most P[P_MAXSUB]).

    cmd = [engine order, bucket angle ordered]; the impeller speed ramps linearly (paper 2.5)
    and the bucket moves at a limited rate; both are held within each RK4 substep."""
    nsub = int(math.ceil(dt / min(hmax, P[P_MAXSUB]) - 1e-9))
    if nsub < 1:
        nsub = 1
    h = dt / nsub
    tmp = np.empty(12)
    for _ in range(nsub):
        act[0] = _approach(act[0], cmd[0], P[P_NRAMP] * h)
        act[1] = _approach(act[1], cmd[1], P[P_DRATE] * h)
        k1 = rhs(x, P, C, rtab, act[0], act[1], wrenches, current, diag)
        k2 = rhs(rk4_stage(x, 0.5 * h, k1, tmp), P, C, rtab, act[0], act[1], wrenches, current, diag)
        k3 = rhs(rk4_stage(x, 0.5 * h, k2, tmp), P, C, rtab, act[0], act[1], wrenches, current, diag)
        k4 = rhs(rk4_stage(x, h, k3, tmp), P, C, rtab, act[0], act[1], wrenches, current, diag)
        rk4_update(x, h, k1, k2, k3, k4)
    # diagnostics at the final state
    rhs(x, P, C, rtab, act[0], act[1], wrenches, current, diag)
    # keep yaw in (-pi, pi]
    if x[5] > math.pi:
        x[5] -= 2.0 * math.pi
    elif x[5] <= -math.pi:
        x[5] += 2.0 * math.pi


@njit(cache=True)
def integrate_in_environment(x, act, cmd, P, C, rtab, wrenches, current, dt, diag, hmax, env):
    """integrate in the environment (env: a EnvironmentSampler's data) as sampled at the
    start state: its wind and the bottom's friction are the last two wrench rows (filled here);
    then the environment is sampled at the new state, its time advanced by dt, and its current
    set for the next step (Savitsky's forces are deep-water ones: the depth changes nothing else)."""
    e = env[E0:E0 + N_SAMPLE]
    k = wrenches.shape[0] - 2
    for i in range(wrenches.shape[1]):
        wrenches[k, i] = 0.0
        wrenches[k + 1, i] = 0.0
    wrenches[k, 0], wrenches[k, 1] = e[E_WIND_FX], e[E_WIND_FY]
    wrenches[k, 3], wrenches[k, 5] = e[E_WIND_X], e[E_WIND_Z]
    wrenches[k + 1, 0], wrenches[k + 1, 1] = e[E_GROUND_FX], e[E_GROUND_FY]
    integrate(x, act, cmd, P, C, rtab, wrenches, current, dt, diag, hmax)
    env[P_TIME] += dt
    sample(env, x[0], x[1], x[5], x[6], x[7])
    current[0], current[1], current[2] = e[E_CURRENT_X], e[E_CURRENT_Y], 0.0
