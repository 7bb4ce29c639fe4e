"""Wave-frequency motions and mean wave drift of a displacement hull in the simulator's sea, from
precomputed hydrodynamic data (ships/hydro/<ship>.npz, made by scripts/hydro_data.py with the
BEM code Capytaine). ROS-free, numpy only at run time (no capytaine import).

    from tug_dynamics.wave_response import HydroData, WaveResponse, hydro_path
    hydro = HydroData.load(hydro_path("asd_tug"))        # ValueError naming file and key if bad
    resp = WaveResponse(hydro, wave_field)                # sea_environment.waves.WaveField
    s = resp.evaluate(x, y, psi, u, t)                     # every vessel step
    s.displacement   # (6,) surge, sway, heave (m), roll, pitch, yaw (rad): wave-frequency motion
    s.velocity       # (6,) its time derivative (m/s, rad/s)
    s.drift          # (3,) mean drift force X, Y (N), N (N m), body axes
    resp.drift_force(psi, t)                               # the drift alone (it needs no position)

One WaveResponse per vessel (it holds per-component tables of that hull); evaluate costs a few
vectorised numpy operations over the N wave components (about 50 us for N = 150-200 on a
shared core).

Axes and inputs: world ENU (x east, y north), psi the heading (rad, math angle from east, CCW;
REP-103), u the forward speed through the water (m/s, body x), (x, y) the position of the body
origin (midships, centreline, still waterline: the data's reference point). Outputs are in body
axes (x forward, y port, z up), rotations positive by the right-hand rule about them (roll
positive = port side up). The wave-frequency motion is meant to be superposed on the
manoeuvring (low-frequency) motion, the drift force added to the manoeuvring forces (Fossen 2021,
Handbook of Marine Craft Hydrodynamics and Motion Control, 2nd ed., ch. 10: the RAO method of the
MSS toolbox).

Method. The sea is eta = r(t) sum_i a_i cos(theta_i), theta_i = k_i (x cos psi_i + y sin psi_i)
- omega_i t + phi_i (psi_i the direction component i travels TOWARDS, waves.py). For each
component:
  beta_i = psi_i - psi (wrapped to [0, 2 pi)): the wave direction relative to the hull, the
    direction of travel measured CCW from the bow, i.e. the usual seakeeping angle: beta = 180 deg
    head seas (waves from ahead), 0 following seas, 90 deg waves travelling to port (coming from
    starboard), 270 deg from port. (A scenario's compass "from" direction is converted to psi_i
    once in sea_environment; nothing here uses compass angles.)
  X_j(omega_i, beta_i): the complex RAO (amplitude and phase per unit wave amplitude; e^{-i w t}
    convention), linearly interpolated in omega (clamped to the data's range: below it the
    long-wave limits, above it the last, small, value) and periodically in beta.
  xi_j = r(t) sum_i a_i |X_ij| cos(theta_i + arg X_ij),  theta_i at the vessel's own position, so
    two vessels see the phase difference k.dx of their positions (Newman 1977, Marine
    Hydrodynamics, 6.17; Faltinsen 1990, Sea Loads on Ships and Offshore Structures, ch. 3).
  dxi_j/dt = r sum_i a_i omega_e,i |X_ij| sin(theta_i + arg X_ij) + r'(t) sum_i a_i |X_ij| cos(...),
    omega_e,i = omega_i - k_i u cos(beta_i), the encounter frequency (Fossen 2021 ch. 10;
    Faltinsen 1990 ch. 3): along a track at speed u, d theta_i / dt = -omega_e,i. Evaluating
    theta_i at the vessel's current position therefore carries the encounter frequency in the
    displacement too; omega_e appears explicitly only in the velocity.
  Mean drift (Faltinsen 1990 ch. 5, without cross terms; Maruo 1960 far-field data):
    F = r(t)^2 sum_i a_i^2 D(omega_i, beta_i), D per unit amplitude squared, the same
    interpolation. Slowly-varying (difference-frequency) drift is not modelled.
Limits: zero-speed, deep-water data (the RAO is taken at the wave frequency; only the time
dependence uses omega_e); linear motions (small amplitudes); no coupling back of the
wave-frequency motion into the manoeuvring model except through what the integrator adds.

Data file (scripts/hydro_data.py documents every key): format_version 1, ship, omega (nw,
increasing), heading (nb, uniform on [0, 2 pi)), rao_amplitude / rao_phase (nw, nb, 6),
drift (nw, nb, 3), plus the added mass, damping, excitation, hydrostatics and mass properties
it was made from (validated here only for shape and finiteness).
"""
from __future__ import annotations

