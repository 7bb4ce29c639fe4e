"""Numba kernels of the finite-difference towed cable of Park, Jung, "Nonlinear Dynamic
Analysis on Low-Tension Towed Cable by Finite Difference Method" (Eq 2-21).

Paper frame (Ablow-Schechter convention, used by the paper): X vertical UP (weight is -w0 X,
that is what the signs of the w0 terms of Eq 2 imply), Y and Z horizontal. Local triad from
Eq (1): rotate by phi about Z, then by theta about n:
    t = ( cos th cos ph,  cos th sin ph, -sin th)
    n = (-sin ph,         cos ph,          0    )
    b = ( sin th cos ph,  sin th sin ph,  cos th)   (Eq 1 row 3 is OCR-damaged; b = t x n)
Unknowns per node (Eq 9): H = (T, Sn, Sb, vt, vn, vb, phi, theta, On, Ob).
Arc length s is unstretched, s = 0 at the free end, s = L at the towing point.

Continuous system (Eq 8, J H' = K H_dot + L), rows re-derived from Newton's law, moment
balance and compatibility (Eq 2-5) because Eq 10-12 are OCR-damaged:
  0  T'   = m(vt. + vb th. - vn ph. cos th) + Sn Ob - Sb On + w0 cos ph cos th - Rt
  1  Sn'  = (m+ma) vn. + mr ph.(vt cos th + vb sin th) - Ob(T + Sb tan th) - w0 sin ph - Rn
  2  Sb'  = (m+ma) vb. - mr(vn ph. sin th + vt th.) + Sn Ob tan th + T On
            + w0 cos ph sin th - Rb
  3  vt'         = T./EA + Ob vn - On vb                       (Eq 4: e_dot = T_dot/EA)
  4  vn'         = (1+e) cos th ph. - Ob(vt + vb tan th)
  5  vb'         = -(1+e) th. + Ob vn tan th + On vt
  6  cos th ph'  = Ob                                          (Eq 5)
  7  th'         = On
  8  EI On'      = -EI Ob^2 tan th + Sb (1+e)^3                (Eq 3)
  9  EI Ob'      = EI Ob On tan th - Sn (1+e)^3
e = T/EA; mr = m + ma (added mass on the whole normal acceleration, frame-invariant) or m
(the paper's Eq 12 literally: added mass on vn., vb. only). Fluid acceleration terms vanish
for a uniform steady current. Drag Eq 6 on the velocity relative to the current (R_t on
v_t - u_t; see FD_CABLE.md, 'Tangential drag: statics against the turn').

Waves (issue 31): the water velocity of each node is the current plus the wave particles'
(Airy with Wheeler stretching, sea_environment.waves; zero for a node in the air), and the
particles' acceleration a adds Morison's inertia (Morison et al. 1950; DNV-RP-C205 6.2) per
unit length, rho A ((1 + C_a) a_n + a_t) on the normal (n, b) and tangential parts (Froude-
Krylov alone along the axis: the model has no tangential added mass) to R of rows 0-2. The
added mass's reaction to the cable's own acceleration is already in K (m + m_a).
"""
import cmath
import math

import numpy as np
from numba import njit

from sea_environment.environment import current_xy_at, tidal_factor
from sea_environment.sampler import P_DEPTH_MIN, P_TIME, depth_at, wave_offset
from sea_environment.waves import wave_kinematics
from sim_math.linalg import lu_factor, lu_solve_columns

NV = 10
# columns of H, the unknowns of Eq 9 in the paper's order (the equation code below indexes them
# by these numbers, as the paper's rows and columns); FdCable uses the names
H_T, H_SN, H_SB, H_VT, H_VN, H_VB, H_PHI, H_THETA, H_ON, H_OB = range(NV)
H_FORCE = slice(H_T, H_SB + 1)  # (T, Sn, Sb), N: the internal force in the local triad
H_VEL = slice(H_VT, H_VB + 1)  # (vt, vn, vb), m/s: the velocity in the local triad
H_ANGLES = slice(H_PHI, H_THETA + 1)  # (phi, theta), rad: the triad's angles (Eq 1)
# parameter vector layout
P_M, P_MA, P_MR, P_W0, P_EA, P_EI, P_KT, P_KN, P_KB, P_RHOA = range(10)
NP = 10
# columns of a node's row of `cur` (paper frame): the water velocity the normal drag acts on
# (current + waves), the tangential drag's reference, the wave particles' acceleration
CUR_WATER, CUR_REF, CUR_ACC, CUR_COLS = 0, 3, 6, 9
# rows of a cell's 10 equations that go to the block row of its left node (Y) and of its right
# node (X): Y holds the vt', vn', vb', phi', theta' rows whose J/ds diagonal covers exactly the
# unknowns the free-end BC (T, Sn, Sb, On, Ob) leaves open, so the first diagonal block is
# well conditioned; X the rest.
ROWS_Y = np.array([3, 4, 5, 6, 7])
ROWS_X = np.array([0, 1, 2, 8, 9])
CSTEP = 1e-20  # complex-step size: derivatives exact to rounding


