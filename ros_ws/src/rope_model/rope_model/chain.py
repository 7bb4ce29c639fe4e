"""RopeChain: the towing rope as a chain of rigid cylinders after Yoon, Lee, Park, Kim,
"Dynamic Modeling and Simulation of a Towing Rope using Multiple Finite Element Method"
(2012). No ROS here. The sub-steps run in kernels.run_substeps; the winch's link insertion
and removal (_winch, _split0, _merge01, _drop0, _halve) happen here between kernel calls.

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
        """The winch at end a, its drum stopped, in the mode and with the settings of the rope
        file's winch: section (set_winch changes them later)."""
        params = self.params
        self.winch = bool(winch)
        if self.winch and self.end_modes[0] == "free":
            raise ValueError("a winch needs end a attached ('pinned' or 'fixed')")
        self.l_nom = float(nominal_element_length or params.nominal_element_length)
        self.payout_rate = 0.0  # the drum's pay-out rate now, m/s (+ out): the order in 'speed'
        self._paying = False  # pay-out active in the current sub-step (not at a limit)
        w = params.winch.resolved(params.breaking_load, params.winch_max_payout_speed)
        self.winch_mode = w["mode"]
        self.set_tension = w["set_tension"]
        self.recover_tension = w["recover_tension"]
        self.brake_load = w["brake_load"]
        self.winch_gain = w["gain"]
        self.speed_order = 0.0  # the last 'speed' order, m/s

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
        self._nev = io[K.IO_INFO, 2:3]  # parting events recorded by the kernel

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
    ENV_CUR, ENV_WIND, ENV_DEPTH = 0, 3, 6  # columns of env

    @staticmethod
    def _calm_env(n):
        env = np.zeros((n, 7))
        env[:, 6] = math.inf
        return env

    def element_centres(self):
        """(N, 3) element centres, m, world: where the caller samples the current, wind and
        seabed depth for set_environment (N changes when the winch turns)."""
        return self.X.copy()

    def attach_environment(self, data) -> None:
        """From now on every step samples the environment itself at the element centres (at
        its start; the current, wind and seabed depth set_environment would take) from `data`,
        a sea_environment.sampler.EnvironmentSampler's packed array, whose time it advances by
        each step's dt. None detaches (the last values stay, as after set_environment)."""
        self._environment = data

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
        if cur is None:
            io[K.IO_CUR] = 0.0
            env[:, 0:3] = 0.0
        elif cur.ndim == 1:
            io[K.IO_CUR] = cur
            env[:, 0:3] = 0.0
        else:
            io[K.IO_CUR] = 0.0
            env[:, 0:3] = cur
        env[:, 3:6] = 0.0 if wnd is None else wnd
        env[:, 6] = math.inf if dep is None else dep

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
        return self.env[:, 3:6].copy()

    @property
    def seabed_depth(self):
        """(N,) seabed depth at the elements, m (inf: none; a copy)."""
        return self.env[:, 6].copy()

    def element_currents(self):
        """(N, 3) current at each element, m/s: the uniform part plus the per-element one."""
        return self.env[:, 0:3] + self._io[K.IO_CUR]

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
        if self.winch and self.winch_mode == "speed" and self.payout_rate != 0.0:
            raise ValueError("settle: the winch must be stopped while settling")
        mode = self.winch_mode  # 'hold' and 'constant_tension' settle with the drum locked
        self.winch_mode, self.payout_rate = "speed", 0.0
        try:
            return self._settle(va, vb)
        finally:
            self.winch_mode = mode

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

    def set_payout_rate(self, rate_m_per_s):
        """Winch at end a: positive pays out, negative heaves in (m/s). Length stays within
        [params.min_deployed_length, params.length]. Like any winch order the rate is clamped
        to params.winch_max_payout_speed / winch_max_heave_speed; returns a list of
        human-readable notes, one per clamp (empty: taken as given). NaN / inf: ValueError,
        nothing changed."""
        r = float(rate_m_per_s)
        if not math.isfinite(r):
            raise ValueError(f"payout rate must be finite, got {rate_m_per_s!r}")
        if not self.winch:
            raise ValueError("this rope has no winch (use RopeChain.wound_on_winch)")
        p = self.params
        notes = []
        if r > p.winch_max_payout_speed:
            notes.append(f"payout_rate {r:g} m/s clamped to {p.winch_max_payout_speed:g} m/s "
                         f"(winch_max_payout_speed)")
            r = float(p.winch_max_payout_speed)
        elif r < -p.winch_max_heave_speed:
            notes.append(f"payout_rate {r:g} m/s clamped to {-p.winch_max_heave_speed:g} m/s "
                         f"(winch_max_heave_speed)")
            r = -float(p.winch_max_heave_speed)
        self.speed_order = r
        if self.winch_mode == "speed":
            self.payout_rate = r
        return notes

    # winch modes (README "Winch"): what the drum does in each
    WINCH_MODES = ("speed", "hold", "constant_tension")

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
        if not self.winch:
            raise ValueError("this rope has no winch (use RopeChain.wound_on_winch)")
        if mode is not None and mode not in self.WINCH_MODES:
            raise ValueError(f"winch mode: expected one of {', '.join(self.WINCH_MODES)}, got {mode!r}")

        def value(name, v, allow_zero):
            if v is None:
                return None
            try:
                x = float(v)
            except (TypeError, ValueError):
                raise ValueError(f"winch {name}: expected a number (N), got {v!r}") from None
            if not math.isfinite(x) or x < 0.0 or (x == 0.0 and not allow_zero):
                raise ValueError(f"winch {name}: expected a finite {'non-negative' if allow_zero else 'positive'} "
                                 f"tension (N), got {v!r}")
            return x

        ts = value("set_tension", set_tension, False)
        tr = value("recover_tension", recover_tension, True)
        tb = value("brake_load", brake_load, False)
        if payout_rate is not None:
            r = float(payout_rate)
            if not math.isfinite(r):
                raise ValueError(f"payout rate must be finite, got {payout_rate!r}")
        notes = []
        bl = float(self.params.breaking_load)
        if ts is not None and ts > bl:
            notes.append(f"set_tension {ts:g} N clamped to {bl:g} N (breaking_load)")
            ts = bl
        if tr is not None and tr > bl:
            notes.append(f"recover_tension {tr:g} N clamped to {bl:g} N (breaking_load)")
            tr = bl
        if tb is not None and tb > 2.0 * bl:
            notes.append(f"brake_load {tb:g} N clamped to {2.0 * bl:g} N (2 x breaking_load)")
            tb = 2.0 * bl
        new_ts = self.set_tension if ts is None else ts
        new_tr = self.recover_tension if tr is None else tr
        if new_tr > new_ts:
            raise ValueError(f"winch recover_tension {new_tr:g} N is above set_tension {new_ts:g} N: "
                             f"the lower (recover) tension must not exceed the set (render) tension")
        if payout_rate is not None:
            notes += self.set_payout_rate(payout_rate)
        self.set_tension, self.recover_tension = new_ts, new_tr
        if tb is not None:
            self.brake_load = tb
        if mode is not None and mode != self.winch_mode:
            self.winch_mode = mode
            self.payout_rate = self.speed_order if mode == "speed" else 0.0
        return notes

    def drum_rate(self, tension=None):
        """Pay-out rate (m/s, + out) the winch mode gives for the drum tension (N; default
        the present tension at end a, connection 0): the laws of set_winch."""
        mode = self.winch_mode
        if mode == "speed":
            return self.speed_order
        if not self.conn_ok[0]:
            return 0.0
        T = float(self.tensions[0]) if tension is None else float(tension)
        p, g = self.params, self.winch_gain
        if mode == "hold":
            return min(g * (T - self.brake_load), p.winch_max_payout_speed) if T > self.brake_load else 0.0
        if T > self.set_tension:
            return min(g * (T - self.set_tension), p.winch_max_payout_speed)
        if T < self.recover_tension:
            return -min(g * (self.recover_tension - T), p.winch_max_heave_speed)
        return 0.0

    def _auto_rate(self, h):
        """The drum rate for the next sub-step h in 'hold' / 'constant_tension': drum_rate()
        taken implicitly for the drum connection's own response. Paying out dv faster lowers
        the drum tension within the sub-step by about K dv, K = theta h k0 + c0 (the drum
        connection's spring k0 = EA / (L0 / 2) over the theta point and its damper c0 =
        2 zeta_x sqrt(k0 mu L0), kernels._connection_constants); solving v = law(T - K (v -
        v_last)) instead of v = law(T) keeps the loop stable however short the drum link
        (the explicit law gives G k0 h > 2 from about N = 50 up and chatters) and changes no
        steady state: v_n = (law(T_n) + G K v_last) / (1 + G K), a lag of G K h per step."""
        v = self.drum_rate()
        if not self.conn_ok[0]:
            return v
        p = self.params
        l0 = float(self.L[0])
        k0 = p.ea / (0.5 * l0)
        c0 = 2.0 * p.damping_ratio_axial * math.sqrt(k0 * p.mass_per_length * l0)
        a = self.winch_gain * (self.theta * h * k0 + c0)
        return (v + a * self.payout_rate) / (1.0 + a)

    @property
    def winch_state(self):
        """What the drum does now: 'locked' (speed 0), 'paying out', 'heaving in' (speed
        order), 'held', 'slipping' (hold), 'rendering', 'recovering' (constant tension)."""
        r = self.payout_rate if self._winch_running() else 0.0
        mode = self.winch_mode
        if mode == "speed":
            return "locked" if r == 0 else ("paying out" if r > 0 else "heaving in")
        if r == 0:
            return "held"
        if mode == "hold":
            return "slipping"
        return "rendering" if r > 0 else "recovering"

    # ------------------------------------------------------------------ stepping
    def _pack(self):
        """Copy the state arrays into the kernel's packed arrays (S float, F int, see
        kernels.py) and make the attributes views into them: the kernel then takes 4 array
        arguments instead of 11 (numba's dispatch costs about 50 ns per array)."""
        d = self.__dict__
        L = d["_L"]
        n = L.shape[0]
        S = np.zeros((n + 1, K.S_COLS))
        F = np.zeros((n + 1, 2), dtype=np.int64)
        for key, col in (("_X", K.SX), ("_E", K.SE), ("_V", K.SV), ("_W", K.SW)):
            S[:n, col:col + 3] = d[key]
            d[key] = S[:n, col:col + 3]
        S[:n, K.SL] = L
        d["_L"] = S[:n, K.SL]
        S[:n, K.SCUR:K.SDEPTH + 1] = d["_env"]
        d["_env"] = S[:n, K.SCUR:K.SDEPTH + 1]
        for key, col in (("_breaking_load", K.SB), ("_tensions", K.ST)):
            S[:, col] = d[key]
            d[key] = S[:, col]
        for key, col in (("_conn_ok", 0), ("_armed", 1)):
            F[:, col] = d[key]
            d[key] = F[:, col]
        self._S, self._F = S, F
        if self._ws.shape[1] < n + 1:
            self._ws = K.new_workspace(n)
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
        if self.winch and (self.payout_rate != 0.0 or self.winch_mode != "speed"):
            if self._environment is not None:    # at the step's start, as the kernel's path below
                if not self._packed:
                    self._pack()
                K.sample_environment(self._S, self._io, self._environment)
                self._environment[K.P_TIME] += dt
            st = self._step_winch(dt, n_sub, h)
        else:  # the kernel restores the last good state itself on divergence, moves the
            # attachments on and writes the mean end force (impulse / dt)
            if not self._packed:
                self._pack()
            if self._environment is None:
                st = K.run_substeps(self._S, self._F, self._io, self._ws, h, n_sub, 0.0, dt)
            else:
                st = K.run_substeps_in_environment(self._S, self._F, self._io, self._ws, h, n_sub, 0.0, dt,
                                                   self._environment)
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
                pair = (f"attachment a and element 0" if c == 0 else f"element {n - 1} and "
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

    def _step_winch(self, dt, n_sub, h):
        """step() with the winch running: one kernel call per sub-step, the winch changes
        the arrays in between."""
        info = self._info
        snap = self._snapshot()
        rate0 = self.payout_rate
        imp_total = np.zeros((2, 3))
        pos0 = self.att_pos.copy()
        st = K.OK
        auto = self.winch_mode != "speed"
        for k in range(n_sub):
            self.att_pos[:] = pos0 + self.att_vel * (k * h)
            if auto:  # hold / constant tension: the rate from the drum tension of the last evaluation
                self.payout_rate = self._auto_rate(h)
            self._paying = self._winch_running()
            st = self._kernel(h, 1, self.payout_rate if self._paying else 0.0, 0.0) & ~K.PARTED
            self._collect_events(self.time + k * h)
            if st != K.OK:
                info[0] = k
                self._restore(snap)
                self.payout_rate = rate0
                break
            imp_total += self._imp
            self._winch(self.payout_rate * h, h)
        self._paying = False
        if st == K.OK:
            # tensions at the end of the step: the attachments where they are then, the rope
            # still sliding through the drum
            self.att_pos[:] = pos0 + self.att_vel * dt
            st = self._refresh(self.time + dt, self.payout_rate if self._winch_running() else 0.0) & ~K.PARTED
            if st != K.OK:
                info[0] = n_sub - 1
                self._restore(snap)
                self.payout_rate = rate0
                self.att_pos[:] = pos0
            else:
                self._mean_end_force[:] = imp_total * (1.0 / dt)
        else:
            self.att_pos[:] = pos0
        return st

    def _winch_running(self):
        """True while the winch turns: a pay-out rate is set, the rope is whole at the drum
        and the deployed length is inside its limits in the direction of the rate."""
        dep = float(self.L.sum())
        return bool(self.conn_ok[0]) and (
            (self.payout_rate > 0 and dep < self.params.length) or
            (self.payout_rate < 0 and dep > self.params.min_deployed_length))

    # ------------------------------------------------------------------ winch
    TINY = 1e-3  # element 0 is wound in completely below this fraction of a nominal length

    def _winch(self, dl, h):
        p = self.params
        if not self.conn_ok[0]:  # the rope has parted at the drum: nothing to wind
            return
        dep = float(self.L.sum())
        tgt = min(max(dep + dl, p.min_deployed_length), p.length)
        dl = tgt - dep
        tiny = self.TINY * self.l_nom
        can_drop = self.n_elements >= 2 and bool(self.conn_ok[1])
        if dl < 0.0:  # element 0 never shrinks below 'tiny' (then it is dropped)
            dl = max(dl, (tiny if can_drop else 0.5 * min(self.l_nom, self.L[0])) - self.L[0])
        if dl == 0.0:
            return
        l0 = self.L[0]
        l_new = l0 + dl
        # rope leaves / enters at the winch end of element 0: its far end stays (a material
        # point) and the element grows / shrinks along its axis at the drum end. The rope
        # slides out of the drum at the pay-out rate: new rope leaves with the drum velocity
        # minus rate * e, and the kernel gives the end connection the same sliding velocity,
        # so the end spring-damper sees no spurious motion.
        e = self.E[0]
        aft = self.X[0] - 0.5 * l0 * e
        m0 = p.mass_per_length * l0
        if dl > 0:
            v_new = self.att_vel[0] - (dl / h) * e
            self.V[0] = (m0 * self.V[0] + p.mass_per_length * dl * v_new) / (
                p.mass_per_length * l_new)
        self.X[0] = aft + 0.5 * l_new * e
        self.L[0] = l_new
        # slack rope piles up behind the drum: the drum end may not pass the drum
        drum = self.att_pos[0] + self.att_vel[0] * h  # attachment at the end of the sub-step
        over = (self.X[0] + 0.5 * l_new * e - drum) @ e
        if over > 0.0:
            self.X[0] -= over * e
        while self.L[0] > 1.5 * self.l_nom:
            self._split0()
        if dl < 0.0 and can_drop:
            if self.L[0] <= tiny * (1.0 + 1e-9):
                # wound in completely: element 1 now hangs from the drum, its front within
                # 'tiny' of it (merging two links at an angle would jump the geometry)
                self._drop0()
            elif (self.L[0] < 0.5 * self.l_nom and self.E[0] @ self.E[1] > 0.98
                  and self.n_elements > self.MIN_WINCH_ELEMENTS):
                self._merge01()  # nearly straight: merging moves nothing noticeably
            elif self.L[0] < 0.1 * self.L[1]:
                # a link much shorter than its neighbour is stiff and light (its axial
                # frequency grows as 1/length): merged even at an angle before it spins up
                self._merge01()
        if dl < 0.0:
            # a short rope of few long rigid links cannot fold between close bollards (two
            # 9 m links hung from bollards 3 m apart lock up and part): heave-in keeps at
            # least MIN_WINCH_ELEMENTS links, none longer than 1.25 times their share
            while True:
                j = int(np.argmax(self.L))
                dep = float(self.L.sum())
                if self.L[j] < 4.0 * tiny or (self.n_elements >= self.MIN_WINCH_ELEMENTS
                                              and self.L[j] <= 1.25 * dep / self.MIN_WINCH_ELEMENTS):
                    break
                self._halve(j)

    MIN_WINCH_ELEMENTS = 4  # heave-in keeps at least this many links (see _winch)

    def _halve(self, j):
        """Split element j into two collinear halves moving as the rigid element did: mass,
        momentum and angular momentum unchanged, the new joint whole and unloaded."""
        l, e, x, v, w = self.L[j], self.E[j].copy(), self.X[j].copy(), self.V[j].copy(), self.W[j].copy()
        q = 0.25 * l * e  # centre of each half from the element centre (front half towards end a)
        self.X = np.vstack([self.X[:j], x + q, x - q, self.X[j + 1:]])
        self.E = np.vstack([self.E[:j], e, e, self.E[j + 1:]])
        self.V = np.vstack([self.V[:j], v + np.cross(w, q), v - np.cross(w, q), self.V[j + 1:]])
        self.W = np.vstack([self.W[:j], w, w, self.W[j + 1:]])
        self.L = np.concatenate([self.L[:j], [0.5 * l, 0.5 * l], self.L[j + 1:]])
        self.env = np.insert(self.env, j + 1, self.env[j], axis=0)
        self.conn_ok = np.insert(self.conn_ok, j + 1, 1)
        self.armed = np.insert(self.armed, j + 1, 1)
        self.breaking_load = np.insert(self.breaking_load, j + 1, self.params.breaking_load)
        self.tensions = np.insert(self.tensions, j + 1, 0.0)

    def _drop0(self):
        self.X, self.E, self.V, self.W = self.X[1:], self.E[1:], self.V[1:], self.W[1:]
        self.L = self.L[1:].copy()
        self.X, self.E = self.X.copy(), self.E.copy()
        self.V, self.W = self.V.copy(), self.W.copy()
        self.env = self.env[1:].copy()
        self.conn_ok = np.delete(self.conn_ok, 1)
        self.armed = np.delete(self.armed, 1)
        self.breaking_load = np.delete(self.breaking_load, 1)
        self.tensions = np.delete(self.tensions, 1)

    def _split0(self):
        l0, ln = self.L[0], self.l_nom
        e, x0, v0, w0 = self.E[0].copy(), self.X[0].copy(), self.V[0].copy(), self.W[0].copy()
        front = x0 + 0.5 * l0 * e
        c_near = front - 0.5 * (l0 - ln) * e
        c_far = front - (l0 - ln) * e - 0.5 * ln * e
        # under tension (paying out a taut line: render, brake slip) the connections' gaps
        # hold the stretch of the half elements beside them (compliance l_rep / EA, l_rep the
        # two half lengths): redistribute them along e so that every tension is kept, the new
        # inner connection taking the drum tension; splitting with the gaps unchanged would
        # triple the drum connection's tension (its l_rep drops from l0/2 to (l0 - ln)/2)
        T0 = float(self.tensions[0]) if self.conn_ok[0] else 0.0
        T1 = float(self.tensions[1]) if self.conn_ok[1] else 0.0
        if T0 > 0.0 or T1 > 0.0:
            ea = self.params.ea
            back = T1 * 0.5 * (l0 - ln) / ea  # old connection 1: l_rep l0/2 + .. -> ln/2 + ..
            fwd = T0 * 0.5 * l0 / ea - back  # the new inner connection's gap, minus that shift
            if self.att_on[0] and self.conn_ok[0]:  # never past the drum
                fwd = min(fwd, max(0.0, float((self.att_pos[0] - front) @ e)))
            c_far = c_far - back * e
            c_near = c_near + max(fwd, -back) * e
        v_near = v0 + np.cross(w0, c_near - x0)
        v_far = v0 + np.cross(w0, c_far - x0)
        self.X = np.vstack([c_near, c_far, self.X[1:]])
        self.E = np.vstack([e, e, self.E[1:]])
        self.V = np.vstack([v_near, v_far, self.V[1:]])
        self.W = np.vstack([w0, w0, self.W[1:]])
        self.L = np.concatenate([[l0 - ln, ln], self.L[1:]])
        self.env = np.insert(self.env, 1, self.env[0], axis=0)
        self.conn_ok = np.insert(self.conn_ok, 1, 1)
        self.armed = np.insert(self.armed, 1, 1)
        self.breaking_load = np.insert(self.breaking_load, 1, self.params.breaking_load)
        self.tensions = np.insert(self.tensions, 1, self.tensions[0])

    def _merge01(self):
        mu = self.params.mass_per_length
        L0, L1 = self.L[0], self.L[1]
        front = self.X[0] + 0.5 * L0 * self.E[0]
        aft = self.X[1] - 0.5 * L1 * self.E[1]
        ln = L0 + L1
        # aim the merged element from the joint with element 2 (kept) at the drum, so that
        # any excess length is axial (slack), never a sideways jump
        d = (self.att_pos[0] if (self.att_on[0] and self.conn_ok[0]) else front) - aft
        nd = np.linalg.norm(d)
        e = d / nd if nd > 1e-9 else self.E[1].copy()
        m0, m1 = mu * L0, mu * L1
        v = (m0 * self.V[0] + m1 * self.V[1]) / (m0 + m1)
        # momentum kept (v); the rotation rate makes the kept joint move on as before, so
        # that its spring-damper sees no jump
        v_aft = self.V[1] + np.cross(self.W[1], aft - self.X[1])
        dv = v_aft - v
        dv -= (dv @ e) * e
        w = -(2.0 / ln) * np.cross(e, dv)
        x = aft + 0.5 * ln * e  # the joint with element 2 stays; any excess is at the drum
        self.X = np.vstack([x, self.X[2:]])
        self.E = np.vstack([e, self.E[2:]])
        self.V = np.vstack([v, self.V[2:]])
        self.W = np.vstack([w, self.W[2:]])
        self.L = np.concatenate([[ln], self.L[2:]])
        env = self.env
        merged = (L0 * env[0] + L1 * env[1]) / ln if np.isfinite(env[:2, 6]).all() else env[1]
        self.env = np.vstack([merged, env[2:]])
        self.conn_ok = np.delete(self.conn_ok, 1)
        self.armed = np.delete(self.armed, 1)
        self.breaking_load = np.delete(self.breaking_load, 1)
        self.tensions = np.delete(self.tensions, 1)

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
        p = self.params
        n = self.n_elements
        fr, af = self.front_points(), self.aft_points()
        e_tot = 0.0
        for c in range(n + 1):
            if not self.conn_ok[c]:
                continue
            hp, hn = c > 0, c < n
            if (not hp and not self.att_on[0]) or (not hn and not self.att_on[1]):
                continue
            Pp = af[c - 1] if hp else self.att_pos[0]
            Pn = fr[c] if hn else self.att_pos[1]
            if hp and np.linalg.norm(Pn - self.X[c - 1]) <= 0.5 * self.L[c - 1]:
                continue
            if hn and np.linalg.norm(Pp - self.X[c]) <= 0.5 * self.L[c]:
                continue
            lrep = (0.5 * self.L[c - 1] if hp else 0.0) + (0.5 * self.L[c] if hn else 0.0)
            d = Pp - Pn
            e_tot += 0.5 * p.ea / lrep * float(d @ d)
        return e_tot

    def total_energy(self):
        return self.kinetic_energy() + self.potential_energy()
