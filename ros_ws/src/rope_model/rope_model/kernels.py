"""Numba kernels of the element-chain rope (seed 000, Eq 1-26).

State per element j (world frame ENU, z up, water surface z = 0):
  X[j]  centre of mass (R of Eq 5)            V[j]  its velocity
  E[j]  unit axis = body x, pointing to end a  W[j]  angular velocity, kept perpendicular to E
The paper's 5 DOF (u, v, w, q, r) are (V, W) seen in the yaw-pitch body frame; storing
the axis vector instead of (theta, psi) removes the 1/cos(theta) singularity of Eq (6)
for hanging (vertical) elements. Generalised velocity per element for the implicit
solve: nu = (V, W.b1, W.b2) with (E, b1, b2) a right-handed basis: 5 DOF as in Eq (2).

Connections c = 0..N: c joins the aft point of element c-1 (or attachment a when c = 0)
to the front point of element c (or attachment b when c = N).

Integrator: linearly implicit theta-method (theta = 1/2: trapezoidal / Newmark average
acceleration) with the exact Jacobian of the connection springs (incl. geometric
stiffness), of the connection dampers, of drag and of the water-entry term; the system is
block tri-diagonal (5x5 blocks) and solved in O(N) by block Thomas elimination.
"""
import math

from numba import njit

# status codes returned by run_substeps
OK = 0
STRICT_EQ25 = False  # compile-time switch, see evaluate()
DIVERGED = 1


@njit(cache=True)
def _segment(z, R):
    """Submerged fraction of a circle of radius R centred at height z (water at 0), d/dz."""
    if z >= R:
        return 0.0, 0.0
    if z <= -R:
        return 1.0, 0.0
    zz = z / R
    s = math.sqrt(max(0.0, 1.0 - zz * zz))
    return (math.acos(zz) - zz * s) / math.pi, -2.0 * s / (math.pi * R)


# 4-point Gauss-Legendre rule along the element axis
_GX = (-0.8611363115940526, -0.3399810435848563, 0.3399810435848563, 0.8611363115940526)
_GW = (0.1739274225687269, 0.3260725774312731, 0.3260725774312731, 0.1739274225687269)


@njit(cache=True)
def immersion(z, ez, half_len, r):
    """Immersed fraction f of an element (centre height z, axis z-component ez), df/dz and
    m1 = mean of f(s) * s along the axis (s from the centre, m).

    Eq (12) switches buoyancy on at 'Z <= 0'. Here it is distributed along the axis (4
    Gauss points, each a circle segment over the vertical half extent of the piece it stands
    for): smooth (C1) in z, and a half-immersed inclined element gets the righting moment
    rho Vol g m1 (e x z) that keeps the paper's floating elements level (section 4.3)."""
    rs = r * math.sqrt(max(0.0, 1.0 - ez * ez))
    f = 0.0
    df = 0.0
    m1 = 0.0
    for k in range(4):
        s = half_len * _GX[k]
        w = _GW[k]
        fk, dk = _segment(z + s * ez, rs + w * half_len * abs(ez))
        f += w * fk
        df += w * dk
        m1 += w * fk * s
    return f, df, m1


@njit(cache=True)
def basis(e, b1, b2):
    """Right-handed (e, b1, b2), deterministic; written into b1, b2."""
    if abs(e[2]) < 0.9:
        hx, hy, hz = 0.0, 0.0, 1.0
    else:
        hx, hy, hz = 1.0, 0.0, 0.0
    d = hx * e[0] + hy * e[1] + hz * e[2]
    b1[0] = hx - d * e[0]
    b1[1] = hy - d * e[1]
    b1[2] = hz - d * e[2]
    nb = math.sqrt(b1[0] ** 2 + b1[1] ** 2 + b1[2] ** 2)
    b1[0] /= nb
    b1[1] /= nb
    b1[2] /= nb
    b2[0] = e[1] * b1[2] - e[2] * b1[1]
    b2[1] = e[2] * b1[0] - e[0] * b1[2]
    b2[2] = e[0] * b1[1] - e[1] * b1[0]


@njit(cache=True)
def _cross(a, b, out):
    x = a[1] * b[2] - a[2] * b[1]
    y = a[2] * b[0] - a[0] * b[2]
    z = a[0] * b[1] - a[1] * b[0]
    out[0] = x
    out[1] = y
    out[2] = z


@njit(cache=True)
def _jac(J, s_half, b1, b2):
    """J (3x5): dP = J dq for the point P = X + s_half*E (s_half = +-l/2)."""
    for r in range(3):
        for c in range(3):
            J[r, c] = 1.0 if r == c else 0.0
        J[r, 3] = -s_half * b2[r]  # dE = a1*(-b2) + a2*b1
        J[r, 4] = s_half * b1[r]


