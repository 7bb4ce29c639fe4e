"""Waves: one linear (Airy) sea that every body samples at its own position and time. Pure
numpy/scipy/numba, no ROS.

Inside everything is SI, radians and REP-103 world ENU (x east, y north, z up from the still
surface). A wave direction here is the direction the waves travel TOWARDS, as a math angle from
+x (east) counter-clockwise; the scenario's compass "from" direction is converted once, at the
edge (environment.WavesSpec -> WaveField).

The sea is a sum of N long-crested components (amplitude a_i, circular frequency omega_i,
wavenumber k_i, direction psi_i, phase phi_i):

    eta(x, y, t) = r(t) sum_i a_i cos(theta_i),
    theta_i = k_i (x cos psi_i + y sin psi_i) - omega_i t + phi_i,

so two bodies at different places see the same sea, shifted by k.x (the spatial phase).

Sources:
- Spectra, DNV-RP-C205 (2010/2019) 3.5.5: Pierson-Moskowitz
  S_PM(w) = 5/16 Hs^2 wp^4 w^-5 exp(-5/4 (w/wp)^-4), JONSWAP
  S_J(w) = A_gamma S_PM(w) gamma^exp(-0.5 ((w - wp)/(sigma wp))^2), sigma = 0.07 (w <= wp),
  0.09 (w > wp). A_gamma is not taken from DNV's approximation 1 - 0.287 ln(gamma) (good to about
  1 %) but computed numerically so that m0 = int S dw = Hs^2/16 exactly; `dnv_a_gamma` gives
  DNV's value for comparison. Pierson-Moskowitz is JONSWAP with gamma = 1.
- Directional spreading, Longuet-Higgins et al. (1963) cos-2s: D(theta) = C(s) cos^2s((theta -
  theta0)/2), C(s) = Gamma(s+1) / (2 sqrt(pi) Gamma(s+1/2)), normalised on (-pi, pi]
  (DNV-RP-C205 3.5.8 gives the cos^n form of the same idea).
- Dispersion, omega^2 = g k tanh(k h) (Faltinsen 1990, Sea Loads on Ships and Offshore
  Structures, ch. 2, Table 2.1), solved by Newton's method in x = k h to machine precision from
  Eckart's (1952) approximation; omega^2 = g k in deep water (no depth).
- Kinematics, linear (Airy) theory, Faltinsen (1990) Table 2.1, finite depth h:
  u_h = omega a cosh(k(z+h))/sinh(kh) cos(theta) along psi, w = omega a sinh(k(z+h))/sinh(kh)
  sin(theta), accelerations their time derivatives, dynamic pressure
  p_d = rho g a cosh(k(z+h))/cosh(kh) cos(theta) = rho (omega/k) u_h; deep water exp(kz). The
  profiles are evaluated as exp(kz) (1 +- exp(-2k(z+h))) / (1 - exp(-2kh)), which never
  overflows (z <= 0 after stretching) and is the deep-water exp(kz) when h = inf.
- Above the still surface: Wheeler (1970) stretching, z' = (z - eta) h / (h + eta) (deep water
  z' = z - eta): the linear profile is stretched to the instantaneous surface, so at z = eta the
  velocity is the linear theory's at z = 0. The accelerations are the linear ones at z' (the
  usual engineering practice; the time derivative of the stretching itself is second order).
  Above eta (in air) and below the bottom the kinematics are zero.
- Start-up ramp r(t) = (1 - cos(pi t / T_r)) / 2 for t < T_r, 1 after: the sea grows from calm
  without a step; the acceleration includes r'(t) times the velocity.

Discretisation: N equal-width bins on [0.5 wp, 5 wp] (the PM spectrum holds exp(-20) of its
energy below 0.5 wp and 0.2 % above 5 wp; JONSWAP less), one component per bin at a frequency
drawn at random within the bin with density S(w) there (so the frequencies are incommensurate
and the record does not repeat, unlike bin centres, which repeat after 2 pi / dw, e.g. 5 min for
Tp = 9 s and N = 150; weighted by S so the expected energy is where the spectrum puts it),
amplitude a_i = sqrt(2 int_bin S dw) (8-point Gauss-Legendre per bin: the discrete m0 is the
spectrum's over the range, not S(w_i) dw). Directions, one per component (the single-direction
method: no phase locking between directions of one frequency), drawn from D by its inverse CDF,
stratified: component i takes stratum perm(i) of N equal-probability strata, so the realised
spreading follows D closely at any N. Phases uniform on [0, 2 pi). All draws come from numpy's
PCG64 Generator seeded with `seed`: the same seed gives the same sea on every machine and node.

A regular wave (`regular`) is one component of height H (a = H/2) and period T, phase 0: a crest
at the origin at t = 0 (before the ramp).

Why no spectrum library (wavespectra, mhkit): neither is in the pinned environment, and the
spectra are short closed forms (DNV-RP-C205) checked against their own normalisation here.

Compiled layout (`WaveField.packed`, one float array; a kernel reads it from offset `at`, so it
can later sit inside sampler.EnvironmentSampler.data like the gust record): a header W_* then
N rows of STRIDE floats C_*; `wave_elevation` and `wave_kinematics` evaluate it.
"""
from __future__ import annotations

