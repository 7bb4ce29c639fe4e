"""Numba kernels of the element-chain rope of Yoon, Lee, Park, Kim, "Dynamic Modeling and
Simulation of a Towing Rope using Multiple Finite Element Method" (2012), Eq 1-26.

State per element j (world frame ENU, z up, water surface z = 0):
  X[j]  centre of mass (R of Eq 5)            V[j]  its velocity
  E[j]  unit axis = body x, pointing to end a  W[j]  angular velocity, kept perpendicular to E
The paper's 5 DOF (u, v, w, q, r) are (V, W) seen in the yaw-pitch body frame; storing
the axis vector instead of (theta, psi) removes the 1/cos(theta) singularity of Eq (6) for
hanging (vertical) elements. Generalised velocity per element for the implicit solve:
nu = (V, W.b1, W.b2) with (E, b1, b2) a right-handed basis: 5 DOF as in Eq (2).

Connections c = 0..N: c joins the aft point of element c-1 (or attachment a when c = 0)
to the front point of element c (or attachment b when c = N).

Integrator: linearly implicit theta-method (theta = 1/2: trapezoidal / Newmark average
acceleration) with the exact Jacobian of the connection springs (incl. geometric
stiffness), of the connection dampers, of drag and of the water-entry term; the system

    (M - h theta C - h^2 theta^2 K) dnu = h f + h^2 theta K nu + attachment terms

is block tri-diagonal (5x5 blocks) and solved in O(N) by block Thomas elimination.

Everything runs in one call per exchange step, run_substeps(). Per sub-step one pass over
j = 0..N writes element j's block (_element_terms), connection j's terms (spring-damper
_tension_only_spring_damper, bending damper _bending_damper, their Jacobians
_add_connection_to_element and _coupling_block) and eliminates block j - 1
(_eliminate_block); the back substitution then advances every element (_advance_element).
Each force component or equation group is a helper named after it, compiled into the one
entry point (inline="always"). Numba counts references (atomic operations) for every array
a helper takes unless the helper's uses of it are straight-line or end in one place: so
helpers that branch take scalars, the ones that touch arrays do not branch on them, and
the loops and branches over the arrays stay in run_substeps (a helper branching on its
arrays per connection made the kernel 14-70 % slower). The arguments are few and packed
(numba's dispatch costs about 50 ns per array argument): the state S and flags F
(RopeChain's X, E, V, W, ... are views into them), one float array io for parameters,
attachment data and outputs, and the work space ws. kernels_reference.py is a plain numpy
transcription of the same sub-step, used as a test oracle (of the calm sea: it has no waves).

Waves (issue 31): sample_waves writes the sea's particle velocity and acceleration (Airy,
Wheeler-stretched) and the local elevation eta at each element once per exchange step; drag
acts relative to current + particles, Morison's inertia is added (_wave_inertia) and the
immersion and water entry are judged against eta (README, "Waves"). It advances each element's
wave phasors and depth factors from the last step's (the rope's wave cache, RopeChain's
_wave_cache: see "wave cache" below) rather than summing cos, sin and exp anew: about 3 ns
instead of 30 ns per component and element; waves.wave_kinematics_wet stays the oracle.
"""
import math
from collections import namedtuple

import numpy as np
from numba import njit

from sea_environment.environment import tidal_factor
from sea_environment.sampler import (P_DEPTH_MIN, P_TIME, P_WAVE_AT, depth_at, flow_at_point, wave_offset,
                                     wind_at_10m)
from sea_environment.waves import (C_A, C_DX, C_DY, C_INV_S, C_K, C_KX, C_KY, C_OMEGA, C_PHASE, N_HEADER, STRIDE,
                                   W_DEPTH, W_N, wave_kinematics_wet, wave_ramp)
from sim_math.linalg import lu_factor, lu_solve, lu_solve_columns

# status codes returned by run_substeps
OK = 0
DIVERGED = 1
NEED_WS = 2  # ws holds fewer than N + 1 element slots: pass new_workspace(N)
PARTED = 4  # flag or-ed into OK: parting events were recorded (io[IO_NEV] of them)
STRICT_EQ25 = False  # compile-time switch, see run_substeps()
# Parting or blow-up. A rope breaks when its material strain reaches the strain at break, so
# at a genuine parting the spring part of the connection force, EA x strain (along the rope),
# carries most of the breaking load; the axial damper (Eq 16, c = 2 zeta sqrt(EA mu)) only adds
# to it. A tension that is mostly damper force needs the points to separate at more than
# BL / (4 zeta sqrt(EA mu)) (58 m/s for Table 1), and a folded pair of links pulls sideways
# with its axial strain negative: neither is a rope reaching its breaking strain, both are the
# signature of a numerical or input blow-up (measured: partings pulled apart at 2 m/s or
# stretched at 0.3 1/s carry 85-100 % elastically; theta = 0.5 instabilities 13-47 %, a
# 1e6 m/s heave-in 0 %). Such a "parting" is reported as divergence, not as an event.
PART_MIN_ELASTIC = 0.5
# fused multiply-add allowed (results change at the round-off level only); no other
# fast-math assumption: NaN and inf keep their meaning for the divergence check
FMA = {"contract"}

# S: float64 (N + 1, S_COLS), the state: per element j (rows 0..N-1) centre X, axis E,
# velocity V, angular velocity W (3 columns each from SX, SE, SV, SW) and length (SL); per
# connection c (rows 0..N) breaking load (SB) and tension (ST). RopeChain's X, E, ... are
# views into it. F: int64 (N + 1, F_COLS): connection intact (column F_OK), parting armed
# (F_ARMED).
SX, SE, SV, SW, SL, SB, ST = 0, 3, 6, 9, 12, 13, 14
# environment per element j (rows 0..N-1), sampled at the element centres by the caller
# (RopeChain.set_environment): water current (3 columns from SCUR, added to the uniform
# current of io[IO_CUR]), wind (3 from SWIND) and seabed depth below the water surface
# (SDEPTH, m, positive down; inf = no seabed)
SCUR, SWIND, SDEPTH = 15, 18, 21
# waves at element j (sample_environment, from the sea packed in the environment; zero on a
# calm sea): the water particles' velocity (3 columns from SWV, added to the current) and
# acceleration (SWA) at the element centre, or at the surface for a centre above it, and the
# local surface elevation eta (SETA, m), against which the element's immersion is judged
SWV, SWA, SETA = 22, 25, 28
S_COLS = 29
F_OK, F_ARMED = 0, 1
F_COLS = 2
# io: float64 (IO_ROWS, 3), RopeChain._io; the attributes att_pos, att_vel etc. are views
IO_POS, IO_VEL, IO_FORCE, IO_IMPULSE, IO_MEAN = 0, 2, 4, 6, 8  # rows (end a, end b):
# attachment position and velocity, force on the attachment, impulse over the call,
# impulse / dt
P_MU, P_RADIUS, P_EA = (10, 0), (10, 1), (10, 2)  # scalar parameters (row, column)
P_CD, P_CF, P_TFAC = (11, 0), (11, 1), (11, 2)
P_CA, P_RHO_W, P_RHO_A = (12, 0), (12, 1), (12, 2)
P_G, P_Z_AX, P_Z_TR = (13, 0), (13, 1), (13, 2)  # gravity, damping ratios
P_Z_ROT, P_P_ROT, P_RELAX = (14, 0), (14, 1), (14, 2)  # bending reference load P_ROT
IO_CUR = 15  # row: uniform current (m/s)
P_THETA, P_VMAX, P_WMAX = (16, 0), (16, 1), (16, 2)
P_PMAX = (17, 0)
IO_ATT = 17  # columns 1, 2: attachment a, b on (1.0) or not (0.0)
IO_INFO = 18  # columns 0, 1: divergence (sub-step, element); column 2: events recorded
IO_NEV = (IO_INFO, 2)
IO_DIAG = 19  # a parting refused as a blow-up (PART_MIN_ELASTIC): (connection or -1, T, EA strain)
# seabed contact (MoorDyn's model): stiffness kbot (Pa/m) and damping cbot (Pa s/m) per
# unit contact area (diameter x length), Coulomb friction coefficients along and across the
# element axis, regularised linearly below the slip speed (m/s)
P_KBOT, P_CBOT, P_MU_AX = (20, 0), (20, 1), (20, 2)
P_MU_TR, P_VSLIP = (21, 0), (21, 1)
IO_EVENTS = 22  # rows: parting events (t, c, T)
N_EVENTS_MAX = 64
IO_ROWS = IO_EVENTS + N_EVENTS_MAX
# ws: float64 (6, cap, 5, 5), cap >= N + 1: 0 Ad, 1 Ao, 2 Wm (= D^-1 Ao), 3 per-element
# vectors (row 0 rhs / y, row 1 dnu, row 2 b1, row 3 b2, row 4 (I_y, backup of tension,
# conn_ok, armed)), 4 backup of X, E, V, W (rows 0-3) and connection constants (row 4:
# k, c_x, c_t, c_m, element length they were computed for), 5 backup of the end forces
# (slot 0, rows 0-1) and the element count of the constants (slot 1, [0, 0])
WS_SLOTS = 6


def new_workspace(n):
    """Work space for n elements (a few spare slots for winch splits)."""
    return np.zeros((WS_SLOTS, n + 5, 5, 5))


# scalar parameters of one call, read from io once (a tuple of floats: no reference counting)
KernelParams = namedtuple("KernelParams", (
    "mu", "radius", "EA", "Cd", "Cf", "tfac", "Ca", "rho_w", "rho_a", "g", "z_ax", "z_tr",
    "z_rot", "P_rot", "cur0", "cur1", "cur2", "relax", "theta", "vmax2", "wmax2", "pmax2",
    "D", "r2", "h", "hth", "h2t", "h2t2", "kbot", "cbot", "mu_ax", "mu_tr", "vslip"))


@njit(cache=True, inline="always", fastmath=FMA)
def _read_params(io, h):
    """The scalar parameters and the sub-step factors h theta, h^2 theta, (h theta)^2."""
    radius = io[P_RADIUS]
    theta = io[P_THETA]
    hth = h * theta
    return KernelParams(io[P_MU], radius, io[P_EA], io[P_CD], io[P_CF], io[P_TFAC], io[P_CA],
                        io[P_RHO_W], io[P_RHO_A], io[P_G], io[P_Z_AX], io[P_Z_TR], io[P_Z_ROT],
                        io[P_P_ROT], io[IO_CUR, 0], io[IO_CUR, 1], io[IO_CUR, 2], io[P_RELAX],
                        theta, io[P_VMAX] ** 2, io[P_WMAX] ** 2, io[P_PMAX] ** 2, 2.0 * radius,
                        radius * radius, h, hth, h * h * theta, hth * hth, io[P_KBOT],
                        io[P_CBOT], io[P_MU_AX], io[P_MU_TR], io[P_VSLIP])


# ------------------------------------------------------------------ geometry
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


@njit(cache=True, fastmath=FMA)
def immersion(z, ez, half_len, r):
    """Immersed fraction f of an element (centre height z, axis z-component ez), df/dz and
    m1 = mean of f(s) * s along the axis (s from the centre, m).

    Eq (12) switches buoyancy on at 'Z <= 0'. Here it is distributed along the axis (4
    Gauss points, each a circle segment over the vertical half extent of the piece it stands
    for): smooth (C1) in z, and a half-immersed inclined element gets the righting moment
    rho Vol g m1 (e x z) that keeps the paper's floating elements level (section 4.3)."""
    rs = r * math.sqrt(max(0.0, 1.0 - ez * ez))
    if z - half_len * abs(ez) >= rs + half_len * abs(ez):  # all 4 pieces out of the water
        return 0.0, 0.0, 0.0
    if z + half_len * abs(ez) <= -(rs + half_len * abs(ez)):  # all 4 pieces submerged
        m1 = 0.0
        for k in range(4):
            m1 += _GW[k] * (half_len * _GX[k])
        return 1.0, 0.0, m1
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


@njit(cache=True, inline="always", fastmath=FMA)
def _basis(ex, ey, ez):
    """Right-handed orthonormal (e, b1, b2): b1 is z (x for a near-vertical e) made normal
    to e, b2 = e x b1. Returns b1, b2 (6 scalars)."""
    if abs(ez) < 0.9:
        hx, hy, hz = 0.0, 0.0, 1.0
    else:
        hx, hy, hz = 1.0, 0.0, 0.0
    d = hx * ex + hy * ey + hz * ez
    p0 = hx - d * ex
    p1 = hy - d * ey
    p2 = hz - d * ez
    nb = math.sqrt(p0 * p0 + p1 * p1 + p2 * p2)
    p0 /= nb
    p1 /= nb
    p2 /= nb
    return p0, p1, p2, ey * p2 - ez * p1, ez * p0 - ex * p2, ex * p1 - ey * p0


@njit(cache=True, inline="always")
def _stored_basis(B1, B2, j):
    """(b1, b2) of element j as written by _store_element this sub-step (6 scalars)."""
    return B1[j, 0], B1[j, 1], B1[j, 2], B2[j, 0], B2[j, 1], B2[j, 2]