import math
import os
from typing import NamedTuple

import numpy as np
from numba import njit

FORMAT_VERSION = 1
DOFS = ("surge", "sway", "heave", "roll", "pitch", "yaw")
TWO_PI = 2.0 * math.pi

# key -> shape, with "nw", "nb" for the grid sizes; () a scalar
_NUMERIC = {
    "omega": ("nw",), "heading": ("nb",),
    "rao_amplitude": ("nw", "nb", 6), "rao_phase": ("nw", "nb", 6), "drift": ("nw", "nb", 3),
    "added_mass": ("nw", 6, 6), "radiation_damping": ("nw", 6, 6),
    "excitation_amplitude": ("nw", "nb", 6), "excitation_phase": ("nw", "nb", 6),
    "froude_krylov_amplitude": ("nw", "nb", 6), "froude_krylov_phase": ("nw", "nb", 6),
    "inertia_matrix": (6, 6), "hydrostatic_stiffness": (6, 6), "viscous_damping": (6, 6),
    "center_of_gravity": (3,), "rho": (), "g": (), "mass": (), "length": (), "beam": (), "draft": (),
    "draft_mesh": (), "displaced_volume": (), "mesh_panel_size": (), "mesh_faces": (), "format_version": (),
}
_TEXT = ("ship", "units", "notes")


def hydro_path(ship: str) -> str:
    """ships/hydro/<ship>.npz of the tug_dynamics package (source tree, else the installed share)."""
    from sim_math.data_files import package_data_dir
    return os.path.join(package_data_dir("tug_dynamics", "ships"), "hydro", ship + ".npz")