import math
from typing import NamedTuple, Optional

import numpy as np
from numba import njit

G = 9.80665
OMEGA_LO, OMEGA_HI = 0.5, 5.0      # discretised range, multiples of the peak frequency

# the packed header, then N component rows of STRIDE floats
W_N, W_DEPTH, W_RAMP, W_G, N_HEADER = range(5)
(C_A, C_OMEGA, C_K, C_KX, C_KY, C_DX, C_DY, C_PHASE, C_INV_S, C_CELERITY, STRIDE) = range(11)
# the values wave_kinematics returns, in order
(K_ETA, K_U, K_V, K_W, K_AX, K_AY, K_AZ, K_P, N_KIN) = range(9)


# ---- dispersion -------------------------------------------------------------------------------

def wavenumber(omega, depth: float = math.inf, g: float = G):
    """k (rad/m) of omega (rad/s) in water of depth h (m; inf = deep): omega^2 = g k tanh(k h)."""
    omega = np.asarray(omega, float)
    k_deep = omega * omega / g
    if math.isinf(depth):
        return k_deep
    x0 = k_deep * depth                                    # omega^2 h / g
    with np.errstate(divide="ignore", invalid="ignore"):
        x = np.where(x0 > 0.0, x0 / np.sqrt(np.tanh(x0)), 0.0)   # Eckart (1952), within 5 %
    for _ in range(60):
        th = np.tanh(x)
        dx = (x * th - x0) / (th + x * (1.0 - th * th))    # d/dx (x tanh x) = tanh x + x sech^2 x
        dx = np.where(x0 > 0.0, dx, 0.0)
        x = x - dx
        if np.all(np.abs(dx) <= 4e-16 * np.maximum(x, 1e-300)):
            break
    return x / depth


# ---- spectra ------------------------------------------------------------------------------------

def pierson_moskowitz_shape(omega, hs: float, tp: float):
    """DNV-RP-C205 3.5.5 Pierson-Moskowitz S(w), m^2 s / rad (0 at w <= 0)."""
    w = np.asarray(omega, float)
    wp = 2.0 * math.pi / tp
    out = np.zeros_like(w)
    pos = w > 0.0
    r = wp / w[pos]
    out[pos] = 5.0 / 16.0 * hs * hs * wp ** 4 * w[pos] ** -5 * np.exp(-1.25 * r ** 4)
    return out


def _peak_factor(omega, tp: float, gamma: float):
    wp = 2.0 * math.pi / tp
    w = np.asarray(omega, float)
    sigma = np.where(w <= wp, 0.07, 0.09)
    return gamma ** np.exp(-0.5 * ((w - wp) / (sigma * wp)) ** 2)


def dnv_a_gamma(gamma: float) -> float:
    """DNV-RP-C205 3.5.5.2's approximate JONSWAP normalising factor 1 - 0.287 ln(gamma)."""
    return 1.0 - 0.287 * math.log(gamma)


def jonswap_a_gamma(gamma: float) -> float:
    """The JONSWAP normalising factor making m0 = Hs^2 / 16 exactly (numerical quadrature of the
    shape, which scales with Hs^2 and whose m0 does not depend on Tp)."""
    if gamma == 1.0:
        return 1.0
    from scipy.integrate import quad
    tp = 2.0 * math.pi                                     # wp = 1: the m0 ratio is Tp-free
    f = lambda w: float(pierson_moskowitz_shape(np.array([w]), 4.0, tp)[0] * _peak_factor(w, tp, gamma))
    m0 = sum(quad(f, lo, hi, limit=200, epsabs=0.0, epsrel=1e-12)[0] for lo, hi in
             ((0.0, 0.7), (0.7, 1.0), (1.0, 1.5), (1.5, 4.0), (4.0, np.inf)))
    return 1.0 / m0                                        # Hs = 4: the target m0 is 1