@njit(cache=True)
def local_triad(phi, th, out):
    """Rows t, n, b of the local triad in the paper frame (Eq 1, row 3 corrected)."""
    cp, sp, ct, st = math.cos(phi), math.sin(phi), math.cos(th), math.sin(th)
    out[0, 0], out[0, 1], out[0, 2] = ct * cp, ct * sp, -st
    out[1, 0], out[1, 1], out[1, 2] = -sp, cp, 0.0
    out[2, 0], out[2, 1], out[2, 2] = st * cp, st * sp, ct


@njit(cache=True)
def node_terms(H, Hold, P, cur, use_k, L, g):
    """L(H) of Eq 10 (re-derived) and g = K(H) (H - Hold) of Eq 12 (re-derived).

    Generic in the dtype of H (complex for the complex-step Jacobian). cur (9,), this node's:
    the water velocity (cur[0:3]: current + wave particles), the velocity the tangential drag
    R_t is measured against (cur[3:6]; the water's for Morison drag on the relative velocity),
    paper frame, m/s, and the wave particles' acceleration (cur[6:9], m/s^2; zero on a calm
    sea), whose Morison inertia joins R.
    """
    T, Sn, Sb, vt, vn, vb, ph, th, On, Ob = (H[0], H[1], H[2], H[3], H[4], H[5], H[6], H[7],
                                             H[8], H[9])
    m, ma, mr, w0, EA, EI = P[P_M], P[P_MA], P[P_MR], P[P_W0], P[P_EA], P[P_EI]
    cp, sp, ct, st = cmath.cos(ph), cmath.sin(ph), cmath.cos(th), cmath.sin(th)
    tt = st / ct
    e1 = 1.0 + T / EA
    # current in the local frame (Eq 1); R_t acts on v_t relative to cur[3:6] (the velocity
    # the tangential drag is measured against, FdCable(tangential_reference=)), R_n, R_b on the
    # velocity relative to the current cur[0:3]
    un = -cur[0] * sp + cur[1] * cp
    ub = cur[0] * st * cp + cur[1] * st * sp + cur[2] * ct
    ut = cur[3] * ct * cp + cur[4] * ct * sp - cur[5] * st
    vtr, vnr, vbr = vt - ut, vn - un, vb - ub
    # Eq 6: Morison drag; (1+e)^0.5 = stretched length x Poisson-thinned diameter.
    # x*sqrt(x*x) is x|x| in a complex-step-safe form.
    se = cmath.sqrt(e1)
    Rt = -P[P_KT] * vtr * cmath.sqrt(vtr * vtr) * se
    vp = cmath.sqrt(vnr * vnr + vbr * vbr)
    Rn = -P[P_KN] * vnr * vp * se
    Rb = -P[P_KB] * vbr * vp * se
    if cur[6] != 0.0 or cur[7] != 0.0 or cur[8] != 0.0:   # waves: Morison's inertia
        an = -cur[6] * sp + cur[7] * cp
        ab = cur[6] * st * cp + cur[7] * st * sp + cur[8] * ct
        at = cur[6] * ct * cp + cur[7] * ct * sp - cur[8] * st
        ra = P[P_RHOA]
        Rt = Rt + ra * at
        Rn = Rn + (ra + ma) * an
        Rb = Rb + (ra + ma) * ab
    e3 = e1 * e1 * e1
    L[0] = Sn * Ob - Sb * On + w0 * ct * cp - Rt
    L[1] = -Ob * (T + Sb * tt) - w0 * sp - Rn
    L[2] = Sn * Ob * tt + T * On + w0 * cp * st - Rb
    L[3] = Ob * vn - On * vb
    L[4] = -Ob * (vt + vb * tt)
    L[5] = Ob * vn * tt + On * vt
    L[6] = Ob
    L[7] = On
    L[8] = -EI * Ob * Ob * tt + Sb * e3
    L[9] = EI * Ob * On * tt - Sn * e3
    if use_k:
        y0 = H[0] - Hold[0]
        y3 = H[3] - Hold[3]
        y4 = H[4] - Hold[4]
        y5 = H[5] - Hold[5]
        y6 = H[6] - Hold[6]
        y7 = H[7] - Hold[7]
        g[0] = m * y3 - m * vn * ct * y6 + m * vb * y7
        g[1] = (m + ma) * y4 + mr * (vt * ct + vb * st) * y6
        g[2] = (m + ma) * y5 - mr * vn * st * y6 - mr * vt * y7
        g[3] = y0 / EA
        g[4] = e1 * ct * y6
        g[5] = -e1 * y7
        for i in range(6, NV):
            g[i] = 0.0 * y0
    else:
        for i in range(NV):
            g[i] = 0.0 * T


