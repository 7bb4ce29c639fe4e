"""Numba kernels of the 6-DOF planing hull (seed 004, Yoon & Kang). ROS-free.

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

# --- scalar parameter slots -------------------------------------------------------------
(P_RHO, P_G, P_MASS, P_XG, P_YG, P_ZG, P_IXX, P_IYY, P_IZZ,
 P_LREF, P_BLIFT, P_D0, P_V0, P_NEXP, P_LIFT_FADE, P_UFIT,
 P_ZWD, P_KPD, P_MQD, P_ZQ1, P_CZ0, P_CZ1, P_CQ0, P_CQ1, P_CP0, P_CP1, P_CKV,
 P_YVV, P_NRR, P_YPHI, P_NPHI, P_KPHI,
 P_AJ, P_UDES, P_ETAREV, P_XT, P_YT, P_ZT,
 P_RTAB_U0, P_RTAB_DU, P_RAST, P_NRAMP, P_DRATE, P_DMAX, P_MAXSUB, P_NPAR) = range(46)

# --- polynomial rows (coefficients a0..a4 in U, m/s) --------------------------------------
(C_YVD, C_YRD, C_YV, C_YR, C_NVD, C_NRD, C_NV, C_NR, C_KS, C_MS, C_CL, C_CM, C_MW, C_NPOLY) = range(14)

# --- diagnostics slots --------------------------------------------------------------------
(D_THRUST, D_LIFT, D_RISE, D_DRAFT, D_UJ, D_RES, D_ND) = range(7)


@njit(cache=True)
def poly(c, row, x):
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


@njit(cache=True)
def solve6(A, b):
    """Gaussian elimination with partial pivoting for the 6x6 mass matrix."""
    n = 6
    M = A.copy()
    x = b.copy()
    for k in range(n):
        piv = k
        big = abs(M[k, k])
        for i in range(k + 1, n):
            if abs(M[i, k]) > big:
                big = abs(M[i, k])
                piv = i
        if piv != k:
            for j in range(n):
                t = M[k, j]
                M[k, j] = M[piv, j]
                M[piv, j] = t
            t = x[k]
            x[k] = x[piv]
            x[piv] = t
        for i in range(k + 1, n):
            f = M[i, k] / M[k, k]
            if f != 0.0:
                for j in range(k, n):
                    M[i, j] -= f * M[k, j]
                x[i] -= f * x[k]
    for i in range(n - 1, -1, -1):
        s = x[i]
        for j in range(i + 1, n):
            s -= M[i, j] * x[j]
        x[i] = s / M[i, i]
    return x


@njit(cache=True)
def forces(x, P, C, rtab, n_imp, delta_cmd, wr, cur, diag, b, A):
    """Generalised mass matrix A (6x6) and right-hand side b (6) of A nu_dot = b at state x.

    x = [X, Y, Z, phi, theta, psi, u, v, w, p, q, r]; n_imp: impeller speed fraction (-1..1);
    delta_cmd: bucket angle, interface sign (+ = port). wr: (k, 9) external wrenches
    [F_world, r_body, M_world]; cur: (3,) current, world. Returns the heave rate of the origin.
    """
    phi, th, psi = x[3], x[4], x[5]
    u, v, w, p, q, r = x[6], x[7], x[8], x[9], x[10], x[11]
    cf, sf = math.cos(phi), math.sin(phi)
    ct, st = math.cos(th), math.sin(th)
    cp, sp = math.cos(psi), math.sin(psi)
    # R = Rz Ry Rx (body -> world), vessel.rotation_body_to_world
    R00 = cp * ct
    R01 = cp * st * sf - sp * cf
    R02 = cp * st * cf + sp * sf
    R10 = sp * ct
    R11 = sp * st * sf + cp * cf
    R12 = sp * st * cf - cp * sf
    R20 = -st
    R21 = ct * sf
    R22 = ct * cf

    rho = P[P_RHO]
    g = P[P_G]
    m = P[P_MASS]
    L = P[P_LREF]
    # velocity through the water (body): subtract the current
    ur = u - (R00 * cur[0] + R10 * cur[1] + R20 * cur[2])
    vr = v - (R01 * cur[0] + R11 * cur[1] + R21 * cur[2])
    wr_ = w - (R02 * cur[0] + R12 * cur[1] + R22 * cur[2])
    U = math.sqrt(ur * ur + vr * vr)           # resultant speed (paper 3.4)
    ahead = ur > 0.0
    # Eq 13 coefficients: at the resultant speed ahead, at rest astern (paper 4.1)
    Up = min(U, P[P_UFIT]) if ahead else 0.0

    # ---- gravity + hydrostatics, Eqs 3-4: buoyancy lost with the rise Z0 of the origin ----
    z0 = x[2]
    d1 = P[P_D0] - z0
    vol = P[P_V0] * (max(d1, 0.0) / P[P_D0]) ** P[P_NEXP]
    dzs = -rho * g * (P[P_V0] - vol)            # Eq 3 (negative when risen)
    fx = -dzs * st
    fy = dzs * ct * sf
    fz = dzs * ct * cf
    rhogvl = rho * g * P[P_V0] * L                 # Table 6 scale (see planing.py)
    mk = poly(C, C_KS, Up) * rhogvl * phi         # Eq 4 K_S phi
    mm = poly(C, C_MS, Up) * rhogvl * th          # Eq 4 M_S theta
    mn = 0.0

    # ---- lift and lift moment, Eqs 9 and 14: only ahead and bow up (theta < 0) ----
    lift = 0.0
    if ahead and th < 0.0:
        fade = min(max(d1 / P[P_LIFT_FADE], 0.0), 1.0)   # no lift once the hull is out
        qd = 0.5 * rho * U * U * fade
        B = P[P_BLIFT]
        lift = qd * B * B * poly(C, C_CL, Up)
        fx += -lift * st
        fz += lift * ct
        mm += qd * B * B * B * poly(C, C_CM, Up)
        # roll due to sway from the asymmetric bottom lift (estimated, see PLANING.md)
        mk += P[P_CKV] * lift / U * vr

    # ---- horizontal-plane hydrodynamics, Eqs 7-8, 13 (prime system on L) ----
    h = 0.5 * rho
    yvd = poly(C, C_YVD, Up) * h * L ** 3
    yrd = poly(C, C_YRD, Up) * h * L ** 4
    nvd = poly(C, C_NVD, Up) * h * L ** 4
    nrd = poly(C, C_NRD, Up) * h * L ** 5
    yv = poly(C, C_YV, Up) * h * L * L * U
    yr = poly(C, C_YR, Up) * h * L ** 3 * U
    nv = poly(C, C_NV, Up) * h * L ** 3 * U
    nr = poly(C, C_NR, Up) * h * L ** 4 * U
    if ahead:
        res = -resistance(P, rtab, ur)
    else:
        res = P[P_RAST] * ur * ur               # astern: quadratic, opposes motion
    fx += res - yvd * vr * r - yrd * r * r      # Eq 8: X_vr = -Y_vdot, X_rr = -Y_rdot
    fy += (yv * vr + yr * r + P[P_YVV] * vr * abs(vr) + P[P_YPHI] * phi)
    mn += (nv * vr + nr * r + P[P_NRR] * r * abs(r) + P[P_NPHI] * phi)
    # attitude rates: roll/pitch damping acts on phi_dot, theta_dot, not on the part of
    # p, q that a trimmed or heeled hull gets from turning (no bottom velocity there)
    ct_safe = ct if abs(ct) > 1e-6 else 1e-6
    phidot = p + (sf * q + cf * r) * st / ct_safe
    thdot = cf * q - sf * r
    mk += P[P_KPHI] * phi - (P[P_CP0] + P[P_CP1] * U) * phidot

    # ---- vertical plane: Z_q, M_w (Eq 7) + heave/pitch damping (estimated) ----
    fz += P[P_ZQ1] * U * q
    mm += poly(C, C_MW, Up) * h * L ** 3 * U * wr_ - (P[P_CQ0] + P[P_CQ1] * U) * thdot
    zdot = R20 * u + R21 * v + R22 * w           # world heave rate of the origin
    cz = -(P[P_CZ0] + P[P_CZ1] * U) * zdot
    fx += cz * R20
    fy += cz * R21
    fz += cz * R22

    # ---- waterjet, Eqs 10-12 ----
    uj = jet_speed(P, rtab, abs(n_imp))
    if n_imp >= 0.0:
        thrust = rho * P[P_AJ] * uj * (uj - ur)             # Eq 10
    else:
        # astern: reversing bucket, reduced efficiency; inlet momentum drag kept
        thrust = -rho * P[P_AJ] * uj * (P[P_ETAREV] * uj + ur)
    dl = -delta_cmd                                  # paper's delta: + turns to starboard
    xd = thrust * math.cos(dl)
    yd = thrust * math.sin(dl)
    xt, yt, zt = P[P_XT], P[P_YT], P[P_ZT]
    fx += xd
    fy += yd
    mk += -zt * yd                                   # Eq 12 (Z_delta = 0)
    mm += zt * xd
    mn += xt * yd - yt * xd

    # ---- external wrenches (world force at a body point) ----
    for k in range(wr.shape[0]):
        Fw0, Fw1, Fw2 = wr[k, 0], wr[k, 1], wr[k, 2]
        bx = R00 * Fw0 + R10 * Fw1 + R20 * Fw2
        by = R01 * Fw0 + R11 * Fw1 + R21 * Fw2
        bz = R02 * Fw0 + R12 * Fw1 + R22 * Fw2
        rx, ry, rz = wr[k, 3], wr[k, 4], wr[k, 5]
        fx += bx
        fy += by
        fz += bz
        mk += ry * bz - rz * by + R00 * wr[k, 6] + R10 * wr[k, 7] + R20 * wr[k, 8]
        mm += rz * bx - rx * bz + R01 * wr[k, 6] + R11 * wr[k, 7] + R21 * wr[k, 8]
        mn += rx * by - ry * bx + R02 * wr[k, 6] + R12 * wr[k, 7] + R22 * wr[k, 8]

    # ---- rigid body about the origin, CG at rg (Eq 1 in vector form) ----
    xg, yg, zg = P[P_XG], P[P_YG], P[P_ZG]
    # inertia about the origin: about-CG principal values + parallel axis
    Ixx = P[P_IXX] + m * (yg * yg + zg * zg)
    Iyy = P[P_IYY] + m * (xg * xg + zg * zg)
    Izz = P[P_IZZ] + m * (xg * xg + yg * yg)
    Ixy = -m * xg * yg
    Ixz = -m * xg * zg
    Iyz = -m * yg * zg
    # omega x v
    wv0 = q * w - r * v
    wv1 = r * u - p * w
    wv2 = p * v - q * u
    # omega x (omega x rg)
    wr0 = p * (p * xg + q * yg + r * zg) - xg * (p * p + q * q + r * r)
    wr1 = q * (p * xg + q * yg + r * zg) - yg * (p * p + q * q + r * r)
    wr2 = r * (p * xg + q * yg + r * zg) - zg * (p * p + q * q + r * r)
    # I omega, omega x I omega
    Iw0 = Ixx * p + Ixy * q + Ixz * r
    Iw1 = Ixy * p + Iyy * q + Iyz * r
    Iw2 = Ixz * p + Iyz * q + Izz * r
    b[0] = fx - m * (wv0 + wr0)
    b[1] = fy - m * (wv1 + wr1)
    b[2] = fz - m * (wv2 + wr2)
    b[3] = mk - (q * Iw2 - r * Iw1) - m * (yg * wv2 - zg * wv1)
    b[4] = mm - (r * Iw0 - p * Iw2) - m * (zg * wv0 - xg * wv2)
    b[5] = mn - (p * Iw1 - q * Iw0) - m * (xg * wv1 - yg * wv0)
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
    # added mass (Eq 7 acceleration terms moved to the left; X_udot = 0 by Eq 8)
    A[1, 1] -= yvd
    A[1, 5] -= yrd
    A[5, 1] -= nvd
    A[5, 5] -= nrd
    A[2, 2] -= P[P_ZWD]
    A[3, 3] -= P[P_KPD]
    A[4, 4] -= P[P_MQD]
    diag[D_THRUST] = thrust
    diag[D_LIFT] = lift
    diag[D_RISE] = z0
    diag[D_DRAFT] = d1
    diag[D_UJ] = uj
    diag[D_RES] = res
    return zdot


@njit(cache=True)
def rhs(x, P, C, rtab, n_imp, delta_cmd, wr, cur, diag):
    """Time derivative of x = [X, Y, Z, phi, theta, psi, u, v, w, p, q, r]."""
    b = np.empty(6)
    A = np.empty((6, 6))
    zdot = forces(x, P, C, rtab, n_imp, delta_cmd, wr, cur, diag, b, A)
    acc = solve6(A, b)
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
def _approach(cur, target, max_change):
    if target > cur + max_change:
        return cur + max_change
    if target < cur - max_change:
        return cur - max_change
    return target


@njit(cache=True)
def integrate(x, act, cmd, P, C, rtab, wr, cur, dt, diag):
    """Advance x (12) and actuators act = [impeller fraction, bucket angle] by dt (RK4).

    cmd = [engine order, bucket angle ordered]; the impeller speed ramps linearly (paper 2.5)
    and the bucket moves at a limited rate; both are held within each RK4 substep."""
    nsub = int(math.ceil(dt / P[P_MAXSUB] - 1e-9))
    if nsub < 1:
        nsub = 1
    h = dt / nsub
    tmp = np.empty(12)
    for _ in range(nsub):
        act[0] = _approach(act[0], cmd[0], P[P_NRAMP] * h)
        act[1] = _approach(act[1], cmd[1], P[P_DRATE] * h)
        k1 = rhs(x, P, C, rtab, act[0], act[1], wr, cur, diag)
        for i in range(12):
            tmp[i] = x[i] + 0.5 * h * k1[i]
        k2 = rhs(tmp, P, C, rtab, act[0], act[1], wr, cur, diag)
        for i in range(12):
            tmp[i] = x[i] + 0.5 * h * k2[i]
        k3 = rhs(tmp, P, C, rtab, act[0], act[1], wr, cur, diag)
        for i in range(12):
            tmp[i] = x[i] + h * k3[i]
        k4 = rhs(tmp, P, C, rtab, act[0], act[1], wr, cur, diag)
        for i in range(12):
            x[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
    # diagnostics at the final state
    rhs(x, P, C, rtab, act[0], act[1], wr, cur, diag)
    # keep yaw in (-pi, pi]
    if x[5] > math.pi:
        x[5] -= 2.0 * math.pi
    elif x[5] <= -math.pi:
        x[5] += 2.0 * math.pi
