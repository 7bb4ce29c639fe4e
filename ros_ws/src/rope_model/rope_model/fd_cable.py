"""FdCable: low-tension towed cable by finite differences (Park & Jung, "Nonlinear Dynamic
Analysis on Low-Tension Towed Cable by Finite Difference Method"). No ROS here.

Model: 10 unknowns per node (Eq 9), governing equations with bending stiffness (Eq 2-5),
Morison drag on the velocity relative to a uniform current (Eq 6), added mass (Eq 7), the
centred box scheme in space and time (Eq 13), Newton-Raphson per step from the extrapolated
guess (Eq 19-20), block tri-diagonal solve of the 10x10-block Jacobian (Fig. 2), free lower
end (Eq 14), top end moving with the ship with zero moment (Eq 15). The initial state is the
steady solution (Newton on the time-independent equations). Kernels: fd_kernels.py.

World frame ENU (x east, y north, z up; water surface z = 0), SI units, radians. The
paper's frame (X up, Y/Z horizontal, see fd_kernels) is converted at the edge: world =
R @ paper with R's columns = (up, h, up x h), h = (cos yaw, sin yaw, 0) the frame yaw. The
frame yaw starts along the steady cable (upstream; the heading in still water) and is
re-based about the vertical when the cable swings sideways (theta -> 90 deg is the
Euler-angle singularity of Eq 1).

Public node arrays are ordered from the towing point (index 0, paper node n, s = L; "end a"
of tug_msgs/RopeState) to the free end (index N-1, paper node 1, s = 0).

    params = load_cable_params(path)                      # FdCableParams; FdCableParamsError
    cable = FdCable(params, top_position, top_velocity, heading, n_nodes=None, current=None,
                    tangential_reference=None)                # None: R_t on v_t - u_t (Eq 6)
    cable.set_top_kinematics(position(3,), velocity(3,))  # world; ValueError on NaN/inf
    cable.step(dt)                                        # FdCableConvergenceError(step, ...)
    cable.top_force()                                     # (3,) force ON the ship, N, world
    cable.positions, .velocities, .tensions, .rotations, .angular_velocities,
    .segment_lengths, .stretched_segment_lengths, .unstretched_length, .stretched_length,
    .total_mass, .arc_lengths, .time, .steps
"""
from __future__ import annotations

import dataclasses
import math
import os
from dataclasses import dataclass, field

import numpy as np

from . import fd_kernels as FK
from .params import check_numbers, finite_vec3, shipped_rope_file
from .schema import (CableFile, RopeParamsError, check_density, read_yaml_mapping,
                     validate_file)

G0 = 9.80665  # m/s^2


class FdCableParamsError(RopeParamsError):
    """Bad cable parameter; the message names the file and the key (a RopeParamsError, so one
    except clause serves both rope file kinds)."""


class _Fail(Exception):
    def __init__(self, it, res, corr):
        super().__init__()
        self.it, self.res, self.corr = it, res, corr


class FdCableConvergenceError(RuntimeError):
    """Newton-Raphson did not converge within its limit; the cable keeps its last good step."""

    def __init__(self, message, step, time, residual, iterations):
        super().__init__(message)
        self.step = step
        self.time = time
        self.residual = residual
        self.iterations = iterations