@njit(cache=True, inline="always", fastmath=FMA)
def _rodrigues(k0, k1, k2, co, sa, x0, x1, x2):
    """x rotated about the unit axis k by the angle of cosine co and sine sa."""
    kv = (k0 * x0 + k1 * x1 + k2 * x2) * (1.0 - co)
    return (x0 * co + (k1 * x2 - k2 * x1) * sa + k0 * kv,
            x1 * co + (k2 * x0 - k0 * x2) * sa + k1 * kv,
            x2 * co + (k0 * x1 - k1 * x0) * sa + k2 * kv)


# ------------------------------------------------------------------ constants of a call
@njit(cache=True, inline="always", fastmath=FMA)
def _update_length_constants(S, ws, cc, misc, N, p):
    """Element I_y (Eq 4) and connection constants: spring k, axial and transverse dampers
    c_x, c_t (Eq 16-17) and bending damper c_m (Eq 19). They depend on the lengths only
    (fixed during a call, changed by the winch) and are recomputed when those differ from
    the last call."""
    same = ws[5, 1, 0, 0] == N
    for j in range(N):
        same = same and cc[j, 4] == S[j, SL]
    for j in range(0 if same else N):
        l = S[j, SL]
        cc[j, 4] = l
        misc[j, 0] = p.mu * l * ((l * l + 3.0 * p.r2) / 12.0)  # I_y, Eq (4)
    ws[5, 1, 0, 0] = N
    for c in range(0 if same else N + 1):
        # spring: stiffness equivalent to EA over the rope length it represents
        lrep = 0.0
        msum = 0.0
        cnt = 0.0
        if c > 0:
            lrep += 0.5 * S[c - 1, SL]
            msum += p.mu * S[c - 1, SL]
            cnt += 1.0
        if c < N:
            lrep += 0.5 * S[c, SL]
            msum += p.mu * S[c, SL]
            cnt += 1.0
        kc = p.EA / lrep
        skm = math.sqrt(kc * (msum / cnt))
        cc[c, 0] = kc
        cc[c, 1] = 2.0 * p.z_ax * skm  # Eq (16): c_x = 2 zeta_x sqrt(k m)
        cc[c, 2] = 2.0 * p.z_tr * skm  # Eq (17): transverse ratio
        cc[c, 3] = 0.0
        if 0 < c < N:  # bending damper, Eq (19)
            cc[c, 3] = 2.0 * p.z_rot * math.sqrt(p.P_rot * 0.5 * (misc[c - 1, 0] + misc[c, 0]))


# ------------------------------------------------------------------ element forces, Eq (1)
@njit(cache=True, inline="always", fastmath=FMA)
def _element_inertia(p, l, fr):
    """Mass m, volume, added mass m_y = m_z (Eq 9, scaled by the immersed fraction fr),
    rot_fac = (l^2 + 3 r^2) / 12 and the rotational inertia I_y + J_y (Eq 4, 9)."""
    m = p.mu * l
    vol = math.pi * p.r2 * l
    ma = p.Ca * p.rho_w * vol * fr
    rot_fac = (l * l + 3.0 * p.r2) / 12.0
    Ip = m * rot_fac + p.Ca * p.rho_w * vol * rot_fac * fr
    return m, vol, ma, rot_fac, Ip


@njit(cache=True, inline="always", fastmath=FMA)
def _mass_matrix(m, ma, ex, ey, ez):
    """Translational M + M_A of Eq (3) in world axes: m I + m_y (I - e e^T), m_x ~ 0 (Eq 9).
    Returns the entries 00, 11, 22, 01, 02, 12."""
    return ((m + ma) - ma * ex * ex, (m + ma) - ma * ey * ey, (m + ma) - ma * ez * ez,
            -(ma * ex * ey), -(ma * ex * ez), -(ma * ey * ez))


@njit(cache=True, inline="always", fastmath=FMA)
def _gravity_and_buoyancy(p, m, vol, fr, m1, ex, ey):
    """Gravity Eq (13) plus buoyancy Eq (12) on the immersed fraction: vertical force, and
    the x, y moment of the buoyancy distributed along the axis, rho Vol g m1 (e x z)."""
    Fz = -m * p.g + p.rho_w * vol * p.g * fr
    return Fz, p.rho_w * vol * p.g * m1 * ey, -(p.rho_w * vol * p.g * m1 * ex)


@njit(cache=True, inline="always", fastmath=FMA)
def _morison_drag(p, rho, l, r0, r1, r2, ex, ey, ez):
    """Drag Eq (10)-(11) on the velocity r relative to the fluid of density rho: normal
    part 1/2 rho D l C_D |r_n| r_n, tangential 1/2 rho D l C_f tfac |u| u. Returns the force
    and its Jacobian dF/dV (entries 00, 11, 22, 01, 02, 12), which is treated implicitly."""
    u = r0 * ex + r1 * ey + r2 * ez
    n0 = r0 - u * ex
    n1 = r1 - u * ey
    n2 = r2 - u * ez
    sn = math.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
    cn = 0.5 * rho * p.D * l * p.Cd
    ct = 0.5 * rho * p.D * l * p.Cf * p.tfac
    cs = cn * sn
    ca = ct * abs(u)
    k2 = 2.0 * ca
    k3 = cn / sn if sn > 1e-12 else 0.0
    return (-cs * n0 - ca * u * ex, -cs * n1 - ca * u * ey, -cs * n2 - ca * u * ez,
            -cs * (1.0 - ex * ex) - k2 * ex * ex - k3 * n0 * n0,
            -cs * (1.0 - ey * ey) - k2 * ey * ey - k3 * n1 * n1,
            -cs * (1.0 - ez * ez) - k2 * ez * ez - k3 * n2 * n2,
            cs * ex * ey - k2 * ex * ey - k3 * n0 * n1,
            cs * ex * ez - k2 * ex * ez - k3 * n0 * n2,
            cs * ey * ez - k2 * ey * ez - k3 * n1 * n2)


@njit(cache=True, inline="always", fastmath=FMA)
def _wave_inertia(p, vol, fr, a0, a1, a2, ex, ey, ez):
    """Inertia term of Morison's equation (Morison et al. 1950; DNV-RP-C205 6.2) for the wave
    particle acceleration a at the element: Froude-Krylov plus added mass on the normal part,
    rho Vol f (1 + C_a) a_n, and Froude-Krylov alone on the tangential part, rho Vol f a_t (the
    model's axial added mass m_x ~ 0, Eq 9). The reaction of the added mass to the element's
    own acceleration, -C_a rho Vol f dV_n/dt, is the mass matrix's M_A (Eq 9). f: the immersed
    fraction."""
    at = a0 * ex + a1 * ey + a2 * ez
    c = p.rho_w * vol * fr
    cn = c * (1.0 + p.Ca)
    return (cn * (a0 - at * ex) + c * at * ex, cn * (a1 - at * ey) + c * at * ey,
            cn * (a2 - at * ez) + c * at * ez)


@njit(cache=True, inline="always", fastmath=FMA)
def _fluid_inertia_forces(ma, r0, r1, r2, ue, ex, ey, ez, wx, wy, wz):
    """Fluid Coriolis force C_A of Eq (8) in world form, -(dM_A/dt) V_r with dE/dt = W x E,
    and the Munk moment of Eq (8) rows 4-5, (m_z - m_x) w u, (m_x - m_y) u v. r: velocity
    relative to the current, ue = r.e. Returns the force and the moment."""
    ed0 = wy * ez - wz * ey
    ed1 = wz * ex - wx * ez
    ed2 = wx * ey - wy * ex
    ued = r0 * ed0 + r1 * ed1 + r2 * ed2
    return (ma * (ed0 * ue + ex * ued), ma * (ed1 * ue + ey * ued), ma * (ed2 * ue + ez * ued),
            ma * ue * (r1 * ez - r2 * ey), ma * ue * (r2 * ex - r0 * ez),
            ma * ue * (r0 * ey - r1 * ex))


@njit(cache=True, inline="always", fastmath=FMA)
def _water_entry_impact(mdot, rot_fac, r0, r1, r2, ue, ex, ey, ez, wx, wy, wz):
    """Water entry, Eq (14): H = -dm_a/dt * v_normal (mdot > 0: entering), and its moment
    -dJ/dt W. Returns the force, its Jacobian dF/dV (00, 11, 22, 01, 02, 12), the moment and
    its Jacobian on the rotations."""
    jdot = mdot * rot_fac
    return (-mdot * (r0 - ue * ex), -mdot * (r1 - ue * ey), -mdot * (r2 - ue * ez),
            -mdot * (1.0 - ex * ex), -mdot * (1.0 - ey * ey), -mdot * (1.0 - ez * ez),
            mdot * ex * ey, mdot * ex * ez, mdot * ey * ez,
            -jdot * wx, -jdot * wy, -jdot * wz, -jdot)


@njit(cache=True, inline="always", fastmath=FMA)
def _relaxation_forces(relax, m00, m11, m22, m01, m02, m12, Ip, vx, vy, vz, wx, wy, wz):
    """Numerical relaxation (0 in normal use, speeds up settling): -relax * M nu. Returns
    the force, its Jacobian (00, 11, 22, 01, 02, 12), the moment and its Jacobian."""
    return (-relax * (m00 * vx + m01 * vy + m02 * vz),
            -relax * (m01 * vx + m11 * vy + m12 * vz),
            -relax * (m02 * vx + m12 * vy + m22 * vz),
            -relax * m00, -relax * m11, -relax * m22, -relax * m01, -relax * m02, -relax * m12,
            -relax * Ip * wx, -relax * Ip * wy, -relax * Ip * wz, -relax * Ip)


@njit(cache=True, inline="always")
def _element_state(S, j):
    """Length, centre height, axis e, velocity V and angular velocity W of element j, the
    current and wind at its centre (the per-element part of the current) and the waves there
    (particle velocity, acceleration, surface elevation)."""
    return (S[j, SL], S[j, SX + 2], S[j, SE], S[j, SE + 1], S[j, SE + 2], S[j, SV], S[j, SV + 1],
            S[j, SV + 2], S[j, SW], S[j, SW + 1], S[j, SW + 2], S[j, SCUR], S[j, SCUR + 1],
            S[j, SCUR + 2], S[j, SWIND], S[j, SWIND + 1], S[j, SWIND + 2], S[j, SWV],
            S[j, SWV + 1], S[j, SWV + 2], S[j, SWA], S[j, SWA + 1], S[j, SWA + 2], S[j, SETA])


@njit(cache=True, inline="always", fastmath=FMA)
def _element_terms(state, p):
    """Element part of the system for one element (state from _element_state): the forces
    of Eq (1) on the element itself (gravity, buoyancy, drag, fluid Coriolis and Munk,
    water entry, relaxation) and their velocity Jacobian C. Returns its basis b1, b2, the
    right-hand side h f (5) and the upper triangle of M - h theta C: entries 00, 11, 22,
    01, 02, 12 and 33 = 44 (no translation-rotation coupling, 34 = 0)."""
    (l, z, ex, ey, ez, vx, vy, vz, wx, wy, wz, uc0, uc1, uc2, ua0, ua1, ua2, uw0, uw1, uw2,
     aw0, aw1, aw2, eta) = state
    # water velocity at the element: the uniform current plus the element's own (a sampled
    # field) plus the wave particles' (zero on a calm sea: adding 0.0 changes no bit)
    uc0 += p.cur0 + uw0
    uc1 += p.cur1 + uw1
    uc2 += p.cur2 + uw2
    p0, p1, p2, q0, q1, q2 = _basis(ex, ey, ez)
    # immersion against the local surface eta (a horizontal plane at the element: the wave
    # slope k a, at most about 0.3 before breaking, is neglected across the element's section)
    fr, dfr, m1 = immersion(z - eta, ez, 0.5 * l, p.radius)
    m, vol, ma, rot_fac, Ip = _element_inertia(p, l, fr)
    m00, m11, m22, m01, m02, m12 = _mass_matrix(m, ma, ex, ey, ez)
    # force F, moment t and the velocity Jacobian C (symmetric) of the element forces
    c00 = c01 = c02 = c11 = c12 = c22 = crot = 0.0
    F0 = 0.0
    F1 = 0.0
    F2, t0, t1 = _gravity_and_buoyancy(p, m, vol, fr, m1, ex, ey)
    t2 = 0.0
    if fr > 0.0 and (aw0 != 0.0 or aw1 != 0.0 or aw2 != 0.0):  # Morison's wave inertia
        # (a calm sea has no acceleration: skipped, the calm path's arithmetic unchanged)
        d0, d1, d2 = _wave_inertia(p, vol, fr, aw0, aw1, aw2, ex, ey, ez)
        F0 += d0
        F1 += d1
        F2 += d2
    for part in range(2):  # water part on the velocity relative to the current, air part
        if part == 0:  # relative to the wind
            rho = p.rho_w * fr
            r0 = vx - uc0
            r1 = vy - uc1
            r2 = vz - uc2
        else:
            rho = p.rho_a * (1.0 - fr)
            r0 = vx - ua0
            r1 = vy - ua1
            r2 = vz - ua2
        if rho <= 0.0:
            continue
        d0, d1, d2, e00, e11, e22, e01, e02, e12 = _morison_drag(p, rho, l, r0, r1, r2, ex, ey, ez)
        F0 += d0
        F1 += d1
        F2 += d2
        c00 += e00
        c11 += e11
        c22 += e22
        c01 += e01
        c02 += e02
        c12 += e12
    r0 = vx - uc0
    r1 = vy - uc1
    r2 = vz - uc2
    ue = r0 * ex + r1 * ey + r2 * ez
    d0, d1, d2, u0, u1, u2 = _fluid_inertia_forces(ma, r0, r1, r2, ue, ex, ey, ez, wx, wy, wz)
    F0 += d0
    F1 += d1
    F2 += d2
    t0 += u0
    t1 += u1
    t2 += u2
    # rate of immersion: the element's vertical speed relative to the surface's, which is the
    # wave particles' vertical speed there (linear theory: w = d eta / dt at the surface)
    mdot = p.Ca * p.rho_w * vol * dfr * (vz - uw2)
    if mdot > 0.0:
        (d0, d1, d2, e00, e11, e22, e01, e02, e12, u0, u1, u2,
         erot) = _water_entry_impact(mdot, rot_fac, r0, r1, r2, ue, ex, ey, ez, wx, wy, wz)
        F0 += d0
        F1 += d1
        F2 += d2
        c00 += e00
        c11 += e11
        c22 += e22
        c01 += e01
        c02 += e02
        c12 += e12
        t0 += u0
        t1 += u1
        t2 += u2
        crot += erot
    if p.relax > 0.0:
        (d0, d1, d2, e00, e11, e22, e01, e02, e12, u0, u1, u2,
         erot) = _relaxation_forces(p.relax, m00, m11, m22, m01, m02, m12, Ip, vx, vy, vz, wx,
                                    wy, wz)
        F0 += d0
        F1 += d1
        F2 += d2
        c00 += e00
        c01 += e01
        c02 += e02
        c11 += e11
        c12 += e12
        c22 += e22
        t0 += u0
        t1 += u1
        t2 += u2
        crot += erot
    h = p.h
    hth = p.hth
    return (p0, p1, p2, q0, q1, q2,
            h * F0, h * F1, h * F2, h * (t0 * p0 + t1 * p1 + t2 * p2),
            h * (t0 * q0 + t1 * q1 + t2 * q2),
            m00 - hth * c00, m11 - hth * c11, m22 - hth * c22, m01 - hth * c01, m02 - hth * c02,
            m12 - hth * c12, Ip - hth * crot)