@njit(cache=True)
def _add_pair(out, ha, b1a, b2a, hb, b1b, b2b, S, coef):
    """out (5x5) += coef * Ja^T S Jb for J = [I | h*(-b2) | h*b1] (see _jac), using the
    structure (about 45 multiply-adds instead of 120)."""
    # S g1b, S g2b with g1 = -h b2, g2 = h b1
    u0 = -hb * (S[0, 0] * b2b[0] + S[0, 1] * b2b[1] + S[0, 2] * b2b[2])
    u1 = -hb * (S[1, 0] * b2b[0] + S[1, 1] * b2b[1] + S[1, 2] * b2b[2])
    u2 = -hb * (S[2, 0] * b2b[0] + S[2, 1] * b2b[1] + S[2, 2] * b2b[2])
    w0 = hb * (S[0, 0] * b1b[0] + S[0, 1] * b1b[1] + S[0, 2] * b1b[2])
    w1 = hb * (S[1, 0] * b1b[0] + S[1, 1] * b1b[1] + S[1, 2] * b1b[2])
    w2 = hb * (S[2, 0] * b1b[0] + S[2, 1] * b1b[1] + S[2, 2] * b1b[2])
    for r in range(3):
        for c in range(3):
            out[r, c] += coef * S[r, c]
    out[0, 3] += coef * u0
    out[1, 3] += coef * u1
    out[2, 3] += coef * u2
    out[0, 4] += coef * w0
    out[1, 4] += coef * w1
    out[2, 4] += coef * w2
    for c in range(3):
        out[3, c] += -coef * ha * (b2a[0] * S[0, c] + b2a[1] * S[1, c] + b2a[2] * S[2, c])
        out[4, c] += coef * ha * (b1a[0] * S[0, c] + b1a[1] * S[1, c] + b1a[2] * S[2, c])
    out[3, 3] += -coef * ha * (b2a[0] * u0 + b2a[1] * u1 + b2a[2] * u2)
    out[3, 4] += -coef * ha * (b2a[0] * w0 + b2a[1] * w1 + b2a[2] * w2)
    out[4, 3] += coef * ha * (b1a[0] * u0 + b1a[1] * u1 + b1a[2] * u2)
    out[4, 4] += coef * ha * (b1a[0] * w0 + b1a[1] * w1 + b1a[2] * w2)


@njit(cache=True)
def _add_Jt_vec(out, J, F, coef):
    for r in range(5):
        acc = 0.0
        for k in range(3):
            acc += J[k, r] * F[k]
        out[r] += coef * acc