class HydroData:
    """The arrays of one hull's data file (attributes named as the file's keys) and `rao`, the
    complex RAO (nw, nb, 6). Build with `HydroData.load(path)`."""

    def __init__(self, path: str, arrays: dict):
        self.path = path
        for key, value in arrays.items():
            setattr(self, key, value)
        self.rao = self.rao_amplitude * np.exp(1j * self.rao_phase)
        self.excitation = self.excitation_amplitude * np.exp(1j * self.excitation_phase)

    @classmethod
    def load(cls, path: str) -> "HydroData":
        """Read and validate a data file; ValueError naming the file (and the key) otherwise."""
        path = os.path.abspath(path)
        if not os.path.isfile(path):
            raise ValueError(f"{path}: hydrodynamic data file not found (make it with scripts/hydro_data.py)")
        try:
            with np.load(path, allow_pickle=False) as z:
                raw = {k: z[k] for k in z.files}
        except Exception as exc:  # noqa: BLE001 - any unreadable file: name it
            raise ValueError(f"{path}: not a readable .npz hydrodynamic data file ({exc})") from None
        for key in (*_TEXT, *_NUMERIC):
            if key not in raw:
                raise ValueError(f"{path}: key '{key}' missing")
        out = {}
        for key in _TEXT:
            v = raw[key]
            if v.shape != () or v.dtype.kind != "U":
                raise ValueError(f"{path}: key '{key}' must be a string")
            out[key] = str(v)
        version = raw["format_version"]
        if version.shape != () or not np.issubdtype(version.dtype, np.number) or int(version) != FORMAT_VERSION:
            raise ValueError(f"{path}: key 'format_version' is {version!r}, this reader knows {FORMAT_VERSION}")
        for key in ("omega", "heading"):
            if raw[key].ndim != 1:
                raise ValueError(f"{path}: key '{key}' must be 1-D, has shape {raw[key].shape}")
        sizes = {"nw": raw["omega"].shape[0], "nb": raw["heading"].shape[0]}
        for key, spec in _NUMERIC.items():
            v = raw[key]
            want = tuple(sizes[s] if isinstance(s, str) else s for s in spec)
            if not np.issubdtype(v.dtype, np.number):
                raise ValueError(f"{path}: key '{key}' is not numeric (dtype {v.dtype})")
            if v.shape != want:
                raise ValueError(f"{path}: key '{key}' has shape {v.shape}, expected {want} "
                                 f"(nw = {sizes['nw']} frequencies, nb = {sizes['nb']} headings)")
            if not np.all(np.isfinite(v)):
                raise ValueError(f"{path}: key '{key}' has non-finite values (NaN or inf)")
            out[key] = v.astype(float) if v.ndim else (int(v) if v.dtype.kind in "iu" else float(v))
        w, b = out["omega"], out["heading"]
        if sizes["nw"] < 2 or not (np.all(np.diff(w) > 0.0) and w[0] > 0.0):
            raise ValueError(f"{path}: key 'omega' must hold >= 2 positive, increasing frequencies")
        if sizes["nb"] < 2 or abs(b[0]) > 1e-9 or not np.allclose(np.diff(b), TWO_PI / sizes["nb"], rtol=0, atol=1e-9):
            raise ValueError(f"{path}: key 'heading' must be uniform on [0, 2 pi): 0, 2 pi / nb, ...")
        if np.any(out["rao_amplitude"] < 0.0):
            raise ValueError(f"{path}: key 'rao_amplitude' has negative values")
        return cls(path, out)

    def _freq_table(self, table: np.ndarray, omega: np.ndarray) -> np.ndarray:
        """table (nw, nb, ...) linearly interpolated at each omega (clamped): (n, nb, ...)."""
        w = self.omega
        x = np.clip(np.asarray(omega, float), w[0], w[-1])
        j = np.clip(np.searchsorted(w, x, side="right") - 1, 0, len(w) - 2)
        f = ((x - w[j]) / (w[j + 1] - w[j])).reshape((-1,) + (1,) * (table.ndim - 1))
        return (1.0 - f) * table[j] + f * table[j + 1]

    def _heading_interp(self, table: np.ndarray, beta: np.ndarray) -> np.ndarray:
        """table (n, nb, ...) periodically interpolated at beta (n,) rad: (n, ...)."""
        nb = table.shape[1]
        pos = np.mod(beta, TWO_PI) * (nb / TWO_PI)
        j = np.floor(pos).astype(np.intp)
        f = (pos - j).reshape((-1,) + (1,) * (table.ndim - 2))
        j %= nb
        rows = np.arange(table.shape[0])
        return (1.0 - f) * table[rows, j] + f * table[rows, (j + 1) % nb]

    def rao_at(self, omega, beta) -> np.ndarray:
        """Complex RAO (n, 6) at frequencies omega (n,) rad/s and relative headings beta (n,) rad."""
        omega, beta = np.broadcast_arrays(np.atleast_1d(np.asarray(omega, float)), np.atleast_1d(np.asarray(beta, float)))
        return self._heading_interp(self._freq_table(self.rao, omega), beta)

    def drift_at(self, omega, beta) -> np.ndarray:
        """Drift coefficients (n, 3) X, Y (N/m^2), N (N m/m^2) at omega (n,), beta (n,)."""
        omega, beta = np.broadcast_arrays(np.atleast_1d(np.asarray(omega, float)), np.atleast_1d(np.asarray(beta, float)))
        return self._heading_interp(self._freq_table(self.drift, omega), beta)


class WaveSample(NamedTuple):
    displacement: np.ndarray    # (6,) m, m, m, rad, rad, rad (body axes)
    velocity: np.ndarray        # (6,) m/s, rad/s
    drift: np.ndarray           # (3,) N, N, N m (body axes)
    elevation: float = 0.0      # m, the sea surface at (x, y) (the ramp included)