@dataclass(frozen=True)
class FdCableParams:
    """Cable of Park & Jung (their Table 1 defaults). Derived values are documented at each property."""

    model: str = "fd_cable"
    name: str = "cable"
    length: float = 170.0  # m, unstretched
    n_nodes: int = 7  # Table 1 "node number"
    diameter: float = 0.035  # m
    weight_in_water: float = 17.7  # N/m, w0 of Eq 2
    # Table 1 gives no mass: None -> w0/g + rho*pi*d^2/4 (weight in water + buoyancy)
    mass_per_length: float | None = None
    youngs_modulus: float = 4.4e8  # Pa
    axial_stiffness: float | None = None  # N, EA; None -> E*pi*d^2/4
    # Table 1 gives no EI: None -> E*pi*d^4/64 (solid section of the Table 1 modulus)
    bending_stiffness: float | None = None
    drag_tangential: float = 0.01  # C_dt (Eq 6 on the surface pi*d)
    drag_normal: float = 1.5  # C_dn
    drag_binormal: float = 1.5  # C_db
    added_mass_coefficient: float = 1.0  # C_m = C_M - 1 (Eq 7)
    # True: added mass on the whole normal acceleration (frame-invariant); False: only on
    # vn_dot, vb_dot as Eq 12 literally writes K(2,5), K(3,6) = m + ma.
    added_mass_full_acceleration: bool = True
    water_density: float = 1025.0  # kg/m^3 (not in Table 1: sea water)
    gravity: float = G0
    # scenario defaults of Table 1 (the constructor's current=None uses current_along_heading)
    current_along_heading: float = -1.0  # m/s along the initial heading (Table 1: against the ship)
    tow_speed: float = 1.0  # m/s, Table 1 vessel speed
    # numerics
    time_weight: float = 0.5  # Eq 13 centred in time (0.5); up to 1 for numerical damping
    newton_tol: float = 1e-9  # max scaled correction (step 3 of section 3.2)
    newton_max_iter: int = 25
    # on failure: retry unextrapolated, then split the step in halves (top velocity
    # interpolated) up to this depth before raising
    max_halvings: int = 4
    rebase_angle: float = 0.7  # rad: re-base the paper frame when |theta| exceeds this
    source: str = field(default="<defaults>", compare=False)

    @property
    def area(self) -> float:
        return 0.25 * math.pi * self.diameter ** 2

    @property
    def mass(self) -> float:
        """m of Eq 2, kg/m."""
        if self.mass_per_length is not None:
            return float(self.mass_per_length)
        return self.weight_in_water / self.gravity + self.water_density * self.area

    @property
    def added_mass(self) -> float:
        """m_a of Eq 7, kg/m."""
        return self.added_mass_coefficient * self.water_density * self.area

    @property
    def ea(self) -> float:
        if self.axial_stiffness is not None:
            return float(self.axial_stiffness)
        return self.youngs_modulus * self.area

    @property
    def ei(self) -> float:
        if self.bending_stiffness is not None:
            return float(self.bending_stiffness)
        return self.youngs_modulus * math.pi * self.diameter ** 4 / 64.0

    def replace(self, **changes) -> "FdCableParams":
        """Copy with changes, validated like a file."""
        new = dataclasses.replace(self, **changes)
        _validate(new, new.source)
        return new


_POSITIVE = ("length", "diameter", "youngs_modulus", "water_density", "rebase_angle",
             "newton_tol")
_NONNEG = ("weight_in_water", "drag_tangential", "drag_normal", "drag_binormal",
           "added_mass_coefficient", "gravity")
_OPTIONAL_POSITIVE = ("mass_per_length", "axial_stiffness", "bending_stiffness")
_ANY = ("current_along_heading", "tow_speed")
_INTS = ("n_nodes", "newton_max_iter", "max_halvings")
_BOOLS = ("added_mass_full_acceleration",)


def _is_number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _validate(p: FdCableParams, src: str) -> None:
    def bad(key, what, got):
        raise FdCableParamsError(f"{src}: key '{key}': expected {what}, got {got!r}")

    if p.model != "fd_cable":
        bad("model", "'fd_cable'", p.model)
    if not isinstance(p.name, str):
        bad("name", "a string", p.name)
    check_numbers(p, bad, _POSITIVE, _NONNEG, _OPTIONAL_POSITIVE)
    for k in _ANY:
        if not _is_number(getattr(p, k)):
            bad(k, "a number", getattr(p, k))
    for k in _BOOLS:
        if not isinstance(getattr(p, k), bool):
            bad(k, "true or false", getattr(p, k))
    if not isinstance(p.n_nodes, int) or isinstance(p.n_nodes, bool) or p.n_nodes < 3:
        bad("n_nodes", "an integer >= 3", p.n_nodes)
    if not isinstance(p.newton_max_iter, int) or isinstance(p.newton_max_iter, bool) \
            or p.newton_max_iter < 1:
        bad("newton_max_iter", "an integer >= 1", p.newton_max_iter)
    if not (_is_number(p.time_weight) and 0.5 <= p.time_weight <= 1.0):
        bad("time_weight", "a number in [0.5, 1]", p.time_weight)
    if not isinstance(p.max_halvings, int) or isinstance(p.max_halvings, bool) \
            or not 0 <= p.max_halvings <= 12:
        bad("max_halvings", "an integer in 0..12", p.max_halvings)
    if p.rebase_angle >= 1.4:
        bad("rebase_angle", "below 1.4 rad (theta = pi/2 is singular)", p.rebase_angle)