@njit(cache=True)
def evaluate(X, E, V, W, L, conn_ok, brk, armed, att_on, att_pos, att_vel,
             mu, radius, EA, Cd, Cf, tfac, Ca, rho_w, rho_a, g,
             z_ax, z_tr, z_rot, P_rot, cur, relax, h, theta, t, payout_a,
             f, Md, Kd, Ko, Cdd, Cdo, rhs_att, tension, end_force, events, n_events, B1, B2,
             need_jac, Iy, sv, sJ, S):
    """Forces f (N,5) at the current state, mass blocks Md, stiffness (Kd, Ko) and damping
    (Cdd, Cdo) Jacobian blocks (diagonal and upper off-diagonal), attachment terms,
    connection tensions and the forces on the two attachments. Parts the most overloaded
    armed connection (records (t, c, T) in events) and returns True if it did."""
    N = X.shape[0]
    pi = math.pi
    D = 2.0 * radius
    r2 = radius * radius
    f[:] = 0.0
    Md[:] = 0.0
    Kd[:] = 0.0
    Ko[:] = 0.0
    Cdd[:] = 0.0
    Cdo[:] = 0.0
    rhs_att[:] = 0.0
    tension[:] = 0.0
    end_force[:] = 0.0
    vr = sv[0]
    F = sv[1]
    tau = sv[2]
    vn = sv[3]
    edot = sv[4]
    vxe = sv[5]
    for j in range(N):
        l = L[j]
        e = E[j]
        b1 = B1[j]
        b2 = B2[j]
        basis(e, b1, b2)
        m = mu * l
        vol = pi * r2 * l
        fr, dfr, m1 = immersion(X[j, 2], e[2], 0.5 * l, radius)
        ma = Ca * rho_w * vol * fr  # Eq (9), scaled by the immersed fraction
        rot_fac = (l * l + 3.0 * r2) / 12.0  # Eq (4)
        Iy[j] = m * rot_fac
        Ip = m * rot_fac + Ca * rho_w * vol * rot_fac * fr  # I_y + J_y, Eq (4), (9)
        # mass matrix, Eq (3), in world axes: m*I + m_y*(I - e e^T), m_x ~ 0
        for a in range(3):
            for b in range(3):
                Md[j, a, b] = (m + ma if a == b else 0.0) - ma * e[a] * e[b]
        Md[j, 3, 3] = Ip
        Md[j, 4, 4] = Ip
        F[:] = 0.0
        tau[:] = 0.0
        # gravity Eq (13) and buoyancy Eq (12) (distributed immersion, see immersion())
        F[2] += -m * g + rho_w * vol * g * fr
        tau[0] += rho_w * vol * g * m1 * e[1]  # moment of the buoyancy: m1 (e x z)
        tau[1] -= rho_w * vol * g * m1 * e[0]
        # drag Eq (10): water part on velocity relative to current, air part on V
        for part in range(2):
            if part == 0:
                rho = rho_w * fr
                for a in range(3):
                    vr[a] = V[j, a] - cur[a]
            else:
                rho = rho_a * (1.0 - fr)
                for a in range(3):
                    vr[a] = V[j, a]
            if rho <= 0.0:
                continue
            u = vr[0] * e[0] + vr[1] * e[1] + vr[2] * e[2]
            for a in range(3):
                vn[a] = vr[a] - u * e[a]
            sn = math.sqrt(vn[0] ** 2 + vn[1] ** 2 + vn[2] ** 2)
            cn = 0.5 * rho * D * l * Cd
            ct = 0.5 * rho * D * l * Cf * tfac
            for a in range(3):
                F[a] += -cn * sn * vn[a] - ct * abs(u) * u * e[a]
            # drag Jacobian dF/dV (treated implicitly)
            for a in range(3):
                for b in range(3):
                    pa = (1.0 if a == b else 0.0) - e[a] * e[b]
                    dd = -cn * sn * pa - 2.0 * ct * abs(u) * e[a] * e[b]
                    if sn > 1e-12:
                        dd += -cn * vn[a] * vn[b] / sn
                    Cdd[j, a, b] += dd
        # fluid Coriolis, Eq (8) C_A, in world form: -(dM_A/dt) V_r, dE/dt = W x E
        for a in range(3):
            vr[a] = V[j, a] - cur[a]
        _cross(W[j], e, edot)
        ue = vr[0] * e[0] + vr[1] * e[1] + vr[2] * e[2]
        ued = vr[0] * edot[0] + vr[1] * edot[1] + vr[2] * edot[2]
        for a in range(3):
            F[a] += ma * (edot[a] * ue + e[a] * ued)
        # Munk moment, Eq (8) rows 4-5: (m_z - m_x) w u, (m_x - m_y) u v
        _cross(vr, e, vxe)
        for a in range(3):
            tau[a] += ma * ue * vxe[a]
        # water entry, Eq (14): H = -dm_a/dt * v_normal, only while entering
        mdot = Ca * rho_w * vol * dfr * V[j, 2]
        if mdot > 0.0:
            for a in range(3):
                F[a] += -mdot * (vr[a] - ue * e[a])
                for b in range(3):
                    Cdd[j, a, b] += -mdot * ((1.0 if a == b else 0.0) - e[a] * e[b])
            jdot = mdot * rot_fac
            for a in range(3):
                tau[a] += -jdot * W[j, a]
            Cdd[j, 3, 3] += -jdot
            Cdd[j, 4, 4] += -jdot
        # numerical relaxation (0 in normal use): -relax * M nu
        if relax > 0.0:
            for a in range(3):
                acc = 0.0
                for b in range(3):
                    acc += Md[j, a, b] * V[j, b]
                    Cdd[j, a, b] += -relax * Md[j, a, b]
                F[a] += -relax * acc
            for a in range(3):
                tau[a] += -relax * Ip * W[j, a]
            Cdd[j, 3, 3] += -relax * Ip
            Cdd[j, 4, 4] += -relax * Ip
        for a in range(3):
            f[j, a] += F[a]
        f[j, 3] += tau[0] * b1[0] + tau[1] * b1[1] + tau[2] * b1[2]
        f[j, 4] += tau[0] * b2[0] + tau[1] * b2[1] + tau[2] * b2[2]

    # connections: tension-only springs (Eq 20-26) with dampers (Eq 15-19)
    Jp = sJ[0]
    Jn = sJ[1]
    I3 = sJ[2, :, 0:3]
    Pp = sv[6]
    Pn = sv[7]
    Vp = sv[8]
    Vn = sv[9]
    d = sv[10]
    dv = sv[11]
    nax = sv[12]
    Fc = sv[13]
    arm = sv[14]
    wa = sv[15]
    dw = sv[16]
    best_c = -1
    best_ratio = 1.0
    best_T = 0.0
    for c in range(N + 1):
        if conn_ok[c] == 0:
            continue
        hp = c > 0
        hn = c < N
        if (not hp and att_on[0] == 0) or (not hn and att_on[1] == 0):
            continue
        i = c - 1
        k = c
        if hp:
            half = 0.5 * L[i]
            for a in range(3):
                arm[a] = -half * E[i, a]
                Pp[a] = X[i, a] + arm[a]
            _cross(W[i], arm, wa)
            for a in range(3):
                Vp[a] = V[i, a] + wa[a]
            _jac(Jp, -half, B1[i], B2[i])
        else:
            for a in range(3):
                Pp[a] = att_pos[0, a] + att_vel[0, a] * t
                Vp[a] = att_vel[0, a]
        if hn:
            half = 0.5 * L[k]
            for a in range(3):
                arm[a] = half * E[k, a]
                Pn[a] = X[k, a] + arm[a]
            _cross(W[k], arm, wa)
            for a in range(3):
                Vn[a] = V[k, a] + wa[a]
            if c == 0:  # winch at end a: rope slides out of the drum at the pay-out rate
                for a in range(3):
                    Vn[a] += payout_a * E[k, a]
            _jac(Jn, half, B1[k], B2[k])
        else:
            for a in range(3):
                Pn[a] = att_pos[1, a] + att_vel[1, a] * t
                Vn[a] = att_vel[1, a]
        # Eq (25) switches a connection off when one point enters the neighbour's half
        # length (|d|^2 + l d.e <= 0, i.e. axial compression). Done continuously below:
        # only the compressive axial part of the connection force is removed (STRICT_EQ25
        # = True restores the paper's all-or-nothing switch).
        active = True
        if STRICT_EQ25:
            if hp:
                q = 0.0
                for a in range(3):
                    q += (Pn[a] - X[i, a]) ** 2
                if math.sqrt(q) <= 0.5 * L[i]:
                    active = False
            if hn:
                q = 0.0
                for a in range(3):
                    q += (Pp[a] - X[k, a]) ** 2
                if math.sqrt(q) <= 0.5 * L[k]:
                    active = False
        if hp and hn:  # bending damping, Eq (18)-(19), on the relative angular velocity
            cm = 2.0 * z_rot * math.sqrt(P_rot * 0.5 * (Iy[i] + Iy[k]))
            if cm > 0.0:
                for a in range(3):
                    dw[a] = W[i, a] - W[k, a]
                f[k, 3] += cm * (dw[0] * B1[k, 0] + dw[1] * B1[k, 1] + dw[2] * B1[k, 2])
                f[k, 4] += cm * (dw[0] * B2[k, 0] + dw[1] * B2[k, 1] + dw[2] * B2[k, 2])
                f[i, 3] -= cm * (dw[0] * B1[i, 0] + dw[1] * B1[i, 1] + dw[2] * B1[i, 2])
                f[i, 4] -= cm * (dw[0] * B2[i, 0] + dw[1] * B2[i, 1] + dw[2] * B2[i, 2])
                Cdd[k, 3, 3] -= cm
                Cdd[k, 4, 4] -= cm
                Cdd[i, 3, 3] -= cm
                Cdd[i, 4, 4] -= cm
                for a in range(3):  # d torque_i / d w_k = cm B_i^T B_k
                    Cdo[i, 3, 3] += cm * B1[i, a] * B1[k, a]
                    Cdo[i, 3, 4] += cm * B1[i, a] * B2[k, a]
                    Cdo[i, 4, 3] += cm * B2[i, a] * B1[k, a]
                    Cdo[i, 4, 4] += cm * B2[i, a] * B2[k, a]
        if not active:
            continue
        # spring: stiffness equivalent to EA over the rope length it represents
        lrep = 0.0
        msum = 0.0
        cnt = 0.0
        for a in range(3):
            nax[a] = 0.0
        if hp:
            lrep += 0.5 * L[i]
            msum += mu * L[i]
            cnt += 1.0
            for a in range(3):
                nax[a] += E[i, a]
        if hn:
            lrep += 0.5 * L[k]
            msum += mu * L[k]
            cnt += 1.0
            for a in range(3):
                nax[a] += E[k, a]
        nn = math.sqrt(nax[0] ** 2 + nax[1] ** 2 + nax[2] ** 2)
        if nn < 1e-9:  # folded back on itself: use the gap direction
            for a in range(3):
                nax[a] = Pp[a] - Pn[a]
            nn = math.sqrt(nax[0] ** 2 + nax[1] ** 2 + nax[2] ** 2) + 1e-300
        for a in range(3):
            nax[a] /= nn
        kc = EA / lrep
        mc = msum / cnt
        cax = 2.0 * z_ax * math.sqrt(kc * mc)  # Eq (16): c_x = 2 zeta_x sqrt(k m)
        ctr = 2.0 * z_tr * math.sqrt(kc * mc)
        for a in range(3):
            d[a] = Pp[a] - Pn[a]
            dv[a] = Vp[a] - Vn[a]
        ndv = nax[0] * dv[0] + nax[1] * dv[1] + nax[2] * dv[2]
        for a in range(3):
            Fc[a] = kc * d[a] + cax * nax[a] * ndv + ctr * (dv[a] - nax[a] * ndv)
        ax = Fc[0] * nax[0] + Fc[1] * nax[1] + Fc[2] * nax[2]
        axial_damp = cax
        if ax < 0.0:  # a rope cannot push: drop the compressive axial part
            for a in range(3):
                Fc[a] -= ax * nax[a]
            axial_damp = 0.0
        T = math.sqrt(Fc[0] ** 2 + Fc[1] ** 2 + Fc[2] ** 2)
        if T > brk[c]:  # parting candidate (issue 3 item 4)
            if armed[c] != 0 and T / brk[c] > best_ratio:
                best_ratio = T / brk[c]
                best_c = c
                best_T = T
        else:
            armed[c] = 1
        tension[c] = T
        # Fc acts on the 'next' point, -Fc on the 'prev' point
        if hn:
            _add_Jt_vec(f[k], Jn, Fc, 1.0)
        else:
            for a in range(3):
                end_force[1, a] = Fc[a]
        if hp:
            _add_Jt_vec(f[i], Jp, Fc, -1.0)
        else:
            for a in range(3):
                end_force[0, a] = -Fc[a]
        if not need_jac:
            continue
        hi = -0.5 * L[i] if hp else 0.0  # lever of the aft point of i / front point of k
        hk = 0.5 * L[k] if hn else 0.0
        for a in range(3):
            for b in range(3):
                S[a, b] = (axial_damp * nax[a] * nax[b]
                           + ctr * ((1.0 if a == b else 0.0) - nax[a] * nax[b]))
        if hn:  # spring -kc Jn^T Jn, damper -Jn^T S Jn, geometric stiffness of the moment
            _add_pair(Kd[k], hk, B1[k], B2[k], hk, B1[k], B2[k], I3, -kc)
            _add_pair(Cdd[k], hk, B1[k], B2[k], hk, B1[k], B2[k], S, -1.0)
            fe = Fc[0] * E[k, 0] + Fc[1] * E[k, 1] + Fc[2] * E[k, 2]
            Kd[k, 3, 3] += -0.5 * L[k] * fe
            Kd[k, 4, 4] += -0.5 * L[k] * fe
        if hp:
            _add_pair(Kd[i], hi, B1[i], B2[i], hi, B1[i], B2[i], I3, -kc)
            _add_pair(Cdd[i], hi, B1[i], B2[i], hi, B1[i], B2[i], S, -1.0)
            fe = Fc[0] * E[i, 0] + Fc[1] * E[i, 1] + Fc[2] * E[i, 2]
            Kd[i, 3, 3] += -0.5 * L[i] * fe
            Kd[i, 4, 4] += -0.5 * L[i] * fe
        if hp and hn:
            _add_pair(Ko[i], hi, B1[i], B2[i], hk, B1[k], B2[k], I3, kc)
            _add_pair(Cdo[i], hi, B1[i], B2[i], hk, B1[k], B2[k], S, 1.0)
        # attachment moving during the sub-step (position extrapolated with its velocity)
        if not hp:  # (winch heave-in: the drum end also retracts along the rope; pay-out
            # extensions are capped at the drum in chain._winch, so they are not anticipated)
            pin = min(payout_a, 0.0)
            for a in range(3):
                d[a] = kc * (att_vel[0, a] - pin * E[k, a]) * h
            _add_Jt_vec(rhs_att[k], Jn, d, h * theta)
        if not hn:
            for a in range(3):
                d[a] = kc * att_vel[1, a] * h
            _add_Jt_vec(rhs_att[i], Jp, d, h * theta)
    if best_c >= 0:
        # the rope parts at the most overloaded connection only; the others that carry
        # the same overload survived it (they are disarmed until they unload)
        conn_ok[best_c] = 0
        ne = n_events[0]
        if ne < events.shape[0]:
            events[ne, 0] = t
            events[ne, 1] = best_c
            events[ne, 2] = best_T
        n_events[0] = ne + 1
        for c in range(N + 1):
            if tension[c] > brk[c]:
                armed[c] = 0
        return True
    return False