def jonswap(omega, hs: float, tp: float, gamma: float = 3.3, a_gamma: Optional[float] = None):
    """DNV-RP-C205 3.5.5 JONSWAP S(w), m^2 s / rad, normalised to m0 = Hs^2/16 (a_gamma: the
    normalising factor if already computed)."""
    a = jonswap_a_gamma(gamma) if a_gamma is None else a_gamma
    return a * pierson_moskowitz_shape(omega, hs, tp) * _peak_factor(omega, tp, gamma)


# ---- directional spreading ----------------------------------------------------------------------

def cos2s_spreading(theta, s: float):
    """Longuet-Higgins cos-2s D(theta) = C(s) cos^2s(theta/2) on (-pi, pi], theta from the mean."""
    from scipy.special import gammaln
    c = math.exp(gammaln(s + 1.0) - gammaln(s + 0.5)) / (2.0 * math.sqrt(math.pi))
    return c * np.abs(np.cos(0.5 * np.asarray(theta, float))) ** (2.0 * s)


def _sample_cos2s(u, s: float):
    """Angles (from the mean) whose CDF under cos-2s is u (inverse CDF on a fine grid)."""
    th = np.linspace(-math.pi, math.pi, 8001)
    d = cos2s_spreading(th, s)
    cdf = np.concatenate(([0.0], np.cumsum(0.5 * (d[1:] + d[:-1]) * np.diff(th))))
    cdf /= cdf[-1]
    return np.interp(u, cdf, th)


def _draw_in_bins(spectrum, edges, u):
    """One frequency per bin with probability density S(w) / int_bin S (inverse CDF on 64
    sub-intervals): the expected energy then lies where the spectrum puts it, where a uniform
    draw would shift each bin's energy towards its less energetic side (+9 % on average in the
    steep band below the peak, measured)."""
    sub = edges[:-1, None] + np.diff(edges)[:, None] * np.linspace(0.0, 1.0, 65)
    dens = spectrum(sub)
    cdf = np.concatenate([np.zeros((sub.shape[0], 1)),
                          np.cumsum(0.5 * (dens[:, 1:] + dens[:, :-1]) * np.diff(sub, axis=1), axis=1)], axis=1)
    out = np.empty(len(u))
    for i, ui in enumerate(u):
        total = cdf[i, -1]
        out[i] = np.interp(ui * total, cdf[i], sub[i]) if total > 0.0 else sub[i, 0] + ui * (sub[i, -1] - sub[i, 0])
    return out


# ---- the field ----------------------------------------------------------------------------------

class WaveKinematics(NamedTuple):
    """Airy kinematics at M points: elevation (M,), velocity and acceleration (M, 3) ENU, and the
    dynamic pressure divided by the water density (M,), m^2/s^2 (x rho for Pa)."""
    eta: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    pressure: np.ndarray


def pack(amplitude, omega, direction, phase, depth: float = math.inf, ramp_time: float = 0.0,
         g: float = G) -> np.ndarray:
    """The compiled layout of components (a, omega, psi towards, phase) in depth h (inf: deep)."""
    a = np.asarray(amplitude, float)
    w = np.asarray(omega, float)
    psi = np.asarray(direction, float)
    k = wavenumber(w, depth, g)
    n = a.size
    rows = np.zeros((n, STRIDE))
    rows[:, C_A], rows[:, C_OMEGA], rows[:, C_K] = a, w, k
    rows[:, C_DX], rows[:, C_DY] = np.cos(psi), np.sin(psi)
    rows[:, C_KX], rows[:, C_KY] = k * rows[:, C_DX], k * rows[:, C_DY]
    rows[:, C_PHASE] = np.asarray(phase, float)
    rows[:, C_INV_S] = 1.0 / -np.expm1(-2.0 * k * depth)   # 1 / (1 - exp(-2kh)); 1 in deep water
    rows[:, C_CELERITY] = w / k
    head = np.zeros(N_HEADER)
    head[W_N], head[W_DEPTH], head[W_RAMP], head[W_G] = n, depth, ramp_time, g
    return np.concatenate([head, rows.ravel()])