@njit(cache=True, inline="always")
def _store_element(Ad, rhs, B1, B2, j, terms):
    """Writes _element_terms into B1[j], B2[j], rhs[j] and Ad[j] (upper triangle: Ad is
    symmetric, only that part is written and read)."""
    (B1[j, 0], B1[j, 1], B1[j, 2], B2[j, 0], B2[j, 1], B2[j, 2],
     rhs[j, 0], rhs[j, 1], rhs[j, 2], rhs[j, 3], rhs[j, 4],
     Ad[j, 0, 0], Ad[j, 1, 1], Ad[j, 2, 2], Ad[j, 0, 1], Ad[j, 0, 2], Ad[j, 1, 2],
     Ad[j, 3, 3]) = terms
    Ad[j, 4, 4] = Ad[j, 3, 3]
    Ad[j, 3, 4] = 0.0
    Ad[j, 0, 3] = Ad[j, 1, 3] = Ad[j, 2, 3] = 0.0
    Ad[j, 0, 4] = Ad[j, 1, 4] = Ad[j, 2, 4] = 0.0


# ------------------------------------------------------------------ seabed contact
@njit(cache=True, inline="always")
def _contact_state(S, j):
    """Element j for the seabed contact: length, centre, axis, V, W and the seabed depth."""
    return (S[j, SL], S[j, SX], S[j, SX + 1], S[j, SX + 2], S[j, SE], S[j, SE + 1],
            S[j, SE + 2], S[j, SV], S[j, SV + 1], S[j, SV + 2], S[j, SW], S[j, SW + 1],
            S[j, SW + 2], S[j, SDEPTH])


@njit(cache=True, inline="always", fastmath=FMA)
def _seabed_in_reach(p, l, z, ez, depth):
    """True if the underside of either end of the element is below the seabed (z < -depth;
    depth inf: no seabed, never)."""
    return z - 0.5 * l * abs(ez) - p.radius < -depth


@njit(cache=True, inline="always", fastmath=FMA)
def _seabed_point(p, s, lc, depth, z, ex, ey, ez, vx, vy, vz, wx, wy, wz, b10, b11, b12, b20,
                  b21, b22):
    """Seabed contact at the point at lever s on the element axis (an end, s = +-l/2), which
    stands for the contact length lc; MoorDyn's seabed model. Normal force on the underside
    penetration pen (the point's height minus the radius below z = -depth): D lc (kbot pen -
    cbot v_z) while pen > 0. Coulomb friction on the slip velocity of the point along the
    seabed, separately along (a: the horizontal part of the axis) and across (t) the
    element: -mu N u / max(|u|, v_slip), i.e. min(mu N, mu N |u| / v_slip) against u.

    Returns its terms of the element's system (right-hand side 5, upper triangle of the 5x5
    block 15): rhs += J^T (h F + h^2 K v_p), Ad += J^T (-h C - h^2 theta K) J with
    J = [I | -s b2 | s b1] the point's Jacobian (the force at the end of the sub-step, see
    below). K is the normal spring (vertical);
    C the normal damper and, for the friction, its secant mu N / max(|u|, v_slip) along a
    and t (the exact tangent is zero while sliding, which lets a sliding element overshoot
    to the opposite slip and chatter by mu g h per sub-step; the secant makes it converge
    monotonically). The friction's dependence on N (position, vertical velocity) and the
    geometric stiffness of the contact moment are explicit."""
    zero = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
            0.0, 0.0, 0.0)
    pz = z + s * ez
    pen = -depth - (pz - p.radius)
    if not pen > 0.0:
        return zero
    # velocity of the point: V + W x (s e)
    a0 = s * ex
    a1 = s * ey
    a2 = s * ez
    u0 = vx + (wy * a2 - wz * a1)
    u1 = vy + (wz * a0 - wx * a2)
    u2 = vz + (wx * a1 - wy * a0)
    kn = p.kbot * p.D * lc
    cn = p.cbot * p.D * lc
    fn = kn * pen - cn * u2  # as MoorDyn: the damper may pull while the point penetrates
    nf = max(fn, 0.0)  # the normal load of the friction
    # horizontal axis a and across t = z x a
    eh = math.sqrt(ex * ex + ey * ey)
    if eh > 1e-9:
        ax = ex / eh
        ay = ey / eh
    else:  # a vertical element standing on its end: no axis along the seabed
        ax = 1.0
        ay = 0.0
    tx = -ay
    ty = ax
    ua = u0 * ax + u1 * ay
    ut = u0 * tx + u1 * ty
    mu_a = p.mu_ax if eh > 1e-9 else p.mu_tr
    ca = mu_a * nf / max(abs(ua), p.vslip)  # secant: friction = -ca ua along a
    ct = p.mu_tr * nf / max(abs(ut), p.vslip)
    F0 = -(ca * ua) * ax - (ct * ut) * tx
    F1 = -(ca * ua) * ay - (ct * ut) * ty
    F2 = fn
    # The contact force is taken at the end of the sub-step (backward Euler), not at the
    # theta point: f(q_n + h (nu + theta dnu), nu + dnu) ~ f + h K nu + (C + h theta K) dnu,
    # i.e. Q = h F + h^2 K v_p (K = -kn z z^T) and the matrix Sm = -h C - h^2 theta K.
    # The contact modes are stiff (kbot: omega h ~ 1-10) and heavily damped; at theta = 0.55
    # their amplification tends to -(1 - theta) / theta = -0.82 per sub-step, and the
    # velocity flipping sign every sub-step made the friction and the lift-off chatter.
    # Backward Euler damps them monotonically; the static state is the same.
    h = p.h
    h2t = h * p.hth
    Q0 = h * F0
    Q1 = h * F1
    Q2 = h * F2 - h * h * kn * u2
    s00 = h * (ca * ax * ax + ct * tx * tx)
    s01 = h * (ca * ax * ay + ct * tx * ty)
    s11 = h * (ca * ay * ay + ct * ty * ty)
    s22 = h * cn + h2t * kn
    # J^T Q and J^T Sm J, J = [I | -s b2 | s b1]
    m0b1 = s00 * b10 + s01 * b11  # Sm b1
    m1b1 = s01 * b10 + s11 * b11
    m2b1 = s22 * b12
    m0b2 = s00 * b20 + s01 * b21  # Sm b2
    m1b2 = s01 * b20 + s11 * b21
    m2b2 = s22 * b22
    ss = s * s
    return (Q0, Q1, Q2, -s * (b20 * Q0 + b21 * Q1 + b22 * Q2), s * (b10 * Q0 + b11 * Q1 + b12 * Q2),
            s00, s01, 0.0, -s * m0b2, s * m0b1,
            s11, 0.0, -s * m1b2, s * m1b1,
            s22, -s * m2b2, s * m2b1,
            ss * (b20 * m0b2 + b21 * m1b2 + b22 * m2b2),
            -ss * (b20 * m0b1 + b21 * m1b1 + b22 * m2b1),
            ss * (b10 * m0b1 + b11 * m1b1 + b12 * m2b1))


@njit(cache=True, inline="always", fastmath=FMA)
def _seabed_terms(state, b, p):
    """Seabed contact of one element (state from _contact_state, b its basis b1, b2): the
    two ends, each standing for half the element (MoorDyn's nodes). Returns the sum of the
    _seabed_point terms (rhs 5, upper triangle 15)."""
    l, x, y, z, ex, ey, ez, vx, vy, vz, wx, wy, wz, depth = state
    b10, b11, b12, b20, b21, b22 = b
    t = _seabed_point(p, 0.5 * l, 0.5 * l, depth, z, ex, ey, ez, vx, vy, vz, wx, wy, wz, b10,
                      b11, b12, b20, b21, b22)
    u = _seabed_point(p, -0.5 * l, 0.5 * l, depth, z, ex, ey, ez, vx, vy, vz, wx, wy, wz, b10,
                      b11, b12, b20, b21, b22)
    return (t[0] + u[0], t[1] + u[1], t[2] + u[2], t[3] + u[3], t[4] + u[4], t[5] + u[5],
            t[6] + u[6], t[7] + u[7], t[8] + u[8], t[9] + u[9], t[10] + u[10], t[11] + u[11],
            t[12] + u[12], t[13] + u[13], t[14] + u[14], t[15] + u[15], t[16] + u[16],
            t[17] + u[17], t[18] + u[18], t[19] + u[19])


@njit(cache=True, inline="always")
def _add_seabed(Ad, rhs, j, terms):
    """Adds _seabed_terms to rhs[j] and the upper triangle of Ad[j]."""
    (r0, r1, r2, r3, r4, a00, a01, a02, a03, a04, a11, a12, a13, a14, a22, a23, a24, a33, a34,
     a44) = terms
    rhs[j, 0] += r0
    rhs[j, 1] += r1
    rhs[j, 2] += r2
    rhs[j, 3] += r3
    rhs[j, 4] += r4
    Ad[j, 0, 0] += a00
    Ad[j, 0, 1] += a01
    Ad[j, 0, 2] += a02
    Ad[j, 0, 3] += a03
    Ad[j, 0, 4] += a04
    Ad[j, 1, 1] += a11
    Ad[j, 1, 2] += a12
    Ad[j, 1, 3] += a13
    Ad[j, 1, 4] += a14
    Ad[j, 2, 2] += a22
    Ad[j, 2, 3] += a23
    Ad[j, 2, 4] += a24
    Ad[j, 3, 3] += a33
    Ad[j, 3, 4] += a34
    Ad[j, 4, 4] += a44


# ------------------------------------------------------------------ connections, Eq (15)-(26)
@njit(cache=True, inline="always", fastmath=FMA)
def _element_end_point(S, j, s):
    """Point at lever s on the axis of element j (front s = l/2, aft s = -l/2), R + C r of
    Eq (20): position R + s e and velocity V + W x (s e)."""
    a0 = s * S[j, SE]
    a1 = s * S[j, SE + 1]
    a2 = s * S[j, SE + 2]
    return ((S[j, SX] + a0, S[j, SX + 1] + a1, S[j, SX + 2] + a2),
            (S[j, SV] + (S[j, SW + 1] * a2 - S[j, SW + 2] * a1),
             S[j, SV + 1] + (S[j, SW + 2] * a0 - S[j, SW] * a2),
             S[j, SV + 2] + (S[j, SW] * a1 - S[j, SW + 1] * a0)))


@njit(cache=True, inline="always", fastmath=FMA)
def _attachment_point(io, end, t):
    """Attachment a (end 0) or b (end 1) at time t into the call: pos + vel t, vel."""
    v0 = io[IO_VEL + end, 0]
    v1 = io[IO_VEL + end, 1]
    v2 = io[IO_VEL + end, 2]
    return ((io[IO_POS + end, 0] + v0 * t, io[IO_POS + end, 1] + v1 * t,
             io[IO_POS + end, 2] + v2 * t), (v0, v1, v2))


