"""Prescribed motion: a vessel that follows a given track whatever the forces on it, as the tug
of Yoon, Lee, Park & Kim's towing-rope paper ("Dynamic Modeling and Simulation of a Towing Rope
using Multiple Finite Element Method") does in its section 4 (constant speed 4.4 / 4.6,
sinusoidal sway 4.5, acceleration).

The track is written in the vessel's initial frame (x along the initial heading, y to port):
  constant_speed     x = U t
  sinusoidal_sway    x = U t,  y = A sin(2 pi t / T)          (towing-rope paper 4.5: 2 kn, 10 m, 50 s)
  acceleration       x = a t^2 / 2 until U_max is reached, then U_max
  turn               speed U straight, from turn_start a circular arc at turn_rate (positive
                     to port) for turn_duration, then straight again (Park & Jung's towed-cable
                     paper: 1 m/s, 0.5 deg/s to port for 100 s)
The heading follows the track tangent (heading: track) or keeps its initial value (heading:
fixed). The track is over ground: external wrenches and the current do not move the vessel.
The attachment kinematics are exact derivatives.
"""
from __future__ import annotations

import dataclasses
import math
from typing import List, Sequence

import numpy as np

from tug_dynamics.vessel import (Command, ExternalWrench, StatusRecord, Vessel, VesselState, check_current,
                                 rotation_body_to_world)

MOTION_KINDS = ("constant_speed", "sinusoidal_sway", "acceleration", "turn")


@dataclasses.dataclass(frozen=True)
class MotionLaw:
    kind: str
    speed: float = 0.0  # m/s: U (constant_speed, sinusoidal_sway) or U_max (acceleration)
    amplitude: float = 0.0  # m
    period: float = 0.0  # s
    acceleration: float = 0.0  # m/s^2
    heading: str = "track"  # track | fixed
    turn_rate: float = 0.0  # rad/s, positive to port
    turn_start: float = 0.0  # s
    turn_duration: float = 0.0  # s

    def __post_init__(self):
        def bad(key, what):
            raise ValueError(f"prescribed motion '{self.kind}': {key} {what}")
        if self.kind not in MOTION_KINDS:
            raise ValueError(f"prescribed motion: unknown type {self.kind!r}; expected one of {MOTION_KINDS}")
        for key in ("speed", "amplitude", "period", "acceleration", "turn_rate", "turn_start", "turn_duration"):
            if not math.isfinite(getattr(self, key)):
                bad(key, f"must be finite, got {getattr(self, key)}")
        if self.heading not in ("track", "fixed"):
            bad("heading", f"must be 'track' or 'fixed', got {self.heading!r}")
        if self.kind == "sinusoidal_sway" and self.period <= 0:
            bad("period", f"must be positive, got {self.period}")
        if self.kind == "acceleration" and (self.acceleration <= 0 or self.speed <= 0):
            bad("acceleration/speed", f"must both be positive, got {self.acceleration}, {self.speed}")
        if self.kind == "turn" and (self.turn_rate == 0 or self.turn_duration < 0 or self.turn_start < 0):
            bad("turn_rate/turn_start/turn_duration", "need a non-zero rate and non-negative start and duration")

    def track(self, t: float):
        """Position, velocity, acceleration (x, y) in the initial frame at time t."""
        if self.kind == "acceleration":
            t_full = self.speed / self.acceleration
            if t < t_full:
                return (0.5 * self.acceleration * t * t, 0.0), (self.acceleration * t, 0.0), (self.acceleration, 0.0)
            x = 0.5 * self.acceleration * t_full ** 2 + self.speed * (t - t_full)
            return (x, 0.0), (self.speed, 0.0), (0.0, 0.0)
        if self.kind == "turn":
            return self._turn_track(t)
        x, vx = self.speed * t, self.speed
        if self.kind == "constant_speed":
            return (x, 0.0), (vx, 0.0), (0.0, 0.0)
        w = 2.0 * math.pi / self.period
        a = self.amplitude
        return (x, a * math.sin(w * t)), (vx, a * w * math.cos(w * t)), (0.0, -a * w * w * math.sin(w * t))


    def _turn_track(self, t: float):
        U, r, t0, T = self.speed, self.turn_rate, self.turn_start, self.turn_duration
        if t <= t0:
            return (U * t, 0.0), (U, 0.0), (0.0, 0.0)
        tau = min(t - t0, T)
        psi = r * tau
        x = U * t0 + U / r * math.sin(psi)
        y = U / r * (1.0 - math.cos(psi))
        vx, vy = U * math.cos(psi), U * math.sin(psi)
        if t - t0 <= T:
            return (x, y), (vx, vy), (-r * vy, r * vx)
        extra = t - t0 - T
        return (x + vx * extra, y + vy * extra), (vx, vy), (0.0, 0.0)