@njit(cache=True)
def _solve_dense(A, Bm, n, m):
    """Solve A X = Bm in place (A n x n, Bm n x m), partial pivoting. Returns False if singular."""
    for col in range(n):
        piv = col
        best = abs(A[col, col])
        for r in range(col + 1, n):
            if abs(A[r, col]) > best:
                best = abs(A[r, col])
                piv = r
        if best == 0.0 or not math.isfinite(best):
            return False
        if piv != col:
            for c in range(n):
                tmp = A[col, c]
                A[col, c] = A[piv, c]
                A[piv, c] = tmp
            for c in range(m):
                tmp = Bm[col, c]
                Bm[col, c] = Bm[piv, c]
                Bm[piv, c] = tmp
        inv = 1.0 / A[col, col]
        for r in range(col + 1, n):
            fac = A[r, col] * inv
            if fac != 0.0:
                for c in range(col, n):
                    A[r, c] -= fac * A[col, c]
                for c in range(m):
                    Bm[r, c] -= fac * Bm[col, c]
    for col in range(n - 1, -1, -1):
        inv = 1.0 / A[col, col]
        for c in range(m):
            acc = Bm[col, c]
            for k in range(col + 1, n):
                acc -= A[col, k] * Bm[k, c]
            Bm[col, c] = acc * inv
    return True