@njit(cache=True, inline="always", fastmath=FMA)
def _drum_sliding(S, Vp, Pn, Vn, payout_a, t):
    """Winch at end a (drum connection c = 0): rope slides through the drum at the pay-out
    rate, and the drum end of element 0 extends (retracts) along it during the call;
    winch.Winch.wind then grows (shrinks) the element by that length, so the drum connection
    never sees the flow of rope. Returns g (the next point's velocity relative to the
    attachment without the sliding, J nu) and the next point moved on by the sliding."""
    e0 = S[0, SE]
    e1 = S[0, SE + 1]
    e2 = S[0, SE + 2]
    g = (Vn[0] - (Vp[0] - payout_a * e0), Vn[1] - (Vp[1] - payout_a * e1),
         Vn[2] - (Vp[2] - payout_a * e2))
    Pn = (Pn[0] + payout_a * t * e0, Pn[1] + payout_a * t * e1, Pn[2] + payout_a * t * e2)
    Vn = (Vn[0] + payout_a * e0, Vn[1] + payout_a * e1, Vn[2] + payout_a * e2)
    return g, Pn, Vn


@njit(cache=True, inline="always", fastmath=FMA)
def _connection_points(S, io, c, N, t, payout_a):
    """The two points connection c joins: prev = aft point of element c - 1 (attachment a
    when c = 0), next = front point of element c (attachment b when c = N). Returns their
    levers si, sk (0 at an attachment), positions and velocities, and g, the velocity of the
    next point relative to the prev one without the pay-out sliding (J nu)."""
    si = 0.0
    sk = 0.0
    if c > 0:
        si = -0.5 * S[c - 1, SL]
        Pp, Vp = _element_end_point(S, c - 1, si)
    else:
        Pp, Vp = _attachment_point(io, 0, t)
    if c < N:
        sk = 0.5 * S[c, SL]
        Pn, Vn = _element_end_point(S, c, sk)
    else:
        Pn, Vn = _attachment_point(io, 1, t)
    if c > 0:
        g = (Vn[0] - Vp[0], Vn[1] - Vp[1], Vn[2] - Vp[2])
    else:
        g, Pn, Vn = _drum_sliding(S, Vp, Pn, Vn, payout_a, t)
    return si, sk, Pp, Vp, Pn, Vn, g


@njit(cache=True, inline="always", fastmath=FMA)
def _bending_damper(S, Ad, rhs, i, k, cm, bi, bk, h, hth):
    """Rotational damper c_m of Eq (15), (18)-(19) on the relative angular velocity of
    elements i and k: its torque into rhs, its Jacobian into Ad; returns the rotation block
    of the coupling Ao[i] (d torque_i / d w_k = cm B_i^T B_k): 33, 34, 43, 44."""
    i10, i11, i12, i20, i21, i22 = bi
    k10, k11, k12, k20, k21, k22 = bk
    dw0 = S[i, SW] - S[k, SW]
    dw1 = S[i, SW + 1] - S[k, SW + 1]
    dw2 = S[i, SW + 2] - S[k, SW + 2]
    v = h * cm
    rhs[k, 3] += v * (dw0 * k10 + dw1 * k11 + dw2 * k12)
    rhs[k, 4] += v * (dw0 * k20 + dw1 * k21 + dw2 * k22)
    rhs[i, 3] -= v * (dw0 * i10 + dw1 * i11 + dw2 * i12)
    rhs[i, 4] -= v * (dw0 * i20 + dw1 * i21 + dw2 * i22)
    v = hth * cm
    Ad[k, 3, 3] += v
    Ad[k, 4, 4] += v
    Ad[i, 3, 3] += v
    Ad[i, 4, 4] += v
    return (-v * (i10 * k10 + i11 * k11 + i12 * k12), -v * (i10 * k20 + i11 * k21 + i12 * k22),
            -v * (i20 * k10 + i21 * k11 + i22 * k12), -v * (i20 * k20 + i21 * k21 + i22 * k22))


@njit(cache=True, inline="always", fastmath=FMA)
def _point_inside_neighbour(S, c, N, Pp, Pn):
    """Eq (25)-(26): one point of connection c within half a length of the other element's
    centre (the all-or-nothing switch, used only with STRICT_EQ25)."""
    if c > 0 and math.sqrt((Pn[0] - S[c - 1, SX]) ** 2 + (Pn[1] - S[c - 1, SX + 1]) ** 2
                           + (Pn[2] - S[c - 1, SX + 2]) ** 2) <= 0.5 * S[c - 1, SL]:
        return True
    return c < N and math.sqrt((Pp[0] - S[c, SX]) ** 2 + (Pp[1] - S[c, SX + 1]) ** 2
                               + (Pp[2] - S[c, SX + 2]) ** 2) <= 0.5 * S[c, SL]


@njit(cache=True, inline="always", fastmath=FMA)
def _rope_axis(S, c, N, Pp, Pn):
    """Local rope axis n at connection c: the mean of the adjacent element axes, or the gap
    direction where the links fold back on themselves."""
    i = max(c - 1, 0)  # rows read before branching (numba then counts no references)
    k = min(c, N - 1)
    ei0, ei1, ei2, ek0, ek1, ek2 = (S[i, SE], S[i, SE + 1], S[i, SE + 2], S[k, SE], S[k, SE + 1],
                                    S[k, SE + 2])
    n0 = 0.0
    n1 = 0.0
    n2 = 0.0
    if c > 0:
        n0 += ei0
        n1 += ei1
        n2 += ei2
    if c < N:
        n0 += ek0
        n1 += ek1
        n2 += ek2
    nn = math.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
    if nn < 1e-9:  # folded back on itself: use the gap direction
        n0 = Pp[0] - Pn[0]
        n1 = Pp[1] - Pn[1]
        n2 = Pp[2] - Pn[2]
        nn = math.sqrt(n0 * n0 + n1 * n1 + n2 * n2) + 1e-300
    return n0 / nn, n1 / nn, n2 / nn


@njit(cache=True, inline="always", fastmath=FMA)
def _tension_only_spring_damper(kc, cax, ctr, Pp, Pn, Vp, Vn, n):
    """Force on the next point: spring k (Pp - Pn) (Eq 21-22) plus the axial and transverse
    dampers c_x, c_t on the relative velocity (Eq 15-17). A rope cannot push: a compressive
    axial part is removed, the continuous form of the slack switch of Eq (25). Returns the
    force, its magnitude (the tension) and the axial damping it carries (c_x or 0)."""
    n0, n1, n2 = n
    dv0 = Vp[0] - Vn[0]
    dv1 = Vp[1] - Vn[1]
    dv2 = Vp[2] - Vn[2]
    ndv = n0 * dv0 + n1 * dv1 + n2 * dv2
    F0 = kc * (Pp[0] - Pn[0]) + cax * n0 * ndv + ctr * (dv0 - n0 * ndv)
    F1 = kc * (Pp[1] - Pn[1]) + cax * n1 * ndv + ctr * (dv1 - n1 * ndv)
    F2 = kc * (Pp[2] - Pn[2]) + cax * n2 * ndv + ctr * (dv2 - n2 * ndv)
    ax = F0 * n0 + F1 * n1 + F2 * n2
    axd = cax
    if ax < 0.0:  # a rope cannot push: drop the compressive axial part
        F0 -= ax * n0
        F1 -= ax * n1
        F2 -= ax * n2
        axd = 0.0
    return F0, F1, F2, math.sqrt(F0 * F0 + F1 * F1 + F2 * F2), axd


@njit(cache=True, inline="always", fastmath=FMA)
def _jsj(s, b10, b11, b12, b20, b21, b22, beta, gamma, n0, n1, n2):
    """Upper triangle (row by row) of J^T S J for a connection point at lever s on an
    element with basis (b1, b2): J = [I | -s b2 | s b1] (dP = J dq), S = beta I + gamma n n^T."""
    nb1 = n0 * b10 + n1 * b11 + n2 * b12
    nb2 = n0 * b20 + n1 * b21 + n2 * b22
    ss = s * s
    return (beta + gamma * n0 * n0, gamma * n0 * n1, gamma * n0 * n2,
            -s * (beta * b20 + gamma * n0 * nb2), s * (beta * b10 + gamma * n0 * nb1),
            beta + gamma * n1 * n1, gamma * n1 * n2,
            -s * (beta * b21 + gamma * n1 * nb2), s * (beta * b11 + gamma * n1 * nb1),
            beta + gamma * n2 * n2,
            -s * (beta * b22 + gamma * n2 * nb2), s * (beta * b12 + gamma * n2 * nb1),
            ss * (beta + gamma * nb2 * nb2), -ss * gamma * nb2 * nb1,
            ss * (beta + gamma * nb1 * nb1))


@njit(cache=True, inline="always", fastmath=FMA)
def _add_connection_to_element(S, Ad, rhs, j, s, sg, b, Q, Fc, n, beta, gamma, h2t, h2t2):
    """Terms of a connection point at lever s on element j (sg = +1: the next point, -1:
    the prev one): rhs += sg J^T Q (the tension and its moment, Eq 24), Ad += J^T S J; and
    the geometric stiffness of the moment of the end force, -l/2 F.e on both rotations
    (K), entering rhs with the angular velocity (nu) and Ad."""
    b10, b11, b12, b20, b21, b22 = b
    Q0, Q1, Q2 = Q
    F0, F1, F2 = Fc
    n0, n1, n2 = n
    geo = -0.5 * S[j, SL] * (F0 * S[j, SE] + F1 * S[j, SE + 1] + F2 * S[j, SE + 2])
    rhs[j, 0] += sg * Q0
    rhs[j, 1] += sg * Q1
    rhs[j, 2] += sg * Q2
    rhs[j, 3] += sg * (-s * (b20 * Q0 + b21 * Q1 + b22 * Q2)) + h2t * geo * (
        S[j, SW] * b10 + S[j, SW + 1] * b11 + S[j, SW + 2] * b12)
    rhs[j, 4] += sg * (s * (b10 * Q0 + b11 * Q1 + b12 * Q2)) + h2t * geo * (
        S[j, SW] * b20 + S[j, SW + 1] * b21 + S[j, SW + 2] * b22)
    (v00, v01, v02, v03, v04, v11, v12, v13, v14, v22, v23, v24, v33, v34,
     v44) = _jsj(s, b10, b11, b12, b20, b21, b22, beta, gamma, n0, n1, n2)
    Ad[j, 0, 0] += v00
    Ad[j, 0, 1] += v01
    Ad[j, 0, 2] += v02
    Ad[j, 0, 3] += v03
    Ad[j, 0, 4] += v04
    Ad[j, 1, 1] += v11
    Ad[j, 1, 2] += v12
    Ad[j, 1, 3] += v13
    Ad[j, 1, 4] += v14
    Ad[j, 2, 2] += v22
    Ad[j, 2, 3] += v23
    Ad[j, 2, 4] += v24
    Ad[j, 3, 3] += v33 - h2t2 * geo
    Ad[j, 3, 4] += v34
    Ad[j, 4, 4] += v44 - h2t2 * geo


@njit(cache=True, inline="always", fastmath=FMA)
def _add_connection_to_elements(S, Ad, rhs, c, N, si, sk, bi, bk, Q, Fc, n, beta, gamma, h2t,
                                h2t2):
    """_add_connection_to_element for the next point of connection c (on element c) and
    its prev point (on element c - 1), where they are elements."""
    i10, i11, i12, i20, i21, i22 = bi
    k10, k11, k12, k20, k21, k22 = bk
    for side in range(2):
        if side == 0:
            if c >= N:
                continue
            j, s, sg = c, sk, 1.0
            b10, b11, b12, b20, b21, b22 = k10, k11, k12, k20, k21, k22
        else:
            if c == 0:
                continue
            j, s, sg = c - 1, si, -1.0
            b10, b11, b12, b20, b21, b22 = i10, i11, i12, i20, i21, i22
        _add_connection_to_element(S, Ad, rhs, j, s, sg, (b10, b11, b12, b20, b21, b22), Q, Fc,
                                   n, beta, gamma, h2t, h2t2)


@njit(cache=True, inline="always")
def _set_vec3(a, row, x, y, z):
    a[row, 0] = x
    a[row, 1] = y
    a[row, 2] = z


@njit(cache=True, inline="always")
def _set_rotation_block(Ao, i, a33, a34, a43, a44):
    Ao[i, 3, 3] = a33
    Ao[i, 3, 4] = a34
    Ao[i, 4, 3] = a43
    Ao[i, 4, 4] = a44


@njit(cache=True, inline="always")
def _clear_block(Ao, i):
    for a in range(5):
        for q in range(5):
            Ao[i, a, q] = 0.0


