"""The environment of a run in one object: wind, current and depth as fields in space and time,
built from the scenario's ``environment`` section. Pure numpy/scipy, no ROS. The vessel and rope
nodes sample it where their bodies and elements are, once per exchange step.

Scenario form (knots and compass degrees true at this edge, SI inside)::

    environment:
      wind: {speed_kn: 30.0, from_deg: 270.0, gusts: true, seed: 7}   # 1-hour mean at 10 m
      current: [0.3, 0.0]                  # uniform, m/s east, north; or a field:
      current: {speed_kn: 2.0, towards_deg: 90.0,        # along the stream's axis
                shear_per_s: 0.001,        # + this speed (m/s) per metre to the stream's left
                tidal_period_s: 44712.0,   # reversing stream: speed * cos(2 pi t / T + phase)
                phase_deg: 0.0}
      depth: 15.0                          # uniform, m; or a bathymetry grid:
      depth: {grid: harbour.asc}           # ESRI ASCII grid (bathymetry.py), path relative to the scenario
      waves: {hs: 3.0, tp: 9.0, from_deg: 0.0,   # significant height m, peak period s, coming FROM (deg true)
              spectrum: jonswap,           # jonswap | pierson_moskowitz | regular (hs: height H, tp: period)
              gamma: 3.3,                  # JONSWAP peak enhancement (default 3.3; jonswap only)
              spreading_s: null,           # null: long-crested; s: cos-2s short-crested spreading
              components: 150, seed: 1,    # the sea's components and their random draws
              ramp_time: 30.0}             # s of half-cosine start-up (default 3 Tp)

Without ``wind`` the air is still; without ``depth`` the water is deep (no shallow-water effects,
no seabed); without ``waves`` (or with hs 0) the sea is calm and no wave field exists. The waves
(waves.py) are one linear sea every body samples at its own place and time; their dispersion
uses the uniform depth, or a grid's mean wet depth (one sea over the scene: no refraction or
shoaling over the grid). The current field is the analytic one above: a steady or tidally reversing stream
with a linear cross-stream shear (a channel's edge or a river bend's outer side: the speed grows
towards one bank). Everything is validated here (pydantic, strict): a bad value fails before any
node starts, naming the key.
"""
from __future__ import annotations

import math
import re
from typing import List, Literal, Optional, Union

import numpy as np
from numba import njit
from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator
from typing_extensions import Annotated

from .bathymetry import DepthGrid
from .waves import G, WaveField, WaveKinematics, wavenumber
from .wind import KNOT, GustRecord

# pydantic's names of Union members in an error's location (list[...], constrained-float, ...Spec)
_UNION_BRANCH = re.compile(r"\[|^constrained-|^function-|^[A-Z][A-Za-z0-9]*Spec$|^float$|^int$")
MAX_CURRENT = 10.0  # m/s (about 19 kn): faster than any tidal stream or river a tow works in


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, strict=True, allow_inf_nan=False)


class WindSpec(_Strict):
    speed_kn: float = Field(ge=0.0, le=120.0)       # 1-hour mean at 10 m; 120 kn: beyond hurricane force
    from_deg: float = Field(ge=-360.0, le=360.0)     # compass, where it comes from
    gusts: bool = True                               # NPD / ISO 19901-1 gusts (wind.py)
    seed: int = Field(0, ge=0)


class CurrentFieldSpec(_Strict):
    speed_kn: float = Field(ge=0.0, le=MAX_CURRENT / KNOT)
    towards_deg: float = Field(ge=-360.0, le=360.0)  # compass, where the stream sets (flood direction)
    shear_per_s: float = Field(0.0, ge=-0.1, le=0.1)  # d(speed)/d(distance to the stream's left), 1/s
    tidal_period_s: Optional[float] = Field(None, gt=60.0, le=1e6)
    phase_deg: float = Field(0.0, ge=-360.0, le=360.0)
    # half-width of the stream (m) beyond which the shear stops growing (keeps the speed bounded)
    half_width_m: float = Field(2000.0, gt=0.0, le=1e6)


