"""A displacement hull in the run's sea: the two-time-scale superposition (Fossen 2021, Handbook
of Marine Craft Hydrodynamics and Motion Control, 2nd ed., ch. 10; the RAO method of the MSS
toolbox). ROS-free; the vessel node builds one VesselInWaves per vessel when the scenario has
waves.

- The manoeuvring model keeps its own (low-frequency) state; the mean wave drift force of that
  state's heading (wave_response, Maruo far-field data) is one more external wrench on it over
  the next step.
- The wave-frequency motion (surge, sway, heave, roll, pitch, yaw from the hull's RAOs, the
  sea's components met at the vessel's own position with the encounter frequency) is superposed
  on the manoeuvring state for everything that leaves the vessel: the odometry, /tf and the
  attachment points the ropes hang on. Small angles: the wave-frequency translations are in the
  heading-fixed (seakeeping) frame, rotations add to roll, pitch and yaw.
- A rope end's coupling (docs/step-protocol.md) refers to the attachment's published (total)
  state; the manoeuvring integration follows the low-frequency point, so the reference is moved
  by the wave-frequency part of the point's motion at the step's start (`point_offsets`):
  the coupling spring then acts on the line's stretch, not on the wave motion it already saw.

Which data: ships/hydro/<ship file stem>.npz next to the ship file (scripts/hydro_data.py makes
it for a new hull). The data's reference point (midships, centreline, still waterline) is taken
as the body origin of the manoeuvring model.
"""
from __future__ import annotations

import dataclasses
import math
import os

import numpy as np
from sea_environment.waves import wavenumber

from .planing import PlaningHull
from .vessel import BodyPoints, ExternalWrench, VesselState
from .wave_response import HydroData, WaveResponse, WaveSample


def hydro_data_path(ship_path: str) -> str:
    """hydro/<stem>.npz beside the ship file."""
    stem = os.path.splitext(os.path.basename(ship_path))[0]
    return os.path.join(os.path.dirname(os.path.abspath(ship_path)), "hydro", stem + ".npz")


@dataclasses.dataclass
class SeaStatus:
    """The sea at a vessel (tug_msgs/VesselStatus' sea block; sim_plumbing.cdr.VESSEL_STATUS_FLOATS_SEA)."""
    wave_elevation: float = 0.0           # m at the reference point
    wave_significant_height: float = 0.0  # m, 4 sqrt(m0) of the realised components
    wave_encounter_period: float = 0.0    # s, the spectral peak as met
    wave_encounter_angle: float = 0.0     # rad, where the sea comes from, 0 = ahead, + from port
    heave: float = 0.0                    # m, wave-frequency
    roll: float = 0.0                     # rad, wave-frequency, REP-103
    pitch: float = 0.0                    # rad, wave-frequency, REP-103


class VesselInWaves:
    """One vessel's wave response; `sample(state, t)` once per published state, then `total`,
    `drift_wrench`, `status` and `point_offsets` of that sample."""

    def __init__(self, hydro: HydroData, wave_field):
        self.response = WaveResponse(hydro, wave_field)
        self.waves = wave_field
        self.hs = 4.0 * math.sqrt(wave_field.m0)
        # the spectral peak (2 pi / Tp) and its wavenumber in the sea's depth
        self._peak_omega = float(wave_field.peak_omega)
        self._peak_k = float(wavenumber(self._peak_omega, wave_field.depth, wave_field.g))
        self.mean_direction = float(wave_field.mean_direction)
        self.last: WaveSample | None = None
        self._state: VesselState | None = None
        self._t = 0.0

    @classmethod
    def for_ship(cls, ship_path: str, wave_field) -> "VesselInWaves":
        """From the ship file's hydrodynamic data (ValueError naming the file and key if bad)."""
        return cls(HydroData.load(hydro_data_path(ship_path)), wave_field)

    def sample(self, state: VesselState, t: float) -> WaveSample:
        x, y, _ = state.position
        self._state, self._t = state, float(t)
        self.last = self.response.evaluate(float(x), float(y), float(state.rpy[2]),
                                           float(state.linear_velocity_body[0]), float(t))
        return self.last

    def total(self, state: VesselState, sample: WaveSample) -> VesselState:
        """The manoeuvring state with the wave-frequency motion superposed (module docstring)."""
        d, dv = sample.displacement, sample.velocity
        c, s = math.cos(state.rpy[2]), math.sin(state.rpy[2])
        position = state.position + np.array([c * d[0] - s * d[1], s * d[0] + c * d[1], d[2]])
        return VesselState(position, state.rpy + d[3:], state.linear_velocity_body + dv[:3],
                           state.angular_velocity_body + dv[3:])

    def drift_wrench(self, state: VesselState, sample: WaveSample) -> ExternalWrench:
        """The mean drift force (body X, Y and yaw moment N) on the reference point, world axes."""
        X, Y, N = sample.drift
        c, s = math.cos(state.rpy[2]), math.sin(state.rpy[2])
        return ExternalWrench(force_world=np.array([c * X - s * Y, s * X + c * Y, 0.0]), point_body=np.zeros(3),
                              moment_world=np.array([0.0, 0.0, N]))

    @staticmethod
    def point_offsets(low: VesselState, total: VesselState, points: BodyPoints):
        """The wave-frequency part (n, 3) of body points' world positions and velocities: total
        minus low-frequency. A rope end's coupling reference (the attachment's published, total,
        state) minus it is the low-frequency point the manoeuvring integration follows."""
        p_tot, v_tot = points.world(total)
        p_lf, v_lf = points.world(low)
        return p_tot - p_lf, v_tot - v_lf

    def status(self, state: VesselState, sample: WaveSample) -> SeaStatus:
        eta = sample.elevation
        psi = float(state.rpy[2])
        u = float(state.linear_velocity_body[0])
        # the sea travels towards mean_direction: it comes from the opposite, relative to the bow
        frm = math.remainder(self.mean_direction + math.pi - psi, 2.0 * math.pi)
        omega_e = abs(self._peak_omega - self._peak_k * u * math.cos(self.mean_direction - psi))
        period = 2.0 * math.pi / omega_e if omega_e > 1e-9 else math.inf
        d = sample.displacement
        return SeaStatus(eta, self.hs, period, frm, float(d[2]), float(d[3]), float(d[4]))


def waves_refused(model, ship_path: str) -> str:
    """Why a vessel cannot take the run's waves ('' if it can): the planing hull is a calm-water
    model (its seed, 004, is run in calm sea), and a displacement hull needs its hydrodynamic data."""
    if isinstance(model, PlaningHull):
        return (f"{ship_path}: a planing hull (model: planing_6dof) is a calm-water model (seed 004's trials are in "
                "calm sea) and takes no waves: run it without environment.waves, or with hs 0")
    try:
        HydroData.load(hydro_data_path(ship_path))
    except ValueError as exc:
        return str(exc)
    return ""