@njit(cache=True, inline="always", fastmath=FMA)
def _coupling_block(Ao, i, si, sk, bi, bk, n, beta, gamma, bo):
    """Ao[i], the block coupling elements i and k = i + 1 through connection i + 1:
    bending damper part bo minus Jp^T S Jn (Jp at the aft point of i, Jn at the front of k)."""
    i10, i11, i12, i20, i21, i22 = bi
    k10, k11, k12, k20, k21, k22 = bk
    n0, n1, n2 = n
    nk1 = n0 * k10 + n1 * k11 + n2 * k12
    nk2 = n0 * k20 + n1 * k21 + n2 * k22
    ni1 = n0 * i10 + n1 * i11 + n2 * i12
    ni2 = n0 * i20 + n1 * i21 + n2 * i22
    Ao[i, 0, 0] = -(beta + gamma * n0 * n0)
    Ao[i, 1, 1] = -(beta + gamma * n1 * n1)
    Ao[i, 2, 2] = -(beta + gamma * n2 * n2)
    Ao[i, 0, 1] = Ao[i, 1, 0] = -(gamma * n0 * n1)
    Ao[i, 0, 2] = Ao[i, 2, 0] = -(gamma * n0 * n2)
    Ao[i, 1, 2] = Ao[i, 2, 1] = -(gamma * n1 * n2)
    Ao[i, 0, 3] = sk * (beta * k20 + gamma * n0 * nk2)
    Ao[i, 1, 3] = sk * (beta * k21 + gamma * n1 * nk2)
    Ao[i, 2, 3] = sk * (beta * k22 + gamma * n2 * nk2)
    Ao[i, 0, 4] = -sk * (beta * k10 + gamma * n0 * nk1)
    Ao[i, 1, 4] = -sk * (beta * k11 + gamma * n1 * nk1)
    Ao[i, 2, 4] = -sk * (beta * k12 + gamma * n2 * nk1)
    Ao[i, 3, 0] = si * (beta * i20 + gamma * ni2 * n0)
    Ao[i, 3, 1] = si * (beta * i21 + gamma * ni2 * n1)
    Ao[i, 3, 2] = si * (beta * i22 + gamma * ni2 * n2)
    Ao[i, 4, 0] = -si * (beta * i10 + gamma * ni1 * n0)
    Ao[i, 4, 1] = -si * (beta * i11 + gamma * ni1 * n1)
    Ao[i, 4, 2] = -si * (beta * i12 + gamma * ni1 * n2)
    ss = si * sk
    d11 = i10 * k10 + i11 * k11 + i12 * k12  # b_x of i . b_y of k
    d12 = i10 * k20 + i11 * k21 + i12 * k22
    d21 = i20 * k10 + i21 * k11 + i22 * k12
    d22 = i20 * k20 + i21 * k21 + i22 * k22
    Ao[i, 3, 3] = bo[0] - ss * (beta * d22 + gamma * ni2 * nk2)
    Ao[i, 3, 4] = bo[1] + ss * (beta * d21 + gamma * ni2 * nk1)
    Ao[i, 4, 3] = bo[2] + ss * (beta * d12 + gamma * ni1 * nk2)
    Ao[i, 4, 4] = bo[3] - ss * (beta * d11 + gamma * ni1 * nk1)


# ------------------------------------------------------------------ parting
@njit(cache=True, inline="always", fastmath=FMA)
def _elastic_tension(kc, Pp, Pn, n):
    """Elastic part of a connection's tension, EA x strain along the rope, k (Pp - Pn).n
    (see PART_MIN_ELASTIC)."""
    return kc * ((Pp[0] - Pn[0]) * n[0] + (Pp[1] - Pn[1]) * n[1] + (Pp[2] - Pn[2]) * n[2])


@njit(cache=True)
def _part(best_c, best_T, t, N, S, F, io):
    """The rope parts at the most overloaded connection only; the others that carry the
    same overload survived it (they are disarmed until they unload)."""
    F[best_c, F_OK] = 0
    ne = int(io[IO_NEV])
    if ne < N_EVENTS_MAX:
        io[IO_EVENTS + ne, 0] = t
        io[IO_EVENTS + ne, 1] = best_c
        io[IO_EVENTS + ne, 2] = best_T
    io[IO_NEV] = ne + 1
    for c in range(N + 1):
        if S[c, ST] > S[c, SB]:
            F[c, F_ARMED] = 0


# ------------------------------------------------------------------ block tri-diagonal solve
@njit(cache=True, inline="always", fastmath=FMA)
def _ldl5(a00, a01, a02, a03, a04, a11, a12, a13, a14, a22, a23, a24, a33, a34, a44):
    """L diag L^T of a symmetric 5x5 (upper triangle a). Returns ok (every pivot > 0: the
    matrix is positive definite and the factorisation needs no pivoting), the inverse
    pivots and the factors below the unit diagonal."""
    i0 = i1 = i2 = i3 = i4 = 0.0
    l10 = l20 = l30 = l40 = l21 = l31 = l41 = l32 = l42 = l43 = 0.0
    ok = a00 > 0.0
    if ok:
        i0 = 1.0 / a00
        l10 = a01 * i0
        l20 = a02 * i0
        l30 = a03 * i0
        l40 = a04 * i0
        u11 = a11 - l10 * a01
        ok = u11 > 0.0
        if ok:
            i1 = 1.0 / u11
            u12 = a12 - l10 * a02
            u13 = a13 - l10 * a03
            u14 = a14 - l10 * a04
            l21 = u12 * i1
            l31 = u13 * i1
            l41 = u14 * i1
            u22 = a22 - l20 * a02 - l21 * u12
            ok = u22 > 0.0
            if ok:
                i2 = 1.0 / u22
                u23 = a23 - l20 * a03 - l21 * u13
                u24 = a24 - l20 * a04 - l21 * u14
                l32 = u23 * i2
                l42 = u24 * i2
                u33 = a33 - l30 * a03 - l31 * u13 - l32 * u23
                ok = u33 > 0.0
                if ok:
                    i3 = 1.0 / u33
                    u34 = a34 - l30 * a04 - l31 * u14 - l32 * u24
                    l43 = u34 * i3
                    u44 = a44 - l40 * a04 - l41 * u14 - l42 * u24 - l43 * u34
                    ok = u44 > 0.0
                    if ok:
                        i4 = 1.0 / u44
    return ok, i0, i1, i2, i3, i4, l10, l20, l30, l40, l21, l31, l41, l32, l42, l43


@njit(cache=True, inline="always", fastmath=FMA)
def _ldl5_solve(i0, i1, i2, i3, i4, l10, l20, l30, l40, l21, l31, l41, l32, l42, l43,
                b0, b1, b2, b3, b4):
    """x = D^-1 b with the factors of _ldl5()."""
    z1 = b1 - l10 * b0
    z2 = b2 - l20 * b0 - l21 * z1
    z3 = b3 - l30 * b0 - l31 * z1 - l32 * z2
    z4 = b4 - l40 * b0 - l41 * z1 - l42 * z2 - l43 * z3
    x4 = z4 * i4
    x3 = z3 * i3 - l43 * x4
    x2 = z2 * i2 - l32 * x3 - l42 * x4
    x1 = z1 * i1 - l21 * x2 - l31 * x3 - l41 * x4
    x0 = b0 * i0 - l10 * x1 - l20 * x2 - l30 * x3 - l40 * x4
    return x0, x1, x2, x3, x4


@njit(cache=True, inline="always", fastmath=FMA)
def _eliminate_block(Ad, Ao, Wm, rhs, j, N):
    """Forward elimination of block j (block Thomas on the symmetric system: diagonal Ad,
    upper Ao, lower Ao^T): D_j = Ad_j - Ao_{j-1}^T Wm_{j-1} (symmetric), Wm_j = D_j^-1 Ao_j,
    rhs_j <- D_j^-1 (rhs_j - Ao_{j-1}^T rhs_{j-1}), D_j factored as L diag L^T. Returns False
    if D_j is not positive definite: Ad[j] then holds D_j in full and rhs[j] the right-hand
    side, for _eliminate_block_pivoting."""
    a00 = Ad[j, 0, 0]
    a01 = Ad[j, 0, 1]
    a02 = Ad[j, 0, 2]
    a03 = Ad[j, 0, 3]
    a04 = Ad[j, 0, 4]
    a11 = Ad[j, 1, 1]
    a12 = Ad[j, 1, 2]
    a13 = Ad[j, 1, 3]
    a14 = Ad[j, 1, 4]
    a22 = Ad[j, 2, 2]
    a23 = Ad[j, 2, 3]
    a24 = Ad[j, 2, 4]
    a33 = Ad[j, 3, 3]
    a34 = Ad[j, 3, 4]
    a44 = Ad[j, 4, 4]
    y0 = rhs[j, 0]
    y1 = rhs[j, 1]
    y2 = rhs[j, 2]
    y3 = rhs[j, 3]
    y4 = rhs[j, 4]
    if j > 0:
        i = j - 1
        for q in range(5):
            o0 = Ao[i, q, 0]
            o1 = Ao[i, q, 1]
            o2 = Ao[i, q, 2]
            o3 = Ao[i, q, 3]
            o4 = Ao[i, q, 4]
            w0 = Wm[i, q, 0]
            w1 = Wm[i, q, 1]
            w2 = Wm[i, q, 2]
            w3 = Wm[i, q, 3]
            w4 = Wm[i, q, 4]
            a00 -= o0 * w0
            a01 -= o0 * w1
            a02 -= o0 * w2
            a03 -= o0 * w3
            a04 -= o0 * w4
            a11 -= o1 * w1
            a12 -= o1 * w2
            a13 -= o1 * w3
            a14 -= o1 * w4
            a22 -= o2 * w2
            a23 -= o2 * w3
            a24 -= o2 * w4
            a33 -= o3 * w3
            a34 -= o3 * w4
            a44 -= o4 * w4
            yq = rhs[i, q]
            y0 -= o0 * yq
            y1 -= o1 * yq
            y2 -= o2 * yq
            y3 -= o3 * yq
            y4 -= o4 * yq
    m = 5 if j < N - 1 else 0  # the last block has no upper neighbour
    (ok, i0, i1, i2, i3, i4, l10, l20, l30, l40, l21, l31, l41, l32, l42,
     l43) = _ldl5(a00, a01, a02, a03, a04, a11, a12, a13, a14, a22, a23, a24, a33, a34, a44)
    if ok:
        for c in range(m):
            x0, x1, x2, x3, x4 = _ldl5_solve(
                i0, i1, i2, i3, i4, l10, l20, l30, l40, l21, l31, l41, l32, l42, l43,
                Ao[j, 0, c], Ao[j, 1, c], Ao[j, 2, c], Ao[j, 3, c], Ao[j, 4, c])
            Wm[j, 0, c] = x0
            Wm[j, 1, c] = x1
            Wm[j, 2, c] = x2
            Wm[j, 3, c] = x3
            Wm[j, 4, c] = x4
        y0, y1, y2, y3, y4 = _ldl5_solve(
            i0, i1, i2, i3, i4, l10, l20, l30, l40, l21, l31, l41, l32, l42, l43,
            y0, y1, y2, y3, y4)
    else:  # D_j in full for the pivoting fallback
        Ad[j, 0, 0] = a00
        Ad[j, 0, 1] = Ad[j, 1, 0] = a01
        Ad[j, 0, 2] = Ad[j, 2, 0] = a02
        Ad[j, 0, 3] = Ad[j, 3, 0] = a03
        Ad[j, 0, 4] = Ad[j, 4, 0] = a04
        Ad[j, 1, 1] = a11
        Ad[j, 1, 2] = Ad[j, 2, 1] = a12
        Ad[j, 1, 3] = Ad[j, 3, 1] = a13
        Ad[j, 1, 4] = Ad[j, 4, 1] = a14
        Ad[j, 2, 2] = a22
        Ad[j, 2, 3] = Ad[j, 3, 2] = a23
        Ad[j, 2, 4] = Ad[j, 4, 2] = a24
        Ad[j, 3, 3] = a33
        Ad[j, 3, 4] = Ad[j, 4, 3] = a34
        Ad[j, 4, 4] = a44
    rhs[j, 0] = y0
    rhs[j, 1] = y1
    rhs[j, 2] = y2
    rhs[j, 3] = y3
    rhs[j, 4] = y4
    return ok


@njit(cache=True, fastmath=FMA)
def _eliminate_block_pivoting(Ad, Ao, Wm, rhs, j, N):
    """_eliminate_block for a D_j that is not positive definite (Ad[j] = D_j in full):
    LU with partial pivoting (sim_math.linalg), Ad[j] overwritten by the factors. Returns
    False if D_j is singular or not finite."""
    m = 5 if j < N - 1 else 0
    for r in range(5):
        for c in range(m):
            Wm[j, r, c] = Ao[j, r, c]
    piv = np.empty(5, np.int64)
    if not lu_factor(Ad[j], piv):
        return False
    lu_solve_columns(Ad[j], piv, Wm[j], m)
    lu_solve(Ad[j], piv, rhs[j])
    return True