class DepthGridSpec(_Strict):
    grid: str = Field(min_length=1)                 # ESRI ASCII grid file (bathymetry.py)


class WavesSpec(_Strict):
    """One linear sea for every body (waves.py): a regular wave or a JONSWAP / Pierson-Moskowitz
    spectrum, long- or short-crested, from a seed; hs 0 is a calm sea."""
    hs: float = Field(ge=0.0, le=20.0)              # m, significant wave height 4 sqrt(m0); regular: height H
    tp: float = Field(ge=1.0, le=30.0)              # s, spectral peak period; regular: the period
    from_deg: float = Field(ge=-360.0, le=360.0)     # compass, where the waves come from (like the wind)
    spectrum: Literal["jonswap", "pierson_moskowitz", "regular"] = "jonswap"   # DNV-RP-C205 3.5.5; PM is gamma 1
    gamma: Optional[float] = Field(None, ge=1.0, le=10.0)   # JONSWAP peak enhancement; null: 3.3
    spreading_s: Optional[float] = Field(None, gt=0.0, le=100.0)  # cos-2s exponent; null: long-crested
    components: int = Field(150, ge=10, le=2000)    # irregular seas: one per frequency bin
    seed: int = Field(0, ge=0)                      # random frequencies, directions and phases
    ramp_time: Optional[float] = Field(None, ge=0.0, le=3600.0)  # s, half-cosine start-up; null: 3 tp

    @model_validator(mode="after")
    def _consistent(self):
        if self.gamma is not None and self.spectrum != "jonswap":
            raise ValueError(f"gamma is only for spectrum jonswap (pierson_moskowitz is gamma 1), got spectrum "
                             f"{self.spectrum!r}")
        if self.spreading_s is not None and self.spectrum == "regular":
            raise ValueError("spreading_s is only for an irregular sea (a regular wave is long-crested)")
        return self


# Miche (1944): a wave breaks beyond H / L = 0.142 tanh(k h) (1/7 in deep water)
BREAKING_STEEPNESS = 1.0 / 7.0


Uniform2 = Annotated[List[Annotated[float, Field(ge=-MAX_CURRENT, le=MAX_CURRENT)]],
                     Field(min_length=2, max_length=2)]


class EnvironmentSpec(_Strict):
    current: Union[Uniform2, CurrentFieldSpec] = [0.0, 0.0]
    wind: Optional[WindSpec] = None
    depth: Optional[Union[Annotated[float, Field(gt=0.0, le=12000.0)], DepthGridSpec]] = None
    waves: Optional[WavesSpec] = None

    @field_validator("waves")
    @classmethod
    def _not_breaking(cls, waves, info):
        """Hs over the peak wavelength (at the uniform depth; deep water for a grid, whose depths
        are read later) within Miche's limit."""
        if waves is None or waves.hs == 0.0:
            return waves
        depth = info.data.get("depth")
        h = float(depth) if isinstance(depth, (int, float)) else math.inf
        k = float(wavenumber(2.0 * math.pi / waves.tp, h))
        limit = BREAKING_STEEPNESS * (math.tanh(k * h) if math.isfinite(h) else 1.0)
        steep = waves.hs * k / (2.0 * math.pi)
        if steep > limit:
            where = f"depth {h:g} m" if math.isfinite(h) else "deep water"
            raise ValueError(f"hs {waves.hs:g} m over the peak wavelength {2.0 * math.pi / k:.1f} m (tp {waves.tp:g} s, "
                             f"{where}) is {steep:.3f}, above the breaking limit {limit:.3f} (Miche: 1/7 tanh(k h))")
        return waves


def _towards(deg: float) -> np.ndarray:
    """Unit vector (east, north) of a compass direction (0 = north, clockwise)."""
    th = math.radians(deg)
    return np.array([math.sin(th), math.cos(th)])


