"""A vessel in its environment: what the wind, the current and the depth do to it, whatever its
model. ROS-free; the vessel node builds one VesselInEnvironment per vessel, then steps the model.

The environment of a state acts over the step that follows it (sampled once per exchange step):

- current: sampled at the vessel's reference point and given to the model as its (uniform over
  the hull) current, so the hull, propeller and rudder all work on the velocity through the water.
- wind: the apparent wind (the air's velocity relative to the vessel's reference point, wind at
  10 m, the height Blendermann's coefficients refer to) -> Blendermann (1994) force and centre
  of pressure (sea_environment.wind_loads), one more external wrench on the model.
- depth: sampled at the reference point; the shallow-water factors (README "Shallow water") and the
  anchor chain's holding (the model's set_depth effects); squat (ICORELS) and the under-keel
  clearance h - T - squat are reported; below zero the vessel is aground: the lost buoyancy
  rho g A_wp (T + squat - h) presses it on the bottom and Coulomb friction (GROUND_FRICTION)
  resists its horizontal motion at the reference point (regularised linearly below GROUND_SLIP
  speed so it stops without chatter).

All of it is computed by sea_environment.sampler inside the model's compiled step (the
same work as Python calls cost twice a model step: benchmarks/bench_vessels.py).
"""
from __future__ import annotations

import dataclasses
import math

from sea_environment.environment import Environment
from sea_environment.sampler import (E_APPARENT_ANGLE, E_APPARENT_SPEED, E_CLEARANCE, E_DEPTH, E_GROUNDED,
                                     E_SQUAT, EnvironmentSampler)
from sea_environment.wind_loads import RHO_AIR

from .vessel import Vessel

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
    """Attaches the environment to the vessel model (from then on its every step feels it) at
    simulation time t0; `status` is the environment at the model's present state."""

    def __init__(self, vessel: Vessel, env: Environment, rho_water: float = 1025.0, rho_air: float = RHO_AIR,
                 t0: float = 0.0):
        self.vessel = vessel
        self.env = env
        src = getattr(vessel, "source", "") or vessel.name
        if env.wind is not None and vessel.windage is None:
            raise ValueError(f"{src}: the scenario has wind but the ship file has no 'windage' section "
                             "(above-water areas for Blendermann's wind loads)")
        if not env.depth.is_deep and not math.isfinite(vessel.draft):
            raise ValueError(f"{src}: the scenario has a depth but the vessel's draft is unknown")
        self.sampler = EnvironmentSampler(env, length=vessel.length, beam=vessel.beam, draft=vessel.draft,
                                                volume=vessel.volume, windage=vessel.windage, rho_water=rho_water,
                                                rho_air=rho_air, ground_friction=GROUND_FRICTION,
                                                ground_slip=GROUND_SLIP)
        self.sampler.time = float(t0)
        vessel.attach_environment(self.sampler)

    @property
    def status(self) -> EnvironmentStatus:
        e = self.sampler.out
        return EnvironmentStatus(float(e[E_APPARENT_SPEED]), float(e[E_APPARENT_ANGLE]), float(e[E_DEPTH]),
                                 float(e[E_SQUAT]), float(e[E_CLEARANCE]), bool(e[E_GROUNDED]))