@njit(cache=True)
def k_matrix(H, P, K):
    """K(H) (Eq 12, re-derived from Eq 2 and 4): coefficient of H_dot in row i."""
    m, ma, mr, EA = P[P_M], P[P_MA], P[P_MR], P[P_EA]
    vt, vn, vb, th = H[3], H[4], H[5], H[7]
    ct, st = math.cos(th), math.sin(th)
    e1 = 1.0 + H[0] / EA
    K[:, :] = 0.0
    K[0, 3] = m
    K[0, 6] = -m * vn * ct  # Eq 12 K(1,7)
    K[0, 7] = m * vb  # Eq 12 "K(1,8) = m w": w is vb
    K[1, 4] = m + ma
    K[1, 6] = mr * (vt * ct + vb * st)
    K[2, 5] = m + ma
    K[2, 6] = -mr * vn * st
    K[2, 7] = -mr * vt  # Eq 12 "K(3,8) = -m u": u is vt
    K[3, 0] = 1.0 / EA
    K[4, 6] = e1 * ct
    K[5, 7] = -e1


@njit(cache=True)
def k_matrices(H, P):
    """K at every node, (n, 10, 10)."""
    n = H.shape[0]
    K = np.empty((n, NV, NV))
    for j in range(n):
        k_matrix(H[j], P, K[j])
    return K


@njit(cache=True, inline="always")
def _load_node(H, j, Hc):
    """Hc = H[j] (into a complex buffer, for the complex-step derivatives)."""
    for i in range(NV):
        Hc[i] = H[j, i]


@njit(cache=True)
def linearise_nodes(H, Hold, P, cur, use_k, Lv, gv, dL, dg):
    """Per node: L, g and their exact Jacobians d/dH by complex step: perturbing unknown
    k by i CSTEP gives d/dH_k = imaginary part / CSTEP, exact to rounding."""
    n = H.shape[0]
    Hc = np.empty(NV, np.complex128)
    Ho = np.empty(NV, np.complex128)
    Lc = np.empty(NV, np.complex128)
    gc = np.empty(NV, np.complex128)
    for j in range(n):
        _load_node(Hold, j, Ho)
        for k in range(NV):
            _load_node(H, j, Hc)
            Hc[k] += 1j * CSTEP
            node_terms(Hc, Ho, P, cur[j], use_k, Lc, gc)
            for i in range(NV):
                dL[j, i, k] = Lc[i].imag / CSTEP
                dg[j, i, k] = gc[i].imag / CSTEP
        for i in range(NV):
            Lv[j, i] = Lc[i].real
            gv[j, i] = gc[i].real


@njit(cache=True)
def node_values(H, P, cur, Lv):
    """L at every node (real), for the old-level part of the box scheme."""
    n = H.shape[0]
    Hc = np.empty(NV, np.complex128)
    Lc = np.empty(NV, np.complex128)
    gc = np.empty(NV, np.complex128)
    for j in range(n):
        _load_node(H, j, Hc)
        node_terms(Hc, Hc, P, cur[j], False, Lc, gc)
        for i in range(NV):
            Lv[j, i] = Lc[i].real


@njit(cache=True, inline="always")
def _jbar_diag(i, ca, cb, EI):
    """Row i of the diagonal J_bar of a cell, J = diag(1,1,1,1,1,1,cos theta,1,EI,EI) (Eq 11)
    with cos theta averaged over the two nodes (ca, cb)."""
    if i == 6:
        return 0.5 * (ca + cb)
    if i >= 8:
        return EI
    return 1.0