_FIELDS = {f.name for f in dataclasses.fields(FdCableParams)} - {"source"}


def load_cable_params(path: str | os.PathLike) -> FdCableParams:
    """Read a cable YAML file (schema.CableFile: the FdCableParams field names, `model:
    fd_cable` required).

    Raises FileNotFoundError (with the path) or FdCableParamsError (file + key + expected).
    """
    src, data = read_yaml_mapping(path, "cable", FdCableParamsError)
    f = validate_file(CableFile, data, src, FdCableParamsError)
    kw = {k: getattr(f, k) for k in _FIELDS}
    p = FdCableParams(**kw, source=src)
    _validate(p, src)
    if not 1.0e3 <= p.ea <= 1.0e10:  # schema.EA: also when derived as E pi d^2 / 4
        raise FdCableParamsError(f"{src}: key 'youngs_modulus': E pi d^2 / 4 = {p.ea:g} N is "
                                 f"outside the axial stiffness range 1e3..1e10 N")
    if f.mass_per_length is not None:
        check_density(src, f.mass_per_length, f.diameter, FdCableParamsError)
    return p


def default_cable_path() -> str:
    """Path of the shipped Table 1 cable (ropes/cable_001.yaml)."""
    return shipped_rope_file("cable_001.yaml")


_vec3 = finite_vec3


def _frame(yaw):
    """R: world = R @ paper. Columns: paper X = up, Y = (cos yaw, sin yaw, 0), Z = X x Y."""
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[0.0, c, -s], [0.0, s, c], [1.0, 0.0, 0.0]])


def _triads(H):
    """(n, 3, 3) rows t, n, b in the paper frame (Eq 1, row 3 corrected)."""
    ph, th = H[:, FK.H_PHI], H[:, FK.H_THETA]
    cp, sp, ct, st = np.cos(ph), np.sin(ph), np.cos(th), np.sin(th)
    z = np.zeros_like(ph)
    t = np.stack([ct * cp, ct * sp, -st], axis=1)
    n = np.stack([-sp, cp, z], axis=1)
    b = np.stack([st * cp, st * sp, ct], axis=1)
    return np.stack([t, n, b], axis=1)


def _angles(t):
    """phi, theta of unit tangents t (n, 3) in the paper frame (inverse of Eq 1 row 1)."""
    return np.arctan2(t[:, 1], t[:, 0]), -np.arcsin(np.clip(t[:, 2], -1.0, 1.0))


def _parameter_vector(p):
    """The kernels' parameter vector (fd_kernels.P_*): masses, weight in water, stiffnesses
    and the drag factors of Eq 6."""
    mr = p.mass + (p.added_mass if p.added_mass_full_acceleration else 0.0)
    rho = p.water_density
    P = np.empty(FK.NP)
    P[FK.P_M], P[FK.P_MA], P[FK.P_MR], P[FK.P_W0] = p.mass, p.added_mass, mr, p.weight_in_water
    P[FK.P_EA], P[FK.P_EI] = p.ea, p.ei
    P[FK.P_KT] = 0.5 * rho * math.pi * p.diameter * p.drag_tangential  # Eq 6: R_t on pi*d
    P[FK.P_KN] = 0.5 * rho * p.diameter * p.drag_normal
    P[FK.P_KB] = 0.5 * rho * p.diameter * p.drag_binormal
    P[FK.P_RHOA] = rho * p.area  # Froude-Krylov per metre (Morison's inertia in waves)
    return P