class PrescribedMotion(Vessel):
    """Wraps a vessel model: same name, attachments and command interface; motion imposed."""

    def __init__(self, base: Vessel, law: MotionLaw):
        self.base = base
        self.law = law
        self.name = base.name
        self.attachments = base.attachments
        self.length, self.beam, self.draft, self.volume = base.length, base.beam, base.draft, base.volume
        self.windage = base.windage
        self.time = 0.0
        self._environment = None    # attach_environment
        self.wrench_work = np.zeros(0)
        self.set_state(base.state)

    # ---- commands: validated and held by the base model; they do not move this vessel ----
    @property
    def command(self) -> Command:
        return self.base.command

    def set_command(self, cmd: Command) -> List[str]:
        return self.base.set_command(cmd)

    def settle_command(self, cmd: Command) -> List[str]:
        return self.base.settle_command(cmd)

    # ---- state and environment ----------------------------------------------------------
    def set_state(self, state: VesselState) -> None:
        """Start the track (time 0) at this state's position and heading."""
        self.origin = np.array(state.position, float)
        self.yaw0 = float(state.rpy[2])
        self.time = 0.0
        self._apply()
        if self._environment is not None:
            self._sample_environment()

    def set_current(self, current_world: Sequence[float]) -> None:
        """Checked, then without effect: the track is prescribed over ground, so the water's
        motion cannot move this vessel (status reports its speed over ground as
        speed_through_water, as the track defines no speed through the water)."""
        check_current(current_world)

    def set_depth(self, depth: float) -> None:
        """Without effect: the track is prescribed."""

    def attach_environment(self, sampler) -> None:
        """The environment changes nothing on the track; the sampler is kept up to date on every
        step's state (its apparent wind, depth, squat and clearance are reported)."""
        self._environment = sampler
        self._sample_environment()

    def _sample_environment(self) -> None:
        s = self.state
        self._environment.sample(s.position[0], s.position[1], s.rpy[2], s.linear_velocity_body[0],
                                 s.linear_velocity_body[1])

    # ---- stepping ---------------------------------------------------------------------------
    def step(self, dt: float, wrenches: Sequence[ExternalWrench] = ()) -> None:
        """Advance along the track; wrenches have no effect on a prescribed motion (their work
        on the moving points is booked: the track is an energy source or sink)."""
        before = [self._point_world(w.point_body) for w in wrenches]
        self.time += dt
        self._apply()
        self.wrench_work = np.array([float(np.asarray(w.force_world, float) @ (self._point_world(w.point_body) - p0))
                                     for w, p0 in zip(wrenches, before)])
        if self._environment is not None:
            self._environment.time += dt
            self._sample_environment()

    def _point_world(self, point_body) -> np.ndarray:
        s = self.state
        return s.position + rotation_body_to_world(s.rpy) @ np.asarray(point_body, float)

    def point_mobility(self, point_body) -> float:
        """A prescribed motion is not moved by forces: mobility 0."""
        return 0.0

    def _apply(self) -> None:
        (x, y), (vx, vy), (ax, ay) = self.law.track(self.time)
        c, s = math.cos(self.yaw0), math.sin(self.yaw0)
        pos = self.origin + np.array([c * x - s * y, s * x + c * y, 0.0])
        vel_world = np.array([c * vx - s * vy, s * vx + c * vy, 0.0])
        if self.law.heading == "track" and math.hypot(vx, vy) > 1e-9:
            yaw = self.yaw0 + math.atan2(vy, vx)
            yaw_rate = (vx * ay - vy * ax) / (vx * vx + vy * vy)
        else:
            yaw, yaw_rate = self.yaw0, 0.0
        cy, sy = math.cos(yaw), math.sin(yaw)
        u = cy * vel_world[0] + sy * vel_world[1]
        v = -sy * vel_world[0] + cy * vel_world[1]
        self.state = VesselState(pos, np.array([0.0, 0.0, yaw]), np.array([u, v, 0.0]), np.array([0.0, 0.0, yaw_rate]))

    def status(self) -> StatusRecord:
        """The base model's status (its actuators, held still) with this motion's speed and no heel."""
        return dataclasses.replace(self.base.status(),
                                   speed_through_water=float(math.hypot(*self.state.linear_velocity_body[:2])),
                                   heel=0.0)