class WindField:
    """The air's velocity over ground (east, north), m/s: the NPD mean profile with one gust
    record along the mean direction (gusts are taken as coherent over the scene: a tow is a few
    hundred metres, the gusts that move a ship are tens of seconds, i.e. several hundred metres)."""

    def __init__(self, spec: WindSpec):
        self.u10 = spec.speed_kn * KNOT
        self.direction = tuple(-_towards(spec.from_deg))  # it blows towards the opposite of "from"
        self.record = GustRecord(self.u10, 10.0, seed=spec.seed) if spec.gusts else None

    def speed_at_10m(self, t: float) -> float:
        return self.record.speed(t) if self.record is not None else self.u10

    def velocity_xy(self, t: float) -> tuple:
        """(east, north) m/s at 10 m: the scalar form a vessel needs every step."""
        s10 = self.speed_at_10m(t)
        return s10 * self.direction[0], s10 * self.direction[1]

    def velocity(self, t: float, z=10.0):
        """(2,) for a scalar height, (N, 2) for heights (N,); heights below 1 m count as 1 m."""
        s10 = self.speed_at_10m(t)
        if self.u10 <= 0.0:
            return np.zeros(2) if np.ndim(z) == 0 else np.zeros((np.size(z), 2))
        ratio = _profile_ratio(self.u10, np.maximum(np.asarray(z, float), 1.0))
        return np.multiply.outer(s10 * ratio, np.array(self.direction))


def profile_c(u10: float) -> float:
    """C of the ISO 19901-1 mean profile U(z) = U(10 m) (1 + C ln(z/10)) (wind.mean_speed_at)."""
    return 5.73e-2 * math.sqrt(1.0 + 0.148 * u10)


def _profile_ratio(u10: float, z):
    """U(z) / U(10 m) of the ISO 19901-1 mean profile (wind.mean_speed_at)."""
    return 1.0 + profile_c(u10) * np.log(z / 10.0)


# CurrentField.packed: the field's parameters in the order current_xy reads them
(CUR_UNIFORM, CUR_UX, CUR_UY, CUR_AXIS_X, CUR_AXIS_Y, CUR_LEFT_X, CUR_LEFT_Y, CUR_SPEED, CUR_SHEAR,
 CUR_HALF_WIDTH, CUR_OMEGA, CUR_PHASE, N_CURRENT) = range(13)


class CurrentField:
    """Water velocity over ground (east, north), m/s, at (x, y) and time t (CurrentFieldSpec)."""

    def __init__(self, spec: Union[List[float], CurrentFieldSpec]):
        if isinstance(spec, CurrentFieldSpec):
            self.axis = tuple(_towards(spec.towards_deg))
            self.left = (-self.axis[1], self.axis[0])
            self.speed = spec.speed_kn * KNOT
            self.shear = spec.shear_per_s
            self.half_width = spec.half_width_m
            self.omega = 2.0 * math.pi / spec.tidal_period_s if spec.tidal_period_s else 0.0
            self.phase = math.radians(spec.phase_deg)
            self.uniform = None
        else:
            self.uniform = (float(spec[0]), float(spec[1]))
        self.varies_in_space = self.uniform is None and self.shear != 0.0
        self.varies_in_time = self.uniform is None and self.omega != 0.0
        self.packed = np.zeros(N_CURRENT)
        if self.uniform is not None:
            self.packed[[CUR_UNIFORM, CUR_UX, CUR_UY]] = (1.0, *self.uniform)
        else:
            self.packed[CUR_AXIS_X:] = (*self.axis, *self.left, self.speed, self.shear, self.half_width, self.omega,
                                        self.phase)

    def velocity_xy(self, t: float, x: float, y: float) -> tuple:
        """(east, north) m/s at one point: the scalar form a vessel needs every step."""
        return current_xy(self.packed, t, x, y)

    def velocity(self, t: float, x, y):
        """(2,) for scalar x, y; (N, 2) for arrays."""
        if self.uniform is not None:
            u = np.array(self.uniform)
            return u if np.ndim(x) == 0 else np.tile(u, (np.size(x), 1))
        s = np.clip(np.asarray(x, float) * self.left[0] + np.asarray(y, float) * self.left[1],
                    -self.half_width, self.half_width)
        speed = self.speed + self.shear * s
        if self.omega:
            speed = speed * math.cos(self.omega * t + self.phase)
        return np.multiply.outer(speed, np.array(self.axis))


