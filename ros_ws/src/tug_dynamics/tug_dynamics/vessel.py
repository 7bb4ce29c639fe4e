"""The interface every vessel model offers, whatever its physics.

One vessel node runs every ship file; it only talks to this interface. Conventions
(REP-103), used by every model here:

- world frame: ENU, x east, y north, z up; water surface at z = 0.
- body frame: origin at the reference point named in the ship file (midship on the
  waterline unless the file says otherwise), x forward, y port, z up.
- orientation: roll, pitch, yaw (rad) as the intrinsic z-y'-x'' sequence, i.e.
  R = Rz(yaw) Ry(pitch) Rx(roll); yaw 0 points the bow east, positive yaw turns to port.
  A paper using NED / starboard-positive conventions is converted inside its model.
- command: ``engine_order`` is the fraction of rated engine (or impeller) rpm, -1 full
  astern .. +1 full ahead; ``steering_angle`` (rad) is rudder or waterjet-bucket angle,
  positive turns the vessel to port (gives a positive yaw rate at forward speed).
- thruster orders (azimuth thrusters, e.g. an ASD tug): per thruster an azimuth (rad, the
  direction of the thrust in the body's horizontal plane: 0 = thrust ahead, positive turns the
  thrust vector to port) and an rpm fraction of the thruster's rated rpm (0..1; -1..1 for a
  reversible unit). ``Vessel.set_thruster_command`` takes them; ``Command`` keeps working.
"""
from __future__ import annotations

import dataclasses
import enum
import math
from abc import ABC, abstractmethod
from typing import Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

from sim_math.rotations import matrix_from_rpy

ANCHOR_NO_CHANGE = 0
ANCHOR_LET_GO = 1
ANCHOR_HEAVE_UP = 2


class CommandRejected(ValueError):
    """A command that cannot be applied at all (NaN, infinite, unknown anchor order)."""


@dataclasses.dataclass
class Command:
    engine_order: float = 0.0
    steering_angle: float = 0.0
    anchor: int = ANCHOR_NO_CHANGE


@dataclasses.dataclass
class ThrusterOrder:
    """An order for one azimuth thruster.

    thruster: its index in the ship file's ``thrusters:`` list, or its name.
    azimuth: rad, direction of the thrust (0 = ahead, + to port).
    rpm: fraction of the thruster's rated rpm, 0..1 (-1..1 for a reversible unit).
    """
    thruster: Union[int, str]
    azimuth: float
    rpm: float


@dataclasses.dataclass(frozen=True, slots=True)
class ThrusterStatus:
    """One azimuth thruster's actual and ordered state, SI units."""
    name: str
    azimuth: float            # rad, actual, (-pi, pi], 0 = thrust ahead, + to port
    azimuth_ordered: float    # rad, held order after clamping
    rpm: float                # rev/min, actual (negative: reversed rotation)
    rpm_ordered: float        # rev/min, held order
    thrust: float             # N, force delivered to the hull along the azimuth (after the hull's
                              # thrust deduction and thruster-thruster interaction)
    open_water_thrust: float  # N, the unit's own thrust (K_T at the inflow's J), before those


@dataclasses.dataclass
class ExternalWrench:
    """A force acting on the vessel, e.g. a towline at a bollard.

    force_world: (3,) N in the world frame (ENU).
    point_body: (3,) m, where it acts, in the body frame.
    moment_world: (3,) N m extra pure moment in the world frame (usually zero).

    A coupled force (another node's spring, e.g. a rope end; docs/step-protocol.md) also gives
    its linearisation, world axes: the model applies
        force_world + stiffness (p - reference_position) + damping (v - reference_velocity)
    at every stage of its integration, p and v the point's world position and velocity there.
    Without it (stiffness None) the force is held constant over the step.
    """
    force_world: np.ndarray
    point_body: np.ndarray
    moment_world: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(3))
    stiffness: Optional[np.ndarray] = None            # (3, 3) dF/dx, N/m
    damping: Optional[np.ndarray] = None              # (3, 3) dF/dv, N s/m
    reference_position: Optional[np.ndarray] = None  # (3,) m, world, where force_world holds
    reference_velocity: Optional[np.ndarray] = None   # (3,) m/s, world

    @property
    def coupled(self) -> bool:
        return self.stiffness is not None


# A coupled wrench as the kernels take it (one row per wrench): dF/dx (3x3 row-major), dF/dv
# (3x3), the reference position and velocity (world), 1.0 = coupled (0: a constant force)
CPL_K, CPL_C, CPL_P, CPL_V, CPL_ON = 0, 9, 18, 21, 24
NCPL = 25
# A coupled spring is inside the model's explicit RK4: its sub-step h keeps omega h at most this
# (omega^2 = |K| x the point's mobility); RK4's phase error per period is then below 1e-4
SPRING_SUBSTEP = 0.25