class WaveField:
    """A sea of linear components (module docstring). Build with `regular`, `irregular` or
    `from_components`; sample with `elevation` / `kinematics` (numpy, arrays of points) or the
    compiled `wave_elevation` / `wave_kinematics` on `.packed`."""

    def __init__(self, amplitude, omega, direction, phase, depth: float = math.inf, ramp_time: float = 0.0,
                 g: float = G, spectrum=None, mean_direction: float = 0.0):
        self.depth, self.ramp_time, self.g = float(depth), float(ramp_time), float(g)
        if not (self.depth > 0.0 and self.ramp_time >= 0.0 and self.g > 0.0):
            raise ValueError(f"waves: depth {depth!r} m must be > 0, ramp time {ramp_time!r} s >= 0")
        self.packed = pack(amplitude, omega, direction, phase, self.depth, self.ramp_time, self.g)
        rows = self.rows
        self.amplitude, self.omega, self.k = rows[:, C_A], rows[:, C_OMEGA], rows[:, C_K]
        self.direction = np.arctan2(rows[:, C_DY], rows[:, C_DX])
        self.phase = rows[:, C_PHASE]
        self.spectrum = spectrum          # target S(w) (callable) of an irregular sea, else None
        self.mean_direction = float(mean_direction)
        # the spectral peak (rad/s): an irregular sea's 2 pi / Tp, else its largest component's
        self.peak_omega = float(self.omega[np.argmax(self.amplitude)]) if self.amplitude.size else 0.0

    @property
    def rows(self) -> np.ndarray:
        return self.packed[N_HEADER:].reshape(-1, STRIDE)

    @property
    def m0(self) -> float:
        """Variance of the elevation, sum a_i^2 / 2 (m^2)."""
        return float(0.5 * np.sum(self.amplitude ** 2))

    @staticmethod
    def regular(height: float, period: float, direction: float = 0.0, depth: float = math.inf,
                ramp_time: float = 0.0, g: float = G, phase: float = 0.0) -> "WaveField":
        """A regular wave of height H (crest to trough) and period T travelling towards
        `direction` (rad, math angle ENU)."""
        return WaveField([0.5 * height], [2.0 * math.pi / period], [direction], [phase], depth, ramp_time, g,
                         mean_direction=direction)

    @staticmethod
    def irregular(hs: float, tp: float, direction: float = 0.0, gamma: float = 3.3,
                  spreading_s: Optional[float] = None, components: int = 150, seed: int = 0,
                  depth: float = math.inf, ramp_time: float = 0.0, g: float = G) -> "WaveField":
        """A JONSWAP sea (gamma = 1: Pierson-Moskowitz) of Hs, Tp whose mean direction is
        `direction` (rad, math angle ENU, towards); long-crested without spreading_s, else cos-2s."""
        n = int(components)
        if n < 1 or not (hs >= 0.0 and tp > 0.0 and gamma >= 1.0):
            raise ValueError(f"waves: need components >= 1, Hs >= 0, Tp > 0, gamma >= 1 (got {n}, {hs}, {tp}, {gamma})")
        a_gamma = jonswap_a_gamma(gamma)
        spectrum = lambda w: jonswap(w, hs, tp, gamma, a_gamma)
        wp = 2.0 * math.pi / tp
        edges = wp * np.linspace(OMEGA_LO, OMEGA_HI, n + 1)
        xg, wg = np.polynomial.legendre.leggauss(8)
        mid, half = 0.5 * (edges[1:] + edges[:-1]), 0.5 * np.diff(edges)
        energy = np.sum(wg * spectrum(mid[:, None] + half[:, None] * xg), axis=1) * half
        rng = np.random.default_rng(seed)
        omega = _draw_in_bins(spectrum, edges, rng.uniform(size=n))
        phase = rng.uniform(0.0, 2.0 * math.pi, n)
        strata = (rng.permutation(n) + rng.uniform(size=n)) / n
        psi = direction + (_sample_cos2s(strata, spreading_s) if spreading_s else np.zeros(n))
        field = WaveField(np.sqrt(2.0 * energy), omega, psi, phase, depth, ramp_time, g, spectrum, direction)
        field.peak_omega = wp
        return field

    def ramp(self, t):
        """(r(t), r'(t)) of the half-cosine start-up ramp."""
        if isinstance(t, float) and 0.0 < t < self.ramp_time:   # one time, inside the ramp: a vessel's every step
            s = math.pi * t / self.ramp_time
            return 0.5 * (1.0 - math.cos(s)), 0.5 * math.pi / self.ramp_time * math.sin(s)
        t = np.asarray(t, float)
        if self.ramp_time <= 0.0:
            return np.ones_like(t), np.zeros_like(t)
        s = np.clip(t / self.ramp_time, 0.0, 1.0)
        inside = (t > 0.0) & (t < self.ramp_time)
        return 0.5 * (1.0 - np.cos(math.pi * s)), np.where(inside, 0.5 * math.pi / self.ramp_time * np.sin(math.pi * s), 0.0)

    def _theta(self, x, y, t):
        return (np.multiply.outer(x, self.rows[:, C_KX]) + np.multiply.outer(y, self.rows[:, C_KY])
                - np.multiply.outer(t, self.omega) + self.phase)

    def elevation(self, x, y, t):
        """eta (m) at points and times broadcast together."""
        x, y, t = np.broadcast_arrays(np.asarray(x, float), np.asarray(y, float), np.asarray(t, float))
        return self.ramp(t)[0] * (np.cos(self._theta(x, y, t)) @ self.amplitude)

    def kinematics(self, x, y, z, t) -> WaveKinematics:
        """Airy kinematics with Wheeler stretching at points (x, y, z) and times t broadcast
        together (1-D); zero in air (z > eta) and below the bottom."""
        x, y, z, t = (np.atleast_1d(v).astype(float) for v in np.broadcast_arrays(x, y, z, t))
        rows, h = self.rows, self.depth
        r, dr = self.ramp(t)
        theta = self._theta(x, y, t)
        c, s = np.cos(theta), np.sin(theta)
        eta = r * (c @ self.amplitude)
        deep = math.isinf(h)
        wet = (z <= eta) & (deep or (z >= -h)) & (deep or (h + eta > 0.0))
        with np.errstate(divide="ignore", invalid="ignore"):
            zs = z - eta if deep else (z - eta) * h / (h + eta)      # Wheeler (1970)
        zs = np.where(wet, np.minimum(zs, 0.0), -1.0)                 # dry points: any finite z' (masked)
        kz = np.multiply.outer(zs, self.k)
        ez = np.exp(kz) * rows[:, C_INV_S]
        if deep:
            fc = fs = ez
        else:
            e2 = np.exp(-2.0 * np.maximum(np.multiply.outer(zs + h, self.k), 0.0))
            fc, fs = ez * (1.0 + e2), ez * (1.0 - e2)
        aw = self.amplitude * self.omega
        uh = aw * fc * c                        # horizontal speed along psi, per component
        wz = aw * fs * s
        ah = aw * self.omega * fc * s
        az = -aw * self.omega * fs * c
        vel = np.stack([uh @ rows[:, C_DX], uh @ rows[:, C_DY], wz.sum(axis=1)], axis=1)
        acc = np.stack([ah @ rows[:, C_DX], ah @ rows[:, C_DY], az.sum(axis=1)], axis=1)
        p = uh @ rows[:, C_CELERITY]
        m = np.where(wet, 1.0, 0.0)
        acc = (r * m)[:, None] * acc + (dr * m)[:, None] * vel
        vel = (r * m)[:, None] * vel
        return WaveKinematics(eta, vel, acc, r * m * p)