@njit(cache=True)
def current_xy(c, t, x, y):
    """CurrentField.velocity_xy on its packed parameters c, as a kernel."""
    return current_xy_at(c, tidal_factor(c, t), x, y)


@njit(cache=True)
def tidal_factor(c, t):
    """cos(2 pi t / T + phase) of a reversing stream (1 for a steady one): the time-dependent
    part, computed once per call where many points are sampled at one time."""
    return math.cos(c[CUR_OMEGA] * t + c[CUR_PHASE]) if c[CUR_OMEGA] != 0.0 else 1.0


@njit(cache=True, inline="always")
def current_xy_at(c, factor, x, y):
    """The current at (x, y) at the time whose tidal_factor is `factor`."""
    if c[CUR_UNIFORM] != 0.0:
        return c[CUR_UX], c[CUR_UY]
    hw = c[CUR_HALF_WIDTH]
    s = min(max(x * c[CUR_LEFT_X] + y * c[CUR_LEFT_Y], -hw), hw)
    speed = c[CUR_SPEED] + c[CUR_SHEAR] * s
    if c[CUR_OMEGA] != 0.0:
        speed *= factor
    return speed * c[CUR_AXIS_X], speed * c[CUR_AXIS_Y]


class DepthField:
    """Water depth (m, positive) below the still surface at (x, y); math.inf = deep water."""

    def __init__(self, spec, base_dir: str = "."):
        self.grid = None
        self.uniform = math.inf
        if isinstance(spec, DepthGridSpec):
            import os
            path = spec.grid if os.path.isabs(spec.grid) else os.path.join(base_dir, spec.grid)
            self.grid = DepthGrid.load(path)
        elif spec is not None:
            self.uniform = float(spec)

    @property
    def is_deep(self) -> bool:
        return self.grid is None and math.isinf(self.uniform)

    @property
    def representative(self) -> float:
        """One depth for the waves' dispersion: the uniform depth, a grid's mean wet depth, inf."""
        if self.grid is not None:
            wet = self.grid.values[self.grid.values > 0.0]
            return float(wet.mean()) if wet.size else math.inf
        return self.uniform

    def at(self, x, y):
        if self.grid is not None:
            return self.grid.depth_at(x, y)
        return self.uniform if np.ndim(x) == 0 else np.full(np.size(x), self.uniform)


def wave_field(spec: WavesSpec, depth: float = math.inf, g: float = G) -> Optional[WaveField]:
    """The sea of a WavesSpec (None for hs 0: calm); the compass "from" becomes the ENU math
    angle the waves travel towards, here and nowhere else."""
    if spec.hs == 0.0:
        return None
    towards = -_towards(spec.from_deg)
    psi = math.atan2(towards[1], towards[0])
    ramp = 3.0 * spec.tp if spec.ramp_time is None else spec.ramp_time
    if spec.spectrum == "regular":
        return WaveField.regular(spec.hs, spec.tp, psi, depth, ramp, g)
    gamma = (3.3 if spec.gamma is None else spec.gamma) if spec.spectrum == "jonswap" else 1.0
    return WaveField.irregular(spec.hs, spec.tp, psi, gamma, spec.spreading_s, spec.components, spec.seed,
                               depth, ramp, g)