@njit(cache=True, inline="always")
def _cell_balance(i, x, ca, cb, EI, ds, La, Lb):
    """Row i of J_bar dH/ds - L_bar over a cell (Eq 13): x = H_b - H_a of unknown i, La, Lb
    = row i of L at the two nodes."""
    return _jbar_diag(i, ca, cb, EI) * x / ds - 0.5 * (La + Lb)


@njit(cache=True)
def old_level(Ho, P, cur, ds, alpha):
    """Old-level part of each cell equation: (1-alpha) [J_bar dH/ds - L_bar]_old (Eq 13)."""
    n = Ho.shape[0]
    Lo = np.empty((n, NV))
    node_values(Ho, P, cur, Lo)
    C = np.zeros((n - 1, NV))
    EI = P[P_EI]
    for j in range(n - 1):
        ca, cb = math.cos(Ho[j, 7]), math.cos(Ho[j + 1, 7])
        for i in range(NV):
            C[j, i] = (1.0 - alpha) * _cell_balance(i, Ho[j + 1, i] - Ho[j, i], ca, cb, EI, ds,
                                                    Lo[j, i], Lo[j + 1, i])
    return C


@njit(cache=True)
def assemble(H, Ho, Ko, Cold, P, cur, vtop, ds, dt, alpha, dynamic, A, D, C, r):
    """Residual Phi (Eq 13 + BC Eq 14-15) and its Jacobian (Eq 21) in block tri-diagonal form.

    Cell equation (Eq 13 divided by 4; alpha = 1/2 is the paper's centred scheme):
      Phi = alpha [J_bar dH/ds - L_bar]_new + (1-alpha) [...]_old
            - sum_{a,b} [alpha K + (1-alpha) K_old] (H - H_old) / (2 dt)
    dynamic = False: the steady equations (no time terms, one level).
    Block row k: rows 0-4 = cell k-1 rows ROWS_X (bottom BC for k = 0), rows 5-9 = cell k rows
    ROWS_Y (top BC for k = n-1). A[k] = d/dH[k-1], D[k] = d/dH[k], C[k] = d/dH[k+1].
    r = -Phi in the same row order. Returns max |Phi|.
    """
    n = H.shape[0]
    EI = P[P_EI]
    Lv = np.empty((n, NV))
    gv = np.empty((n, NV))
    dL = np.empty((n, NV, NV))
    dg = np.empty((n, NV, NV))
    linearise_nodes(H, Ho, P, cur, dynamic, Lv, gv, dL, dg)
    A[:, :, :] = 0.0
    D[:, :, :] = 0.0
    C[:, :, :] = 0.0
    a = alpha if dynamic else 1.0
    ka = 1.0 / (2.0 * dt) if dynamic else 0.0
    Phi = np.empty(NV)
    Ja = np.empty((NV, NV))
    Jb = np.empty((NV, NV))
    x = np.empty(NV)
    resmax = 0.0
    for j in range(n - 1):
        for i in range(NV):
            x[i] = H[j + 1, i] - H[j, i]
        ca, cb = math.cos(H[j, 7]), math.cos(H[j + 1, 7])
        for i in range(NV):
            v = a * _cell_balance(i, x[i], ca, cb, EI, ds, Lv[j, i], Lv[j + 1, i])
            if dynamic:
                v += Cold[j, i]
                v -= ka * (a * (gv[j, i] + gv[j + 1, i])
                           + (1.0 - a) * _kdot(Ko, j, i, H, Ho)
                           + (1.0 - a) * _kdot(Ko, j + 1, i, H, Ho))
            Phi[i] = v
            if abs(v) > resmax:
                resmax = abs(v)
        # d Phi / d H_a (Ja) and d Phi / d H_b (Jb)
        for i in range(NV):
            jd = _jbar_diag(i, ca, cb, EI)
            for k in range(NV):
                va = -0.5 * a * dL[j, i, k]
                vb = -0.5 * a * dL[j + 1, i, k]
                if dynamic:
                    va -= ka * (a * dg[j, i, k] + (1.0 - a) * Ko[j, i, k])
                    vb -= ka * (a * dg[j + 1, i, k] + (1.0 - a) * Ko[j + 1, i, k])
                Ja[i, k] = va
                Jb[i, k] = vb
            Ja[i, i] -= a * jd / ds
            Jb[i, i] += a * jd / ds
        # J(7,7) = cos theta depends on theta at both nodes
        Ja[6, 7] += a * (-0.5 * math.sin(H[j, 7]) * x[6]) / ds
        Jb[6, 7] += a * (-0.5 * math.sin(H[j + 1, 7]) * x[6]) / ds
        # scatter: rows Y -> block row j (rows 5-9), rows X -> block row j+1 (rows 0-4)
        for q in range(5):
            iy = ROWS_Y[q]
            ix = ROWS_X[q]
            for k in range(NV):
                D[j, 5 + q, k] = Ja[iy, k]
                C[j, 5 + q, k] = Jb[iy, k]
                A[j + 1, q, k] = Ja[ix, k]
                D[j + 1, q, k] = Jb[ix, k]
            r[j, 5 + q] = -Phi[iy]
            r[j + 1, q] = -Phi[ix]
    # Eq 14, free end (s = 0): T = EI On = EI Ob = 0; EI On' = EI Ob' = 0 <=> Sb = Sn = 0 (Eq 3)
    bc = (0, 1, 2, 8, 9)
    for q in range(5):
        k = bc[q]
        D[0, q, k] = 1.0
        r[0, q] = -H[0, k]
        if abs(H[0, k]) > resmax:
            resmax = abs(H[0, k])
    # Eq 15, towing point (s = L): cable velocity = ship velocity (local components), On = Ob = 0
    m = n - 1
    ph, th = H[m, 6], H[m, 7]
    cp, sp, ct, st = math.cos(ph), math.sin(ph), math.cos(th), math.sin(th)
    U, V, W = vtop[0], vtop[1], vtop[2]
    ut = U * ct * cp + V * ct * sp - W * st
    un = -U * sp + V * cp
    ub = U * st * cp + V * st * sp + W * ct
    bres = (H[m, 3] - ut, H[m, 4] - un, H[m, 5] - ub, H[m, 8], H[m, 9])
    for q in range(5):
        r[m, 5 + q] = -bres[q]
        if abs(bres[q]) > resmax:
            resmax = abs(bres[q])
    D[m, 5, 3] = 1.0
    D[m, 5, 6] = -(-U * ct * sp + V * ct * cp)
    D[m, 5, 7] = -(-U * st * cp - V * st * sp - W * ct)
    D[m, 6, 4] = 1.0
    D[m, 6, 6] = -(-U * cp - V * sp)
    D[m, 7, 5] = 1.0
    D[m, 7, 6] = -(-U * st * sp + V * st * cp)
    D[m, 7, 7] = -(U * ct * cp + V * ct * sp - W * st)
    D[m, 8, 8] = 1.0
    D[m, 9, 9] = 1.0
    return resmax


