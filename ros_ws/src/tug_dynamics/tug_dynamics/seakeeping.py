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
from numba import njit
from sea_environment.waves import wavenumber
from sim_math.rotations import matrix_entries_from_trig

from .planing import PlaningHull
from .vessel import BodyPoints, ExternalWrench, VesselState
from .wave_response import HydroData, WaveResponse, WaveSample, _evaluate


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
    """One vessel's wave response: `step(low, t, points)` once per published state (compiled);
    `sample(state, t)` then `total`, `drift_wrench`, `status` and `point_offsets` of that sample
    are the same in numpy steps, its oracle."""

    def __init__(self, hydro: HydroData, wave_field):
        self.response = WaveResponse(hydro, wave_field)
        self.waves = wave_field
        self.hs = 4.0 * math.sqrt(wave_field.m0)
        # the spectral peak (2 pi / Tp) and its wavenumber in the sea's depth
        self._peak_omega = float(wave_field.peak_omega)
        self._peak_k = float(wavenumber(self._peak_omega, wave_field.depth, wave_field.g))
        self.mean_direction = float(wave_field.mean_direction)
        self._sea = np.array([self.hs, self._peak_omega, self._peak_k, self.mean_direction])
        self._sample, self._total, self._motion, self._extras = np.zeros(16), np.zeros(12), np.zeros((0, 24)), np.zeros(10)
        self._drift = ExternalWrench(force_world=np.zeros(3), point_body=np.zeros(3), moment_world=np.zeros(3))
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

    def step(self, low: VesselState, t: float, points: BodyPoints) -> WaveStep:
        """`sample`, `total`, `point_offsets`, `drift_wrench` and `status` in one compiled call
        (the vessel node's per-step path: as separate numpy steps they cost four times as much)."""
        n = points.body.shape[0]
        if self._motion.shape[0] != n:
            self._motion = np.zeros((n, 24))
        low12 = np.concatenate((low.position, low.rpy, low.linear_velocity_body, low.angular_velocity_body))
        total, motion, extras, drift = self._total, self._motion, self._extras, self._drift
        r, rdot = self.response.ramp(t)
        resp = self.response
        _step(resp.table, resp.comp, resp.work, resp.work_j, low12, float(t), r, rdot, points.body, self._sea,
              self._sample, total, motion, extras)
        drift.force_world[0], drift.force_world[1], drift.moment_world[2] = extras[0], extras[1], extras[2]
        return WaveStep(VesselState(total[0:3], total[3:6], total[6:9], total[9:12]), motion[:, 0:3],
                        motion[:, 3:6], (motion[:, 12:15], motion[:, 15:18]), drift, tuple(extras[3:10].tolist()))

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


class WaveStep:
    """What one published state needs of the sea (VesselInWaves.step): the total state, every
    body point's total world position and velocity and their wave-frequency parts, the drift
    wrench for the next step and VesselStatus' sea floats. Arrays are views of the vessel's
    buffers: valid until its next step."""
    __slots__ = ("total", "positions", "velocities", "offsets", "drift", "sea_floats")

    def __init__(self, total, positions, velocities, offsets, drift, sea_floats):
        self.total, self.positions, self.velocities = total, positions, velocities
        self.offsets, self.drift, self.sea_floats = offsets, drift, sea_floats


@njit(cache=True)
def _points_world(state, points, out, col):
    """p = x + R r, v = R (v_b + w x r) of the body points (n, 3) in state (12,: position, rpy,
    body velocities) into out[:, col:col + 6]."""
    e = matrix_entries_from_trig(math.cos(state[3]), math.sin(state[3]), math.cos(state[4]), math.sin(state[4]),
                                 math.cos(state[5]), math.sin(state[5]))
    p, q, r = state[9], state[10], state[11]
    for i in range(points.shape[0]):
        x, y, z = points[i, 0], points[i, 1], points[i, 2]
        vx, vy, vz = state[6] + q * z - r * y, state[7] + r * x - p * z, state[8] + p * y - q * x
        for a in range(3):
            out[i, col + a] = state[a] + e[3 * a] * x + e[3 * a + 1] * y + e[3 * a + 2] * z
            out[i, col + 3 + a] = e[3 * a] * vx + e[3 * a + 1] * vy + e[3 * a + 2] * vz


@njit(cache=True)
def _step(table, comp, work, work_j, low, t, r, rdot, points, sea, sample, total, motion, extras):
    """The response at the manoeuvring state low (12,) at t (wave_response._evaluate, into
    sample (16,)), then `_superpose`: one call per published state."""
    _evaluate(table, comp, work, work_j, low[0], low[1], low[5], low[6], t, r, rdot, sample)
    _superpose(sample, low, points, sea, total, motion, extras)


@njit(cache=True)
def _superpose(sample, low, points, sea, total, motion, extras):
    """The compiled `total`, `point_offsets`, `drift_wrench` and `status` of one sample (their
    numpy versions are its oracle, tests/physics/test_seakeeping.py). sample (16,) from
    WaveResponse; low (12,) the manoeuvring state; sea (4,): hs, peak omega, its wavenumber,
    mean direction. Out: total (12,); motion (n, 24): total position and velocity, low ones,
    then total minus low; extras (10,): drift force x, y and moment z (world), then the seven
    sea floats of VesselStatus."""
    c, s = math.cos(low[5]), math.sin(low[5])
    total[0] = low[0] + c * sample[0] - s * sample[1]
    total[1] = low[1] + s * sample[0] + c * sample[1]
    total[2] = low[2] + sample[2]
    for a in range(3):
        total[3 + a] = low[3 + a] + sample[3 + a]
    for a in range(6):
        total[6 + a] = low[6 + a] + sample[6 + a]
    _points_world(total, points, motion, 0)
    _points_world(low, points, motion, 6)
    for i in range(points.shape[0]):
        for a in range(6):
            motion[i, 12 + a] = motion[i, a] - motion[i, 6 + a]
    X, Y = sample[12], sample[13]
    extras[0], extras[1], extras[2] = c * X - s * Y, s * X + c * Y, sample[14]
    psi, u = low[5], low[6]
    hs, peak_omega, peak_k, mean_direction = sea[0], sea[1], sea[2], sea[3]
    frm = mean_direction + math.pi - psi
    frm -= 2.0 * math.pi * round(frm / (2.0 * math.pi))   # math.remainder, which numba lacks
    omega_e = abs(peak_omega - peak_k * u * math.cos(mean_direction - psi))
    extras[3], extras[4] = sample[15], hs
    extras[5] = 2.0 * math.pi / omega_e if omega_e > 1e-9 else math.inf
    extras[6], extras[7], extras[8], extras[9] = frm, sample[2], sample[3], sample[4]


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