@njit(cache=True)
def solve_block_tridiag(Ad, Ao, b, x, Wm, y, Dp, R):
    """Symmetric block tri-diagonal solve: diag Ad (N,5,5), upper Ao (N,5,5) (block j,j+1),
    lower = Ao^T. Block Thomas elimination, O(N); Wm (N,5,5), y (N,5), Dp (5,5), R (5,6)
    are scratch. Returns the index of a singular block or -1."""
    N = Ad.shape[0]
    for j in range(N):
        for r in range(5):
            for c in range(5):
                Dp[r, c] = Ad[j, r, c]
            R[r, 5] = b[j, r]
        if j > 0:
            # D'_j = A_jj - L_j W_{j-1}, L_j = Ao[j-1]^T ; rhs'_j = b_j - L_j y_{j-1}
            for r in range(5):
                for c in range(5):
                    acc = 0.0
                    for k in range(5):
                        acc += Ao[j - 1, k, r] * Wm[j - 1, k, c]
                    Dp[r, c] -= acc
                acc = 0.0
                for k in range(5):
                    acc += Ao[j - 1, k, r] * y[j - 1, k]
                R[r, 5] -= acc
        for r in range(5):
            for c in range(5):
                R[r, c] = Ao[j, r, c] if j < N - 1 else 0.0
        if not _solve_dense(Dp, R, 5, 6):
            return j
        for r in range(5):
            for c in range(5):
                Wm[j, r, c] = R[r, c]
            y[j, r] = R[r, 5]
    for r in range(5):
        x[N - 1, r] = y[N - 1, r]
    for j in range(N - 2, -1, -1):
        for r in range(5):
            acc = y[j, r]
            for c in range(5):
                acc -= Wm[j, r, c] * x[j + 1, c]
            x[j, r] = acc
    return -1