@njit(cache=True, inline="always", fastmath=FMA)
def _back_substitute(rhs, dnu, Wm, j, N):
    """dnu_j = y_j - Wm_j dnu_{j+1}: the velocity change of element j (5 scalars)."""
    d0 = rhs[j, 0]
    d1 = rhs[j, 1]
    d2 = rhs[j, 2]
    d3 = rhs[j, 3]
    d4 = rhs[j, 4]
    if j < N - 1:
        for q in range(5):
            xq = dnu[j + 1, q]
            d0 -= Wm[j, 0, q] * xq
            d1 -= Wm[j, 1, q] * xq
            d2 -= Wm[j, 2, q] * xq
            d3 -= Wm[j, 3, q] * xq
            d4 -= Wm[j, 4, q] * xq
    dnu[j, 0] = d0
    dnu[j, 1] = d1
    dnu[j, 2] = d2
    dnu[j, 3] = d3
    dnu[j, 4] = d4
    return d0, d1, d2, d3, d4


# ------------------------------------------------------------------ integration step
@njit(cache=True, inline="always", fastmath=FMA)
def _advance_element(S, B1, B2, j, d0, d1, d2, d3, d4, p):
    """Theta-method step of element j with its velocity change dnu = (d0..d4), the
    kinematics of Eq (5)-(6): X advanced by h ((1 - theta) V + theta V_new); e and W rotated
    (Rodrigues) by h ((1 - theta) W + theta W_new), W kept perpendicular to e. Returns False
    if the new state is non-finite or absurd (NaN fails every comparison)."""
    h = p.h
    theta = p.theta
    Vn0 = S[j, SV] + d0
    Vn1 = S[j, SV + 1] + d1
    Vn2 = S[j, SV + 2] + d2
    S[j, SX] += h * ((1.0 - theta) * S[j, SV] + theta * Vn0)
    S[j, SX + 1] += h * ((1.0 - theta) * S[j, SV + 1] + theta * Vn1)
    S[j, SX + 2] += h * ((1.0 - theta) * S[j, SV + 2] + theta * Vn2)
    S[j, SV] = Vn0
    S[j, SV + 1] = Vn1
    S[j, SV + 2] = Vn2
    Wn0 = S[j, SW] + d3 * B1[j, 0] + d4 * B2[j, 0]
    Wn1 = S[j, SW + 1] + d3 * B1[j, 1] + d4 * B2[j, 1]
    Wn2 = S[j, SW + 2] + d3 * B1[j, 2] + d4 * B2[j, 2]
    f0 = h * ((1.0 - theta) * S[j, SW] + theta * Wn0)
    f1 = h * ((1.0 - theta) * S[j, SW + 1] + theta * Wn1)
    f2 = h * ((1.0 - theta) * S[j, SW + 2] + theta * Wn2)
    e0 = S[j, SE]
    e1 = S[j, SE + 1]
    e2 = S[j, SE + 2]
    ang = math.sqrt(f0 * f0 + f1 * f1 + f2 * f2)
    if ang < 1e-300:
        en0, en1, en2 = e0, e1, e2
        wr0, wr1, wr2 = Wn0, Wn1, Wn2
    else:
        k0 = f0 / ang
        k1 = f1 / ang
        k2 = f2 / ang
        co = math.cos(ang)
        sa = math.sin(ang)
        en0, en1, en2 = _rodrigues(k0, k1, k2, co, sa, e0, e1, e2)
        wr0, wr1, wr2 = _rodrigues(k0, k1, k2, co, sa, Wn0, Wn1, Wn2)
    nrm = math.sqrt(en0 * en0 + en1 * en1 + en2 * en2)
    en0 /= nrm
    en1 /= nrm
    en2 /= nrm
    we = wr0 * en0 + wr1 * en1 + wr2 * en2
    S[j, SE] = en0
    S[j, SE + 1] = en1
    S[j, SE + 2] = en2
    S[j, SW] = wr0 - we * en0
    S[j, SW + 1] = wr1 - we * en1
    S[j, SW + 2] = wr2 - we * en2
    sv = Vn0 * Vn0 + Vn1 * Vn1 + Vn2 * Vn2
    sw = S[j, SW] * S[j, SW] + S[j, SW + 1] * S[j, SW + 1] + S[j, SW + 2] * S[j, SW + 2]
    sx = S[j, SX] * S[j, SX] + S[j, SX + 1] * S[j, SX + 1] + S[j, SX + 2] * S[j, SX + 2]
    se = en0 * en0 + en1 * en1 + en2 * en2
    return sv <= p.vmax2 and sw <= p.wmax2 and sx <= p.pmax2 and se <= 2.0


# ------------------------------------------------------------------ call bookkeeping
@njit(cache=True, inline="always")
def _save_call_state(S, F, io, bk, misc, bF, N):
    """Last good state (X, E, V, W, tensions, flags, end forces), restored on divergence;
    the impulses of the call start from zero."""
    for j in range(N):
        for a in range(3):
            bk[j, 0, a] = S[j, SX + a]
            bk[j, 1, a] = S[j, SE + a]
            bk[j, 2, a] = S[j, SV + a]
            bk[j, 3, a] = S[j, SW + a]
    for c in range(N + 1):
        misc[c, 1] = S[c, ST]
        misc[c, 2] = F[c, F_OK]
        misc[c, 3] = F[c, F_ARMED]
    for s in range(2):
        for a in range(3):
            bF[s, a] = io[IO_FORCE + s, a]
            io[IO_IMPULSE + s, a] = 0.0


@njit(cache=True, inline="always")
def _restore_call_state(S, F, io, bk, misc, bF, N, b_nev):
    """Undo the call: the state saved by _save_call_state and the event count."""
    for j in range(N):
        for a in range(3):
            S[j, SX + a] = bk[j, 0, a]
            S[j, SE + a] = bk[j, 1, a]
            S[j, SV + a] = bk[j, 2, a]
            S[j, SW + a] = bk[j, 3, a]
    for c in range(N + 1):
        S[c, ST] = misc[c, 1]
        F[c, F_OK] = np.int64(misc[c, 2])
        F[c, F_ARMED] = np.int64(misc[c, 3])
    for s in range(2):
        for a in range(3):
            io[IO_FORCE + s, a] = bF[s, a]
    io[IO_NEV] = b_nev


@njit(cache=True, inline="always", fastmath=FMA)
def _add_end_impulses(io, w8):
    """Impulse of the end forces, trapezoidal: weight w8 = h / 2 at the ends of the call."""
    for s in range(2):
        for a in range(3):
            io[IO_IMPULSE + s, a] += w8 * io[IO_FORCE + s, a]


@njit(cache=True, inline="always", fastmath=FMA)
def _finish_exchange_step(io, dt):
    """Mean end force = impulse / dt; the attachments move on by att_vel * dt."""
    inv = 1.0 / dt
    for s in range(2):
        for a in range(3):
            io[IO_MEAN + s, a] = io[IO_IMPULSE + s, a] * inv
            io[IO_POS + s, a] = io[IO_POS + s, a] + io[IO_VEL + s, a] * dt


# ------------------------------------------------------------------ environment input
@njit(cache=True)
def set_environment(S, io, cur, wind, depth):
    """RopeChain.set_environment's fast path: current (N, 3), wind (N, 3) and seabed depth
    (N,) per element into S (the uniform current io[IO_CUR] set to 0). Checked first (every
    velocity finite, every depth > 0 or inf), nothing written on error. Returns -1 if taken,
    else what * N + j for the first bad value (what: 0 current, 1 wind, 2 depth; j element)."""
    N = S.shape[0] - 1
    for j in range(N):
        for a in range(3):
            if not math.isfinite(cur[j, a]):
                return j
            if not math.isfinite(wind[j, a]):
                return N + j
        if not depth[j] > 0.0:  # NaN fails too
            return 2 * N + j
    for j in range(N):
        for a in range(3):
            S[j, SCUR + a] = cur[j, a]
            S[j, SWIND + a] = wind[j, a]
            S[j, SWV + a] = 0.0  # the caller's environment has no waves
            S[j, SWA + a] = 0.0
        S[j, SDEPTH] = depth[j]
        S[j, SETA] = 0.0
    for a in range(3):
        io[IO_CUR, a] = 0.0
    return -1


SEABED_MARGIN = 5.0  # m: further than any element moves in one exchange step (250 m/s at 50 Hz)


@njit(cache=True)
def sample_environment(S, io, env, dt, wc):
    """The environment (env: a sea_environment.sampler.EnvironmentSampler's data, at its
    time) at every element centre into S's SCUR / SWIND / SDEPTH columns (horizontal current
    and wind; inf: no seabed within the element's reach), the uniform current io[IO_CUR] set to 0: what
    RopeChain.set_environment takes, sampled here instead of by the caller; and the waves, if
    the environment has a sea, into SWV / SWA / SETA (sample_waves) at the middle of the
    exchange step dt about to be taken (wc: the rope's wave cache, new_wave_cache)."""
    N = S.shape[0] - 1
    sample_waves(S, env, env[P_TIME] + 0.5 * dt, wc)
    tide = tidal_factor(env, env[P_TIME])
    w10 = wind_at_10m(env)
    # two loops, the depth's branch written out in the loop: as one loop, or through a helper
    # function, sampling cost 12-24 ns per element, as here 5 ns (N = 200, measured)
    for j in range(N):
        cx, cy, wx, wy = flow_at_point(env, tide, w10, S[j, SX], S[j, SX + 1], S[j, SX + 2])
        S[j, SCUR], S[j, SCUR + 1], S[j, SCUR + 2] = cx, cy, 0.0
        S[j, SWIND], S[j, SWIND + 1], S[j, SWIND + 2] = wx, wy, 0.0
    radius = io[P_RADIUS]
    shallowest_bed_z = -env[P_DEPTH_MIN]
    for j in range(N):
        # depth inf (no seabed, the same contact without the interpolation) where the element
        # cannot reach the shallowest seabed within a step: its half length and radius, with
        # a SEABED_MARGIN
        reach = 0.5 * S[j, SL] + radius + SEABED_MARGIN
        h = math.inf
        if S[j, SX + 2] - reach < shallowest_bed_z:
            h = depth_at(env, S[j, SX], S[j, SX + 1])
        S[j, SDEPTH] = h
    for a in range(3):
        io[IO_CUR, a] = 0.0


# ------------------------------------------------------------------ wave cache
# The direct evaluation of the sea at an element costs a cos, a sin and an exp per component
# (about 30 ns). Between two calls an element moves little, so its phasors e^{i theta_ij},
# theta_ij = kx_i x_j + ky_i y_j - omega_i t + phi_i, and depth factors exp(k_i z'_j) are
# advanced instead:
#   e^{i theta(t + dt)} = e^{i theta(t)} e^{i (kx_i dx_j + ky_i dy_j)} e^{-i omega_i dt},
#   exp(k_i z'_new) = exp(k_i z'_old) exp(k_i dz'_j),
# the finite-depth factor exp(-2 k_i (z' + h)) times exp(-k_i dz')^2. The time rotation e^{-i
# omega_i dt} is one per component and call, from libm once and then rotated on by omega_i
# times the change of dt (the steps repeat, up to the rounding of the time); the space
# rotation, the depth factor's change and that time correction are Taylor polynomials, taken
# while |kx dx + ky dy| <= k_max |d(x, y)| <= TAYLOR_MAX, |k dz'| <= k_max |dz'| <= TAYLOR_MAX
# and omega_max |dt - dt_libm| <= TAYLOR_MAX (0.5): cos through x^14 and sin
# through x^15 (the alternating series' first omitted terms bound the truncation: x^16 / 16!
# <= 7.3e-19 and x^17 / 17! <= 2.1e-20 at |x| = 0.5), exp(+-y) as E(y) +- O(y), its even part
# through y^14 and odd part through y^15 (truncation <= y^16 / 16! / (1 - y / 17) = 7.6e-19,
# 1.3e-18 of exp(-0.5)). The loops over components then hold no transcendental function and
# vectorise (the component data are contiguous rows of the cache, copied from the packed sea).
# Direct evaluation (which fills the cache) on the first call, beyond those bounds (a jump,
# a new link of the winch), when N or the sea changed, for an element deeper than
# DEEPEST_KZ / k_max (exp(k z') would leave the normal floats) and every WAVE_REFRESH calls, so
# that rounding cannot accumulate (the test holds it to 1e-10 of the kinematics; measured
# about 2e-12 over 3000 steps).
TAYLOR_MAX = 0.5
WAVE_REFRESH = 256
DEEPEST_KZ = -600.0
SKIP_KZ = -40.0  # terms with exp(k z') < exp(-40) ~ 4e-18 left out, as waves.wave_kinematics_wet
# wc: float64 (WC_FIXED + WC_ELEM * capacity, width >= max(components, WC_MIN_WIDTH)): row 0 a
# header (H_*; H_ADVANCED, H_DIRECT count the elements whose phasors were advanced and
# evaluated directly); rows R_* one per component quantity (copied from the packed sea, with
# products of them, the time rotation cos, sin(omega_i dt) of this call's step and of the
# step H_DT libm last evaluated it for); rows R_PACKED.. the
# packed component rows verbatim (flat), to tell a changed sea; then per element j a block of
# WC_ELEM rows from WC_FIXED + WC_ELEM j: cos theta_ij, sin theta_ij, exp(k_i z'_j) / (1 -
# exp(-2 k_i h)), exp(-2 k_i (z'_j + h)) per component, and the (x, y, z') they hold for
# (E_POS, columns 0-2; NaN: none)
WC_HEADER = 0
H_VALID, H_T, H_DT, H_COUNT, H_N, H_NCOMP, H_DEPTH, H_KMAX, H_OMAX, H_ADVANCED, H_DIRECT = range(11)
(R_A, R_OMEGA, R_K, R_KX, R_KY, R_PHASE, R_INV_S, R_AW, R_AWO, R_AW_DX, R_AW_DY, R_AWO_DX, R_AWO_DY,
 R_ROT_C, R_ROT_S, R_ROT0_C, R_ROT0_S, R_PACKED) = range(1, 19)