@njit(cache=True)
def _kdot(Ko, j, i, H, Ho):
    s = 0.0
    for k in range(NV):
        s += Ko[j, i, k] * (H[j, k] - Ho[j, k])
    return s


# ----------------------------------------------------------------- block tri-diagonal solve
@njit(cache=True)
def block_tridiag_solve(A, D, C, r):
    """Solve the block tri-diagonal system (Fig. 2): A[k] x[k-1] + D[k] x[k] + C[k] x[k+1] = r[k].

    Block Thomas elimination (Numerical Recipes' approach, ref [14]) with partial pivoting
    inside each 10x10 block (sim_math.linalg): O(n) instead of the O(n^3) of a dense solve.
    Inputs are not modified. Returns x (n, m); raises ValueError on a singular or non-finite
    diagonal block.
    """
    n, m = r.shape
    X = np.empty((n, m, m))  # D'^-1 C
    y = np.empty((n, m))
    Dp = np.empty((m, m))
    rhs = np.empty((m, m + 1))
    piv = np.empty(m, np.int64)
    for k in range(n):
        for i in range(m):
            for l in range(m):
                Dp[i, l] = D[k, i, l]
            rhs[i, m] = r[k, i]
            for l in range(m):
                rhs[i, l] = C[k, i, l] if k < n - 1 else 0.0
        if k > 0:
            # D' = D - A X[k-1];  r' = r - A y[k-1]
            for i in range(m):
                for l in range(m):
                    aij = A[k, i, l]
                    if aij != 0.0:
                        for c in range(m):
                            Dp[i, c] -= aij * X[k - 1, l, c]
                        rhs[i, m] -= aij * y[k - 1, l]
        if not lu_factor(Dp, piv):
            raise ValueError("block tri-diagonal solve: singular diagonal block")
        lu_solve_columns(Dp, piv, rhs, m + 1)
        for i in range(m):
            for l in range(m):
                X[k, i, l] = rhs[i, l]
            y[k, i] = rhs[i, m]
    x = np.empty((n, m))
    for i in range(m):
        x[n - 1, i] = y[n - 1, i]
    for k in range(n - 2, -1, -1):
        for i in range(m):
            s = y[k, i]
            for l in range(m):
                s -= X[k, i, l] * x[k + 1, l]
            x[k, i] = s
    return x