@njit(cache=True)
def _rodrigues(v, phi, out):
    """out = rotation of v by the rotation vector phi (out may not alias v)."""
    ang = math.sqrt(phi[0] ** 2 + phi[1] ** 2 + phi[2] ** 2)
    if ang < 1e-300:
        out[0] = v[0]
        out[1] = v[1]
        out[2] = v[2]
        return
    k0 = phi[0] / ang
    k1 = phi[1] / ang
    k2 = phi[2] / ang
    c = math.cos(ang)
    s = math.sin(ang)
    kv = (k0 * v[0] + k1 * v[1] + k2 * v[2]) * (1.0 - c)
    out[0] = v[0] * c + (k1 * v[2] - k2 * v[1]) * s + k0 * kv
    out[1] = v[1] * c + (k2 * v[0] - k0 * v[2]) * s + k1 * kv
    out[2] = v[2] * c + (k0 * v[1] - k1 * v[0]) * s + k2 * kv


def workspace_size(n):
    """Length of the work space array run_substeps needs for n elements."""
    return 9 * 25 * n + 6 * 5 * n + 6 * 3 * n + n + (n + 1) + 6 + 63 + 45 + 9 + 25 + 30


@njit(cache=True)
def _restore(X, E, V, W, conn_ok, armed, tension, end_force, bX, bE, bV, bW, b_ok, b_armed,
             b_T, b_F):
    X[:] = bX
    E[:] = bE
    V[:] = bV
    W[:] = bW
    conn_ok[:] = b_ok
    armed[:] = b_armed
    tension[:] = b_T
    end_force[:] = b_F


