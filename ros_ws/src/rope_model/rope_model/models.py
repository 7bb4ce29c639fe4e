"""One face for every rope model, so the one rope node can run any rope file.

The rope file's ``model:`` key picks the model: ``element_chain`` (Yoon, Lee, Park, Kim 2012; the default when
the key is absent) or ``fd_cable`` (Park & Jung). Each adapter offers the same outputs in the
world frame (ENU, m, m/s, N).
"""
from __future__ import annotations

import math
from typing import List, Optional, Tuple

import numpy as np

from sea_environment.environment import Environment
from sea_environment.sampler import P_TIME, EnvironmentSampler
from sim_math.rotations import yaw_pitch_quaternions

from rope_model import fd_kernels as FK
from rope_model.chain import RopeChain, RopeDivergedError
from rope_model.end_coupling import EndCoupling, end_couplings
from rope_model.fd_cable import FdCable, FdCableConvergenceError, load_cable_params
from rope_model.params import load_rope_params
from rope_model.schema import RopeParamsError, read_yaml_mapping

MODELS = ("element_chain", "fd_cable")
# What a model raises when it cannot go on; the node reports it and stops.


class CableOnSeabedError(RuntimeError):
    """The fd cable reached the seabed: it has no bottom contact, so the run cannot go on."""


ModelFailure = (RopeDivergedError, FdCableConvergenceError, CableOnSeabedError)


def rope_file_model(path: str) -> str:
    """The file's model key (default element_chain). Raises FileNotFoundError, or
    RopeParamsError (a ValueError) naming the file for bad YAML, a duplicate or empty file or
    an unknown model."""
    src, data = read_yaml_mapping(path, "rope", RopeParamsError)
    model = data.get("model", "element_chain")
    if model not in MODELS:
        raise RopeParamsError(f"{src}: key 'model': expected one of {', '.join(MODELS)}, got {model!r}")
    return model