class FdCable:
    """Towed cable, free lower end, top end at the ship's towing point (Eq 2-21)."""

    def __init__(self, params: FdCableParams, top_position, top_velocity, heading, *,
                 n_nodes=None, current=None, tangential_reference=None):
        if not isinstance(params, FdCableParams):
            raise TypeError("params must be an FdCableParams (see load_cable_params)")
        n = params.n_nodes if n_nodes is None else n_nodes
        if not isinstance(n, (int, np.integer)) or n < 3:
            raise ValueError(f"n_nodes must be an integer >= 3, got {n!r}")
        if not (isinstance(heading, (int, float)) and math.isfinite(heading)):
            raise ValueError(f"heading: must be a finite number (rad), got {heading!r}")
        self.params = params
        self.n = int(n)
        self.ds = params.length / (self.n - 1)
        self.top_position = _vec3(top_position, "top_position")
        self.top_velocity = _vec3(top_velocity, "top_velocity")
        self._state_top = self.top_position.copy()  # towing point of the current state
        self._state_vtop = self.top_velocity.copy()  # its velocity (BC of the current state)
        if current is None:
            current = params.current_along_heading * np.array(
                [math.cos(heading), math.sin(heading), 0.0])
        self.current = _vec3(current, "current")
        # R_t of Eq 6 acts on v_t relative to this world velocity: None = the current (Morison
        # drag on the relative velocity, the shipped reading); the literal Eq 6 "v_t" is the
        # cable's own velocity, i.e. a reference of 0 (over ground) or the ship's velocity
        # (a frame towed with the ship). Kept for the reading comparison (FD_CABLE.md, issue 15).
        self.tangential_reference = (None if tangential_reference is None
                                     else _vec3(tangential_reference, "tangential_reference"))
        self.heading = float(heading)
        # waves at the nodes, H order (index 0 = the free end), world: None = calm (set_waves)
        self._wave_vel = None
        self._wave_acc = None
        p = params
        self._P = _parameter_vector(p)
        # Newton convergence scales: forces by the cable weight, velocities 1 m/s, rad, 1/m
        self._scale = np.ones(FK.NV)
        self._scale[FK.H_FORCE] = max(p.weight_in_water * p.length, 1.0)
        self.time = 0.0
        self.steps = 0
        self.last_iterations = 0
        # paper frame: its vertical X-Y plane holds the steady cable (the horizontal flow
        # direction, upstream) so that theta ~ 0; the heading when there is no flow
        rel = self.current - self.top_velocity
        self._yaw = (math.atan2(-rel[1], -rel[0]) if math.hypot(rel[0], rel[1]) > 1e-3
                     else self.heading)
        self._R = _frame(self._yaw)
        self.H = self._steady_state()
        self._H_prev = None  # level i-1 for Eq 19
        self._dt_prev = None
        self._rates = np.zeros((self.n, FK.NV))

    # ------------------------------------------------------------------ frame helpers
    def _to_paper(self, w):
        return self._R.T @ w

    def _cur_paper(self):
        """(n, 9) per node, paper frame (fd_kernels.CUR_*): the water velocity (normal drag:
        current + waves), the tangential drag's reference and the waves' acceleration."""
        ref = self.current if self.tangential_reference is None else self.tangential_reference
        cur = np.zeros((self.n, FK.CUR_COLS))
        cur[:, FK.CUR_WATER:FK.CUR_WATER + 3] = self._R.T @ self.current
        cur[:, FK.CUR_REF:FK.CUR_REF + 3] = self._R.T @ ref
        if self._wave_vel is not None:
            wv = self._wave_vel @ self._R          # rows R^T v: world -> paper
            cur[:, FK.CUR_WATER:FK.CUR_WATER + 3] += wv
            if self.tangential_reference is None:  # the reference is the water itself
                cur[:, FK.CUR_REF:FK.CUR_REF + 3] += wv
            cur[:, FK.CUR_ACC:FK.CUR_ACC + 3] = self._wave_acc @ self._R
        return cur

    def set_waves(self, velocity=None, acceleration=None):
        """The wave particles' velocity and acceleration at the nodes for the coming step,
        (N, 3) each, world ENU, in the order of `positions` (index 0 = the towing point);
        None: a calm sea. The drag then acts on the velocity relative to current + waves, and
        Morison's inertia rho A ((1 + C_a) a_n + a_t) is added (fd_kernels' docstring)."""
        if velocity is None:
            self._wave_vel = self._wave_acc = None
            return
        v = np.asarray(velocity, float)
        a = np.asarray(acceleration, float)
        if v.shape != (self.n, 3) or a.shape != (self.n, 3) or not (np.isfinite(v).all() and np.isfinite(a).all()):
            raise ValueError(f"set_waves: expected finite (N, 3) = ({self.n}, 3) velocity and acceleration, "
                             f"got shapes {v.shape}, {a.shape}")
        self._wave_vel, self._wave_acc = v[::-1].copy(), a[::-1].copy()

    def _guess_straight(self):
        """Straight cable trailing 45 deg downstream (or hanging): a rough, generic guess."""
        n, p = self.n, self.params
        rel = self.current - self.top_velocity  # water velocity seen by the towing point
        rel_h = np.array([rel[0], rel[1], 0.0])
        up = np.array([0.0, 0.0, 1.0])
        if np.linalg.norm(rel_h) > 1e-3:
            # t points from the free end to the top: upstream and up
            t_w = -rel_h / np.linalg.norm(rel_h) * math.cos(math.radians(45)) \
                + up * math.sin(math.radians(45))
        else:
            t_w = up
        t_p = self._to_paper(t_w)
        H = np.zeros((n, FK.NV))
        ph, th = _angles(t_p[None, :])
        H[:, FK.H_PHI], H[:, FK.H_THETA] = ph[0], th[0]
        s = np.arange(n) * self.ds
        H[:, FK.H_T] = p.weight_in_water * s * 0.5
        vp = self._to_paper(self.top_velocity)
        tri = _triads(H)
        H[:, FK.H_VEL] = tri @ vp
        return H

    def _steady_state(self):
        """Newton on the time-independent equations (no time terms), damped from a generic
        guess. Raises FdCableConvergenceError(step 0) if it fails."""
        H = self._guess_straight()
        n = self.n
        nv = FK.NV
        A, D, C, r = (np.zeros((n, nv, nv)), np.zeros((n, nv, nv)), np.zeros((n, nv, nv)),
                      np.zeros((n, nv)))
        dummy3 = np.zeros((n, nv, nv))
        dummy2 = np.zeros((max(n - 1, 1), nv))
        vtop = self._to_paper(self.top_velocity)
        cur = self._cur_paper()
        res = math.inf
        max_iter = max(60, self.params.newton_max_iter)
        for it in range(1, max_iter + 1):
            res = FK.assemble(H, H, dummy3, dummy2, self._P, cur, vtop, self.ds, 1.0, 1.0, False,
                              A, D, C, r)
            try:
                dx = FK.block_tridiag_solve(A, D, C, r)
            except ValueError:  # singular: no unique steady shape (e.g. weightless, no flow)
                break
            if not np.all(np.isfinite(dx)):
                break
            # damping: at most 0.3 rad on any angle per iteration (far from the solution)
            big = np.max(np.abs(dx[:, FK.H_ANGLES]))
            lam = min(1.0, 0.3 / big) if big > 0 else 1.0
            H = H + lam * dx
            if lam == 1.0 and np.max(np.abs(dx) / self._scale) < self.params.newton_tol:
                self.last_iterations = it
                return H
        raise FdCableConvergenceError(
            f"fd_cable: steady (initial) solve did not converge at step 0 after {it} "
            f"iterations: residual max|Phi| = {res:.3e}", 0, 0.0, res, it)

    # ------------------------------------------------------------------ inputs
    def set_top_kinematics(self, position, velocity):
        """Towing-point position (3,) m and velocity (3,) m/s, world ENU, for the next step.

        Eq 15 takes the velocity; the position places the cable in the world once the
        step succeeds (positions show the state's towing point until then).
        Raises ValueError on a bad vector without changing the state.
        """
        p = _vec3(position, "top position")
        v = _vec3(velocity, "top velocity")
        self.top_position, self.top_velocity = p, v

    # ------------------------------------------------------------------ stepping
    def linear_system(self, dt):
        """(A, D, C, r): the Newton system (Eq 20-21) of the next step at its first guess,
        block tri-diagonal (A lower, D diagonal, C upper blocks, r = -Phi). For tests."""
        dt = float(dt)
        H0 = self.H
        Hg = self._extrapolate(H0, self._H_prev, self._dt_prev, dt)
        Ko, Cold = self._old_terms(H0)
        n, nv = self.n, FK.NV
        A, D, C, r = (np.zeros((n, nv, nv)), np.zeros((n, nv, nv)), np.zeros((n, nv, nv)),
                      np.zeros((n, nv)))
        FK.assemble(Hg, H0, Ko, Cold, self._P, self._cur_paper(),
                    self._to_paper(self.top_velocity), self.ds, dt, self.params.time_weight,
                    True, A, D, C, r)
        return A, D, C, r

    @staticmethod
    def _extrapolate(H0, Hm, dtm, dt):
        if Hm is None:
            return H0.copy()
        return H0 + dt * (H0 - Hm) / dtm  # Eq 19

    def _old_terms(self, H0):
        Ko = FK.k_matrices(H0, self._P)
        Cold = FK.old_level(H0, self._P, self._cur_paper(), self.ds,
                            self.params.time_weight)
        return Ko, Cold

    def _newton(self, H, H0, vtop_w, dt):
        """Newton-Raphson (section 3.2, steps 2-3) from the guess H. Returns
        (H or None, iterations, max|Phi| of the last iterate, last scaled correction)."""
        p = self.params
        Ko, Cold = self._old_terms(H0)
        vtop, cur = self._to_paper(vtop_w), self._cur_paper()
        n, nv = self.n, FK.NV
        A, D, C, r = (np.empty((n, nv, nv)), np.empty((n, nv, nv)), np.empty((n, nv, nv)),
                      np.empty((n, nv)))
        res, corr = math.inf, math.inf
        for it in range(1, p.newton_max_iter + 1):
            res = FK.assemble(H, H0, Ko, Cold, self._P, cur, vtop, self.ds, dt, p.time_weight,
                              True, A, D, C, r)
            try:
                dx = FK.block_tridiag_solve(A, D, C, r)
            except ValueError:
                return None, it, res, math.nan
            if not np.all(np.isfinite(dx)):
                return None, it, res, math.nan
            H = H + dx
            corr = float(np.max(np.abs(dx) / self._scale))
            if corr < p.newton_tol:
                return H, it, res, corr
        return None, p.newton_max_iter, res, corr

    def _advance(self, H0, Hm, dtm, v0, v1, dt, depth):
        """Advance (H0 at velocity v0) by dt to the top velocity v1. Fallbacks when Newton
        fails from the Eq 19 guess (a guess extrapolated across a sudden input change can be
        poor): the unextrapolated guess H0, then two half steps with the top velocity
        interpolated, up to max_halvings deep. Returns (H, H_prev, dt_prev, iterations) or
        raises _Fail carrying the first attempt's diagnostics."""
        H, it, res, corr = self._newton(self._extrapolate(H0, Hm, dtm, dt), H0, v1, dt)
        if H is not None:
            return H, H0, dt, it
        first = (it, res, corr)
        if Hm is not None:
            H, it2, _, _ = self._newton(H0.copy(), H0, v1, dt)
            if H is not None:
                return H, H0, dt, it + it2
        if depth >= self.params.max_halvings:
            raise _Fail(*first)
        try:
            vm = 0.5 * (v0 + v1)
            Ha, Hpa, dta, ia = self._advance(H0, Hm, dtm, v0, vm, 0.5 * dt, depth + 1)
            Hb, Hpb, dtb, ib = self._advance(Ha, Hpa, dta, vm, v1, 0.5 * dt, depth + 1)
        except _Fail:
            raise _Fail(*first) from None
        return Hb, Hpb, dtb, it + ia + ib

    def step(self, dt):
        """Advance by dt (s): Newton-Raphson on Eq 13-15 from the Eq 19 guess.

        Raises FdCableConvergenceError (naming the step and the residual) when Newton does
        not converge within newton_max_iter (also after the fallbacks of _advance); the
        state then stays at the last good step.
        """
        dt = float(dt)
        if not (math.isfinite(dt) and dt > 0):
            raise ValueError(f"dt must be positive and finite, got {dt}")
        p = self.params
        step_no = self.steps + 1
        H0 = self.H
        try:
            H, Hp, dtp, its = self._advance(H0, self._H_prev, self._dt_prev, self._state_vtop,
                                            self.top_velocity, dt, 0)
        except _Fail as f:
            raise FdCableConvergenceError(
                f"fd_cable: Newton-Raphson did not converge at step {step_no} "
                f"(t = {self.time + dt:.6g} s, dt = {dt:g} s) within {p.newton_max_iter} "
                f"iterations: residual max|Phi| = {f.res:.3e}, last scaled correction "
                f"{f.corr:.3e} (tolerance {p.newton_tol:g}; also failed after "
                f"{p.max_halvings} step halvings); state kept at step {self.steps}",
                step_no, self.time + dt, f.res, f.it) from None
        self._rates = (H - H0) / dt
        self._H_prev, self._dt_prev = Hp, dtp
        self.H = H
        self._state_top = self.top_position.copy()
        self._state_vtop = self.top_velocity.copy()
        self.time += dt
        self.steps = step_no
        self.last_iterations = its
        if np.max(np.abs(H[:, FK.H_THETA])) > p.rebase_angle:
            self._rebase()

    def _rebase(self):
        """Rotate the paper frame about the vertical so that its X-Y plane holds the mean
        cable direction (keeps theta away from the pi/2 singularity of Eq 1)."""
        tw = _triads(self.H)[:, 0, :] @ self._R.T  # world tangents
        h = tw[:, :2].sum(axis=0)
        if np.hypot(h[0], h[1]) < 1e-6:
            return
        yaw = math.atan2(h[1], h[0])
        Rn = _frame(yaw)
        Hn = self._transform(self.H, self._R, Rn, None)
        if self._H_prev is not None:
            self._H_prev = self._transform(self._H_prev, self._R, Rn, Hn[:, FK.H_PHI])
        self._rates = self._transform_rates(Rn)
        self.H, self._R, self._yaw = Hn, Rn, yaw

    @staticmethod
    def _transform(H, Ro, Rn, phi_ref):
        tri_w = _triads(H) @ Ro.T  # rows t, n, b in world
        F = (H[:, FK.H_FORCE, None] * tri_w).sum(axis=1)
        V = (H[:, FK.H_VEL, None] * tri_w).sum(axis=1)
        Kv = H[:, FK.H_ON, None] * tri_w[:, 1] + H[:, FK.H_OB, None] * tri_w[:, 2]
        t_new = tri_w[:, 0] @ Rn
        ph, th = _angles(t_new)
        ph = np.unwrap(ph) if phi_ref is None else phi_ref + (
            (ph - phi_ref + math.pi) % (2 * math.pi) - math.pi)
        out = H.copy()
        out[:, FK.H_PHI], out[:, FK.H_THETA] = ph, th
        tri_n = _triads(out) @ Rn.T
        out[:, FK.H_FORCE] = np.einsum("nki,ni->nk", tri_n, F)
        out[:, FK.H_VEL] = np.einsum("nki,ni->nk", tri_n, V)
        out[:, FK.H_ON] = np.einsum("ni,ni->n", tri_n[:, 1], Kv)
        out[:, FK.H_OB] = np.einsum("ni,ni->n", tri_n[:, 2], Kv)
        return out

    def _transform_rates(self, Rn):
        # only the angle rates are used (angular velocity); recompute them from the world
        # angular velocity after the re-base
        w = self._omega_world()
        tri_n = _triads(self._transform(self.H, self._R, Rn, None)) @ Rn.T
        rates = np.zeros_like(self._rates)
        # omega = phi_dot Z_p + theta_dot n  (Z_p = Rn[:, 2]); solve for the two rates
        zp = Rn[:, 2]
        for j in range(self.n):
            M = np.stack([zp, tri_n[j, 1]], axis=1)
            sol, *_ = np.linalg.lstsq(M, w[j], rcond=None)
            rates[j, FK.H_PHI], rates[j, FK.H_THETA] = sol
        return rates

    # ------------------------------------------------------------------ outputs (world)
    def _tri_world(self):
        return _triads(self.H) @ self._R.T  # (n, 3, 3) rows t, n, b

    def _omega_world(self):
        tri = self._tri_world()
        zp = self._R[:, 2]
        return (self._rates[:, FK.H_PHI, None] * zp[None, :]
                + self._rates[:, FK.H_THETA, None] * tri[:, 1])

    @property
    def n_nodes(self):
        return self.n

    @property
    def state(self):
        """H (n, 10) in the paper's order (columns fd_kernels.H_*; index 0 = free end) and
        paper frame; a copy."""
        return self.H.copy()

    @property
    def frame_yaw(self):
        """Yaw of the paper frame's horizontal Y axis in the world, rad."""
        return self._yaw

    @property
    def positions(self):
        """(N, 3) node positions, m, world; index 0 = towing point, N-1 = free end.

        Integrated from the towing point along the stretched tangent (1+e) t (trapezoid rule).
        """
        pos = np.empty((self.n, 3))
        FK.node_positions(self.H, self._R, self.params.ea, self.ds, self._state_top, pos)
        return pos

    @property
    def velocities(self):
        """(N, 3) node velocities, m/s, world; index 0 = towing point."""
        tri = self._tri_world()
        v = np.einsum("nk,nki->ni", self.H[:, FK.H_VEL], tri)
        return v[::-1].copy()

    @property
    def tensions(self):
        """(N,) effective tension T at the nodes, N (may dip below 0 at low tension: the model
        carries compression through EI); index 0 = towing point."""
        return self.H[::-1, FK.H_T].copy()

    @property
    def shear_forces(self):
        """(N, 2) shear forces (S_n, S_b), N; index 0 = towing point."""
        return self.H[::-1, FK.H_SN:FK.H_SB + 1].copy()

    @property
    def rotations(self):
        """(N, 3, 3) world rotation matrices, columns (t, n, b); t points towards the towing
        point (the RopeState x axis towards end a). Index 0 = towing point."""
        return np.transpose(self._tri_world(), (0, 2, 1))[::-1].copy()

    @property
    def angular_velocities(self):
        """(N, 3) angular velocity of the local frames over the last step, rad/s, world."""
        return self._omega_world()[::-1].copy()

    @property
    def arc_lengths(self):
        """(N,) unstretched arc length s from the free end (paper's s); index 0 = top (s = L)."""
        return (np.arange(self.n) * self.ds)[::-1].copy()

    @property
    def segment_lengths(self):
        """(N-1,) unstretched segment lengths, m (top first)."""
        return np.full(self.n - 1, self.ds)

    @property
    def stretched_segment_lengths(self):
        e = self.H[:, FK.H_T] / self.params.ea
        return (self.ds * (1.0 + 0.5 * (e[1:] + e[:-1])))[::-1].copy()

    @property
    def unstretched_length(self):
        return self.params.length

    @property
    def stretched_length(self):
        return float(self.stretched_segment_lengths.sum())

    @property
    def total_mass(self):
        """Structural mass, kg (without added mass)."""
        return self.params.mass * self.params.length

    def top_force(self):
        """(3,) force the cable exerts ON the ship's towing point, N, world.

        The internal force at s = L is F = T t + Sn n + Sb b (force of the ship on the cable,
        Eq 2); the ship feels -F.
        """
        tri = self._tri_world()[-1]
        return -(self.H[-1, FK.H_FORCE] @ tri)