def coupling_row(w: ExternalWrench, row: np.ndarray) -> None:
    """Write w's linearisation into row (NCPL,); zeros for a constant force."""
    row[:] = 0.0
    if w.coupled:
        row[CPL_K:CPL_K + 9] = np.asarray(w.stiffness, float).reshape(9)
        row[CPL_C:CPL_C + 9] = np.asarray(w.damping, float).reshape(9)
        row[CPL_P:CPL_P + 3] = w.reference_position
        row[CPL_V:CPL_V + 3] = w.reference_velocity
        row[CPL_ON] = 1.0


@dataclasses.dataclass
class VesselState:
    """Kinematic state, SI units.

    position: (3,) world ENU of the body origin, m.
    rpy: (3,) roll, pitch, yaw, rad (z-y'-x'' intrinsic).
    linear_velocity_body: (3,) u, v, w in m/s (body x forward, y port, z up).
    angular_velocity_body: (3,) p, q, r in rad/s.
    """
    position: np.ndarray
    rpy: np.ndarray
    linear_velocity_body: np.ndarray
    angular_velocity_body: np.ndarray

    @staticmethod
    def at_rest(x: float = 0.0, y: float = 0.0, yaw: float = 0.0, z: float = 0.0) -> "VesselState":
        return VesselState(np.array([x, y, z], float), np.array([0.0, 0.0, yaw]),
                           np.zeros(3), np.zeros(3))


def rotation_body_to_world(rpy: Sequence[float]) -> np.ndarray:
    """R such that v_world = R @ v_body, R = Rz(yaw) Ry(pitch) Rx(roll) (sim_math.rotations)."""
    return matrix_from_rpy(float(rpy[0]), float(rpy[1]), float(rpy[2]))


class BodyPoints:
    """Points fixed in the body (n, 3): their world positions and velocities in a state,
    p = x + R r, v = R (v_b + w x r), all at once (`world`)."""

    def __init__(self, points_body):
        self.body = np.asarray(points_body, float).reshape(-1, 3)
        # w x r of every point as one product (cross @ w): a tenth of np.cross's cost
        self._cross = np.array([[[0.0, z, -y], [-z, 0.0, x], [y, -x, 0.0]] for x, y, z in self.body],
                               float).reshape(-1, 3)

    def world(self, state: "VesselState"):
        """(positions, velocities), world, (n, 3) each."""
        rot = rotation_body_to_world(state.rpy)
        relative = (self._cross @ state.angular_velocity_body).reshape(-1, 3)
        return (state.position + self.body @ rot.T,
                (state.linear_velocity_body + relative) @ rot.T)


def check_command(cmd: Command) -> None:
    """Reject commands that cannot be applied; raise CommandRejected naming the field."""
    for field in ("engine_order", "steering_angle"):
        value = getattr(cmd, field)
        if not math.isfinite(value):
            raise CommandRejected(f"{field}={value!r} is not a finite number")
    if cmd.anchor not in (ANCHOR_NO_CHANGE, ANCHOR_LET_GO, ANCHOR_HEAVE_UP):
        raise CommandRejected(f"anchor={cmd.anchor!r} is not one of 0 (no change), 1 (let go), 2 (heave up)")


class AnchorState(enum.IntEnum):
    """Anchor states; the values are tug_msgs/VesselStatus's ANCHOR_* constants."""
    NONE = 0          # the vessel has no anchor
    STOWED = 1
    LETTING_GO = 2
    DREDGING = 3      # on the bottom, dragged
    HEAVING_UP = 4


@dataclasses.dataclass(kw_only=True, slots=True)
class StatusRecord:
    """Actuator and safety status, SI units: every field tug_msgs/VesselStatus publishes
    (sim_plumbing.cdr.VESSEL_STATUS_FLOATS_A/B name the float fields in message order).

    Every field is required: a model states each value, none falls back to a default. Models
    add their own fields in a subclass (DisplacementStatus, PlaningStatus). A fresh record per
    call (slots: a misspelt attribute is an error, not a new field).
    """
    engine_order: float            # held command, after clamping, [-1, 1]
    steering_angle_ordered: float  # held command, after clamping, rad (+ port)
    steering_angle: float          # actual rudder or bucket angle, rad (+ port)
    shaft_speed: float             # actual shaft or impeller speed, rad/s (negative astern)
    thrust: float                  # propulsion thrust along body x, N (negative astern)
    anchor_state: AnchorState
    speed_through_water: float     # m/s, relative to the current
    heel: float                    # rad, + starboard side down (REP-103 roll)
    trim: float                    # rad, + bow down (REP-103 pitch)
    rise: float                    # m, of the reference point above its static position
    girting_ratio: float           # towline heeling moment / largest righting moment
    girting_threshold: float       # girting_ratio at which girting_warning is raised
    girting_warning: bool