class ChainAdapter:
    """The multi-body element chain of Yoon, Lee, Park, Kim (2012)."""

    name = "element_chain"

    def __init__(self, path: str, layout: str, p_a, p_b, *, end_a: str, end_b: str, current,
                 n_elements: Optional[int], deployed_length: Optional[float], max_substep: float,
                 equilibrium: bool = False, velocity_a=(0.0, 0.0, 0.0), velocity_b=(0.0, 0.0, 0.0),
                 seabed=None):
        """seabed: None, or a function of the element centres (N, 3) giving the depth below each
        (m, positive down): the rope is laid, and settled, on that seabed."""
        self.params = load_rope_params(path)
        kw = dict(end_a=end_a, end_b=end_b, current=current)
        if max_substep > 0:
            kw["max_substep"] = max_substep
        if seabed is not None and layout != "straight":
            # over a seabed a hanging bight would start below it: lay the slack in a horizontal
            # bight to the chord's left instead; it sinks onto the bottom while settling / at the start
            chord = np.asarray(p_b, float) - np.asarray(p_a, float)
            side = np.array([-chord[1], chord[0], 0.0])
            if np.linalg.norm(side) > 1e-9:
                kw["sag_direction"] = side / np.linalg.norm(side)
        if layout == "straight":
            self.rope = RopeChain.straight(self.params, p_a, p_b, n_elements=n_elements, **kw)
        elif layout == "slack":
            self.rope = RopeChain.slack(self.params, p_a, p_b, n_elements=n_elements, length=deployed_length, **kw)
        else:
            self.rope = RopeChain.wound_on_winch(self.params, p_a, p_b, deployed_length=deployed_length,
                                                 n_elements=n_elements, **kw)
        if seabed is not None:
            self.rope.set_environment(current=np.array(self.rope.current, float), wind=None,
                                      seabed_depth=np.asarray(seabed(self.rope.element_centres()), float))
        # equilibrium: settled for the ends' step-0 positions and velocities before step 0
        # (RopeChain.settle); settle_time is how long that took, None when laid as is
        self.settle_time = self.rope.settle(velocity_a, velocity_b) if equilibrium else None
        self.breaking_load = self.params.breaking_load
        self.radius = self.params.radius
        self.reported = 0

    def set_end(self, label: str, position, velocity) -> None:
        self.rope.set_end_kinematics(label, position, velocity)

    def drive_end(self, label: str, position, velocity, h: float):
        """Drive a pinned end over the coming step of length h so that it reaches where the
        vessel's attachment will be (position + h velocity) without a jump: from where the last
        step left it, x~, at v + (position - x~) / h. Re-pinning it at `position` every step
        instead jerks the end connection by about a h^2 / 2 (261 kN at 10 Hz on 40 m of wire,
        studies/coupling-stability 4.4). Returns (x~, the drive velocity)."""
        start = self.rope.attachment_position(label)
        drive = np.asarray(velocity, float) + (np.asarray(position, float) - start) / h
        self.rope.set_end_kinematics(label, start, drive)
        return start, drive

    def couplings(self, drives: dict, h: float, averaged: bool) -> dict:
        """{end: end_coupling.EndCoupling} of the pinned ends (drives: {end: (x~, drive velocity)}
        of the step just taken, or their step-0 state; end_coupling.end_couplings)."""
        return end_couplings(self.rope, drives, h, averaged)

    def element_centres(self) -> np.ndarray:
        """(N, 3) element centres (world, m): where to sample current, wind and depth."""
        return self.rope.element_centres()

    def set_environment(self, current=None, wind=None, seabed_depth=None) -> None:
        """RopeChain.set_environment: current and wind (3,) or (N, 3) m/s, seabed depth (m,
        positive down; number or (N,), inf = none); each call replaces all three, None = calm.
        ValueError naming the argument and element for bad values."""
        self.rope.set_environment(current, wind, seabed_depth)

    def attach_environment(self, env: Environment) -> None:
        """From now on every step samples `env` (current, wind at each height, seabed depth) at
        the element centres inside the rope's compiled step, from t = 0 (RopeChain.attach_environment)."""
        self.rope.attach_environment(EnvironmentSampler(env).data)

    def set_payout_rate(self, rate: float) -> List[str]:
        """Winch order, m/s (+ pays out); clamped to the rope file's winch limits. Returns
        the notes of any clamp (empty list: taken as given); ValueError for NaN / inf."""
        return self.rope.set_payout_rate(rate)

    def set_winch(self, mode: Optional[str] = None, **kw) -> List[str]:
        """RopeChain.set_winch: mode 'speed' / 'hold' / 'constant_tension', payout_rate (m/s),
        set_tension, recover_tension, brake_load (N; None keeps). Returns the clamp notes;
        ValueError naming the value for a bad order (nothing changed)."""
        return self.rope.set_winch(mode, **kw)

    def step(self, dt: float) -> None:
        self.rope.step(dt)

    def new_events(self) -> List[Tuple[str, float]]:
        """Partings since the last call, as (description, tension N)."""
        out = [(f"rope parted at connection {e.connection} (t = {e.time:.3f} s) with tension "
                f"{e.tension / 1e3:.1f} kN", e.tension) for e in self.rope.events[self.reported:]]
        self.reported = len(self.rope.events)
        return out

    def end_force(self, label: str, averaged: bool) -> np.ndarray:
        return self.rope.mean_end_force(label) if averaged else self.rope.end_force(label)

    def outputs(self):
        r = self.rope
        quats = yaw_pitch_quaternions(r.axes)
        return dict(positions=r.positions, quaternions=quats, velocities=r.velocities,
                    angular_velocities=r.angular_velocities, lengths=r.lengths, tensions=r.tensions,
                    piece_starts=[a for a, _ in r.pieces], unstretched_length=r.unstretched_length,
                    mass=r.total_mass, line=r.joint_points(), broken=bool(r.events),
                    kinetic_energy=r.kinetic_energy(), potential_energy=r.potential_energy())


