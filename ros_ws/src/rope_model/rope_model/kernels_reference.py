"""Plain numpy transcription of kernels.run_substeps: a slow test oracle, not used by the
simulator.

Same model and integrator as the compiled kernel (Yoon, Lee, Park, Kim, "Dynamic Modeling
and Simulation of a Towing Rope using Multiple Finite Element Method", 2012, Eq 1-26; see
kernels.py for the state layout), written with vectors and small matrices the way the paper
and the kernel's comments state it, and without the kernel's performance devices: the
whole linearly implicit theta-method system

    (M - h theta C - h^2 theta^2 K) dnu = h f + h^2 theta K nu + attachment terms

is assembled as one dense (5N x 5N) matrix and solved by numpy.linalg.solve instead of the
block Thomas elimination. nu = (V, W.b1, W.b2) per element (5 DOF, Eq 2). Results agree with
the kernel to round-off (tests/physics/test_rope_kernel_reference.py).
"""
import math

import numpy as np

from . import kernels as K

_GX = (-0.8611363115940526, -0.3399810435848563, 0.3399810435848563, 0.8611363115940526)
_GW = (0.1739274225687269, 0.3260725774312731, 0.3260725774312731, 0.1739274225687269)
_I3 = np.eye(3)
_I2 = np.eye(2)


class _Params:
    """The scalar parameters of io (kernels.P_*) as attributes."""

    def __init__(self, io, h):
        for name in ("MU", "RADIUS", "EA", "CD", "CF", "TFAC", "CA", "RHO_W", "RHO_A", "G",
                     "Z_AX", "Z_TR", "Z_ROT", "P_ROT", "RELAX", "THETA", "VMAX", "WMAX",
                     "PMAX"):
            setattr(self, name.lower(), float(io[getattr(K, "P_" + name)]))
        self.current = io[K.IO_CUR].copy()
        self.D = 2.0 * self.radius
        self.h = h
        self.hth = h * self.theta


def immersion(z, ez, half_len, r):
    """Immersed fraction f, df/dz and the first moment m1 of an element (kernels.immersion):
    buoyancy of Eq (12) distributed over 4 Gauss points along the axis."""
    rs = r * math.sqrt(max(0.0, 1.0 - ez * ez))
    reach = half_len * abs(ez)
    if z - reach >= rs + reach:
        return 0.0, 0.0, 0.0
    if z + reach <= -(rs + reach):
        return 1.0, 0.0, sum(w * half_len * x for w, x in zip(_GW, _GX))
    f = df = m1 = 0.0
    for x, w in zip(_GX, _GW):
        s = half_len * x
        zc, R = z + s * ez, rs + w * reach
        if zc >= R:
            fk, dk = 0.0, 0.0
        elif zc <= -R:
            fk, dk = 1.0, 0.0
        else:
            zz = zc / R
            q = math.sqrt(max(0.0, 1.0 - zz * zz))
            fk, dk = (math.acos(zz) - zz * q) / math.pi, -2.0 * q / (math.pi * R)
        f += w * fk
        df += w * dk
        m1 += w * fk * s
    return f, df, m1


