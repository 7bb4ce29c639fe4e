"""RopeChain: the towing rope as a chain of rigid cylinders after Yoon, Lee, Park, Kim,
"Dynamic Modeling and Simulation of a Towing Rope using Multiple Finite Element Method"
(2012). No ROS here. The sub-steps run in kernels.run_substeps; the winch at end a
(winch.Winch: the drum, the pay-out and the link insertion and removal between kernel calls)
works on the chain's arrays.

See rope_model/__init__.py for the API summary and README.md for the model.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import kernels as K
from .layout import (catenary_curve, close_with_fabrik, close_with_triangle, elements_from_joints,
                     joints_on_curve, polygon_on_catenary, straight_joints)
from .params import RopeParams, finite_vec3
from .winch import Winch

END_MODES = ("pinned", "fixed", "free")


class RopeDivergedError(RuntimeError):
    """The integration produced NaN/inf or absurd values; the rope keeps its last good state."""

    def __init__(self, message, step, time, element, connection=None):
        super().__init__(message)
        self.step = step
        self.time = time
        self.element = element
        self.connection = connection  # set when a "parting" was refused as a blow-up


@dataclass(frozen=True)
class PartingEvent:
    """A connection exceeded the breaking load and parted.

    connection: index c in 0..N (c joins element c-1 and element c; 0 and N are the
    attachments a and b) counted in the chain as it was at that time.
    """

    time: float
    connection: int
    tension: float


_vec3 = finite_vec3


def _state_array(name, doc):
    """A RopeChain state array: normally a view into the packed kernel arrays; assigning
    a new array (the winch's split / merge / drop, _restore) marks them for repacking."""
    key = "_" + name

    def get(self):
        try:
            return self.__dict__[key]
        except KeyError:
            raise AttributeError(name) from None

    def set(self, value):
        self.__dict__[key] = value
        self._packed = False

    return property(get, set, doc=doc)


def _on_drum(name, doc):
    """A RopeChain attribute that lives on its winch (RopeChain.drum, a winch.Winch)."""

    def get(self):
        return getattr(self.drum, name)

    def set(self, value):
        setattr(self.drum, name, value)

    return property(get, set, doc=doc)


def _end_name(end):
    if end == "a":
        return 0
    if end == "b":
        return 1
    raise ValueError(f"end must be 'a' or 'b', got {end!r}")


def _layout_arrays(X, E, lengths):
    """The layout as float arrays (copies), checked before anything is built from it: N >= 1
    elements, (N, 3) centres and axes, positive finite lengths, finite values; the axes are
    normalised."""
    X = np.array(X, dtype=float)
    E = np.array(E, dtype=float)
    L = np.array(lengths, dtype=float)
    n = L.shape[0] if L.ndim == 1 else -1
    if n < 1:
        raise ValueError(f"n_elements must be >= 1, got {max(n, 0)}")
    if X.shape != (n, 3) or E.shape != (n, 3):
        raise ValueError("positions and axes must have shape (N, 3)")
    if not (np.all(np.isfinite(L)) and np.all(L > 0)):
        raise ValueError(f"element lengths must be positive and finite, got min {L.min()}")
    if not (np.all(np.isfinite(X)) and np.all(np.isfinite(E))):
        raise ValueError("positions and axes must be finite")
    E /= np.linalg.norm(E, axis=1)[:, None]
    return X, E, L


def _check_settings(end_a, end_b, max_substep, theta, relaxation):
    """End modes and integration settings, refused before any state is built (theta: the
    implicit scheme's weight, 0.5 .. 1)."""
    for nm, m in (("end_a", end_a), ("end_b", end_b)):
        if m not in END_MODES:
            raise ValueError(f"{nm}: expected one of {END_MODES}, got {m!r}")
    if not (math.isfinite(max_substep) and max_substep > 0):
        raise ValueError(f"max_substep must be positive, got {max_substep}")
    if not (0.5 <= theta <= 1.0):
        raise ValueError(f"theta must be in [0.5, 1], got {theta}")
    if not (math.isfinite(relaxation) and relaxation >= 0):
        raise ValueError(f"relaxation must be >= 0, got {relaxation}")


class RopeChain:
    """N rigid cylindrical elements joined by tension-only spring-dampers (Eq 1-26).

    Element 0 is at end a (the tug in the paper), element N-1 at end b (the barge).
    Use the factories ``straight``, ``slack`` and ``wound_on_winch``.
    """

    VMAX = 2000.0  # m/s: beyond this the state is called diverged
    WMAX = 1.0e5  # rad/s
    PMAX = 1.0e7  # m from the origin

    # state, (N, 3) per element, (N,) or (N + 1,) per connection; views into the packed
    # kernel arrays (see _pack)
    X = _state_array("X", "element centres (N, 3)")
    E = _state_array("E", "element axes (N, 3), unit, towards end a")
    V = _state_array("V", "element velocities (N, 3)")
    W = _state_array("W", "element angular velocities (N, 3), perpendicular to E")
    L = _state_array("L", "element lengths (N,)")
    breaking_load = _state_array("breaking_load", "per-connection strength (N + 1,), N")
    tensions = _state_array("tensions", "connection tensions (N + 1,), N")
    conn_ok = _state_array("conn_ok", "connection intact (N + 1,), 0 / 1")
    armed = _state_array("armed", "parting armed (N + 1,), 0 / 1 (re-armed once unloaded)")
    env = _state_array("env", "environment per element (N, 7): current (3, added to the uniform "
                       "current), wind (3), seabed depth (inf: none); see set_environment")

    # the winch's drum state and settings, on self.drum (winch.Winch)
    winch = _on_drum("fitted", "True: end a is on a winch (wound_on_winch) that takes orders")
    winch_mode = _on_drum("mode", "the winch mode, one of WINCH_MODES (set_winch)")
    payout_rate = _on_drum("payout_rate", "the drum's pay-out rate now, m/s (+ out)")
    speed_order = _on_drum("speed_order", "the last 'speed' order, m/s (set_payout_rate)")
    set_tension = _on_drum("set_tension", "constant_tension: renders above this drum tension, N")
    recover_tension = _on_drum("recover_tension", "constant_tension: recovers below this drum "
                               "tension, N")
    brake_load = _on_drum("brake_load", "hold: the brake slips above this drum tension, N")
    winch_gain = _on_drum("gain", "the drum laws' gain, m/s per N")
    l_nom = _on_drum("l_nom", "nominal element length, m (element 0 kept within 0.5..1.5 of it)")

    def __init__(self, params: RopeParams, X, E, lengths, *, end_a="pinned", end_b="pinned",
                 p_a=None, p_b=None, winch=False, max_substep=0.01, theta=0.55,
                 relaxation=0.0, current=(0.0, 0.0, 0.0), nominal_element_length=None):
        if not isinstance(params, RopeParams):
            raise TypeError("params must be a RopeParams (see load_rope_params)")
        X, E, L = _layout_arrays(X, E, lengths)
        _check_settings(end_a, end_b, max_substep, theta, relaxation)
        self.params = params
        self._io = self._kernel_io(params)
        self._init_elements(X, E, L)
        self._init_ends(end_a, end_b, p_a, p_b)
        self._init_connections(L.shape[0])
        self._init_winch(winch, nominal_element_length)
        self._init_stepping(max_substep, theta, relaxation, current)
        self._pack()
        self._check_initial_layout(L)

    def _kernel_io(self, p: RopeParams):
        """The kernel's parameters, attachment data, flags and outputs in one array (one
        dispatch argument); the scalar parameters are fixed for the rope's life (params is
        frozen); theta, relaxation and current are properties writing into it, att_pos,
        att_vel, att_on etc. are views into it (_bind_io)."""
        io = np.zeros((K.IO_ROWS, 3))
        for key, v in ((K.P_MU, p.mass_per_length), (K.P_RADIUS, p.radius), (K.P_EA, p.ea),
                       (K.P_CD, p.drag_normal), (K.P_CF, p.drag_tangential),
                       (K.P_TFAC, p.tangential_area_factor), (K.P_CA, p.added_mass_coefficient),
                       (K.P_RHO_W, p.water_density), (K.P_RHO_A, p.air_density),
                       (K.P_G, p.gravity), (K.P_Z_AX, p.damping_ratio_axial),
                       (K.P_Z_TR, p.damping_ratio_transverse),
                       (K.P_Z_ROT, p.damping_ratio_rotational), (K.P_P_ROT, p.breaking_load),
                       (K.P_VMAX, self.VMAX), (K.P_WMAX, self.WMAX), (K.P_PMAX, self.PMAX),
                       (K.P_KBOT, p.seabed.stiffness), (K.P_CBOT, p.seabed.damping),
                       (K.P_MU_AX, p.seabed.friction_axial),
                       (K.P_MU_TR, p.seabed.friction_transverse),
                       (K.P_VSLIP, p.seabed.slip_speed)):
            io[key] = v
        return io

    def _init_elements(self, X, E, L):
        """Per-element state: the layout given, at rest, in calm water."""
        n = L.shape[0]
        self.X, self.E, self.L = X, E, L
        self.V = np.zeros((n, 3))
        self.W = np.zeros((n, 3))
        self.env = self._calm_env(n)
        self._environment = None    # attach_environment
        self._wave_cache = K.new_wave_cache(n, 0)   # the waves' phasors (kernels.sample_waves)

    def _init_ends(self, end_a, end_b, p_a, p_b):
        """End modes and attachment points; by default the points are the rope ends of the
        layout, so that the rope starts attached where it lies."""
        self.end_modes = [end_a, end_b]
        self._bind_io()
        self.att_on[:] = [m != "free" for m in self.end_modes]
        X, E, L = self.X, self.E, self.L
        front = X[0] + 0.5 * L[0] * E[0]
        aft = X[-1] - 0.5 * L[-1] * E[-1]
        self.att_pos[0] = front if p_a is None else _vec3(p_a, "p_a")
        self.att_pos[1] = aft if p_b is None else _vec3(p_b, "p_b")

    def _init_connections(self, n):
        """Per-connection state (N + 1 connections, the attachments included): all intact,
        armed to part, with the rope file's breaking load."""
        self.conn_ok = np.ones(n + 1, dtype=np.int64)
        self.armed = np.ones(n + 1, dtype=np.int64)  # parting re-armed once unloaded
        self.breaking_load = np.full(n + 1, float(self.params.breaking_load))

    def _init_winch(self, winch, nominal_element_length):
        """The winch at end a (self.drum), its drum stopped, in the mode and with the settings
        of the rope file's winch: section (set_winch changes them later)."""
        if winch and self.end_modes[0] == "free":
            raise ValueError("a winch needs end a attached ('pinned' or 'fixed')")
        self.drum = Winch(self.params, winch, nominal_element_length)

    def _init_stepping(self, max_substep, theta, relaxation, current):
        """Integration settings, the clock, the event log and the kernel's outputs and
        workspace, before the first step."""
        n = self.L.shape[0]
        self.max_substep = float(max_substep)
        self.theta = float(theta)
        self.relaxation = float(relaxation)
        self.current = _vec3(current, "current")
        self.time = 0.0
        self.step_count = 0
        self.events: list[PartingEvent] = []
        self.tensions = np.zeros(n + 1)
        self._ws = K.new_workspace(n)
        self._split = (0.0, 0.0, 1, 0.0)

    def _check_initial_layout(self, L):
        """Refuse a layout no run could start from: more rope deployed than the rope has, or
        a connection overloaded before any motion (straight between ends farther apart than
        the rope reaches, or an absurd EA). Computes the initial tensions and end forces."""
        params = self.params
        total = float(L.sum())
        if total > params.length * (1 + 1e-9):
            raise ValueError(f"deployed length {total:.3f} m exceeds rope length {params.length} m")
        self._refresh()
        if self.events or self._diverged_connection() is not None:
            c = int(self.events[0].connection if self.events else self._io[K.IO_DIAG, 0])
            T = float(self.events[0].tension if self.events else self._io[K.IO_DIAG, 1])
            span = float(np.linalg.norm(self.att_pos[1] - self.att_pos[0]))
            raise ValueError(
                f"initial layout overloads connection {c}: tension {T / 1e3:.1f} kN above the "
                f"breaking load {params.breaking_load / 1e3:.1f} kN at t = 0 (ends {span:.3f} m "
                f"apart, {total:.3f} m of rope, EA {params.ea:.4g} N): lay it slack or "
                f"shorten the span")

    _IO_VIEWS = ("att_on", "att_pos", "att_vel", "_io_flat", "_end_force", "_imp",
                 "_mean_end_force", "_end_views", "_ev_buf", "_info", "_nev")

    def _bind_io(self):
        """The attributes that are views into the kernel's io array."""
        io = self._io
        self.att_on = io[K.IO_ATT, 1:3]  # 1.0 / 0.0
        self.att_pos = io[K.IO_POS:K.IO_POS + 2]
        self.att_vel = io[K.IO_VEL:K.IO_VEL + 2]
        # set_end_kinematics writes through a memoryview (faster than numpy item access)
        self._io_flat = memoryview(io.reshape(-1))
        self._end_force = io[K.IO_FORCE:K.IO_FORCE + 2]
        self._imp = io[K.IO_IMPULSE:K.IO_IMPULSE + 2]
        self._mean_end_force = io[K.IO_MEAN:K.IO_MEAN + 2]
        self._end_views = tuple(io[r] for r in (K.IO_FORCE, K.IO_FORCE + 1, K.IO_MEAN,
                                                K.IO_MEAN + 1))
        self._ev_buf = io[K.IO_EVENTS:]
        self._info = io[K.IO_INFO, 0:2]  # divergence: sub-step, element
        self._nev = io[K.IO_NEV[0], K.IO_NEV[1]:K.IO_NEV[1] + 1]  # parting events recorded by the kernel

    def __getstate__(self):  # copy / pickle: views are rebuilt, the state repacked
        state = {k: v for k, v in self.__dict__.items() if k not in self._IO_VIEWS}
        state["_packed"] = False
        return state

    def __setstate__(self, state):
        self.__dict__.update(state)
        self._bind_io()

    # kernel parameters that may be changed between steps
    @property
    def theta(self):
        return float(self._io[K.P_THETA])

    @theta.setter
    def theta(self, value):
        self._io[K.P_THETA] = value

    @property
    def relaxation(self):
        return float(self._io[K.P_RELAX])

    @relaxation.setter
    def relaxation(self, value):
        self._io[K.P_RELAX] = value

    @property
    def current(self):
        """Uniform current (3,), m/s, world (a view: writing into it changes the current).
        A per-element current given to set_environment as an (N, 3) array is added to it
        (set_environment then sets this uniform part to zero)."""
        return self._io[K.IO_CUR]

    @current.setter
    def current(self, value):
        self._io[K.IO_CUR] = _vec3(value, "current")

    # ------------------------------------------------------------------ environment
    # columns of env, the kernel state's S[:N, SCUR:] (see _pack): current (3), wind (3),
    # seabed depth, and the waves (particle velocity 3, acceleration 3, surface elevation;
    # written by the kernel's sample_waves, zero without a sea)
    ENV_CUR, ENV_WIND, ENV_DEPTH = 0, K.SWIND - K.SCUR, K.SDEPTH - K.SCUR
    ENV_WAVE_VEL, ENV_WAVE_ACC, ENV_ETA = K.SWV - K.SCUR, K.SWA - K.SCUR, K.SETA - K.SCUR
    ENV_COLS = K.S_COLS - K.SCUR

    @classmethod
    def _calm_env(cls, n):
        env = np.zeros((n, cls.ENV_COLS))
        env[:, cls.ENV_DEPTH] = math.inf
        return env

    def element_centres(self):
        """(N, 3) element centres, m, world: where the caller samples the current, wind and
        seabed depth for set_environment (N changes when the winch turns)."""
        return self.X.copy()

    def attach_environment(self, data) -> None:
        """From now on every step samples the environment itself at the element centres (at
        its start; the current, wind and seabed depth set_environment would take, and the waves
        of its sea at the step's middle: kernels.sample_waves) from `data`, a
        sea_environment.sampler.EnvironmentSampler's packed array, whose time it advances by
        each step's dt. None detaches (the last values stay, as after set_environment)."""
        self._environment = data
        self._wave_cache = K.new_wave_cache(self.n_elements, 0 if data is None else K.wave_components(data))

    def set_environment(self, current=None, wind=None, seabed_depth=None):
        """The environment for the following steps, sampled by the caller at the element
        centres (element_centres()); each call replaces all three:

        current: water velocity (m/s, world ENU), (3,) uniform (the same as the property
            ``current``) or (N, 3) per element; None: still water. Water drag, fluid inertia
            and water entry of each element use its velocity relative to its own current.
        wind: air velocity (m/s, world; the velocity the air moves with, not the direction it
            comes from), (3,) or (N, 3); None: still air. The emerged part of each element
            feels air drag on its velocity relative to it.
        seabed_depth: depth of the seabed below the water surface z = 0 (m, positive down),
            a number or (N,) per element, inf for none; None: no seabed. An element end whose
            underside is below z = -depth gets the seabed contact of the rope file's
            ``seabed:`` parameters (params.SeabedParams).

        Bad input (wrong shape, NaN / inf velocities, a zero, negative or NaN depth) raises
        ValueError naming the argument and the element, and changes nothing. The winch's
        link changes between calls carry the values along (a new link takes its parent's).
        Fastest (about 1 us, checked in the compiled kernel): all three as float64 arrays of
        shapes (N, 3), (N, 3) and (N,)."""
        n = self.n_elements
        if (type(current) is np.ndarray and type(wind) is np.ndarray
                and type(seabed_depth) is np.ndarray and current.dtype == np.float64
                and wind.dtype == np.float64 and seabed_depth.dtype == np.float64
                and current.shape == (n, 3) and wind.shape == (n, 3)
                and seabed_depth.shape == (n,)):
            if not self._packed:
                self._pack()
            if K.set_environment(self._S, self._io, current, wind, seabed_depth) < 0:
                return
            # a bad value: the general path below names it
        cur = self._env_vectors(current, "current", n)
        wnd = self._env_vectors(wind, "wind", n)
        dep = self._env_depths(seabed_depth, n)
        env = self.env
        io = self._io
        c0, w0 = self.ENV_CUR, self.ENV_WIND
        if cur is None:
            io[K.IO_CUR] = 0.0
            env[:, c0:c0 + 3] = 0.0
        elif cur.ndim == 1:
            io[K.IO_CUR] = cur
            env[:, c0:c0 + 3] = 0.0
        else:
            io[K.IO_CUR] = 0.0
            env[:, c0:c0 + 3] = cur
        env[:, w0:w0 + 3] = 0.0 if wnd is None else wnd
        env[:, self.ENV_DEPTH] = math.inf if dep is None else dep
        env[:, self.ENV_WAVE_VEL:] = 0.0  # the caller's environment has no waves

    @staticmethod
    def _env_vectors(v, what, n):
        if v is None:
            return None
        a = v if (type(v) is np.ndarray and v.dtype == np.float64) else np.asarray(v, dtype=float)
        if a.shape != (3,) and a.shape != (n, 3):
            raise ValueError(f"set_environment: {what}: expected shape (3,) or (N, 3) = ({n}, 3) "
                             f"(one vector per element), got shape {a.shape}")
        if not np.isfinite(a).all():
            bad = np.argwhere(~np.isfinite(a))[0]
            where = f" at element {bad[0]}" if a.ndim == 2 else ""
            raise ValueError(f"set_environment: {what}: must be finite, got "
                             f"{float(a[tuple(bad)])!r}{where}")
        return a

    @staticmethod
    def _env_depths(d, n):
        if d is None:
            return None
        a = d if (type(d) is np.ndarray and d.dtype == np.float64) else np.asarray(d, dtype=float)
        if a.shape != () and a.shape != (n,):
            raise ValueError(f"set_environment: seabed_depth: expected a number or shape (N,) = "
                             f"({n},) (one depth per element), got shape {a.shape}")
        ok = a > 0.0  # NaN fails; inf passes (no seabed there)
        if not ok.all():
            bad = np.argwhere(~ok)[0] if a.ndim else ()
            where = f" at element {bad[0]}" if a.ndim else ""
            raise ValueError(f"set_environment: seabed_depth: expected a positive depth below "
                             f"the water surface (m, positive down) or inf for no seabed, got "
                             f"{float(a[tuple(bad)])!r}{where}")
        return a

    @property
    def wind(self):
        """(N, 3) wind at the elements, m/s (a copy)."""
        return self.env[:, self.ENV_WIND:self.ENV_WIND + 3].copy()

    @property
    def seabed_depth(self):
        """(N,) seabed depth at the elements, m (inf: none; a copy)."""
        return self.env[:, self.ENV_DEPTH].copy()

    def element_currents(self):
        """(N, 3) current at each element, m/s: the uniform part plus the per-element one."""
        return self.env[:, self.ENV_CUR:self.ENV_CUR + 3] + self._io[K.IO_CUR]

    # ------------------------------------------------------------------ factories
    @classmethod
    def _n(cls, params, n_elements):
        if not isinstance(params, RopeParams):
            raise TypeError("params must be a RopeParams (see load_rope_params)")
        n = params.n_elements if n_elements is None else n_elements
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
            raise ValueError(f"n_elements must be an integer >= 1, got {n!r}")
        return int(n)

    @staticmethod
    def _hang(p_a, p_b, L, sag_direction):
        joints = polygon_on_catenary(p_a, p_b, L, sag_direction)
        if joints is None:  # not longer than the span (or one element): along the curve
            joints = joints_on_curve(catenary_curve(p_a, p_b, float(L.sum()), sag_direction), L)
        # close exactly on p_b (the catenary of long links can miss it, e.g. ends on one
        # vertical, the tug and barge of section 4.6 starting side by side)
        joints = close_with_triangle(joints, L, p_b, sag_direction)
        if len(L) > 2:
            joints = close_with_fabrik(joints, L, p_b)
        return joints

    @classmethod
    def straight(cls, params, p_a, p_b, n_elements=None, **kw):
        """Rope laid straight from p_a to p_b (length = params.length; gaps or overlaps
        are spread evenly if the span differs)."""
        n = cls._n(params, n_elements)
        p_a, p_b = _vec3(p_a, "p_a"), _vec3(p_b, "p_b")
        if np.linalg.norm(p_b - p_a) == 0:
            raise ValueError("straight layout: p_a and p_b coincide")
        L = np.full(n, params.length / n)
        X, E = elements_from_joints(straight_joints(p_a, p_b, L), L)
        return cls(params, X, E, L, p_a=p_a, p_b=p_b, **kw)

    @classmethod
    def slack(cls, params, p_a, p_b, n_elements=None, sag_direction=(0.0, 0.0, -1.0),
              length=None, **kw):
        """Rope hanging as an inextensible catenary (longer than the span) in the plane of
        the chord and sag_direction (tilt it to start a sideways swing)."""
        n = cls._n(params, n_elements)
        p_a, p_b = _vec3(p_a, "p_a"), _vec3(p_b, "p_b")
        length = params.length if length is None else float(length)
        if not (math.isfinite(length) and length > 0):
            raise ValueError(f"length must be positive, got {length}")
        L = np.full(n, length / n)
        X, E = elements_from_joints(cls._hang(p_a, p_b, L, sag_direction), L)
        return cls(params, X, E, L, p_a=p_a, p_b=p_b, **kw)

    @classmethod
    def wound_on_winch(cls, params, p_a, p_b, deployed_length=None, n_elements=None,
                       sag_direction=(0.0, 0.0, -1.0), heading=(1.0, 0.0, 0.0), **kw):
        """Rope on a winch at end a with only ``deployed_length`` (default: the minimum)
        out, hanging slack between a and b (section 4.6). Elements have the nominal length
        params.length / n_elements except element 0 (at the winch), which grows and
        shrinks with pay-out and is split / merged to stay within 0.5..1.5 nominal. A slack
        deployed part shorter than 1.5 nominal lengths starts as two equal links. When a and
        b start on one vertical (section 4.6: tug and barge side by side) the hanging loop
        is laid out behind the horizontal ``heading`` the tug will run to, so that the rope
        leaves the drum in that direction."""
        n_full = cls._n(params, n_elements)
        l_nom = params.length / n_full
        dep = params.min_deployed_length if deployed_length is None else float(deployed_length)
        if not (math.isfinite(dep) and dep > 0):
            raise ValueError(f"deployed_length must be positive, got {dep}")
        if dep > params.length:
            raise ValueError(f"deployed_length {dep} exceeds rope length {params.length}")
        p_a, p_b = _vec3(p_a, "p_a"), _vec3(p_b, "p_b")
        n0 = max(1, int(math.floor(dep / l_nom + 0.5)))
        slack = dep > np.linalg.norm(p_b - p_a) * (1.0 + 1e-9)
        if slack and n0 < 2:  # a slack rope needs two links to hang between the ends
            L = np.full(2, 0.5 * dep)
        else:
            L = np.full(n0, l_nom)
            L[0] = dep - (n0 - 1) * l_nom
        g = _vec3(sag_direction, "sag_direction")
        g = g / np.linalg.norm(g)
        d_ab = p_b - p_a
        if np.linalg.norm(d_ab - (d_ab @ g) * g) < 1e-3:  # ends on one vertical
            hd = _vec3(heading, "heading")
            hd = hd - (hd @ g) * g
            if np.linalg.norm(hd) > 0:
                g = g - 0.5 * hd / np.linalg.norm(hd)  # loop hangs behind the heading
        X, E = elements_from_joints(cls._hang(p_a, p_b, L, g), L)
        kw.setdefault("end_a", "pinned")
        return cls(params, X, E, L, p_a=p_a, p_b=p_b, winch=True,
                   nominal_element_length=l_nom, **kw)

    # ------------------------------------------------------------------ settling
    SETTLE_RELAXATION = 2.0  # 1/s, numerical damping while settling (as the catenary tests use)
    SETTLE_STEP = 0.02  # s
    SETTLE_CHECK = 1.0  # s between convergence checks
    SETTLE_TENSION_TOL = (1e-5, 0.01)  # relative to the largest tension, absolute N, per check
    # m/s, element speed in the frame of the ends: a slack rope lying on the water creeps at
    # about 2 mm/s for minutes while its tensions stay put
    SETTLE_SPEED_TOL = 5e-3
    SETTLE_MAX_TIME = 600.0  # s

    def settle(self, velocity_a=(0.0, 0.0, 0.0), velocity_b=(0.0, 0.0, 0.0)):
        """Relax the laid-out rope to static equilibrium for its ends' present positions and
        their initial velocities, before step 0; returns the settling time (s).

        Galilean equivalence: ends moving at V in still water are ends fixed in a current -V.
        The ends are held where they are in the current (the real one minus V, V the mean
        velocity of the attached ends) and the model's own physics steps, with the numerical
        relaxation as extra damping, until every connection tension changes by less than
        SETTLE_TENSION_TOL over SETTLE_CHECK seconds and no element moves faster than
        SETTLE_SPEED_TOL. The rope then gets the ends' motion: each element the velocity
        interpolated along the rope between velocity_a and velocity_b (V itself when both are
        equal) and the rotation rate that matches it. Time, step count and the current are as
        before; nothing of the settling remains but the state. ValueError if the rope parts or
        does not settle within SETTLE_MAX_TIME (the ends too far apart, or a blow-up)."""
        va, vb = _vec3(velocity_a, "velocity_a"), _vec3(velocity_b, "velocity_b")
        drum = self.drum
        if drum.fitted and drum.mode == "speed" and drum.payout_rate != 0.0:
            raise ValueError("settle: the winch must be stopped while settling")
        mode = drum.mode  # 'hold' and 'constant_tension' settle with the drum locked
        drum.mode, drum.payout_rate = "speed", 0.0
        try:
            return self._settle(va, vb)
        finally:
            drum.mode = mode

    def _settle(self, va, vb):
        ends = [v if m == "pinned" else np.zeros(3) for v, m in zip((va, vb), self.end_modes)]
        attached = [v for v, m in zip(ends, self.end_modes) if m != "free"]
        v_ref = np.mean(attached, axis=0) if attached else np.zeros(3)
        # a fixed end does not move; a free end goes with the rest
        va, vb = (v_ref if m == "free" else v for v, m in zip(ends, self.end_modes))
        current, relaxation = self.current.copy(), self.relaxation
        self.att_vel[:] = 0.0
        self.current = current - v_ref
        self.relaxation = self.SETTLE_RELAXATION
        per_check = int(round(self.SETTLE_CHECK / self.SETTLE_STEP))
        last = self.tensions.copy()
        t = 0.0
        try:
            while True:
                for _ in range(per_check):
                    self.step(self.SETTLE_STEP)
                t += per_check * self.SETTLE_STEP
                if self.events:
                    e = self.events[0]
                    raise ValueError(f"the rope parts while settling to equilibrium (connection {e.connection}, "
                                     f"{e.tension / 1e3:.1f} kN): the ends are too far apart for it")
                T = self.tensions
                change = float(np.abs(T - last).max()) if T.shape == last.shape else math.inf
                speed = float(np.abs(self.V).max())
                rtol, atol = self.SETTLE_TENSION_TOL
                if change <= rtol * float(T.max()) + atol and speed <= self.SETTLE_SPEED_TOL:
                    break
                if t >= self.SETTLE_MAX_TIME:
                    raise ValueError(f"the rope did not settle to equilibrium in {t:.0f} s (tension still "
                                     f"changing {change:.3g} N/s, elements moving at {speed:.3g} m/s)")
                last = T.copy()
        finally:
            self.current = current
            self.relaxation = relaxation
        # the ends' motion: a velocity field linear in the unstretched arc length from a to b
        s_front = np.concatenate([[0.0], np.cumsum(self.L)[:-1]]) / self.L.sum()
        s_aft = np.cumsum(self.L) / self.L.sum()
        v_front = va + s_front[:, None] * (vb - va)
        v_aft = va + s_aft[:, None] * (vb - va)
        self.V = 0.5 * (v_front + v_aft)
        self.W = np.cross(self.E, v_front - v_aft) / self.L[:, None]  # perpendicular to E
        for i, v in enumerate((va, vb)):
            if self.end_modes[i] == "pinned":
                self.att_vel[i] = v
        self.events.clear()
        self.time = 0.0
        self.step_count = 0
        self._refresh()
        self._mean_end_force[:] = self._end_force
        return t

    # ------------------------------------------------------------------ inputs
    def set_end_kinematics(self, end, position, velocity=(0.0, 0.0, 0.0)):
        """Pinned end: attachment position (3,) and velocity (3,) at the current time, world
        frame. Rejects non-finite input without touching the state."""
        if end == "a":
            i = 0
        elif end == "b":
            i = 1
        else:
            raise ValueError(f"end must be 'a' or 'b', got {end!r}")
        try:  # fast path: called every exchange step
            px, py, pz = position
            vx, vy, vz = velocity
            px, py, pz = float(px), float(py), float(pz)
            vx, vy, vz = float(vx), float(vy), float(vz)
        except (TypeError, ValueError):
            _vec3(position, f"end {end} position")
            _vec3(velocity, f"end {end} velocity")
            raise
        if not (math.isfinite(px) and math.isfinite(py) and math.isfinite(pz)):
            raise ValueError(f"end {end} position: must be finite, got {[px, py, pz]}")
        if not (math.isfinite(vx) and math.isfinite(vy) and math.isfinite(vz)):
            raise ValueError(f"end {end} velocity: must be finite, got {[vx, vy, vz]}")
        if self.end_modes[i] != "pinned":
            raise ValueError(f"end {end} is '{self.end_modes[i]}', only a pinned end can move")
        io = self._io_flat  # att_pos[i] at 3 (IO_POS + i), att_vel[i] at 3 (IO_VEL + i)
        o = 3 * (K.IO_POS + i)
        io[o], io[o + 1], io[o + 2] = px, py, pz
        o = 3 * (K.IO_VEL + i)
        io[o], io[o + 1], io[o + 2] = vx, vy, vz

    # ------------------------------------------------------------------ winch (winch.Winch)
    WINCH_MODES = Winch.MODES
    MIN_WINCH_ELEMENTS = Winch.MIN_ELEMENTS

    def set_payout_rate(self, rate_m_per_s):
        """Winch at end a: positive pays out, negative heaves in (m/s). Length stays within
        [params.min_deployed_length, params.length]. Like any winch order the rate is clamped
        to params.winch_max_payout_speed / winch_max_heave_speed; returns a list of
        human-readable notes, one per clamp (empty: taken as given). NaN / inf: ValueError,
        nothing changed."""
        return self.drum.set_payout_rate(rate_m_per_s)

    def set_winch(self, mode=None, *, payout_rate=None, set_tension=None, recover_tension=None,
                  brake_load=None):
        """Winch order at end a. None keeps a setting as it is (the rope file's winch: section
        at the start). mode: 'speed' (the drum turns at payout_rate, m/s, + pays out; 0 locks
        it), 'hold' (brake: drum held while the drum tension T <= brake_load; above, it slips
        and pays out at min(gain (T - brake_load), winch_max_payout_speed)) or
        'constant_tension' (render above set_tension at min(gain (T - set_tension),
        winch_max_payout_speed), recover below recover_tension at min(gain (recover_tension -
        T), winch_max_heave_speed), hold in between). Tensions in N. Bad values (NaN, inf, a
        negative or zero set tension or brake load, a negative recover tension, recover above
        set tension, an unknown mode) raise ValueError naming the value, and nothing is
        changed. A set or recover tension above the breaking load, a brake load above twice
        it, and pay-out rates beyond the winch's speeds are clamped; returns the notes (one
        per clamp)."""
        return self.drum.order(mode, payout_rate=payout_rate, set_tension=set_tension,
                               recover_tension=recover_tension, brake_load=brake_load)

    def drum_rate(self, tension=None):
        """Pay-out rate (m/s, + out) the winch mode gives for the drum tension (N; default
        the present tension at end a, connection 0): the laws of set_winch."""
        return self.drum.drum_rate(self, tension)

    @property
    def winch_state(self):
        """What the drum does now: 'locked' (speed 0), 'paying out', 'heaving in' (speed
        order), 'held', 'slipping' (hold), 'rendering', 'recovering' (constant tension)."""
        return self.drum.state(self)

    # ------------------------------------------------------------------ stepping
    def _pack(self):
        """Copy the state arrays into the kernel's packed arrays (S float, F int, see
        kernels.py) and make the attributes views into them: the kernel then takes 4 array
        arguments instead of 11 (numba's dispatch costs about 50 ns per array)."""
        d = self.__dict__
        L = d["_L"]
        n = L.shape[0]
        S = np.zeros((n + 1, K.S_COLS))
        F = np.zeros((n + 1, K.F_COLS), dtype=np.int64)
        for key, col in (("_X", K.SX), ("_E", K.SE), ("_V", K.SV), ("_W", K.SW)):
            S[:n, col:col + 3] = d[key]
            d[key] = S[:n, col:col + 3]
        S[:n, K.SL] = L
        d["_L"] = S[:n, K.SL]
        S[:n, K.SCUR:] = d["_env"]
        d["_env"] = S[:n, K.SCUR:]
        for key, col in (("_breaking_load", K.SB), ("_tensions", K.ST)):
            S[:, col] = d[key]
            d[key] = S[:, col]
        for key, col in (("_conn_ok", K.F_OK), ("_armed", K.F_ARMED)):
            F[:, col] = d[key]
            d[key] = F[:, col]
        self._S, self._F = S, F
        if self._ws.shape[1] < n + 1:
            self._ws = K.new_workspace(n)
        if not K.wave_cache_fits(self._wave_cache, n, 0):   # the winch added links: a larger one
            self._wave_cache = K.new_wave_cache(n, self._wave_cache.shape[1])
        self._packed = True

    def _kernel(self, h, n_sub, payout, dt):
        """One run_substeps call (see kernels.run_substeps; dt > 0: a whole exchange step,
        the kernel also moves the attachments on and writes the mean end force)."""
        if not self._packed:
            self._pack()
        return K.run_substeps(self._S, self._F, self._io, self._ws, h, n_sub, payout, dt)

    def _refresh(self, t=None, payout=0.0):
        """Recompute tensions and end forces for the current state (no time advance;
        payout: rope sliding through the drum at this rate). Returns the kernel status."""
        st = self._kernel(0.0, 0, payout, 0.0)
        self._collect_events(self.time if t is None else t)
        return st

    def _diverged_connection(self):
        """Connection the kernel refused to part in its last call (see kernels.PART_MIN_ELASTIC),
        or None."""
        c = self._io[K.IO_DIAG, 0]
        return None if c < 0 else int(c)

    def _collect_events(self, t0):
        ne = int(self._nev[0])
        for k in range(min(ne, self._ev_buf.shape[0])):
            t, c, T = self._ev_buf[k]
            self.events.append(PartingEvent(t0 + float(t), int(c), float(T)))
        self._nev[0] = 0

    def _snapshot(self):
        return (self.X.copy(), self.E.copy(), self.V.copy(), self.W.copy(), self.L.copy(),
                self.conn_ok.copy(), self.armed.copy(), self.breaking_load.copy(),
                self.att_pos.copy(),
                self.tensions.copy(), self._end_force.copy(), len(self.events), self.env.copy())

    def _restore(self, s):
        (self.X, self.E, self.V, self.W, self.L, self.conn_ok, self.armed,
         self.breaking_load, att_pos, self.tensions, end_force, nev, self.env) = s
        self.att_pos[:] = att_pos  # views into the kernel's io array
        self._end_force[:] = end_force
        del self.events[nev:]
        self._nev[0] = 0

    def step(self, dt):
        """Advance dt seconds with sub-steps <= max_substep. Attachments move linearly with
        the velocity last given. Deterministic. Raises RopeDivergedError (state unchanged)."""
        dt = float(dt)
        if not (math.isfinite(dt) and dt > 0):
            raise ValueError(f"dt must be positive and finite, got {dt}")
        split = self._split  # sub-steps of the last dt (the exchange period rarely changes)
        if split[0] == dt and split[1] == self.max_substep:
            n_sub, h = split[2], split[3]
        else:
            n_sub = max(1, int(math.ceil(dt / self.max_substep - 1e-9)))
            h = dt / n_sub
            self._split = (dt, self.max_substep, n_sub, h)
        drum = self.drum
        if drum.fitted and (drum.payout_rate != 0.0 or drum.mode != "speed"):
            if self._environment is not None:    # at the step's start, as the kernel's path below
                if not self._packed:
                    self._pack()
                K.sample_environment(self._S, self._io, self._environment, dt, self._wave_cache)
                self._environment[K.P_TIME] += dt
            st = drum.step(self, dt, n_sub, h)
        else:  # the kernel restores the last good state itself on divergence, moves the
            # attachments on and writes the mean end force (impulse / dt)
            if not self._packed:
                self._pack()
            if self._environment is None:
                st = K.run_substeps(self._S, self._F, self._io, self._ws, h, n_sub, 0.0, dt)
            else:
                st = K.run_substeps_in_environment(self._S, self._F, self._io, self._ws, h, n_sub, 0.0, dt,
                                                   self._environment, self._wave_cache)
            if st == K.PARTED:
                self._collect_events(self.time)
                st = K.OK
        if st != K.OK:
            info = self._info
            k, j = min(int(info[0]), n_sub - 1), int(info[1])  # n_sub: the end-of-step evaluation
            t_fail = self.time + (k + 1) * h
            where = f"exchange step {self.step_count + 1}, sub-step {k + 1}/{n_sub} (t = {t_fail:.6f} s)"
            c = self._diverged_connection()
            if c is not None:
                T, Te = float(self._io[K.IO_DIAG, 1]), float(self._io[K.IO_DIAG, 2])
                n = self.n_elements
                pair = ("attachment a and element 0" if c == 0 else f"element {n - 1} and "
                        f"attachment b" if c == n else f"elements {c - 1} and {c}")
                raise RopeDivergedError(
                    f"rope diverged at {where}, connection {c} ({pair}): "
                    f"tension {T / 1e3:.1f} kN above the breaking load "
                    f"{float(self.breaking_load[c]) / 1e3:.1f} kN, but its elastic part (EA x "
                    f"axial strain) is only {Te / 1e3:.1f} kN: a damper or folded-link force of "
                    f"a numerical or input blow-up, not a parting; state left at "
                    f"t = {self.time:.6f} s", self.step_count + 1, t_fail, max(0, min(j, self.n_elements - 1)),
                    connection=c)
            raise RopeDivergedError(
                f"rope diverged at {where}, element {j}: non-finite or absurd state; "
                f"state left at t = {self.time:.6f} s", self.step_count + 1, t_fail, j)
        self.time += dt
        self.step_count += 1

    # ------------------------------------------------------------------ outputs
    @property
    def n_elements(self):
        return int(self.L.shape[0])

    @property
    def positions(self):
        return self.X.copy()

    @property
    def axes(self):
        """Unit body x axes (N,3), pointing towards end a."""
        return self.E.copy()

    @property
    def velocities(self):
        return self.V.copy()

    @property
    def angular_velocities(self):
        return self.W.copy()

    @property
    def lengths(self):
        return self.L.copy()

    @property
    def pitch_yaw(self):
        """(N,2) pitch theta and yaw psi of Eq (7), radians: body x = (c psi c theta,
        s psi c theta, -s theta); positive pitch = x axis (towards end a) pointing down."""
        E = self.E
        th = np.arctan2(-E[:, 2], np.hypot(E[:, 0], E[:, 1]))
        ps = np.arctan2(E[:, 1], E[:, 0])
        return np.stack([th, ps], axis=1)

    def body_velocities(self):
        """(N,5) the paper's V = (u, v, w, q, r) of Eq (2) in the yaw-pitch body frame."""
        th, ps = self.pitch_yaw.T
        cth, sth, cps, sps = np.cos(th), np.sin(th), np.cos(ps), np.sin(ps)
        xb = np.stack([cps * cth, sps * cth, -sth], 1)
        yb = np.stack([-sps, cps, np.zeros_like(th)], 1)
        zb = np.stack([cps * sth, sps * sth, cth], 1)
        V, W = self.V, self.W
        return np.stack([(V * xb).sum(1), (V * yb).sum(1), (V * zb).sum(1),
                         (W * yb).sum(1), (W * zb).sum(1)], 1)

    @property
    def unstretched_length(self):
        """Deployed (unstretched) rope length, m."""
        return float(self.L.sum())

    @property
    def total_mass(self):
        """Mass of the deployed rope, kg (= unstretched_length * mass_per_length)."""
        return float(self.params.mass_per_length * self.L.sum())

    @property
    def pieces(self):
        """List of (first, last+1) element ranges separated by parted connections."""
        out, start = [], 0
        for c in range(1, self.n_elements):
            if not self.conn_ok[c]:
                out.append((start, c))
                start = c
        out.append((start, self.n_elements))
        return out

    def end_force(self, end):
        """Force (3,) the rope exerts ON attachment a or b at the current state, N, world."""
        return self._end_views[_end_name(end)].copy()

    def mean_end_force(self, end):
        """Force on the attachment averaged over the last step(dt) (impulse / dt): apply
        this to the vessel for momentum-consistent coupling."""
        return self._end_views[2 + _end_name(end)].copy()

    def attachment_position(self, end):
        return self.att_pos[_end_name(end)].copy()

    def front_points(self):
        return self.X + 0.5 * self.L[:, None] * self.E

    def aft_points(self):
        return self.X - 0.5 * self.L[:, None] * self.E

    def joint_points(self):
        """(N+1,3) rope points: end a, the mid-points of the inner connections, end b.
        Attached ends give the attachment, free or parted ends the element end point."""
        fr, af = self.front_points(), self.aft_points()
        pts = np.empty((self.n_elements + 1, 3))
        pts[1:-1] = 0.5 * (af[:-1] + fr[1:])
        pts[0] = self.att_pos[0] if (self.att_on[0] and self.conn_ok[0]) else fr[0]
        pts[-1] = self.att_pos[1] if (self.att_on[1] and self.conn_ok[-1]) else af[-1]
        return pts

    def _mass_arrays(self):
        p = self.params
        n = self.n_elements
        m = p.mass_per_length * self.L
        ma = np.empty(n)
        ip = np.empty(n)
        for j in range(n):
            fr, _, _ = K.immersion(self.X[j, 2], self.E[j, 2], 0.5 * self.L[j], p.radius)
            vol = math.pi * p.radius ** 2 * self.L[j]
            rot = (self.L[j] ** 2 + 3 * p.radius ** 2) / 12.0
            ma[j] = p.added_mass_coefficient * p.water_density * vol * fr
            ip[j] = m[j] * rot + ma[j] * rot
        return m, ma, ip

    def momentum(self, elements=None):
        """Linear momentum (3,) incl. added mass, of all or of a slice of elements."""
        m, ma, _ = self._mass_arrays()
        V, E = self.V, self.E
        ue = (V * E).sum(1)
        P = m[:, None] * V + ma[:, None] * (V - ue[:, None] * E)
        if elements is not None:
            P = P[slice(*elements)]
        return P.sum(0)

    def kinetic_energy(self):
        m, ma, ip = self._mass_arrays()
        V, E = self.V, self.E
        ue = (V * E).sum(1)
        vn2 = (V * V).sum(1) - ue ** 2
        return float(0.5 * (m * (V * V).sum(1) + ma * vn2 + ip * (self.W * self.W).sum(1)).sum())

    def potential_energy(self):
        """Gravity (z = 0 datum) + elastic energy of the active connections, J.
        Buoyancy potential is not included (use in air)."""
        p = self.params
        m = p.mass_per_length * self.L
        pe = float((m * p.gravity * self.X[:, 2]).sum())
        return pe + self.elastic_energy()

    def elastic_energy(self):
        """Elastic energy of the stretched connections, J: EA / l_rep |d|^2 / 2 each (Eq 14's spring,
        l_rep the half lengths of the elements it joins); none in a compressed (slack) one."""
        p = self.params
        n = self.n_elements
        L, X = self.L, self.X
        Pp = np.vstack((self.att_pos[0:1], self.aft_points()))     # connection c: aft end of c - 1 ...
        Pn = np.vstack((self.front_points(), self.att_pos[1:2]))   # ... to the front end of c
        active = self.conn_ok.astype(bool).copy()
        active[0] &= bool(self.att_on[0])
        active[n] &= bool(self.att_on[1])
        half = 0.5 * L
        # tension only: a connection whose end lies inside the element it pulls on is slack
        active[1:] &= np.linalg.norm(Pn[1:] - X, axis=1) > half
        active[:n] &= np.linalg.norm(Pp[:n] - X, axis=1) > half
        lrep = np.concatenate(([0.0], half)) + np.concatenate((half, [0.0]))
        d2 = ((Pp - Pn) ** 2).sum(1)
        return float((0.5 * p.ea / lrep[active] * d2[active]).sum())

    def total_energy(self):
        return self.kinetic_energy() + self.potential_energy()