# ---- compiled kernels ---------------------------------------------------------------------------

@njit(cache=True, inline="always")
def wave_ramp(w, at, t):
    """(r, dr/dt) of the start-up ramp at time t."""
    tr = w[at + W_RAMP]
    if tr <= 0.0 or t >= tr:
        return 1.0, 0.0
    if t <= 0.0:
        return 0.0, 0.0
    return 0.5 * (1.0 - math.cos(math.pi * t / tr)), 0.5 * math.pi / tr * math.sin(math.pi * t / tr)


@njit(cache=True)
def wave_elevation(w, at, x, y, t):
    """eta (m) at (x, y) and time t of the sea packed in w from offset `at` (WaveField.packed)."""
    n = int(w[at + W_N])
    r, _dr = wave_ramp(w, at, t)
    if n == 0 or r == 0.0:
        return 0.0
    eta = 0.0
    for i in range(n):
        j = at + N_HEADER + i * STRIDE
        eta += w[j + C_A] * math.cos(w[j + C_KX] * x + w[j + C_KY] * y - w[j + C_OMEGA] * t + w[j + C_PHASE])
    return r * eta


@njit(cache=True)
def wave_kinematics(w, at, x, y, z, t):
    """(eta, u, v, w, ax, ay, az, p_d / rho) at (x, y, z) and time t of the sea packed in w
    from offset `at`: Airy theory with Wheeler stretching, zero in air and below the bottom
    (WaveField.kinematics, the same sums in a loop)."""
    n = int(w[at + W_N])
    r, dr = wave_ramp(w, at, t)
    if n == 0 or r == 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    eta = 0.0
    for i in range(n):
        j = at + N_HEADER + i * STRIDE
        eta += w[j + C_A] * math.cos(w[j + C_KX] * x + w[j + C_KY] * y - w[j + C_OMEGA] * t + w[j + C_PHASE])
    eta *= r
    h = w[at + W_DEPTH]
    deep = math.isinf(h)
    if z > eta or (not deep and (z < -h or h + eta <= 0.0)):
        return eta, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    zs = z - eta if deep else (z - eta) * h / (h + eta)      # Wheeler (1970)
    zs = min(zs, 0.0)
    u = v = wz = ax = ay = az = p = 0.0
    for i in range(n):
        j = at + N_HEADER + i * STRIDE
        k = w[j + C_K]
        om = w[j + C_OMEGA]
        th = w[j + C_KX] * x + w[j + C_KY] * y - om * t + w[j + C_PHASE]
        c, s = math.cos(th), math.sin(th)
        ez = math.exp(k * zs) * w[j + C_INV_S]
        if deep:
            fc = fs = ez
        else:
            e2 = math.exp(-2.0 * max(k * (zs + h), 0.0))
            fc, fs = ez * (1.0 + e2), ez * (1.0 - e2)
        aw = w[j + C_A] * om
        uh = aw * fc * c
        ah = aw * om * fc * s
        u += uh * w[j + C_DX]
        v += uh * w[j + C_DY]
        wz += aw * fs * s
        ax += ah * w[j + C_DX]
        ay += ah * w[j + C_DY]
        az -= aw * om * fs * c
        p += uh * w[j + C_CELERITY]
    return (eta, r * u, r * v, r * wz, r * ax + dr * u, r * ay + dr * v, r * az + dr * wz, r * p)