class CableAdapter:
    """The finite-difference towed cable of Park & Jung: end a on the ship, end b free."""

    name = "fd_cable"

    def __init__(self, path: str, layout: str, p_a, p_b, *, end_a: str, end_b: str, current,
                 n_elements: Optional[int], deployed_length: Optional[float], max_substep: float,
                 velocity_a=(0.0, 0.0, 0.0), heading: float = 0.0):
        self.settle_time = None  # it always starts in its steady tow: nothing to settle
        if end_a == "free" or end_b != "free":
            raise ValueError("an fd_cable rope has end a on a vessel (or fixed) and end b 'free' (Park & Jung Eq 14-15)")
        if layout != "straight":
            raise ValueError("an fd_cable rope starts from its steady state: use layout 'straight'")
        self.params = load_cable_params(path)
        self.cable = FdCable(self.params, p_a, velocity_a, heading, n_nodes=n_elements,
                             current=np.asarray(current, float))
        self.breaking_load = float("inf")
        self.radius = 0.5 * self.params.diameter
        self._env = None    # attach_environment

    def set_end(self, label: str, position, velocity) -> None:
        if label == "a":
            self.cable.set_top_kinematics(position, velocity)

    def drive_end(self, label: str, position, velocity, h: float):
        """The cable's top end is set where the vessel's attachment is (its own scheme, Park &
        Jung Eq 14); returns (position, velocity) as ChainAdapter.drive_end does."""
        self.set_end(label, position, velocity)
        return np.asarray(position, float), np.asarray(velocity, float)

    def couplings(self, drives: dict, h: float, averaged: bool) -> dict:
        """The top end's force, held over the step (K = C = 0: a towed cable of a few hundred kg
        hardly couples back into its ship's motion; not linearised)."""
        out = {}
        for end, (x0, v) in drives.items():
            x0, v = np.asarray(x0, float), np.asarray(v, float)
            out[end] = EndCoupling(self.end_force(end, averaged), x0 + 0.5 * h * v if averaged else x0.copy(),
                                   v.copy(), np.zeros((3, 3)), np.zeros((3, 3)))
        return out

    def set_payout_rate(self, rate: float) -> None:
        raise ValueError("an fd_cable rope has no winch")

    def set_winch(self, mode=None, **kw) -> None:
        raise ValueError("an fd_cable rope has no winch")

    def element_centres(self) -> np.ndarray:
        return self.cable.positions

    def set_environment(self, current=None, wind=None, seabed_depth=None) -> None:
        """The environment at the cable's nodes for the coming step. Park & Jung's Eq 6 takes one
        uniform current: the cable gets the mean of the nodes' currents (exact for a uniform or
        tidal current, the cable's average across a sheared one). Wind: none, the towed cable
        is under water. Seabed: the model has no bottom contact, so a node below the seabed
        stops the run (CableOnSeabedError, naming the node and the depth)."""
        if current is not None:
            c = np.asarray(current, float)
            self.cable.current = c.mean(axis=0) if c.ndim == 2 else c.copy()
        if seabed_depth is not None:
            z = self.cable.positions[:, 2]
            below = np.nonzero(z < -np.asarray(seabed_depth, float))[0]
            if below.size:
                i = int(below[0])
                raise _on_seabed(i, z[i], float(np.broadcast_to(seabed_depth, z.shape)[i]))

    def attach_environment(self, env: Environment) -> None:
        """From now on every step samples `env` at the nodes first, from t = 0, in one compiled
        call (fd_kernels.sample_environment; what set_environment takes: the mean current; the
        seabed check) and the waves at each node (fd_kernels.sample_waves, FdCable.set_waves)."""
        self._env = EnvironmentSampler(env).data
        self._waves = np.zeros((self.cable.n, 6))

    def step(self, dt: float) -> None:
        env = self._env
        if env is not None:
            pos = self.cable.positions
            cx, cy, below, depth = FK.sample_environment(pos, env)
            if below >= 0:
                raise _on_seabed(below, pos[below, 2], depth)
            self.cable.current = np.array([cx, cy, 0.0])
            # the waves at the nodes at the step's middle (as the rope chain: kernels.sample_waves)
            if FK.sample_waves(pos, env, env[P_TIME] + 0.5 * dt, self._waves):
                self.cable.set_waves(self._waves[:, :3], self._waves[:, 3:])
            env[P_TIME] += dt
        self.cable.step(dt)

    def new_events(self) -> List[Tuple[str, float]]:
        return []  # the cable model does not part

    def end_force(self, label: str, averaged: bool) -> np.ndarray:
        return self.cable.top_force() if label == "a" else np.zeros(3)

    def outputs(self):
        c = self.cable
        rot = c.rotations  # columns t, n, b in world; t points towards the towing point (end a)
        quats = yaw_pitch_quaternions(rot[:, :, 0])
        return dict(positions=c.positions, quaternions=quats, velocities=c.velocities,
                    angular_velocities=c.angular_velocities, lengths=c.segment_lengths,
                    tensions=np.maximum(c.tensions, 0.0), piece_starts=[0], unstretched_length=c.unstretched_length,
                    mass=c.total_mass, line=c.positions, broken=False,
                    kinetic_energy=math.nan, potential_energy=math.nan)   # not computed for the cable


def _on_seabed(node: int, z: float, depth: float) -> CableOnSeabedError:
    return CableOnSeabedError(
        f"fd_cable: node {node} is at z = {z:.2f} m, below the seabed ({depth:.2f} m deep); the "
        "finite-difference cable has no bottom contact (use an element_chain rope in shallow water)")


def make_model(path: str, layout: str, p_a, p_b, **kw):
    model = rope_file_model(path)
    if model == "fd_cable":
        kw.pop("velocity_b", None)
        kw.pop("equilibrium", None)  # the cable always starts in its steady tow
        if kw.pop("seabed", None) is not None:
            raise ValueError("fd_cable: no seabed contact (element_chain only)")
        return CableAdapter(path, layout, p_a, p_b, **kw)
    kw.pop("heading", None)
    return ChainAdapter(path, layout, p_a, p_b, **kw)


def load_params(path: str):
    """Validated parameters of any rope file (errors name the file and the key)."""
    return load_cable_params(path) if rope_file_model(path) == "fd_cable" else load_rope_params(path)
