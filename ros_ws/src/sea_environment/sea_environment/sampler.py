"""The environment of a run packed for compiled code, and sampled in one compiled call: for a
vessel (`sample`) the current at its reference point, the apparent wind and Blendermann's wind
force, the depth, Ankudinov's shallow-water factors, squat, the under-keel clearance and the
bottom's friction when aground; for a point of a rope or cable (`flow_at_point`, `depth_at`)
the current, the wind at its height and the depth; the waves (waves.WaveField.packed) are
appended for the rope and cable kernels (at data[P_WAVE_AT], `wave_offset`). No ROS.

The models call these from inside their own compiled steps, once per exchange step, on the state
they have just reached (the values then hold over the next step). Every piece is a kernel the
rest of this package uses (current_xy, gust_speed, apparent_wind_xy, wind_wrench, bilinear,
squat, ankudinov_factors): one implementation, which the package's tests check against their
published sources. Why compiled: the same work as Python function calls cost about twice a
whole vessel model step (measured, benchmarks/bench_vessels.py).

Grounding (the physics is tug_dynamics.environment_loads'; its constants come in the
parameters): below zero clearance the lost buoyancy rho g A_wp (T + squat - h) presses the hull
on the bottom and Coulomb friction resists its horizontal motion at the reference point,
regularised linearly below the slip speed so it stops without chatter.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from .bathymetry import bilinear
from .environment import N_CURRENT, Environment, current_xy, current_xy_at, profile_c as _profile_c
from .shallow_water import ankudinov_factors, squat
from .wind import apparent_wind_xy, gust_speed
from .wind_loads import wind_wrench

G = 9.80665

# One float array holds everything the kernel reads and writes (each array handed to a compiled
# function costs its call time: one array, not five): the parameters (the current field's,
# environment.CurrentField.packed, first, then these), the sample (E_*), the gust record and the
# depth grid (row-major, south row first).
(P_TIME, P_HAS_WIND, P_WIND_MEAN, P_WIND_DIR_X, P_WIND_DIR_Y, P_GUST_DT, P_GUST_PERIOD, P_GUST_AT, P_GUST_N,
 P_DEPTH_KIND, P_DEPTH, P_GRID_X0, P_GRID_DX, P_GRID_Y0, P_GRID_DY, P_GRID_AT, P_GRID_NX, P_GRID_NY,
 P_LENGTH, P_BEAM, P_DRAFT, P_VOLUME, P_RHO_WATER, P_RHO_AIR, P_FRICTION, P_SLIP, P_WIND_PROFILE,
 P_WIND_LOW, P_DEPTH_MIN, P_WINDAGE) = range(N_CURRENT, N_CURRENT + 30)
N_PARAMS = P_WINDAGE + 10       # Windage.parameters(): Blendermann's five, then the five particulars
DEEP, UNIFORM_DEPTH, DEPTH_GRID = 0.0, 1.0, 2.0

# the sample, at data[N_PARAMS + E_*]: the current (world), the wind's force (world, horizontal)
# and its point (body x, height above the waterline), the bottom's friction (world, at the
# reference point), the status a vessel reports, and the shallow-water factors of Y'v, Y'r, N'v, N'r
(E_CURRENT_X, E_CURRENT_Y, E_WIND_FX, E_WIND_FY, E_WIND_X, E_WIND_Z, E_GROUND_FX, E_GROUND_FY,
 E_APPARENT_SPEED, E_APPARENT_ANGLE, E_DEPTH, E_SQUAT, E_CLEARANCE, E_GROUNDED,
 E_F_YV, E_F_YR, E_F_NV, E_F_NR, N_SAMPLE) = range(19)
E0 = N_PARAMS                   # where the sample starts in the data array
# after the sample: where the wave field's packed array (waves.WaveField.packed) starts in the
# data array, 0 for a calm sea. Placed after the sample, not among the P_* above, so no
# existing offset moves (compiled callers bake them in as constants).
P_WAVE_AT = E0 + N_SAMPLE
N_FIXED = P_WAVE_AT + 1         # parameters + sample + the wave offset; records follow


class EnvironmentSampler:
    """The packed environment (.data) with the particulars of one vessel (for `sample`; a rope's
    points need none), the sample of a vessel's present state (.out, a view) and the
    simulation time the samples are taken at (.time)."""

    def __init__(self, env: Environment, *, length: float = math.nan, beam: float = math.nan,
                 draft: float = math.nan, volume: float = math.nan, windage=None, rho_water: float = 1025.0,
                 rho_air: float = 1.225, ground_friction: float = 0.4, ground_slip: float = 0.05):
        p = np.zeros(N_FIXED)
        p[:N_CURRENT] = env.current.packed
        gust, grid = np.zeros(0), np.zeros((0, 0))
        if env.wind is not None:
            wind = env.wind
            p[P_HAS_WIND] = 1.0
            p[P_WIND_DIR_X], p[P_WIND_DIR_Y] = wind.direction
            p[P_WIND_MEAN] = wind.record.mean if wind.record is not None else wind.u10
            if wind.record is not None:
                p[P_GUST_DT], p[P_GUST_PERIOD] = wind.record.dt, wind.record.period
                gust = np.asarray(wind.record.gust, float)
            p[P_WIND_PROFILE] = _profile_c(wind.u10)
            p[P_WIND_LOW] = 1.0 + p[P_WIND_PROFILE] * math.log(1.0 / 10.0)
            if windage is not None:
                p[P_WINDAGE:N_PARAMS] = windage.parameters()
        depth = env.depth
        if depth.grid is not None:
            g = depth.grid
            p[P_DEPTH_KIND] = DEPTH_GRID
            p[P_GRID_X0], p[P_GRID_DX] = g.x[0], g.x[1] - g.x[0]
            p[P_GRID_Y0], p[P_GRID_DY] = g.y[0], g.y[1] - g.y[0]
            grid = np.asarray(g.values, float)
            p[P_GRID_NY], p[P_GRID_NX] = grid.shape
            p[P_DEPTH_MIN] = grid.min()
        elif not depth.is_deep:
            p[P_DEPTH_KIND], p[P_DEPTH] = UNIFORM_DEPTH, depth.uniform
            p[P_DEPTH_MIN] = depth.uniform
        else:
            p[P_DEPTH_MIN] = math.inf
        p[P_LENGTH], p[P_BEAM], p[P_DRAFT], p[P_VOLUME] = length, beam, draft, volume
        p[P_RHO_WATER], p[P_RHO_AIR], p[P_FRICTION], p[P_SLIP] = rho_water, rho_air, ground_friction, ground_slip
        p[P_GUST_AT], p[P_GUST_N] = p.size, gust.size
        p[P_GRID_AT] = p.size + gust.size
        # the waves last (a calm sea, env.waves None: nothing appended, P_WAVE_AT 0): the
        # rope and cable kernels sample them from this one array (kernels.sample_environment)
        waves = env.waves.packed if getattr(env, "waves", None) is not None else np.zeros(0)
        if waves.size:
            p[P_WAVE_AT] = p.size + gust.size + grid.size
        self.data = np.concatenate([p, gust, grid.ravel(), waves])
        self.out = self.data[E0:E0 + N_SAMPLE]

    @property
    def time(self) -> float:
        return float(self.data[P_TIME])

    @time.setter
    def time(self, t: float) -> None:
        self.data[P_TIME] = t

    def sample(self, x: float, y: float, yaw: float, u: float, v: float) -> np.ndarray:
        """Sample at .time for a vessel at (x, y) heading yaw with body velocity (u, v); returns
        (and keeps in .out) the E_* values."""
        sample(self.data, x, y, yaw, u, v)
        return self.out


@njit(cache=True, inline="always")
def wave_offset(data):
    """Where the packed wave field starts in data (waves.wave_kinematics' `at`); 0: calm sea."""
    return int(data[P_WAVE_AT])


@njit(cache=True)
def wind_at_10m(data):
    """The wind speed at 10 m (mean + gust) at time data[P_TIME]; 0 without wind."""
    p = data
    if p[P_HAS_WIND] == 0.0:
        return 0.0
    if p[P_GUST_N] == 0.0:
        return p[P_WIND_MEAN]
    at = int(p[P_GUST_AT])
    return gust_speed(p[P_WIND_MEAN], data[at:at + int(p[P_GUST_N])], p[P_GUST_DT], p[P_GUST_PERIOD], p[P_TIME])


@njit(cache=True, inline="always")
def depth_at(data, x, y):
    """The depth at (x, y): the grid's bilinear value, the uniform depth or inf (deep)."""
    p = data
    if p[P_DEPTH_KIND] == DEEP:
        return math.inf
    if p[P_DEPTH_KIND] == DEPTH_GRID:
        at, nx, ny = int(p[P_GRID_AT]), int(p[P_GRID_NX]), int(p[P_GRID_NY])
        return bilinear(p[P_GRID_X0], p[P_GRID_DX], p[P_GRID_Y0], p[P_GRID_DY], data, at, nx, ny, x, y)
    return p[P_DEPTH]


@njit(cache=True, inline="always")
def flow_at_point(data, tide, w10, x, y, z):
    """(current east, north; wind east, north) at (x, y, z) at the time whose tidal factor
    (environment.tidal_factor) and 10 m wind (wind_at_10m) are `tide` and `w10` (the
    time-dependent parts: once per call for a whole rope). The wind at height z follows the
    ISO 19901-1 mean profile, heights below 1 m counting as 1 m (as WindField.velocity)."""
    p = data
    cx, cy = current_xy_at(p, tide, x, y)
    if z > 1.0:
        w = w10 * (1.0 + p[P_WIND_PROFILE] * math.log(z / 10.0))
    else:       # at and below 1 m: the profile's value at 1 m (no log per submerged element)
        w = w10 * p[P_WIND_LOW]
    return cx, cy, w * p[P_WIND_DIR_X], w * p[P_WIND_DIR_Y]


@njit(cache=True)
def sample(data, x, y, yaw, u, v):
    """The E_* values at time data[P_TIME] for a vessel at (x, y) heading yaw (rad) moving at
    (u, v) (body, m/s), into data[E0:]."""
    p = data
    e = data[E0:E0 + N_SAMPLE]
    cx, cy = current_xy(p, p[P_TIME], x, y)
    e[E_CURRENT_X], e[E_CURRENT_Y] = cx, cy
    c, s = math.cos(yaw), math.sin(yaw)
    vx, vy = c * u - s * v, s * u + c * v               # horizontal velocity over ground
    if p[P_HAS_WIND] != 0.0:
        w10 = wind_at_10m(data)
        speed, angle = apparent_wind_xy(w10 * p[P_WIND_DIR_X], w10 * p[P_WIND_DIR_Y], vx, vy, yaw)
        w = P_WINDAGE
        fx, fy, xp, zp, _n = wind_wrench(speed, angle, p[P_RHO_AIR], p[w], p[w + 1], p[w + 2], p[w + 3],
                                         p[w + 4], p[w + 5], p[w + 6], p[w + 7], p[w + 8], p[w + 9])
        # force in the horizontal plane, world axes (heel and trim do not tilt the wind)
        e[E_WIND_FX], e[E_WIND_FY] = c * fx - s * fy, s * fx + c * fy
        e[E_WIND_X], e[E_WIND_Z] = xp, zp
        e[E_APPARENT_SPEED], e[E_APPARENT_ANGLE] = speed, angle
    e[E_GROUND_FX] = 0.0
    e[E_GROUND_FY] = 0.0
    e[E_GROUNDED] = 0.0
    if p[P_DEPTH_KIND] == DEEP:
        e[E_DEPTH], e[E_SQUAT], e[E_CLEARANCE] = math.inf, 0.0, math.inf
        e[E_F_YV] = e[E_F_YR] = e[E_F_NV] = e[E_F_NR] = 1.0
        return
    h = depth_at(data, x, y)
    length, beam, draft, volume = p[P_LENGTH], p[P_BEAM], p[P_DRAFT], p[P_VOLUME]
    block = volume / (length * beam * draft)
    # 0 (dry land in a grid) -> aground, not an error
    f_yv, f_yr, f_nv, f_nr, _g = ankudinov_factors(length, beam, draft, block, max(h, 1e-3))
    e[E_F_YV], e[E_F_YR], e[E_F_NV], e[E_F_NR] = f_yv, f_yr, f_nv, f_nr
    sq = squat(math.hypot(vx - cx, vy - cy), max(h, draft), length, volume)
    clearance = h - draft - sq
    e[E_DEPTH], e[E_SQUAT], e[E_CLEARANCE] = h, sq, clearance
    if clearance < 0.0:
        e[E_GROUNDED] = 1.0
        waterplane = (1.0 + 2.0 * block) / 3.0 * length * beam   # C_wp from C_b (Schneekluth)
        normal = p[P_RHO_WATER] * G * waterplane * -clearance
        scale = p[P_FRICTION] * normal / max(math.hypot(vx, vy), p[P_SLIP])
        e[E_GROUND_FX], e[E_GROUND_FY] = -scale * vx, -scale * vy