class Environment:
    """Wind, current, depth and waves of a run (an EnvironmentSpec made into fields)."""

    def __init__(self, spec: Optional[EnvironmentSpec] = None, base_dir: str = ".", gravity: float = G):
        spec = spec if spec is not None else EnvironmentSpec()
        self.spec = spec
        self.wind = WindField(spec.wind) if spec.wind is not None else None
        self.current = CurrentField(spec.current)
        self.depth = DepthField(spec.depth, base_dir)
        # one sea for every node: the same spec and seed give the same components everywhere
        self.waves = wave_field(spec.waves, self.depth.representative, gravity) if spec.waves is not None else None

    @property
    def acts_on_hulls(self) -> bool:
        """Whether a hull's environment sampler has anything to carry: wind, a depth, or a
        current that is not still water. The waves act on hulls through their own response
        (tug_dynamics.seakeeping), so a sea alone needs no sampler (which cost a waves-only run
        a quarter of a vessel step, benchmarks/bench_waves.py)."""
        return self.wind is not None or not self.depth.is_deep or self.current.uniform != (0.0, 0.0)

    @staticmethod
    def from_mapping(data: Optional[dict], source: str = "environment", base_dir: str = ".",
                     gravity: float = G) -> "Environment":
        """From a plain mapping (a scenario's ``environment`` without water_density / gravity);
        a bad entry raises ValueError naming `source` and the key."""
        from pydantic import ValidationError
        try:
            spec = EnvironmentSpec.model_validate(data or {})
        except ValidationError as exc:
            lines = []
            for err in exc.errors():
                key = ".".join(str(p) for p in err["loc"] if not _UNION_BRANCH.search(str(p)))
                lines.append(f"{source}: key '{key}': {err['msg']} (got {err.get('input')!r})")
            raise ValueError("\n".join(lines)) from None
        return Environment(spec, base_dir, gravity)

    @staticmethod
    def from_parameter(text: str, source: str = "parameter environment"):
        """(Environment, water density) from a node's `environment` parameter: a scenario's
        environment section as YAML / JSON text (water_density and gravity included)."""
        import yaml
        try:
            data = yaml.safe_load(text) if text else {}
        except yaml.YAMLError as exc:
            raise ValueError(f"{source}: not YAML: {exc}") from None
        if data is None:
            data = {}
        if not isinstance(data, dict):
            raise ValueError(f"{source}: expected a YAML mapping, got {text!r}")
        data = dict(data)
        rho = data.pop("water_density", 1025.0)
        g = data.pop("gravity", G)
        if isinstance(rho, bool) or not isinstance(rho, (int, float)) or not 900.0 < rho < 1100.0:
            raise ValueError(f"{source}: key 'water_density': expected a number in (900, 1100), got {rho!r}")
        if isinstance(g, bool) or not isinstance(g, (int, float)) or not 9.0 < g < 10.5:
            raise ValueError(f"{source}: key 'gravity': expected a number in (9, 10.5), got {g!r}")
        return Environment.from_mapping(data, source, gravity=float(g)), float(rho)

    def wind_velocity(self, t: float, z=10.0):
        if self.wind is None:
            return np.zeros(2) if np.ndim(z) == 0 else np.zeros((np.size(z), 2))
        return self.wind.velocity(t, z)

    def current_velocity(self, t: float, x, y):
        return self.current.velocity(t, x, y)

    def depth_at(self, x, y):
        return self.depth.at(x, y)

    def wave_elevation(self, t: float, x, y):
        """eta (m) at (x, y); 0 on a calm sea."""
        if self.waves is None:
            return 0.0 if np.ndim(x) == 0 else np.zeros(np.size(x))
        return self.waves.elevation(x, y, t)

    def wave_kinematics(self, t: float, x, y, z):
        """waves.WaveKinematics at points (x, y, z) (1-D); all zero on a calm sea."""
        if self.waves is None:
            m = np.size(np.broadcast_arrays(x, y, z)[0])
            return WaveKinematics(np.zeros(m), np.zeros((m, 3)), np.zeros((m, 3)), np.zeros(m))
        return self.waves.kinematics(x, y, z, t)