def check_current(current_world: Sequence[float]) -> np.ndarray:
    """A uniform current as a (3,) array, world ENU, m/s; ValueError unless 3 finite numbers."""
    c = np.asarray(current_world, float)
    if c.shape != (3,) or not np.all(np.isfinite(c)):
        raise ValueError(f"current must be 3 finite numbers (world ENU east, north, up; m/s), got {current_world!r}")
    return c.copy()


class Vessel(ABC):
    """A vessel model: holds its state and steps it in time.

    This is everything the vessel node calls. Every method is abstract or has a real default,
    so a model cannot leave out an input (e.g. the current) and be run without it.
    """

    name: str
    state: VesselState
    attachments: Dict[str, np.ndarray]  # name -> (3,) point in body frame, m
    # The ship file's length (hull.length, or hull.length_overall of a planing hull), m: the L
    # of the IMO manoeuvring criteria. Set by ship_file.load_ship.
    length: float = math.nan
    # Hull particulars the environment needs (set by ship_file.load_ship): beam, draft (m),
    # displaced volume (m^3) for shallow water and squat; windage (sea_environment.wind_loads.
    # Windage, the ship file's `windage` section, None without one) for the wind loads.
    beam: float = math.nan
    draft: float = math.nan
    volume: float = math.nan
    windage = None
    # names of the azimuth thrusters, in the ship file's order (empty: none)
    thruster_names: Tuple[str, ...] = ()

    # ---- commands ---------------------------------------------------------------------
    @property
    @abstractmethod
    def command(self) -> Command:
        """The command held (after clamping)."""

    @abstractmethod
    def set_command(self, cmd: Command) -> List[str]:
        """Apply a command; clamp out-of-range values and return one message per clamp.

        Raises CommandRejected (and keeps the previous command) for NaN/inf/unknown values.
        """

    def set_thruster_command(self, orders: Sequence[ThrusterOrder]) -> List[str]:
        """Per-thruster orders (azimuth, rpm fraction); clamp out-of-range values and return one
        message per clamp. Raises CommandRejected (and keeps every held order) for NaN / inf or a
        thruster the vessel does not have. A vessel without azimuth thrusters refuses them."""
        raise CommandRejected(f"{self.name}: has no azimuth thrusters; thruster orders refused")

    def settle_command(self, cmd: Command) -> List[str]:
        """Apply a command as if it had been held for long: actuators (shaft speed, rudder or
        bucket) start at their ordered values. For initial conditions such as "turn from 9 kn at
        half ahead"; models with actuator lags override it."""
        return self.set_command(cmd)

    # ---- state and environment (each environment input is an abstract setter) -------------
    @abstractmethod
    def set_state(self, state: VesselState) -> None:
        """Put the vessel in this kinematic state (the model copies it)."""

    @abstractmethod
    def set_current(self, current_world: Sequence[float]) -> None:
        """Uniform current: the water's velocity over ground, (east, north, up) m/s, world ENU.

        Raises ValueError for anything but 3 finite numbers (check_current). A model on which
        the current has no effect says so in its implementation."""

    @abstractmethod
    def set_depth(self, depth: float) -> None:
        """Water depth (m, > 0; math.inf = not given) under the vessel. A model on which the depth
        has no effect says so in its implementation."""

    @abstractmethod
    def attach_environment(self, sampler) -> None:
        """From now on every step feels the environment of `sampler` (sea_environment.
        sampler.EnvironmentSampler): the model samples it on its present state now
        and, inside its step, on each new state (time sampler.time), and applies the current,
        wind, depth and bottom friction of a state over the step that follows it; sampler.out
        then holds what the environment is at the present state. Used through
        tug_dynamics.environment_loads.VesselInEnvironment."""

    # ---- time stepping and outputs -------------------------------------------------------
    @abstractmethod
    def step(self, dt: float, wrenches: Sequence[ExternalWrench] = ()) -> None:
        """Advance the state by dt seconds with the given external wrenches held constant."""

    @abstractmethod
    def status(self) -> StatusRecord:
        """Actuator and safety status (engine, steering, thrust, anchor, heel, girting...)."""

    def point_mobility(self, point_body) -> float:
        """Largest horizontal mobility (1/kg) of a body point: the inverse of the smallest
        effective mass a horizontal force there meets (rigid body + added mass). A model that
        cannot be moved by forces (a prescribed motion) returns 0."""
        raise NotImplementedError(f"{type(self).__name__} does not state its point mobility")

    def attachment_kinematics(self, name: str) -> Tuple[np.ndarray, np.ndarray]:
        """World position (m) and world velocity (m/s) of a named attachment point."""
        try:
            r_body = self.attachments[name]
        except KeyError:
            raise KeyError(f"vessel {self.name!r} has no attachment {name!r}; "
                           f"it has {sorted(self.attachments)}") from None
        s = self.state
        rot = rotation_body_to_world(s.rpy)
        pos = s.position + rot @ r_body
        vel_body = s.linear_velocity_body + np.cross(s.angular_velocity_body, r_body)
        return pos, rot @ vel_body