def basis(e):
    """b1, b2 completing e to a right-handed orthonormal basis (b1 from z, or x when e is
    near vertical)."""
    helper = np.array([0.0, 0.0, 1.0]) if abs(e[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    b1 = helper - (helper @ e) * e
    b1 /= np.linalg.norm(b1)
    return b1, np.cross(e, b1)


def point_jacobian(s, b1, b2):
    """J of a point at lever s on the axis: dP = J dnu, J = [I | -s b2 | s b1] (3 x 5)."""
    return np.hstack([_I3, -s * b2[:, None], s * b1[:, None]])


# ------------------------------------------------------------------ element, Eq (1)-(14)
def element_terms(x, e, v, w, l, b1, b2, P):
    """Generalised mass M, velocity Jacobian C and force f (5 DOF) of one element."""
    fr, dfr, m1 = immersion(x[2], e[2], 0.5 * l, P.radius)
    m = P.mu * l
    vol = math.pi * P.radius ** 2 * l
    ma = P.ca * P.rho_w * vol * fr  # Eq (9), m_y = m_z, m_x ~ 0
    rot = (l * l + 3.0 * P.radius ** 2) / 12.0
    Ip = m * rot + ma * rot  # I_y + J_y, Eq (4), (9)
    Mt = (m + ma) * _I3 - ma * np.outer(e, e)  # Eq (3) in world axes
    F = np.array([0.0, 0.0, -m * P.g + P.rho_w * vol * P.g * fr])  # Eq (13), (12)
    tq = P.rho_w * vol * P.g * m1 * np.cross(e, [0.0, 0.0, 1.0])  # buoyancy along the axis
    Ct = np.zeros((3, 3))
    crot = 0.0
    for rho, r in ((P.rho_w * fr, v - P.current), (P.rho_a * (1.0 - fr), v)):  # Eq (10)
        if rho <= 0.0:
            continue
        u = r @ e
        rn = r - u * e
        sn = np.linalg.norm(rn)
        cn = 0.5 * rho * P.D * l * P.cd
        ct = 0.5 * rho * P.D * l * P.cf * P.tfac
        F += -cn * sn * rn - ct * abs(u) * u * e
        Ct += (-cn * sn * (_I3 - np.outer(e, e)) - 2.0 * ct * abs(u) * np.outer(e, e)
               - (cn / sn if sn > 1e-12 else 0.0) * np.outer(rn, rn))
    r = v - P.current
    ue = r @ e
    edot = np.cross(w, e)
    F += ma * (edot * ue + e * (r @ edot))  # fluid Coriolis C_A, Eq (8)
    tq += ma * ue * np.cross(r, e)  # Munk moment, Eq (8)
    mdot = P.ca * P.rho_w * vol * dfr * v[2]
    if mdot > 0.0:  # water entry, Eq (14)
        F += -mdot * (r - ue * e)
        Ct += -mdot * (_I3 - np.outer(e, e))
        tq += -mdot * rot * w
        crot += -mdot * rot
    if P.relax > 0.0:  # numerical relaxation -relax M nu
        F += -P.relax * (Mt @ v)
        Ct += -P.relax * Mt
        tq += -P.relax * Ip * w
        crot += -P.relax * Ip
    M = np.zeros((5, 5))
    C = np.zeros((5, 5))
    M[:3, :3], M[3:, 3:] = Mt, Ip * _I2
    C[:3, :3], C[3:, 3:] = Ct, crot * _I2
    return M, C, np.concatenate([F, [tq @ b1, tq @ b2]])


# ------------------------------------------------------------------ connections, Eq (15)-(26)
def connection_constants(L, P):
    """Per connection: spring k = EA / represented length, dampers c_x, c_t (Eq 16-17) and
    bending damper c_m (Eq 19, with I_y of Eq 4)."""
    N = len(L)
    Iy = [P.mu * l * ((l * l + 3.0 * P.radius ** 2) / 12.0) for l in L]
    out = []
    for c in range(N + 1):
        near = [L[j] for j in (c - 1, c) if 0 <= j < N]
        k = P.ea / sum(0.5 * l for l in near)
        skm = math.sqrt(k * sum(P.mu * l for l in near) / len(near))
        cm = 2.0 * P.z_rot * math.sqrt(P.p_rot * 0.5 * (Iy[c - 1] + Iy[c])) if 0 < c < N else 0.0
        out.append((k, 2.0 * P.z_ax * skm, 2.0 * P.z_tr * skm, cm))
    return out


def connection_points(c, X, E, V, W, L, io, t, payout_a):
    """Prev point (aft of element c - 1 or attachment a) and next point (front of element
    c or attachment b), Eq (20): positions, velocities, levers, and g = J nu of the next
    relative to the prev point (the drum's pay-out sliding excluded)."""
    N = len(L)
    if c > 0:
        si = -0.5 * L[c - 1]
        Pp, Vp = X[c - 1] + si * E[c - 1], V[c - 1] + np.cross(W[c - 1], si * E[c - 1])
    else:
        si, Vp = 0.0, io[K.IO_VEL].copy()
        Pp = io[K.IO_POS] + Vp * t
    if c < N:
        sk = 0.5 * L[c]
        Pn, Vn = X[c] + sk * E[c], V[c] + np.cross(W[c], sk * E[c])
    else:
        sk, Vn = 0.0, io[K.IO_VEL + 1].copy()
        Pn = io[K.IO_POS + 1] + Vn * t
    if c > 0:
        g = Vn - Vp
    else:  # winch: rope slides through the drum, element 0's drum end moves with it
        g = Vn - (Vp - payout_a * E[0])
        Vn = Vn + payout_a * E[0]
        Pn = Pn + payout_a * t * E[0]
    return Pp, Vp, si, Pn, Vn, sk, g


def connection_force(c, Pp, Vp, Pn, Vn, E, consts):
    """Tension-only spring-damper force on the next point (Eq 15-17, 21-22, slack switch of
    Eq 25 in continuous form), the rope axis n and the axial damping it carries."""
    N = len(E)
    n = sum(E[j] for j in (c - 1, c) if 0 <= j < N)
    if np.linalg.norm(n) < 1e-9:  # folded back on itself: gap direction
        n = (Pp - Pn) / (np.linalg.norm(Pp - Pn) + 1e-300)
    else:
        n = n / np.linalg.norm(n)
    k, cx, ct, _ = consts[c]
    dv = Vp - Vn
    F = k * (Pp - Pn) + cx * n * (n @ dv) + ct * (dv - n * (n @ dv))
    cx_eff = cx
    if F @ n < 0.0:  # a rope cannot push
        F = F - (F @ n) * n
        cx_eff = 0.0
    return F, n, cx_eff


# ------------------------------------------------------------------ one sub-step
def _evaluate(S, F, io, consts, t, payout_a, full, P, A, b, B):
    """One pass over the connections (and, if full, the elements into A, b): tensions, end
    forces, the best parting candidate (c, T, elastic part) or None."""
    N = S.shape[0] - 1
    X, E, V, W, L = (S[:N, K.SX:K.SX + 3], S[:N, K.SE:K.SE + 3], S[:N, K.SV:K.SV + 3],
                     S[:N, K.SW:K.SW + 3], S[:N, K.SL])
    io[K.IO_FORCE:K.IO_FORCE + 2] = 0.0
    if full:
        A[:] = 0.0
        b[:] = 0.0
        for j in range(N):
            B[j] = basis(E[j])
            M, C, f = element_terms(X[j], E[j], V[j], W[j], L[j], B[j][0], B[j][1], P)
            A[5 * j:5 * j + 5, 5 * j:5 * j + 5] = M - P.hth * C
            b[5 * j:5 * j + 5] = P.h * f
    best, best_ratio = None, 1.0
    att = io[K.IO_ATT, 1] != 0.0, io[K.IO_ATT, 2] != 0.0
    for c in range(N + 1):
        S[c, K.ST] = 0.0
        if not (F[c, K.F_OK] and (c > 0 or att[0]) and (c < N or att[1])):
            continue
        Pp, Vp, si, Pn, Vn, sk, g = connection_points(c, X, E, V, W, L, io, t, payout_a)
        Fc, n, cx_eff = connection_force(c, Pp, Vp, Pn, Vn, E, consts)
        T = float(np.linalg.norm(Fc))
        if T > S[c, K.SB]:
            if F[c, K.F_ARMED] and T / S[c, K.SB] > best_ratio:
                best_ratio = T / S[c, K.SB]
                best = (c, T, consts[c][0] * ((Pp - Pn) @ n))
        else:
            F[c, K.F_ARMED] = 1
        S[c, K.ST] = T
        if c == N:
            io[K.IO_FORCE + 1] = Fc
        if c == 0:
            io[K.IO_FORCE] = -Fc
        if full:
            _add_connection(c, Fc, n, cx_eff, si, sk, g, consts[c], E, W, L, B, P, A, b)
    return best


def _add_connection(c, Fc, n, cx_eff, si, sk, g, const, E, W, L, B, P, A, b):
    """Terms of connection c in the system: spring and dampers J^T (h F - h^2 theta k g)
    and J^T S J with S = h theta (c_x n n^T + c_t (I - n n^T)) + h^2 theta^2 k I, the
    geometric stiffness of the end moment and the bending damper (Eq 18-19)."""
    N = len(L)
    k, _, ct, cm = const
    h, hth, theta = P.h, P.hth, P.theta
    h2t = h * h * theta
    Ssp = (hth * ct + hth * hth * k) * _I3 + hth * (cx_eff - ct) * np.outer(n, n)
    Q = h * Fc - h2t * k * g
    ends = []  # (element, lever, sign of the force on it)
    if c < N:
        ends.append((c, sk, 1.0))
    if c > 0:
        ends.append((c - 1, si, -1.0))
    if c > 0 and c < N and cm > 0.0:
        i, kk = c - 1, c
        Bi, Bk = np.column_stack(B[i]), np.column_stack(B[kk])
        dw = W[i] - W[kk]
        b[5 * kk + 3:5 * kk + 5] += h * cm * (Bk.T @ dw)
        b[5 * i + 3:5 * i + 5] -= h * cm * (Bi.T @ dw)
        for j in (i, kk):
            A[5 * j + 3:5 * j + 5, 5 * j + 3:5 * j + 5] += hth * cm * _I2
        A[5 * i + 3:5 * i + 5, 5 * kk + 3:5 * kk + 5] += -hth * cm * (Bi.T @ Bk)
        A[5 * kk + 3:5 * kk + 5, 5 * i + 3:5 * i + 5] += -hth * cm * (Bk.T @ Bi)
    J = {}
    for j, s, sg in ends:
        J[j] = point_jacobian(s, *B[j])
        geo = -0.5 * L[j] * (Fc @ E[j])  # moment of the end force: -l/2 F.e on both rotations
        b[5 * j:5 * j + 5] += sg * (J[j].T @ Q)
        b[5 * j + 3:5 * j + 5] += h2t * geo * (np.column_stack(B[j]).T @ W[j])
        A[5 * j:5 * j + 5, 5 * j:5 * j + 5] += J[j].T @ Ssp @ J[j]
        A[5 * j + 3:5 * j + 5, 5 * j + 3:5 * j + 5] -= hth * hth * geo * _I2
    if c > 0 and c < N:
        i, kk = c - 1, c
        A[5 * i:5 * i + 5, 5 * kk:5 * kk + 5] -= J[i].T @ Ssp @ J[kk]
        A[5 * kk:5 * kk + 5, 5 * i:5 * i + 5] -= J[kk].T @ Ssp @ J[i]


def _rotate(x, axis, angle):
    """Rodrigues' rotation of x about the unit axis."""
    return (x * math.cos(angle) + np.cross(axis, x) * math.sin(angle)
            + axis * (axis @ x) * (1.0 - math.cos(angle)))


def _advance(S, dnu, B, P):
    """Theta-method update of every element (Eq 5-6 with the axis vector); returns the
    lowest element with a non-finite or absurd state, or -1."""
    N = S.shape[0] - 1
    bad = -1
    for j in range(N - 1, -1, -1):
        V0, W0, e = S[j, K.SV:K.SV + 3].copy(), S[j, K.SW:K.SW + 3].copy(), S[j, K.SE:K.SE + 3]
        V1 = V0 + dnu[5 * j:5 * j + 3]
        W1 = W0 + dnu[5 * j + 3] * B[j][0] + dnu[5 * j + 4] * B[j][1]
        S[j, K.SX:K.SX + 3] += P.h * ((1.0 - P.theta) * V0 + P.theta * V1)
        S[j, K.SV:K.SV + 3] = V1
        phi = P.h * ((1.0 - P.theta) * W0 + P.theta * W1)
        ang = np.linalg.norm(phi)
        if ang >= 1e-300:
            e = _rotate(e, phi / ang, ang)
            W1 = _rotate(W1, phi / ang, ang)
        e = e / np.linalg.norm(e)
        S[j, K.SE:K.SE + 3] = e
        S[j, K.SW:K.SW + 3] = W1 - (W1 @ e) * e
        Wj, Xj = S[j, K.SW:K.SW + 3], S[j, K.SX:K.SX + 3]
        if not (V1 @ V1 <= P.vmax ** 2 and Wj @ Wj <= P.wmax ** 2 and Xj @ Xj <= P.pmax ** 2
                and e @ e <= 2.0):
            bad = j
    return bad


def run_substeps(S, F, io, h, n_sub, payout_a, dt):
    """kernels.run_substeps without the work space: same arguments otherwise, same effect
    on S, F and io, same status. Returns (status, dnu of the last sub-step or None)."""
    N = S.shape[0] - 1
    P = _Params(io, h)
    saved = S.copy(), F.copy(), io[K.IO_FORCE:K.IO_FORCE + 2].copy()
    io[K.IO_IMPULSE:K.IO_IMPULSE + 2] = 0.0
    nev0 = io[K.IO_NEV]
    io[K.IO_DIAG, 0] = -1.0
    consts = connection_constants(S[:N, K.SL].copy(), P)
    A = np.zeros((5 * N, 5 * N))
    b = np.zeros(5 * N)
    B = [None] * N
    dnu = None
    for step in range(n_sub + 1):
        t = step * h
        full = step < n_sub
        bad = -1
        for _ in range(N + 2):  # re-evaluated after each parting
            best = _evaluate(S, F, io, consts, t, payout_a, full, P, A, b, B)
            if best is None:
                break
            c, T, el = best
            if el < K.PART_MIN_ELASTIC * S[c, K.SB]:  # a blow-up, not a parting
                io[K.IO_DIAG] = c, T, el
                bad = max(0, min(c, N - 1))
                break
            F[c, K.F_OK] = 0  # parts; the others above their breaking load are disarmed
            ne = int(io[K.IO_NEV])
            if ne < K.N_EVENTS_MAX:
                io[K.IO_EVENTS + ne] = t, c, T
            io[K.IO_NEV] = ne + 1
            F[S[:, K.ST] > S[:, K.SB], K.F_ARMED] = 0
        w8 = 0.5 * h if step in (0, n_sub) else h
        io[K.IO_IMPULSE:K.IO_IMPULSE + 2] += w8 * io[K.IO_FORCE:K.IO_FORCE + 2]
        if not full and bad < 0:
            break
        if bad < 0:
            try:
                dnu = np.linalg.solve(A, b)
            except np.linalg.LinAlgError:
                bad = 0
        if bad < 0:
            bad = _advance(S, dnu, B, P)
        if bad >= 0:
            io[K.IO_INFO, 0:2] = step, bad
            S[:N, :K.SL], F[:], io[K.IO_FORCE:K.IO_FORCE + 2] = (saved[0][:N, :K.SL], saved[1],
                                                                 saved[2])
            S[:, K.ST] = saved[0][:, K.ST]
            io[K.IO_NEV] = nev0
            return K.DIVERGED, None
    if dt > 0.0:
        io[K.IO_MEAN:K.IO_MEAN + 2] = io[K.IO_IMPULSE:K.IO_IMPULSE + 2] / dt
        io[K.IO_POS:K.IO_POS + 2] += io[K.IO_VEL:K.IO_VEL + 2] * dt
    return (K.PARTED if io[K.IO_NEV] > nev0 else K.OK), dnu