@njit(cache=True)
def run_substeps(X, E, V, W, L, conn_ok, brk, armed, att_on, att_pos, att_vel,
                 mu, radius, EA, Cd, Cf, tfac, Ca, rho_w, rho_a, g,
                 z_ax, z_tr, z_rot, P_rot, cur, relax, h, theta, n_sub, payout_a,
                 vmax, wmax, pmax,
                 tension, end_force, impulse, events, n_events, info, ws):
    """Advance n_sub sub-steps of size h in place. Attachments move as
    att_pos + att_vel * t (t from the call start). On divergence returns DIVERGED with
    info = (sub-step index, element index) after restoring every array to its state at
    the call (the last good state). impulse (2,3) accumulates the force on each attachment
    times time (trapezoidal). ws: float64 work space of workspace_size(N) entries."""
    N = X.shape[0]
    o = 0
    f = ws[o:o + 5 * N].reshape((N, 5))
    o += 5 * N
    Md = ws[o:o + 25 * N].reshape((N, 5, 5))
    o += 25 * N
    Kd = ws[o:o + 25 * N].reshape((N, 5, 5))
    o += 25 * N
    Ko = ws[o:o + 25 * N].reshape((N, 5, 5))
    o += 25 * N
    Cdd = ws[o:o + 25 * N].reshape((N, 5, 5))
    o += 25 * N
    Cdo = ws[o:o + 25 * N].reshape((N, 5, 5))
    o += 25 * N
    Ad = ws[o:o + 25 * N].reshape((N, 5, 5))
    o += 25 * N
    Ao = ws[o:o + 25 * N].reshape((N, 5, 5))
    o += 25 * N
    Wm = ws[o:o + 25 * N].reshape((N, 5, 5))
    o += 25 * N
    rhs_att = ws[o:o + 5 * N].reshape((N, 5))
    o += 5 * N
    b = ws[o:o + 5 * N].reshape((N, 5))
    o += 5 * N
    dnu = ws[o:o + 5 * N].reshape((N, 5))
    o += 5 * N
    nu = ws[o:o + 5 * N].reshape((N, 5))
    o += 5 * N
    y = ws[o:o + 5 * N].reshape((N, 5))
    o += 5 * N
    B1 = ws[o:o + 3 * N].reshape((N, 3))
    o += 3 * N
    B2 = ws[o:o + 3 * N].reshape((N, 3))
    o += 3 * N
    bX = ws[o:o + 3 * N].reshape((N, 3))
    o += 3 * N
    bE = ws[o:o + 3 * N].reshape((N, 3))
    o += 3 * N
    bV = ws[o:o + 3 * N].reshape((N, 3))
    o += 3 * N
    bW = ws[o:o + 3 * N].reshape((N, 3))
    o += 3 * N
    Iy = ws[o:o + N]
    o += N
    b_T = ws[o:o + N + 1]
    o += N + 1
    b_F = ws[o:o + 6].reshape((2, 3))
    o += 6
    sv = ws[o:o + 63].reshape((21, 3))
    o += 63
    sJ = ws[o:o + 45].reshape((3, 3, 5))
    o += 45
    S = ws[o:o + 9].reshape((3, 3))
    o += 9
    Dp = ws[o:o + 25].reshape((5, 5))
    o += 25
    R = ws[o:o + 30].reshape((5, 6))
    o += 30
    Wn = sv[17]
    phi = sv[18]
    en = sv[19]
    wr = sv[20]
    sJ[:] = 0.0
    sJ[2, 0, 0] = 1.0  # identity used by evaluate()
    sJ[2, 1, 1] = 1.0
    sJ[2, 2, 2] = 1.0
    impulse[:] = 0.0
    h2 = h * h * theta * theta
    # last good state, restored on divergence
    bX[:] = X
    bE[:] = E
    bV[:] = V
    bW[:] = W
    b_T[:] = tension
    b_F[:] = end_force
    b_ok = conn_ok.copy()
    b_armed = armed.copy()
    b_nev = n_events[0]
    for step in range(n_sub + 1):
        t = step * h
        for _ in range(N + 2):  # re-evaluate after a parting (at most one per pass)
            if not evaluate(X, E, V, W, L, conn_ok, brk, armed, att_on, att_pos, att_vel,
                            mu, radius, EA, Cd, Cf, tfac, Ca, rho_w, rho_a, g,
                            z_ax, z_tr, z_rot, P_rot, cur, relax, h, theta, t, payout_a,
                            f, Md, Kd, Ko, Cdd, Cdo, rhs_att, tension, end_force, events,
                            n_events, B1, B2, step < n_sub, Iy, sv, sJ, S):
                break
        w8 = 0.5 * h if (step == 0 or step == n_sub) else h
        for s in range(2):
            for a in range(3):
                impulse[s, a] += w8 * end_force[s, a]
        if step == n_sub:
            break
        for j in range(N):
            b1 = B1[j]
            b2 = B2[j]
            for a in range(3):
                nu[j, a] = V[j, a]
            nu[j, 3] = W[j, 0] * b1[0] + W[j, 1] * b1[1] + W[j, 2] * b1[2]
            nu[j, 4] = W[j, 0] * b2[0] + W[j, 1] * b2[1] + W[j, 2] * b2[2]
        # (M - h theta C - h^2 theta^2 K) dnu = h f + h^2 theta K nu + attachment terms
        for j in range(N):
            for r in range(5):
                acc = 0.0
                for c in range(5):
                    Ad[j, r, c] = Md[j, r, c] - h * theta * Cdd[j, r, c] - h2 * Kd[j, r, c]
                    Ao[j, r, c] = -h * theta * Cdo[j, r, c] - h2 * Ko[j, r, c]
                    acc += Kd[j, r, c] * nu[j, c]
                    if j < N - 1:
                        acc += Ko[j, r, c] * nu[j + 1, c]
                    if j > 0:
                        acc += Ko[j - 1, c, r] * nu[j - 1, c]
                b[j, r] = h * f[j, r] + h * h * theta * acc + rhs_att[j, r]
        bad = solve_block_tridiag(Ad, Ao, b, dnu, Wm, y, Dp, R)
        if bad >= 0:
            info[0] = step
            info[1] = bad
            _restore(X, E, V, W, conn_ok, armed, tension, end_force, bX, bE, bV, bW,
                     b_ok, b_armed, b_T, b_F)
            n_events[0] = b_nev
            return DIVERGED
        for j in range(N):
            b1 = B1[j]
            b2 = B2[j]
            for a in range(3):
                Vn_a = V[j, a] + dnu[j, a]
                X[j, a] += h * ((1.0 - theta) * V[j, a] + theta * Vn_a)
                V[j, a] = Vn_a
                Wn[a] = W[j, a] + dnu[j, 3] * b1[a] + dnu[j, 4] * b2[a]
                phi[a] = h * ((1.0 - theta) * W[j, a] + theta * Wn[a])
            _rodrigues(E[j], phi, en)
            nrm = math.sqrt(en[0] ** 2 + en[1] ** 2 + en[2] ** 2)
            for a in range(3):
                en[a] /= nrm
            _rodrigues(Wn, phi, wr)
            we = wr[0] * en[0] + wr[1] * en[1] + wr[2] * en[2]
            for a in range(3):
                E[j, a] = en[a]
                W[j, a] = wr[a] - we * en[a]
            # divergence: non-finite or absurd values
            ok = True
            for a in range(3):
                if not (math.isfinite(X[j, a]) and math.isfinite(V[j, a]) and math.isfinite(W[j, a])
                        and math.isfinite(E[j, a])):
                    ok = False
            if ok:
                spd = math.sqrt(V[j, 0] ** 2 + V[j, 1] ** 2 + V[j, 2] ** 2)
                sw = math.sqrt(W[j, 0] ** 2 + W[j, 1] ** 2 + W[j, 2] ** 2)
                sx = math.sqrt(X[j, 0] ** 2 + X[j, 1] ** 2 + X[j, 2] ** 2)
                if spd > vmax or sw > wmax or sx > pmax:
                    ok = False
            if not ok:
                info[0] = step
                info[1] = j
                _restore(X, E, V, W, conn_ok, armed, tension, end_force, bX, bE, bV, bW,
                         b_ok, b_armed, b_T, b_F)
                n_events[0] = b_nev
                return DIVERGED
    return OK