WC_FIXED = R_PACKED + STRIDE    # width >= components: STRIDE rows hold the packed rows
E_COS, E_SIN, E_EZ, E_E2, E_POS = range(5)
WC_ELEM = 5
WC_MIN_WIDTH = 16
# 1 / n! for the Taylor polynomials
F2, F3, F4, F5, F6, F7, F8 = (1.0 / math.factorial(n) for n in range(2, 9))
F9, F10, F11, F12, F13, F14, F15 = (1.0 / math.factorial(n) for n in range(9, 16))


def wave_components(env):
    """The number of wave components of a sampler's packed environment (0: a calm sea)."""
    at = int(env[P_WAVE_AT])
    return 0 if at == 0 else int(env[at + W_N])


def new_wave_cache(n_elements, n_components):
    """A wave cache (sample_waves) for up to n_elements elements (and spare ones for the winch's
    new links) in a sea of n_components components; it starts empty (the first call fills it)."""
    cap = n_elements + 8 + n_elements // 4
    return np.zeros((WC_FIXED + WC_ELEM * cap, max(int(n_components), WC_MIN_WIDTH)))


@njit(cache=True)
def wave_cache_fits(wc, N, n):
    """wc has room for N elements in a sea of n components."""
    return wc.shape[0] >= WC_FIXED + WC_ELEM * N and wc.shape[1] >= max(n, WC_MIN_WIDTH)


@njit(cache=True)
def _gather_components(wc, env, at, n):
    """The sea's components as contiguous rows of wc (so that the loops over them vectorise);
    True (the cache emptied) if the sea differs from the last call's (the packed rows are
    compared with their copy in one flat pass: about 0.2 us at 150 components)."""
    hdr = wc[WC_HEADER]
    m = n * STRIDE
    packed = wc[R_PACKED:R_PACKED + STRIDE].reshape(-1)      # a view (ravel would copy)
    first = at + N_HEADER
    differ = 0
    for q in range(m):
        differ += packed[q] != env[first + q]
    if differ == 0 and hdr[H_NCOMP] == n and hdr[H_DEPTH] == env[at + W_DEPTH]:
        return False
    packed[:m] = env[first:first + m]
    kmax = omax = 0.0
    for i in range(n):
        j = first + i * STRIDE
        a, om, k = env[j + C_A], env[j + C_OMEGA], env[j + C_K]
        wc[R_A, i], wc[R_OMEGA, i], wc[R_K, i] = a, om, k
        wc[R_KX, i], wc[R_KY, i] = env[j + C_KX], env[j + C_KY]
        wc[R_PHASE, i], wc[R_INV_S, i] = env[j + C_PHASE], env[j + C_INV_S]
        wc[R_AW, i] = a * om
        wc[R_AWO, i] = a * om * om
        wc[R_AW_DX, i], wc[R_AW_DY, i] = a * om * env[j + C_DX], a * om * env[j + C_DY]
        wc[R_AWO_DX, i], wc[R_AWO_DY, i] = a * om * om * env[j + C_DX], a * om * om * env[j + C_DY]
        kmax, omax = max(kmax, k), max(omax, om)
    hdr[H_NCOMP], hdr[H_DEPTH], hdr[H_KMAX], hdr[H_OMAX] = n, env[at + W_DEPTH], kmax, omax
    hdr[H_DT], hdr[H_VALID] = math.nan, 0.0
    return True


@njit(cache=True, fastmath={"contract"})
def _time_rotation(wc, n, t):
    """cos, sin(omega_i dt) of this call's step dt (from the last call's time) into the rotation
    rows: from those of the step H_DT the last libm evaluation was for, rotated by omega_i (dt -
    H_DT) (Taylor), or by libm anew when that is beyond TAYLOR_MAX (or none is held)."""
    hdr = wc[WC_HEADER]
    dt = t - hdr[H_T]
    ddt = dt - hdr[H_DT]
    if not abs(ddt) * hdr[H_OMAX] <= TAYLOR_MAX:
        for i in range(n):
            wc[R_ROT0_C, i] = math.cos(wc[R_OMEGA, i] * dt)
            wc[R_ROT0_S, i] = math.sin(wc[R_OMEGA, i] * dt)
        hdr[H_DT] = dt
        ddt = 0.0
    for i in range(n):
        p = wc[R_OMEGA, i] * ddt
        p2 = p * p
        cp = 1.0 - p2 * (F2 - p2 * (F4 - p2 * (F6 - p2 * (F8 - p2 * (F10 - p2 * (F12 - p2 * F14))))))
        sp = p * (1.0 - p2 * (F3 - p2 * (F5 - p2 * (F7 - p2 * (F9 - p2 * (F11 - p2 * (F13 - p2 * F15)))))))
        c0, s0 = wc[R_ROT0_C, i], wc[R_ROT0_S, i]
        wc[R_ROT_C, i] = c0 * cp - s0 * sp
        wc[R_ROT_S, i] = s0 * cp + c0 * sp


@njit(cache=True)
def _direct_phasors(wc, b, x, y, t, n):
    """cos and sin theta_i at (x, y, t) into element block b; returns sum a_i cos theta_i (the
    operations of waves.wave_kinematics_wet). These loops index wc in two dimensions: a view
    per row would cost about 15 ns each per element (its reference counting)."""
    eta = 0.0
    for i in range(n):
        th = wc[R_KX, i] * x + wc[R_KY, i] * y - wc[R_OMEGA, i] * t + wc[R_PHASE, i]
        ci = math.cos(th)
        eta += wc[R_A, i] * ci
        wc[b + E_COS, i] = ci
        wc[b + E_SIN, i] = math.sin(th)
    return eta


@njit(cache=True, fastmath={"contract", "reassoc"})
def _advance_phasors(wc, b, dx, dy, n):
    """Block b's cos, sin theta_i rotated by kx_i dx + ky_i dy (Taylor, |.| <= TAYLOR_MAX) and
    by -omega_i dt (the rotation rows); returns sum a_i cos theta_i."""
    eta = 0.0
    for i in range(n):
        p = wc[R_KX, i] * dx + wc[R_KY, i] * dy
        p2 = p * p
        cp = 1.0 - p2 * (F2 - p2 * (F4 - p2 * (F6 - p2 * (F8 - p2 * (F10 - p2 * (F12 - p2 * F14))))))
        sp = p * (1.0 - p2 * (F3 - p2 * (F5 - p2 * (F7 - p2 * (F9 - p2 * (F11 - p2 * (F13 - p2 * F15)))))))
        rc, rs = wc[R_ROT_C, i], wc[R_ROT_S, i]
        qc = cp * rc + sp * rs
        qs = sp * rc - cp * rs
        ci, si = wc[b + E_COS, i], wc[b + E_SIN, i]
        cn = ci * qc - si * qs
        wc[b + E_COS, i] = cn
        wc[b + E_SIN, i] = si * qc + ci * qs
        eta += wc[R_A, i] * cn
    return eta


@njit(cache=True)
def _direct_depth_factors(wc, b, n, zs, h, deep):
    """Block b's depth factors exp(k_i z') / (1 - exp(-2 k_i h)) and exp(-2 k_i (z' + h)) (as
    waves.wave_kinematics_wet), every component."""
    for i in range(n):
        k = wc[R_K, i]
        wc[b + E_EZ, i] = math.exp(k * zs) * wc[R_INV_S, i]
        if not deep:
            wc[b + E_E2, i] = math.exp(-2.0 * max(k * (zs + h), 0.0))


@njit(cache=True, fastmath={"contract", "reassoc"})
def _advance_depth_factors(wc, b, n, dzs, deep):
    """Block b's depth factors advanced by exp(k_i dz') (Taylor, |k_i dz'| <= TAYLOR_MAX), the
    finite-depth one by exp(-k_i dz')^2."""
    for i in range(n):
        y = wc[R_K, i] * dzs
        y2 = y * y
        ev = 1.0 + y2 * (F2 + y2 * (F4 + y2 * (F6 + y2 * (F8 + y2 * (F10 + y2 * (F12 + y2 * F14))))))
        od = y * (1.0 + y2 * (F3 + y2 * (F5 + y2 * (F7 + y2 * (F9 + y2 * (F11 + y2 * (F13 + y2 * F15)))))))
        wc[b + E_EZ, i] = wc[b + E_EZ, i] * (ev + od)
        if not deep:
            g = ev - od
            wc[b + E_E2, i] = wc[b + E_E2, i] * g * g


@njit(cache=True, fastmath={"contract", "reassoc"})
def _depth_sums(wc, b, n, zs, deep):
    """The velocity and acceleration sums of waves.wave_kinematics_wet (before the ramp) from
    block b's phasors and depth factors, the terms below exp(SKIP_KZ) left out."""
    u = v = wz = ax = ay = az = 0.0
    for i in range(n):
        ez = wc[b + E_EZ, i] if wc[R_K, i] * zs >= SKIP_KZ else 0.0
        fc = fs = ez
        if not deep:
            e2 = wc[b + E_E2, i]
            fc, fs = ez * (1.0 + e2), ez * (1.0 - e2)
        c, s = wc[b + E_COS, i], wc[b + E_SIN, i]
        hc, hs = fc * c, fc * s
        u += wc[R_AW_DX, i] * hc
        v += wc[R_AW_DY, i] * hc
        ax += wc[R_AWO_DX, i] * hs
        ay += wc[R_AWO_DY, i] * hs
        wz += wc[R_AW, i] * (fs * s)
        az -= wc[R_AWO, i] * (fs * c)
    return u, v, wz, ax, ay, az


@njit(cache=True)
def _deep_element_sums(wc, b, n, zs, h, deep):
    """_depth_sums evaluated directly for an element too deep for the cache (the terms below
    exp(SKIP_KZ) skipped, nothing stored)."""
    u = v = wz = ax = ay = az = 0.0
    for i in range(n):
        k = wc[R_K, i]
        if k * zs < SKIP_KZ:
            continue
        ez = math.exp(k * zs) * wc[R_INV_S, i]
        fc = fs = ez
        if not deep:
            e2 = math.exp(-2.0 * max(k * (zs + h), 0.0))
            fc, fs = ez * (1.0 + e2), ez * (1.0 - e2)
        c, s = wc[b + E_COS, i], wc[b + E_SIN, i]
        u += wc[R_AW_DX, i] * (fc * c)
        v += wc[R_AW_DY, i] * (fc * c)
        ax += wc[R_AWO_DX, i] * (fc * s)
        ay += wc[R_AWO_DY, i] * (fc * s)
        wz += wc[R_AW, i] * (fs * s)
        az -= wc[R_AWO, i] * (fs * c)
    return u, v, wz, ax, ay, az


@njit(cache=True)
def _element_waves(wc, j, n, x, y, z, t, r, h, fresh):
    """(eta, u, v, w, ax, ay, az) of waves.wave_kinematics_wet at element j's centre (x, y, z)
    and time t (the velocity and acceleration sums before the ramp r), from its block of the
    cache (advanced) or evaluated directly (fresh, or beyond the Taylor bounds)."""
    b = WC_FIXED + WC_ELEM * j
    p = b + E_POS
    kmax = wc[WC_HEADER, H_KMAX]
    dx, dy = x - wc[p, 0], y - wc[p, 1]
    if not fresh and kmax * math.sqrt(dx * dx + dy * dy) <= TAYLOR_MAX:
        eta = _advance_phasors(wc, b, dx, dy, n)
        wc[WC_HEADER, H_ADVANCED] += 1.0
    else:
        eta = _direct_phasors(wc, b, x, y, t, n)
        wc[WC_HEADER, H_DIRECT] += 1.0
    wc[p, 0], wc[p, 1] = x, y
    eta *= r
    deep = math.isinf(h)
    zc = min(z, eta)
    if not deep and (zc < -h or h + eta <= 0.0):
        wc[p, 2] = math.nan
        return eta, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    zs = zc - eta if deep else (zc - eta) * h / (h + eta)      # Wheeler (1970)
    zs = min(zs, 0.0)
    if kmax * zs < DEEPEST_KZ:
        wc[p, 2] = math.nan
        u, v, w, ax, ay, az = _deep_element_sums(wc, b, n, zs, h, deep)
        return eta, u, v, w, ax, ay, az
    dzs = zs - wc[p, 2]
    if fresh or not kmax * abs(dzs) <= TAYLOR_MAX:      # NaN (no factors held): direct
        _direct_depth_factors(wc, b, n, zs, h, deep)
    elif dzs != 0.0:                                    # 0: a centre at the surface stays at z' = 0
        _advance_depth_factors(wc, b, n, dzs, deep)
    wc[p, 2] = zs
    u, v, w, ax, ay, az = _depth_sums(wc, b, n, zs, deep)
    return eta, u, v, w, ax, ay, az


