"""A vessel in its environment: what the wind, the current and the depth do to it, once per
exchange step, whatever its model. ROS-free; the vessel node calls `prepare` before each step.

- current: sampled at the vessel's reference point and given to the model as its (uniform over
  the hull) current, so the hull, propeller and rudder all work on the velocity through the water.
- wind: the apparent wind (the air's velocity relative to the vessel's reference point, wind at
  10 m, the height Blendermann's coefficients refer to) -> Blendermann (1994) force and centre
  of pressure (sea_environment.wind_loads), handed to the model as one more external wrench.
- depth: sampled at the reference point and given to the model (model.set_depth: the anchor's
  chain holds according to it); squat (ICORELS) and the under-keel clearance
  h - T - squat are reported; below zero the vessel is aground: the lost buoyancy rho g A_wp (T + squat - h) presses
  it on the bottom and Coulomb friction (GROUND_FRICTION) resists its horizontal motion at the
  reference point (regularised linearly below GROUND_SLIP speed so it stops without chatter).
"""
from __future__ import annotations

import dataclasses
import math
from typing import List, Optional

import numpy as np

from sea_environment.environment import Environment
from sea_environment.shallow_water import squat
from sea_environment.wind import apparent_wind
from sea_environment.wind_loads import RHO_AIR, wind_wrench_body

from .vessel import ExternalWrench, Vessel

G = 9.80665
# Coulomb friction of a steel hull on a sand / mud bottom: 0.3-0.5 is the range grounding analyses
# use (e.g. Simonsen & Pedersen 1997, Marine Structures 10); the middle value.
GROUND_FRICTION = 0.4
GROUND_SLIP = 0.05  # m/s: below this the friction grows linearly from zero (no chatter at rest)


@dataclasses.dataclass
class EnvironmentStatus:
    apparent_wind_speed: float = 0.0    # m/s
    apparent_wind_angle: float = 0.0    # rad, where it comes from, 0 ahead, + from port
    water_depth: float = math.inf       # m at the reference point (inf: deep)
    squat: float = 0.0                  # m (ICORELS bow squat)
    under_keel_clearance: float = math.inf  # m, depth - draft - squat
    grounded: bool = False


class VesselInEnvironment:
    def __init__(self, vessel: Vessel, env: Environment, rho_water: float = 1025.0, rho_air: float = RHO_AIR):
        self.vessel = vessel
        self.env = env
        self.rho_water = rho_water
        self.rho_air = rho_air
        self.status = EnvironmentStatus()
        self._current = (math.nan, math.nan)
        self._depth = math.nan
        src = getattr(vessel, "source", "") or vessel.name
        if env.wind is not None and vessel.windage is None:
            raise ValueError(f"{src}: the scenario has wind but the ship file has no 'windage' section "
                             "(above-water areas for Blendermann's wind loads)")
        if not env.depth.is_deep and not math.isfinite(vessel.draft):
            raise ValueError(f"{src}: the scenario has a depth but the vessel's draft is unknown")

    def prepare(self, t: float) -> List[ExternalWrench]:
        """Set the model's current for the step starting at time t; return the environment's
        wrenches on it (wind, grounding). Scalar arithmetic: it runs every step of every vessel."""
        v = self.vessel
        s = v.state
        x, y = float(s.position[0]), float(s.position[1])
        env = self.env
        cx, cy = env.current.velocity_xy(t, x, y)
        if self._current != (cx, cy):
            v.set_current((cx, cy, 0.0))
            self._current = (cx, cy)
        yaw = float(s.rpy[2])
        cpsi, spsi = math.cos(yaw), math.sin(yaw)
        ub, vb = float(s.linear_velocity_body[0]), float(s.linear_velocity_body[1])
        vx, vy = cpsi * ub - spsi * vb, spsi * ub + cpsi * vb    # horizontal velocity over ground
        wrenches = []
        st = self.status
        if env.wind is not None:
            wx, wy = env.wind.velocity_xy(t)
            speed, angle = apparent_wind((wx, wy), (vx, vy), yaw)
            st.apparent_wind_speed, st.apparent_wind_angle = speed, angle
            fx, fy, xp, zp, _ = wind_wrench_body(speed, angle, v.windage, self.rho_air)
            # force in the horizontal plane, world axes (heel and trim do not tilt the wind)
            wrenches.append(ExternalWrench(force_world=np.array([cpsi * fx - spsi * fy, spsi * fx + cpsi * fy, 0.0]),
                                           point_body=np.array([xp, 0.0, zp])))
        if not env.depth.is_deep:
            h = env.depth.at(x, y)
            if h != self._depth:
                v.set_depth(max(h, 1e-3))   # 0 (dry land in a grid) -> aground, not an error
                self._depth = h
            sq = squat(math.hypot(vx - cx, vy - cy), max(h, v.draft), v.length, v.volume)
            ukc = h - v.draft - sq
            st.water_depth, st.squat, st.under_keel_clearance = h, sq, ukc
            st.grounded = ukc < 0.0
            if st.grounded:
                wrenches.append(self._ground_friction(-ukc, vx, vy))
        return wrenches

    def _ground_friction(self, penetration: float, vx: float, vy: float) -> ExternalWrench:
        v = self.vessel
        block = v.volume / (v.length * v.beam * v.draft)
        waterplane = (1.0 + 2.0 * block) / 3.0 * v.length * v.beam   # C_wp from C_b (Schneekluth)
        normal = self.rho_water * G * waterplane * penetration
        vh = np.array([vx, vy, 0.0])
        speed = math.hypot(vx, vy)
        scale = GROUND_FRICTION * normal / max(speed, GROUND_SLIP)
        return ExternalWrench(force_world=-scale * vh, point_body=np.zeros(3))