def blocks_to_dense(A, D, C):
    """The same Jacobian as a dense (10n x 10n) matrix (tests and the benchmark)."""
    n, m, _ = D.shape
    M = np.zeros((n * m, n * m))
    for k in range(n):
        M[k * m:(k + 1) * m, k * m:(k + 1) * m] = D[k]
        if k > 0:
            M[k * m:(k + 1) * m, (k - 1) * m:k * m] = A[k]
        if k < n - 1:
            M[k * m:(k + 1) * m, (k + 1) * m:(k + 2) * m] = C[k]
    return M


# ------------------------------------------------------------------ node positions, environment
@njit(cache=True)
def node_positions(H, R, ea, ds, top, out):
    """World positions of the nodes into out (n, 3), index 0 = the towing point `top`:
    integrated from it along the stretched tangent (1 + T/EA) t by the trapezoid rule (H in the
    paper's order, index 0 = the free end; R: world = R @ paper). FdCable.positions, compiled
    because the rope node needs them every step (outputs, environment)."""
    n = H.shape[0]
    sx = sy = sz = 0.0
    dx1 = dy1 = dz1 = 0.0
    for k in range(n - 1, -1, -1):
        e1 = 1.0 + H[k, H_T] / ea
        ph, th = H[k, H_PHI], H[k, H_THETA]
        cp, sp, ct, st = math.cos(ph), math.sin(ph), math.cos(th), math.sin(th)
        t0, t1, t2 = ct * cp, ct * sp, -st
        dx = e1 * (R[0, 0] * t0 + R[0, 1] * t1 + R[0, 2] * t2)
        dy = e1 * (R[1, 0] * t0 + R[1, 1] * t1 + R[1, 2] * t2)
        dz = e1 * (R[2, 0] * t0 + R[2, 1] * t1 + R[2, 2] * t2)
        if k < n - 1:
            sx += 0.5 * ds * (dx + dx1)
            sy += 0.5 * ds * (dy + dy1)
            sz += 0.5 * ds * (dz + dz1)
        out[n - 1 - k, 0] = top[0] - sx
        out[n - 1 - k, 1] = top[1] - sy
        out[n - 1 - k, 2] = top[2] - sz
        dx1, dy1, dz1 = dx, dy, dz


@njit(cache=True)
def sample_waves(positions, env, t, out):
    """The waves of the sea packed in env (sampler.P_WAVE_AT) at the nodes at time t into out
    (n, 6): the particles' velocity and acceleration, world ENU (Airy, Wheeler-stretched, zero
    in the air: the towed cable is a submerged model, a node above the surface feels none).
    Returns False (out untouched) on a calm sea."""
    at = wave_offset(env)
    if at == 0:
        return False
    for i in range(positions.shape[0]):
        _eta, u, v, w, ax, ay, az, _p = wave_kinematics(env, at, positions[i, 0], positions[i, 1],
                                                        positions[i, 2], t)
        out[i, 0], out[i, 1], out[i, 2], out[i, 3], out[i, 4], out[i, 5] = u, v, w, ax, ay, az
    return True


@njit(cache=True)
def sample_environment(positions, env):
    """The environment (env: a sea_environment.sampler.EnvironmentSampler's data, at its time)
    at the nodes, as CableAdapter.set_environment takes it: (mean current east, north over the
    nodes; the first node below the seabed, -1 for none; the depth there)."""
    n = positions.shape[0]
    tide = tidal_factor(env, env[P_TIME])
    sx = sy = 0.0
    for i in range(n):
        cx, cy = current_xy_at(env, tide, positions[i, 0], positions[i, 1])
        sx += cx
        sy += cy
    shallowest_bed_z = -env[P_DEPTH_MIN]
    for i in range(n):
        z = positions[i, 2]
        if z < shallowest_bed_z:
            h = depth_at(env, positions[i, 0], positions[i, 1])
            if z < -h:
                return sx / n, sy / n, i, h
    return sx / n, sy / n, -1, math.inf