@njit(cache=True)
def sample_waves(S, env, t, wc):
    """The waves of the sea packed in env (sampler.P_WAVE_AT; nothing on a calm sea) at every
    element centre at time t into SWV / SWA / SETA: Airy kinematics with Wheeler (1970)
    stretching above the mean surface (waves.wave_kinematics_wet: at the surface for a centre
    above it; zero below the bottom).

    Once per exchange step, at its middle (the frozen forcing is then centred in time: its
    error over the step is of order (omega dt)^2 / 24, 1e-4 at dt = 0.02 s and T = 4 s) and
    at the element positions of its start (an element moves k |V| dt of a wave's phase in
    the step, 1e-3 rad at 1 m/s): per sub-step the sum over 100-200 components would cost
    n_sub times as much for no visible change; the immersion itself follows each sub-step's
    position against this eta.

    wc: the rope's wave cache (new_wave_cache): the per element-component phasors are advanced
    from the last call's (the recurrence, see "wave cache" above) instead of evaluated anew;
    a cache too small for N or for the sea's components: the direct evaluation."""
    at = wave_offset(env)
    N = S.shape[0] - 1
    if at == 0:
        return
    n = int(env[at + W_N])
    r, dr = wave_ramp(env, at, t)
    if n == 0 or r == 0.0 or not wave_cache_fits(wc, N, n):
        _sample_waves_direct(S, env, at, t, n)
        return
    hdr = wc[WC_HEADER]
    fresh = _gather_components(wc, env, at, n)
    fresh = fresh or hdr[H_VALID] == 0.0 or hdr[H_N] != N or hdr[H_COUNT] % WAVE_REFRESH == 0.0
    if not fresh:
        _time_rotation(wc, n, t)
    h = env[at + W_DEPTH]
    for j in range(N):
        eta, u, v, w, ax, ay, az = _element_waves(wc, j, n, S[j, SX], S[j, SX + 1], S[j, SX + 2], t, r, h, fresh)
        S[j, SWV], S[j, SWV + 1], S[j, SWV + 2] = r * u, r * v, r * w
        S[j, SWA], S[j, SWA + 1], S[j, SWA + 2] = r * ax + dr * u, r * ay + dr * v, r * az + dr * w
        S[j, SETA] = eta
    hdr[H_VALID], hdr[H_T], hdr[H_N] = 1.0, t, N
    hdr[H_COUNT] += 1.0


@njit(cache=True)
def _sample_waves_direct(S, env, at, t, n):
    """sample_waves by waves.wave_kinematics_wet at every element (the oracle of the cache)."""
    scratch = np.empty(2 * n)
    for j in range(S.shape[0] - 1):
        eta, u, v, w, ax, ay, az = wave_kinematics_wet(env, at, S[j, SX], S[j, SX + 1],
                                                       S[j, SX + 2], t, scratch)
        S[j, SWV], S[j, SWV + 1], S[j, SWV + 2] = u, v, w
        S[j, SWA], S[j, SWA + 1], S[j, SWA + 2] = ax, ay, az
        S[j, SETA] = eta


@njit(cache=True)
def run_substeps_in_environment(S, F, io, ws, h, n_sub, payout_a, dt, env, wc):
    """run_substeps over the exchange step dt in the environment sampled at its start
    (sample_environment), the environment's time then advanced by dt: one compiled call, as
    a separate one costs about a tenth of a short rope's step (benchmarks/bench_rope.py); wc: the
    rope's wave cache (new_wave_cache)."""
    sample_environment(S, io, env, dt, wc)
    st = run_substeps(S, F, io, ws, h, n_sub, payout_a, dt)
    env[P_TIME] += dt
    return st


# ------------------------------------------------------------------ entry point
@njit(cache=True, fastmath=FMA)
def run_substeps(S, F, io, ws, h, n_sub, payout_a, dt):
    """Advance n_sub sub-steps of size h in place. Attachments move as
    att_pos + att_vel * t (t from the call start). Accumulates the force on each
    attachment times time in io[IO_IMPULSE] (trapezoidal). If dt > 0 (a whole exchange step
    dt = n_sub h), also writes the impulse / dt to io[IO_MEAN] and moves the attachments on
    by att_vel * dt. On divergence returns DIVERGED with io[IO_INFO, :2] = (sub-step
    index, element index) after restoring every array to its state at the call (the last good
    state). Returns NEED_WS (nothing done) if ws has fewer than N + 1 slots, else OK, with
    the PARTED flag if parting events were recorded (io[IO_NEV] of them).

    Per sub-step: the system (M - h theta C - h^2 theta^2 K) dnu = h f + h^2 theta K nu +
    attachment terms is written directly (diagonal blocks Ad, upper blocks Ao, lower =
    Ao^T, right-hand side rhs); the spring part of h^2 theta K nu + attachment terms is
    -h^2 theta k J^T g with g the velocity of the next connection point relative to the
    previous one, so no K blocks are stored. After the last sub-step only the connections
    are evaluated: tensions, end forces and the parting check do not depend on the
    element forces.

    Longer than the other functions on purpose: the loops and branches over the arrays
    stay here, the physics is in the helpers (see the module docstring)."""
    N = S.shape[0] - 1
    if ws.shape[1] < N + 1:
        return NEED_WS
    Ad = ws[0]
    Ao = ws[1]
    Wm = ws[2]
    rhs = ws[3, :, 0, :]
    dnu = ws[3, :, 1, :]
    B1 = ws[3, :, 2, :]
    B2 = ws[3, :, 3, :]
    misc = ws[3, :, 4, :]  # Iy, then backup of tension, conn_ok, armed
    bk = ws[4]  # backup of X, E, V, W (rows 0-3)
    cc = ws[4, :, 4, :]  # connection constants: k, c_x, c_t, c_m; element length
    bF = ws[5, 0]  # backup of the end forces (rows 0, 1)
    p = _read_params(io, h)
    att_a = io[IO_ATT, 1] != 0.0
    att_b = io[IO_ATT, 2] != 0.0
    _save_call_state(S, F, io, bk, misc, bF, N)
    b_nev = io[IO_NEV]
    io[IO_DIAG, 0] = -1.0
    _update_length_constants(S, ws, cc, misc, N, p)
    bad = -1
    for step in range(n_sub + 1):
        t = step * h
        full = step < n_sub  # else: end of the call, connections only
        for _ in range(N + 2):  # re-evaluate after a parting (at most one per pass)
            best_c = -1
            best_ratio = 1.0
            best_T = 0.0
            best_el = 0.0
            for a in range(3):
                io[IO_FORCE, a] = 0.0
                io[IO_FORCE + 1, a] = 0.0
            bad = -1
            # One pass over jc = 0..N: element jc, connection jc (joins elements jc - 1 and
            # jc), then the forward elimination of block jc - 1, complete now. A parting
            # found later in the pass discards it (the pass is repeated without that
            # connection).
            for jc in range(N + 1):
                if full and jc < N:  # element jc
                    _store_element(Ad, rhs, B1, B2, jc, _element_terms(_element_state(S, jc), p))
                    if _seabed_in_reach(p, S[jc, SL], S[jc, SX + 2], S[jc, SE + 2],
                                        S[jc, SDEPTH]):
                        _add_seabed(Ad, rhs, jc, _seabed_terms(_contact_state(S, jc),
                                                               _stored_basis(B1, B2, jc), p))
                # connection c = jc: aft point of element i = c - 1 (prev) to the front point
                # of element c (next); its terms of rhs and Ad, and the coupling block Ao[i]
                c = jc
                i = c - 1
                hp = c > 0
                hn = c < N
                S[c, ST] = 0.0
                if not (F[c, F_OK] != 0 and (hp or att_a) and (hn or att_b)):
                    if full and hp and hn:  # parted: no coupling block
                        _clear_block(Ao, i)
                else:
                    si, sk, Pp, Vp, Pn, Vn, g = _connection_points(S, io, c, N, t, payout_a)
                    # (scalars, not tuples: a tuple chosen in a branch changes which
                    # multiply-adds LLVM fuses, i.e. the last bits of the results)
                    i10 = i11 = i12 = i20 = i21 = i22 = 0.0  # basis of i
                    k10 = k11 = k12 = k20 = k21 = k22 = 0.0  # basis of c
                    bo33 = bo34 = bo43 = bo44 = 0.0  # bending part of Ao[i]
                    if full:
                        if hp:
                            i10, i11, i12, i20, i21, i22 = _stored_basis(B1, B2, i)
                        if hn:
                            k10, k11, k12, k20, k21, k22 = _stored_basis(B1, B2, c)
                        if hp and hn and cc[c, 3] > 0.0:
                            bo33, bo34, bo43, bo44 = _bending_damper(
                                S, Ad, rhs, i, c, cc[c, 3], (i10, i11, i12, i20, i21, i22),
                                (k10, k11, k12, k20, k21, k22), h, p.hth)
                    if STRICT_EQ25 and _point_inside_neighbour(S, c, N, Pp, Pn):
                        # Eq (25) as the paper states it: the connection is off
                        if full and hp and hn:  # coupling by the bending damper only
                            _clear_block(Ao, i)
                            _set_rotation_block(Ao, i, bo33, bo34, bo43, bo44)
                    else:
                        n = _rope_axis(S, c, N, Pp, Pn)
                        kc = cc[c, 0]
                        ctr = cc[c, 2]
                        F0, F1, F2, T, axd = _tension_only_spring_damper(kc, cc[c, 1], ctr, Pp,
                                                                         Pn, Vp, Vn, n)
                        if T > S[c, SB]:  # parting candidate: the most overloaded one parts
                            if F[c, F_ARMED] != 0 and T / S[c, SB] > best_ratio:
                                best_ratio = T / S[c, SB]
                                best_c = c
                                best_T = T
                                best_el = _elastic_tension(kc, Pp, Pn, n)
                        else:
                            F[c, F_ARMED] = 1  # re-armed once unloaded
                        S[c, ST] = T
                        if not hn:  # F acts on the next point, -F on the prev point
                            _set_vec3(io, IO_FORCE + 1, F0, F1, F2)
                        if not hp:
                            _set_vec3(io, IO_FORCE, -F0, -F1, -F2)
                        if full:
                            # rhs += J^T (h F - h^2 theta k g) on the next point, minus on the
                            # prev one; Ad += J^T S J with the spring-damper Jacobian
                            # S = h theta (c_x n n^T + c_t (I - n n^T)) + h^2 theta^2 k I
                            Q = (h * F0 - p.h2t * kc * g[0], h * F1 - p.h2t * kc * g[1],
                                 h * F2 - p.h2t * kc * g[2])
                            beta = p.hth * ctr + p.h2t2 * kc
                            gamma = p.hth * (axd - ctr)
                            _add_connection_to_elements(
                                S, Ad, rhs, c, N, si, sk, (i10, i11, i12, i20, i21, i22),
                                (k10, k11, k12, k20, k21, k22), Q, (F0, F1, F2), n, beta, gamma,
                                p.h2t, p.h2t2)
                            if hp and hn:
                                _coupling_block(Ao, i, si, sk, (i10, i11, i12, i20, i21, i22),
                                                (k10, k11, k12, k20, k21, k22), n, beta, gamma,
                                                (bo33, bo34, bo43, bo44))
                if full and jc > 0 and bad < 0 and not _eliminate_block(Ad, Ao, Wm, rhs, jc - 1,
                                                                         N):
                    if not _eliminate_block_pivoting(Ad, Ao, Wm, rhs, jc - 1, N):
                        bad = jc - 1  # singular: diverged unless a parting changes the system
            if best_c < 0:
                break
            if best_el < PART_MIN_ELASTIC * S[best_c, SB]:  # a blow-up, not a parting
                io[IO_DIAG, 0] = best_c
                io[IO_DIAG, 1] = best_T
                io[IO_DIAG, 2] = best_el
                bad = max(0, min(best_c, N - 1))
                break
            _part(best_c, best_T, t, N, S, F, io)
        _add_end_impulses(io, 0.5 * h if (step == 0 or step == n_sub) else h)
        if not full and bad < 0:
            break
        if bad < 0:
            # back substitution; each element is advanced as soon as its dnu is known
            for j in range(N - 1, -1, -1):
                d0, d1, d2, d3, d4 = _back_substitute(rhs, dnu, Wm, j, N)
                if not _advance_element(S, B1, B2, j, d0, d1, d2, d3, d4, p):
                    bad = j  # the lowest bad element is reported
        if bad >= 0:
            io[IO_INFO, 0] = step
            io[IO_INFO, 1] = bad
            _restore_call_state(S, F, io, bk, misc, bF, N, b_nev)
            return DIVERGED
    if dt > 0.0:
        _finish_exchange_step(io, dt)
    return PARTED if io[IO_NEV] > b_nev else OK