@njit(cache=True)
def wave_kinematics_wet(w, at, x, y, z, t, scratch):
    """(eta, u, v, w, ax, ay, az) for a body of the rope or cable at (x, y, z), time t: the
    kinematics of wave_kinematics at min(z, eta), i.e. the surface's own values for a point
    above it (an element whose centre is in the air but whose underside is wet feels the water
    at the surface: the immersed part scales the loads, not a jump to zero as its centre
    emerges); zero below the bottom. scratch: float array of at least 2 N (the cosines and
    sines of the first pass, so each component costs one cos, one sin and at most one exp). Terms
    whose depth factor exp(k z') is below exp(-40) ~ 4e-18 are skipped (a deep element
    of a rope need not pay for the short components)."""
    n = int(w[at + W_N])
    r, dr = wave_ramp(w, at, t)
    if n == 0 or r == 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    eta = 0.0
    for i in range(n):
        j = at + N_HEADER + i * STRIDE
        th = w[j + C_KX] * x + w[j + C_KY] * y - w[j + C_OMEGA] * t + w[j + C_PHASE]
        c = math.cos(th)
        eta += w[j + C_A] * c
        scratch[2 * i] = c
        scratch[2 * i + 1] = math.sin(th)
    eta *= r
    h = w[at + W_DEPTH]
    deep = math.isinf(h)
    zc = min(z, eta)
    if not deep and (zc < -h or h + eta <= 0.0):
        return eta, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    zs = zc - eta if deep else (zc - eta) * h / (h + eta)      # Wheeler (1970)
    zs = min(zs, 0.0)
    u = v = wz = ax = ay = az = 0.0
    for i in range(n):
        j = at + N_HEADER + i * STRIDE
        k = w[j + C_K]
        if k * zs < -40.0:
            continue
        om = w[j + C_OMEGA]
        c = scratch[2 * i]
        s = scratch[2 * i + 1]
        ez = math.exp(k * zs) * w[j + C_INV_S]
        if deep:
            fc = fs = ez
        else:
            e2 = math.exp(-2.0 * max(k * (zs + h), 0.0))
            fc, fs = ez * (1.0 + e2), ez * (1.0 - e2)
        aw = w[j + C_A] * om
        uh = aw * fc * c
        ah = aw * om * fc * s
        u += uh * w[j + C_DX]
        v += uh * w[j + C_DY]
        wz += aw * fs * s
        ax += ah * w[j + C_DX]
        ay += ah * w[j + C_DY]
        az -= aw * om * fs * c
    return (eta, r * u, r * v, r * wz, r * ax + dr * u, r * ay + dr * v, r * az + dr * wz)