@njit(cache=True)
def _evaluate(table, comp, work, work_j, x, y, psi, u, t, r, rdot, out):
    """The compiled `WaveResponse.evaluate` (the numpy `_interp` / `_motion` are its oracle in
    tests/physics/test_wave_response.py): out[0:6] displacement, [6:12] velocity, [12:15] drift,
    [15] elevation. One pass over the components, no temporaries (the vessel node calls it every
    step: 150 components cost about a tenth of the numpy version). comp (9, N): the components'
    a, kx, ky, omega, k, phase, direction and its cosine and sine (WaveResponse.comp: one
    argument, not nine, as numba's call costs per argument).

    work (N, 30), work_j (N,): each component's two table rows around its heading, copied when
    its heading cell changes (work_j holds the cell). The same numbers as gathering from the
    table every step, but the step reads 36 kB in order instead of scattered rows of a
    0.4 MB table: in the vessel node, where the other nodes' steps evict the caches between
    two of its own, that halved the call (benchmarks/bench_waves.py, docs/benchmarks.md)."""
    a, kx, ky, omega, k, phase, psi_w = comp[0], comp[1], comp[2], comp[3], comp[4], comp[5], comp[6]
    cos_w, sin_w = comp[7], comp[8]
    nb = table.shape[1]
    nv = table.shape[2]
    two_pi = 2.0 * math.pi
    cos_psi, sin_psi = math.cos(psi), math.sin(psi)
    out[:] = 0.0
    eta = 0.0
    for i in range(a.size):
        beta = (psi_w[i] - psi) % two_pi
        pos = beta * (nb / two_pi)
        j = int(pos)
        f = pos - j
        j %= nb
        if work_j[i] != j:
            j1 = (j + 1) % nb
            for d in range(nv):
                work[i, d] = table[i, j, d]
                work[i, nv + d] = table[i, j1, d]
            work_j[i] = j
        theta = kx[i] * x + ky[i] * y - omega[i] * t + phase[i]
        c, s = math.cos(theta), math.sin(theta)
        we = omega[i] - k[i] * u * (cos_w[i] * cos_psi + sin_w[i] * sin_psi)   # cos(beta)
        eta += a[i] * c
        for d in range(6):
            re = work[i, d] + f * (work[i, nv + d] - work[i, d])
            im = work[i, 6 + d] + f * (work[i, nv + 6 + d] - work[i, 6 + d])
            disp = c * re - s * im
            out[d] += disp
            out[6 + d] += we * (s * re + c * im)
        for d in range(3):
            out[12 + d] += work[i, 12 + d] + f * (work[i, nv + 12 + d] - work[i, 12 + d])
    for d in range(6):
        out[6 + d] = r * out[6 + d] + rdot * out[d]
        out[d] *= r
    for d in range(3):
        out[12 + d] *= r * r
    out[15] = r * eta


class WaveResponse:
    """One vessel's response to a WaveField (module docstring). `wave_field` needs the
    attributes amplitude, omega, k, direction, phase (arrays over the components) and the
    method ramp(t) -> (r, r'), as sea_environment.waves.WaveField has."""

    def __init__(self, hydro: HydroData, wave_field):
        self.hydro = hydro
        self.waves = wave_field
        self.a = np.asarray(wave_field.amplitude, float)
        self.omega = np.asarray(wave_field.omega, float)
        self.k = np.asarray(wave_field.k, float)
        self.psi_w = np.asarray(wave_field.direction, float)
        self.phase = np.asarray(wave_field.phase, float)
        self.kx = self.k * np.cos(self.psi_w)
        self.ky = self.k * np.sin(self.psi_w)
        # per component: the tables at its frequency over the heading grid, amplitude folded in:
        # columns 0-5 Re(a X), 6-11 Im(a X), 12-14 a^2 D (one gather serves motion and drift)
        rao = self.a[:, None, None] * hydro._freq_table(hydro.rao, self.omega)             # (N, nb, 6)
        drift = (self.a ** 2)[:, None, None] * hydro._freq_table(hydro.drift, self.omega)  # (N, nb, 3)
        self.table = np.ascontiguousarray(np.concatenate([rao.real, rao.imag, drift], axis=2))
        self._nb = self.table.shape[1]
        self._rows = np.arange(len(self.a))
        self._ramp_time = float(getattr(wave_field, "ramp_time", math.inf))
        self.comp = np.ascontiguousarray(np.stack([self.a, self.kx, self.ky, self.omega, self.k, self.phase,
                                                   self.psi_w, np.cos(self.psi_w), np.sin(self.psi_w)]))
        # _evaluate's working rows: none yet (cell -1)
        self.work = np.zeros((len(self.a), 2 * self.table.shape[2]))
        self.work_j = np.full(len(self.a), -1, np.int64)
        self._out = np.zeros(16)

    def ramp(self, t: float):
        """(r, r'): the sea's start-up ramp and its rate at t."""
        return self._ramp(t)

    def _ramp(self, t: float):
        if t >= self._ramp_time:          # r = 1, r' = 0 after the ramp (waves.py)
            return 1.0, 0.0
        r, rdot = self.waves.ramp(t)
        return float(r), float(rdot)

    def _interp(self, beta: np.ndarray) -> np.ndarray:
        """(N, 15) of the per-component table at beta (N,) (periodic, linear)."""
        pos = beta * (self._nb / TWO_PI)
        j = pos.astype(np.intp)                      # beta in [0, 2 pi): floor
        f = (pos - j)[:, None]
        j %= self._nb
        lo = self.table[self._rows, j]
        return lo + f * (self.table[self._rows, (j + 1) % self._nb] - lo)

    def relative_heading(self, psi: float) -> np.ndarray:
        """beta_i = psi_i - psi in [0, 2 pi): 180 deg head seas (module docstring)."""
        return np.mod(self.psi_w - psi, TWO_PI)

    def _motion(self, T: np.ndarray, beta, x, y, u, t, r, rdot):
        theta = self.kx * x + self.ky * y - self.omega * t + self.phase
        c, s = np.cos(theta), np.sin(theta)
        re, im = T[:, :6], T[:, 6:12]
        disp = c @ re - s @ im                       # Re(a X e^{i theta}) summed
        we = self.omega - self.k * u * np.cos(beta)
        vel = r * ((we * s) @ re + (we * c) @ im) + rdot * disp
        return r * disp, vel

    def motion(self, x: float, y: float, psi: float, u: float, t: float):
        """(displacement (6,), velocity (6,)) of the wave-frequency motion, body axes."""
        r, rdot = self._ramp(t)
        beta = self.relative_heading(psi)
        return self._motion(self._interp(beta), beta, x, y, u, t, r, rdot)

    def drift_force(self, psi: float, t: float) -> np.ndarray:
        """Mean drift (3,): X, Y (N), N (N m), body axes, scaled by the ramp squared."""
        r = self._ramp(t)[0]
        return (r * r) * self._interp(self.relative_heading(psi))[:, 12:].sum(axis=0)

    def evaluate(self, x: float, y: float, psi: float, u: float, t: float) -> WaveSample:
        """Displacement, velocity, drift and the elevation at (x, y) at once (compiled)."""
        r, rdot = self._ramp(t)
        out = self._out
        _evaluate(self.table, self.comp, self.work, self.work_j, float(x), float(y), float(psi), float(u), float(t), r, rdot, out)
        return WaveSample(out[0:6].copy(), out[6:12].copy(), out[12:15].copy(), float(out[15]))

    def evaluate_numpy(self, x: float, y: float, psi: float, u: float, t: float) -> WaveSample:
        """`evaluate` in numpy: the oracle of the compiled one."""
        r, rdot = self._ramp(t)
        beta = self.relative_heading(psi)
        T = self._interp(beta)
        disp, vel = self._motion(T, beta, x, y, u, t, r, rdot)
        theta = self.kx * x + self.ky * y - self.omega * t + self.phase
        return WaveSample(disp, vel, (r * r) * T[:, 12:].sum(axis=0), r * float(np.cos(theta) @ self.a))
