"""6-DOF planing hull with a waterjet (Yoon & Kang, "Modeling and Simulation of the 6 DOF Motion
of a High Speed Planing Hull Running in Calm Sea"). ROS-free.

The ship file (``model: planing_6dof``) gives the paper's data (Tables 1, 3-6), the hull
particulars Savitsky's method needs (the calm-water resistance curve is computed from them
at load, savitsky.py), and the values the paper does not give, each listed under
``estimated:``. Physics kernels: planing_core.py. Notes and results: PLANING.md.

Sign conventions (REP-103, see vessel.py): pitch is bow-DOWN positive, so the paper's and
Savitsky's trim tau (bow up positive, Table 2) is -pitch; Eq 9 applies lift when pitch < 0.
steering_angle > 0 turns to port; Eq 12's bucket angle is its negative.
"""
from __future__ import annotations

import dataclasses
import math
from typing import Any, Dict, List, Optional, Sequence, Tuple

import numpy as np

from sea_environment.sampler import E_CURRENT_X, E_CURRENT_Y, EnvironmentSampler
from tug_dynamics import planing_core as pc
from tug_dynamics import savitsky
from tug_dynamics.vessel import (CPL_ON, SPRING_SUBSTEP, AnchorState, Command, ExternalWrench, StatusRecord, Vessel, VesselState,
                                 check_command, check_current, coupling_row, rotation_body_to_world)

KNOT = 1852.0 / 3600.0

# section -> key -> required?  (unknown keys are errors: a typo must not pass silently)
_SCHEMA: Dict[str, Dict[str, bool]] = {
    "": {"model": True, "name": False, "description": False, "sources": False, "estimated": True,
         "environment": True, "hull": True, "resistance": True, "hydrodynamics": True,
         "waterjet": True, "integration": False, "attachments": True, "windage": False},
    "environment": {"water_density": True, "gravity": True, "kinematic_viscosity": True},
    "hull": {"length_overall": True, "beam": True, "draft": True, "mass": True,
             "reference_point_from_transom": True, "chine_beam": True, "deadrise_deg": True,
             "lcg_from_transom": True, "vcg_above_waterline": True, "radii_of_gyration": True,
             "displacement_exponent": True},
    "resistance": {"savitsky_speeds_kn": True, "roughness_allowance": True, "astern_factor": True},
    "hydrodynamics": {"reference_length": True, "lift_reference_beam": True, "lift_fade_draft": True,
                      "polynomials": True, "Y_vv": True, "N_rr": True, "Y_phi": True, "N_phi": True,
                      "K_phi": True, "side_force_froude_range": True, "Z_wdot": True, "K_pdot": True,
                      "M_qdot": True, "Z_q_per_speed": True, "heave_damping": True,
                      "pitch_damping": True, "roll_damping": True},
    "hydrodynamics.polynomials": {k: True for k in (
        "Y_vdot", "Y_rdot", "Y_v", "Y_r", "N_vdot", "N_rdot", "N_v", "N_r",
        "K_S", "M_S", "C_L", "C_M", "M_w")},
    "waterjet": {"nozzle_area": True, "design_speed_kn": True, "astern_efficiency": True,
                 "position": True, "rated_impeller_rpm": True, "impeller_ramp_time": True,
                 "bucket_max_deg": True, "bucket_rate_deg_s": True},
    "integration": {"max_substep": True},
    "windage": {k: True for k in ("type", "frontal_area", "lateral_area", "centroid_x", "centroid_height",
                                  "length_overall")},
}
_POLY_ROWS = {"Y_vdot": pc.C_YVD, "Y_rdot": pc.C_YRD, "Y_v": pc.C_YV, "Y_r": pc.C_YR,
              "N_vdot": pc.C_NVD, "N_rdot": pc.C_NRD, "N_v": pc.C_NV, "N_r": pc.C_NR,
              "K_S": pc.C_KS, "M_S": pc.C_MS, "C_L": pc.C_CL, "C_M": pc.C_CM, "M_w": pc.C_MW}


class ShipFileError(ValueError):
    """A ship file value that is missing, unknown or out of range; names file and key."""


class _Cfg:
    """Typed access to the parsed YAML; every error names the file and the key path."""

    def __init__(self, cfg: dict, source: str):
        if not isinstance(cfg, dict):
            raise ShipFileError(f"{source}: the ship file must be a mapping, got {type(cfg).__name__}")
        self.cfg, self.source = cfg, source
        self._check_keys()

    def _err(self, key: str, msg: str) -> ShipFileError:
        return ShipFileError(f"{self.source}: key '{key}': {msg}")

    def _section(self, path: str) -> dict:
        node = self.cfg
        for part in [p for p in path.split(".") if p]:
            node = node.get(part) if isinstance(node, dict) else None
            if not isinstance(node, dict):
                raise self._err(path, "missing or not a mapping")
        return node

    def _check_keys(self) -> None:
        for sec, keys in _SCHEMA.items():
            if sec and sec.split(".")[0] not in self.cfg and not _SCHEMA[""].get(sec.split(".")[0], False):
                continue  # optional section absent
            node = self._section(sec)
            for k in node:
                if k not in keys:
                    where = f"{sec}.{k}" if sec else k
                    raise self._err(where, f"unknown key (allowed: {sorted(keys)})")
            for k, req in keys.items():
                if req and k not in node:
                    raise self._err(f"{sec}.{k}" if sec else k, "missing")
        if self.cfg["model"] != "planing_6dof":
            raise self._err("model", f"is {self.cfg['model']!r}, this loader is for 'planing_6dof'")
        est = self.cfg["estimated"]
        if not isinstance(est, dict):
            raise self._err("estimated", "must map key paths to how each value was estimated")
        for path in est:
            if self.lookup(path, must=False) is None:
                raise self._err(f"estimated.{path}", "names a key that the file does not have")

    def lookup(self, path: str, must: bool = True) -> Any:
        node: Any = self.cfg
        for part in path.split("."):
            if isinstance(node, dict) and part in node:
                node = node[part]
            else:
                if must:
                    raise self._err(path, "missing")
                return None
        return node

    def num(self, path: str, lo: float = -math.inf, hi: float = math.inf, strict_lo: bool = False) -> float:
        val = self.lookup(path)
        if isinstance(val, bool) or not isinstance(val, (int, float)) or not math.isfinite(val):
            raise self._err(path, f"must be a finite number, got {val!r}")
        if val < lo or val > hi or (strict_lo and val == lo):
            raise self._err(path, f"{val!r} is outside {'(' if strict_lo else '['}{lo}, {hi}]")
        return float(val)

    def vec(self, path: str, n: Optional[int] = None, min_n: int = 1, max_n: int = 99) -> np.ndarray:
        val = self.lookup(path)
        if not isinstance(val, (list, tuple)) or not all(
                isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) for x in val):
            raise self._err(path, f"must be a list of finite numbers, got {val!r}")
        if (n is not None and len(val) != n) or not (min_n <= len(val) <= max_n):
            want = n if n is not None else f"{min_n}..{max_n}"
            raise self._err(path, f"must have {want} numbers, got {len(val)}")
        return np.asarray(val, float)


@dataclasses.dataclass(kw_only=True, slots=True)
class PlaningStatus(StatusRecord):
    """StatusRecord plus the planing hull's own values."""
    bucket_angle: float          # rad, + turns to port (= steering_angle)
    throttle: float              # impeller speed fraction
    impeller_rpm: float
    jet_speed: float             # m/s, Eq 11
    lift: float                  # N, bottom lift (Eq 9)
    planing_trim: float          # rad, Savitsky's tau: + bow up (= -trim)
    draft_at_reference: float    # m, d1 = d0 - Z0 (Eq 3)


class PlaningHull(Vessel):
    """Yoon & Kang's planing hull: 6 DOF, lift bow-up only, waterjet with bucket steering."""

    def __init__(self, name: str, P: np.ndarray, C: np.ndarray, rtab: np.ndarray,
                 hull: savitsky.HullParticulars, attachments: Dict[str, np.ndarray],
                 limits: Dict[str, float], source: str,
                 initial_state: Optional[VesselState] = None):
        self.name = name
        self.source = source
        self.P, self.C, self.rtab = P, C, rtab
        self.hull = hull
        self.attachments = attachments
        self.limits = limits
        self.hmax = float(P[pc.P_MAXSUB])  # RK4 substep bound, s (benchmarks read it)
        self._act = np.zeros(2)          # impeller speed fraction, bucket angle (interface sign)
        self._cmd = np.zeros(2)          # held engine order, bucket angle ordered
        self._command = Command()
        self._diag = np.zeros(pc.D_ND)
        self._no_wrench = np.zeros((0, pc.NWRENCH))
        self.wrench_work = np.zeros(0)   # J, work done by each wrench of the last step on its point
        self._current = np.zeros(3)
        self._environment: Optional[EnvironmentSampler] = None   # attach_environment
        self._x = np.zeros(12)
        self.state = VesselState.at_rest()
        if initial_state is not None:
            self.state = _copied(initial_state)
            u0 = float(self.state.linear_velocity_body[0])
            flat = (self.state.position[2] == 0.0 and self.state.rpy[0] == 0.0 and self.state.rpy[1] == 0.0
                    and not np.any(self.state.linear_velocity_body[1:]) and not np.any(self.state.angular_velocity_body))
            if u0 > 0.0 and flat:
                # an initial speed alone (vessel node): start in the steady run at that speed
                self.set_steady_run(u0)
        self._refresh_diag()

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_config(cls, cfg: dict, source: str, name: Optional[str] = None,
                    initial_state: Optional[VesselState] = None) -> "PlaningHull":
        """Build from a parsed ship file; ShipFileError names the file and the key.

        The sections are read in a fixed order, so a file with several faults names the same
        key first every time."""
        c = _Cfg(cfg, source)
        hull, body = _hull_particulars(c)
        speeds, speed_step, rtab = _savitsky_resistance_table(c, hull)
        P = np.zeros(pc.P_NPAR)
        _fill_mass_and_hydrostatics(P, hull, body)
        _fill_hydrodynamics(P, c, body.draft)
        P[pc.P_UFIT] = speeds[-1]
        _fill_waterjet(P, c, speeds)
        _fill_resistance(P, c, speeds, speed_step, rtab)
        _fill_actuators(P, c)
        P[pc.P_MAXSUB] = (c.num("integration.max_substep", 1e-4, 0.05)
                          if "integration" in cfg else 0.01)
        C = _polynomials(c)
        attachments = _attachments(c)
        limits = {"bucket_max": P[pc.P_DMAX],
                  "rated_impeller_speed": c.num("waterjet.rated_impeller_rpm", 0.0, 1e5, strict_lo=True)
                  * 2.0 * math.pi / 60.0}
        boat = cls(name or str(cfg.get("name", "planing_hull")), P, C, rtab, hull, attachments,
                   limits, source, initial_state)
        boat.length = c.num("hull.length_overall", 0.0, 200.0, strict_lo=True)  # the L of the IMO criteria
        boat.beam = c.num("hull.beam", 0.0, 50.0, strict_lo=True)
        boat.draft = c.num("hull.draft", 0.0, 20.0, strict_lo=True)
        boat.volume = hull.mass / hull.water_density
        if "windage" in cfg:
            from sea_environment.wind_loads import Windage
            try:
                boat.windage = Windage.from_config(cfg["windage"])
            except ValueError as exc:
                raise ShipFileError(f"{source}: key '{str(exc).split(':')[0]}': {str(exc).split(': ', 1)[1]}") from None
        return boat

    # ------------------------------------------------------------------ Vessel interface
    @property
    def command(self) -> Command:
        return self._command

    def settle_command(self, cmd: Command) -> List[str]:
        msgs = self.set_command(cmd)
        self._act[:] = self._cmd  # impeller and bucket at their ordered values
        return msgs

    def set_command(self, cmd: Command) -> List[str]:
        check_command(cmd)  # raises CommandRejected; the held command is untouched
        notes = []
        eo = float(cmd.engine_order)
        if eo > 1.0 or eo < -1.0:
            notes.append(f"engine_order {eo:g} clamped to [-1, 1]")
            eo = min(max(eo, -1.0), 1.0)
        dm = self.limits["bucket_max"]
        st = float(cmd.steering_angle)
        if abs(st) > dm:
            notes.append(f"steering_angle {st:g} rad clamped to +-{dm:.4f} rad (bucket limit)")
            st = min(max(st, -dm), dm)
        if cmd.anchor != 0:
            notes.append(f"anchor order {cmd.anchor} ignored: this boat has no anchor model")
        self._cmd[0], self._cmd[1] = eo, st
        self._command = Command(eo, st, 0)
        return notes

    def set_current(self, current_world: Sequence[float]) -> None:
        """Uniform current (east, north, up) m/s, world ENU; all three components act (6 DOF)."""
        self._current = check_current(current_world)

    def set_depth(self, depth: float) -> None:
        """Without effect: Savitsky's planing forces are deep-water ones and the boat has no
        anchor model (the vessel node still reports its under-keel clearance and grounding)."""
        if not float(depth) > 0.0:
            raise ValueError(f"{self.name}: water depth {depth!r} m must be > 0")

    def attach_environment(self, sampler: EnvironmentSampler) -> None:
        """From now on every step feels the sampler's environment (current, wind, the bottom;
        the depth has no other effect, see set_depth); sampled here on the present state."""
        self._env_rows = np.zeros((2, pc.NWRENCH))
        self._environment = sampler
        self._sample_environment()

    def _sample_environment(self) -> None:
        """The attached environment at the present state (set_state keeps it so)."""
        env, s = self._environment, self.state
        out = env.sample(s.position[0], s.position[1], s.rpy[2], s.linear_velocity_body[0],
                         s.linear_velocity_body[1])
        self._current = np.array([out[E_CURRENT_X], out[E_CURRENT_Y], 0.0])

    def set_state(self, state: VesselState) -> None:
        """Put the boat in this state as given (set_steady_run finds a planing equilibrium)."""
        self.state = _copied(state)
        self._refresh_diag()
        if self._environment is not None:
            self._sample_environment()

    def step(self, dt: float, wrenches: Sequence[ExternalWrench] = ()) -> None:
        if not (dt > 0.0 and math.isfinite(dt)):
            raise ValueError(f"dt must be positive and finite, got {dt!r}")
        s = self.state
        x = self._x
        x[0:3] = s.position
        x[3:6] = s.rpy
        x[6:9] = s.linear_velocity_body
        x[9:12] = s.angular_velocity_body
        env = self._environment
        if wrenches:
            # [F_world, r_body, M_world] per wrench (+ the environment's wind and bottom friction)
            rows = np.zeros((len(wrenches) + (0 if env is None else 2), pc.NWRENCH))
            hmax = float(self.P[pc.P_MAXSUB])
            for i, ew in enumerate(wrenches):
                rows[i, 0:3] = ew.force_world
                rows[i, 3:6] = ew.point_body
                rows[i, 6:9] = ew.moment_world
                coupling_row(ew, rows[i, pc.W_CPL:])
                if ew.coupled:   # the coupled spring is inside the explicit RK4 now: resolve it
                    omega2 = float(np.linalg.norm(np.asarray(ew.stiffness, float), 2)) * self.point_mobility(ew.point_body)
                    if omega2 > 0.0:
                        hmax = min(hmax, SPRING_SUBSTEP / math.sqrt(omega2))
            start = self._points_world(x, rows[:len(wrenches)])
        else:
            rows = self._no_wrench if env is None else self._env_rows
            hmax = float(self.P[pc.P_MAXSUB])
        if env is None:
            pc.integrate(x, self._act, self._cmd, self.P, self.C, self.rtab, rows, self._current, dt, self._diag, hmax)
        else:
            pc.integrate_in_environment(x, self._act, self._cmd, self.P, self.C, self.rtab, rows, self._current, dt,
                                        self._diag, hmax, env.data)
        if wrenches:   # the work of each wrench over the step: its force at both ends, trapezoidal
            end = self._points_world(x, rows[:len(wrenches)])
            self.wrench_work = np.array([0.5 * (f0 + f1) @ (p1 - p0) for (p0, f0), (p1, f1) in zip(start, end)])
        if not np.all(np.isfinite(x)):
            raise FloatingPointError(f"vessel {self.name!r}: state became non-finite")
        s.position[:] = x[0:3]
        s.rpy[:] = x[3:6]
        s.linear_velocity_body[:] = x[6:9]
        s.angular_velocity_body[:] = x[9:12]

    def _points_world(self, x, rows):
        """(world position, coupled force) of each wrench row's point at state x."""
        c = pc.rotation_entries(x)
        out = []
        for row in rows:
            full = pc._coupled_row(row, x, c) if row[pc.W_CPL + CPL_ON] > 0.0 else row
            out.append((pc.point_world_motion(x, c, row[3:6])[0], np.array(full[0:3])))
        return out

    def point_mobility(self, point_body) -> float:
        """vessel.Vessel.point_mobility: the horizontal block of G A^-1 G^T at the present state,
        A the 6x6 rigid-body + added mass matrix of Eq 1 and G the point's lever (body axes)."""
        x = self._x.copy()
        s = self.state
        x[0:3], x[3:6], x[6:9], x[9:12] = s.position, s.rpy, s.linear_velocity_body, s.angular_velocity_body
        b, A = np.empty(6), np.empty((6, 6))
        pc.forces(x, self.P, self.C, self.rtab, self._act[0], 0.0, self._no_wrench, self._current,
                  np.zeros(pc.D_ND), b, A)
        rx, ry, rz = (float(v) for v in point_body)
        g = np.array([[1.0, 0.0, 0.0, 0.0, rz, -ry], [0.0, 1.0, 0.0, -rz, 0.0, rx]])   # a + alpha x r
        mob = g @ np.linalg.solve(A, g.T)
        return float(np.linalg.eigvalsh(0.5 * (mob + mob.T))[-1])

    def status(self) -> PlaningStatus:
        d = self._diag
        s = self.state
        cb = self._current_body() if np.any(self._current) else np.zeros(3)
        u, v = s.linear_velocity_body[0] - cb[0], s.linear_velocity_body[1] - cb[1]
        impeller = self._act[0] * self.limits["rated_impeller_speed"]
        return PlaningStatus(
            engine_order=float(self._cmd[0]),
            steering_angle_ordered=float(self._cmd[1]),
            steering_angle=float(self._act[1]),          # bucket, + turns to port
            shaft_speed=float(impeller),                 # impeller, rad/s
            thrust=float(d[pc.D_THRUST]),
            anchor_state=AnchorState.NONE,               # no anchor on this boat
            speed_through_water=float(math.hypot(u, v)),
            heel=float(s.rpy[0]),                        # REP-103: + starboard down
            trim=float(s.rpy[1]),                        # REP-103: + bow down
            rise=float(s.position[2]),
            girting_ratio=0.0,                           # no towing hook: no girting
            girting_threshold=0.0,
            girting_warning=False,
            bucket_angle=float(self._act[1]),
            throttle=float(self._act[0]),                # impeller speed fraction
            impeller_rpm=float(impeller * 60.0 / (2.0 * math.pi)),
            jet_speed=float(d[pc.D_UJ]),
            lift=float(d[pc.D_LIFT]),
            planing_trim=float(-s.rpy[1]),               # Savitsky tau: + bow up
            draft_at_reference=float(d[pc.D_DRAFT]),
        )

    # ------------------------------------------------------------------ steady state
    def _current_body(self) -> np.ndarray:
        return rotation_body_to_world(self.state.rpy).T @ self._current

    def _refresh_diag(self) -> None:
        x = np.concatenate([self.state.position, self.state.rpy, self.state.linear_velocity_body,
                            self.state.angular_velocity_body])
        pc.rhs(x, self.P, self.C, self.rtab, self._act[0], self._act[1], self._no_wrench,
               self._current, self._diag)

    @property
    def full_speed(self) -> float:
        """Steady straight-run speed at full throttle, m/s (waterjet design speed)."""
        return float(self.P[pc.P_UDES])

    def throttle_for_speed(self, speed: float) -> float:
        """Engine order whose steady straight-run speed is `speed` (m/s): U0(n) linear (2.5)."""
        return speed / self.P[pc.P_UDES]

    def accelerations(self, x: np.ndarray, throttle: float, bucket: float = 0.0) -> np.ndarray:
        """Body accelerations (6,) at state x (12) with the impeller at `throttle`."""
        return pc.rhs(np.asarray(x, float), self.P, self.C, self.rtab, throttle, bucket,
                      self._no_wrench, self._current, np.zeros(pc.D_ND))[6:]

    def steady_state(self, speed: float) -> Dict[str, float]:
        """Steady straight run at body speed `speed` (m/s): rise and pitch where heave and pitch
        balance (the algebraic equilibrium of the same force model)."""
        from scipy.optimize import root
        n = self.throttle_for_speed(speed)
        if not 0.0 <= n <= 1.0:
            raise ValueError(f"speed {speed} m/s is beyond the full-throttle speed "
                             f"{self.P[pc.P_UDES]:.2f} m/s")

        def res(z_th):
            z, th = z_th
            x = np.zeros(12)
            x[2], x[4], x[6], x[8] = z, th, speed, speed * math.tan(th)
            a = self.accelerations(x, n)
            return [a[2], a[4]]

        try:
            tau0 = savitsky.steady_state(self.hull, speed).trim if speed > self.P[pc.P_RTAB_U0] else 0.01
        except ValueError:
            tau0 = 0.05
        best = None
        for th0 in (-tau0, -0.01, -0.1):
            sol = root(res, [0.3 * self.P[pc.P_D0], th0], method="hybr", options={"xtol": 1e-12})
            if sol.success and np.max(np.abs(sol.fun)) < 1e-8:
                best = sol
                break
        if best is None:
            raise RuntimeError(f"no steady state found at {speed} m/s")
        z, th = best.x
        x = np.zeros(12)
        x[2], x[4], x[6], x[8] = z, th, speed, speed * math.tan(th)
        diag = np.zeros(pc.D_ND)
        acc = pc.rhs(x, self.P, self.C, self.rtab, n, 0.0, self._no_wrench, self._current, diag)[6:]
        return {"speed": speed, "throttle": n, "rise": float(z), "pitch": float(th),
                "trim_deg": float(-math.degrees(th)), "w": float(x[8]), "lift": float(diag[pc.D_LIFT]),
                "thrust": float(diag[pc.D_THRUST]), "surge_residual": float(acc[0])}

    def set_steady_run(self, speed: float, heading: Optional[float] = None) -> None:
        """Put the boat in its steady straight run at `speed` with the matching throttle held."""
        ss = self.steady_state(speed)
        s = self.state
        s.position[2] = ss["rise"]
        s.rpy[0], s.rpy[1] = 0.0, ss["pitch"]
        if heading is not None:
            s.rpy[2] = heading
        s.linear_velocity_body[:] = (speed, 0.0, ss["w"])
        s.angular_velocity_body[:] = 0.0
        self._act[:] = (ss["throttle"], 0.0)
        self._cmd[:] = (ss["throttle"], 0.0)
        self._command = Command(ss["throttle"], 0.0, 0)
        self._refresh_diag()


def _nonneg2(c: _Cfg, path: str):
    v = c.vec(path, 2)
    if np.any(v < 0):
        raise c._err(path, f"damping [at rest, per m/s] must be >= 0, got {v.tolist()}")
    return float(v[0]), float(v[1])


def _copied(state: VesselState) -> VesselState:
    return VesselState(np.array(state.position, float), np.array(state.rpy, float),
                       np.array(state.linear_velocity_body, float), np.array(state.angular_velocity_body, float))


@dataclasses.dataclass(frozen=True)
class _BodyParticulars:
    """Hull values the parameter vector needs beside savitsky.HullParticulars."""
    draft: float                          # d0, m (Table 1)
    reference_from_transom: float         # m, the body origin
    vcg: float                            # m above the waterline
    radii_of_gyration: Tuple[float, float, float]
    displacement_exponent: float          # V(d) = V0 (d / d0)^n (Eq 3)


def _hull_particulars(c: _Cfg) -> Tuple[savitsky.HullParticulars, _BodyParticulars]:
    """environment: and hull: (Table 1 and the estimated particulars Savitsky's method needs)."""
    rho = c.num("environment.water_density", 900.0, 1100.0)
    g = c.num("environment.gravity", 9.7, 9.9)
    nu = c.num("environment.kinematic_viscosity", 1e-7, 1e-5)
    loa = c.num("hull.length_overall", 0.0, 200.0, strict_lo=True)
    c.num("hull.beam", 0.0, 50.0, strict_lo=True)
    d0 = c.num("hull.draft", 0.0, 20.0, strict_lo=True)
    mass = c.num("hull.mass", 0.0, 1e7, strict_lo=True)
    x_ref = c.num("hull.reference_point_from_transom", 0.0, loa)
    b = c.num("hull.chine_beam", 0.0, 50.0, strict_lo=True)
    # > 0: a flat bottom's pressure has no side component (side_force_height is unbounded)
    beta = c.num("hull.deadrise_deg", 5.0, 45.0)
    lcg = c.num("hull.lcg_from_transom", 0.0, loa, strict_lo=True)
    vcg = c.num("hull.vcg_above_waterline", -d0, 20.0)
    kxx, kyy, kzz = c.vec("hull.radii_of_gyration", 3)
    if min(kxx, kyy, kzz) <= 0:
        raise c._err("hull.radii_of_gyration", "must be positive")
    nexp = c.num("hull.displacement_exponent", 1.0, 4.0)
    hull = savitsky.HullParticulars(mass, b, beta, lcg, rho, nu,
                                    c.num("resistance.roughness_allowance", 0.0, 0.01), g)
    return hull, _BodyParticulars(d0, x_ref, vcg, (kxx, kyy, kzz), nexp)


def _savitsky_resistance_table(c: _Cfg, hull: savitsky.HullParticulars) -> Tuple[np.ndarray, float, np.ndarray]:
    """resistance.savitsky_speeds_kn: the speeds and their step (m/s), Savitsky's calm-water
    resistance there (N)."""
    sp = c.vec("resistance.savitsky_speeds_kn", 3)
    if not (0 < sp[0] < sp[1] and sp[2] > 0):
        raise c._err("resistance.savitsky_speeds_kn", "must be [first > 0, last > first, step > 0] knots")
    speeds = np.arange(sp[0], sp[1] + 0.5 * sp[2], sp[2]) * KNOT
    try:
        rtab = np.array([savitsky.steady_state(hull, s).resistance for s in speeds])
    except ValueError as exc:
        raise c._err("resistance.savitsky_speeds_kn", f"Savitsky's method fails: {exc}") from None
    return speeds, sp[2] * KNOT, rtab


def _fill_mass_and_hydrostatics(P: np.ndarray, hull: savitsky.HullParticulars, body: _BodyParticulars) -> None:
    """Eq 1's mass, CG and inertia about the CG; Eq 3's displacement law."""
    mass = hull.mass
    kxx, kyy, kzz = body.radii_of_gyration
    P[pc.P_RHO], P[pc.P_G], P[pc.P_MASS] = hull.water_density, hull.gravity, mass
    P[pc.P_XG], P[pc.P_YG], P[pc.P_ZG] = hull.lcg_from_transom - body.reference_from_transom, 0.0, body.vcg
    P[pc.P_IXX], P[pc.P_IYY], P[pc.P_IZZ] = mass * kxx ** 2, mass * kyy ** 2, mass * kzz ** 2
    P[pc.P_D0], P[pc.P_V0], P[pc.P_NEXP] = body.draft, mass / hull.water_density, body.displacement_exponent
    P[pc.P_ZSIDE] = side_force_height(hull, body.draft)


def side_force_height(hull: savitsky.HullParticulars, draft: float) -> float:
    """Height above the origin (static waterline) at which the planing hull's side force acts.

    With dry sides (flow leaving the chines) the side force is the bottom pressure normal to the
    two deadrise panels; a panel's force has a roll moment about the keel equal to itself times
    the distance of its centre of pressure along the panel, s, so a pressure difference between
    the panels (sway or yaw) gives a side force whose line of action crosses the centreline s /
    sin(beta) above the keel. With the difference centred on each panel, s = b / (4 cos beta):
    b / (2 sin 2 beta) above the keel, the keel being `draft` below the origin (PLANING.md)."""
    beta = math.radians(hull.deadrise_deg)
    return hull.chine_beam / (2.0 * math.sin(2.0 * beta)) - draft


def _fill_hydrodynamics(P: np.ndarray, c: _Cfg, d0: float) -> None:
    """hydrodynamics: Eq 7's scalar derivatives, Eq 14's lift scales, the estimated dampings."""
    P[pc.P_LREF] = c.num("hydrodynamics.reference_length", 0.0, 200.0, strict_lo=True)
    P[pc.P_BLIFT] = c.num("hydrodynamics.lift_reference_beam", 0.0, 50.0, strict_lo=True)
    P[pc.P_LIFT_FADE] = c.num("hydrodynamics.lift_fade_draft", 0.0, d0, strict_lo=True)
    P[pc.P_ZWD] = c.num("hydrodynamics.Z_wdot", -1e8, 0.0)
    P[pc.P_KPD] = c.num("hydrodynamics.K_pdot", -1e8, 0.0)
    P[pc.P_MQD] = c.num("hydrodynamics.M_qdot", -1e10, 0.0)
    P[pc.P_ZQ1] = c.num("hydrodynamics.Z_q_per_speed", -1e9, 1e9)
    P[pc.P_CZ0], P[pc.P_CZ1] = _nonneg2(c, "hydrodynamics.heave_damping")
    P[pc.P_CQ0], P[pc.P_CQ1] = _nonneg2(c, "hydrodynamics.pitch_damping")
    P[pc.P_CP0], P[pc.P_CP1] = _nonneg2(c, "hydrodynamics.roll_damping")
    fn0, fn1 = c.vec("hydrodynamics.side_force_froude_range", 2)
    if not 0.0 <= fn0 < fn1:
        raise c._err("hydrodynamics.side_force_froude_range", f"must be [low >= 0, high > low], got {[fn0, fn1]}")
    P[pc.P_FNV0], P[pc.P_FNV1] = fn0, fn1
    P[pc.P_YVV] = c.num("hydrodynamics.Y_vv", -1e9, 0.0)
    P[pc.P_NRR] = c.num("hydrodynamics.N_rr", -1e12, 0.0)
    P[pc.P_YPHI] = c.num("hydrodynamics.Y_phi", -1e9, 1e9)
    P[pc.P_NPHI] = c.num("hydrodynamics.N_phi", -1e9, 1e9)
    P[pc.P_KPHI] = c.num("hydrodynamics.K_phi", -1e9, 1e9)


def _fill_waterjet(P: np.ndarray, c: _Cfg, speeds: np.ndarray) -> None:
    """waterjet: Eqs 10-12's nozzle, design speed (Eq 11's U0 at full rpm) and thrust point."""
    P[pc.P_AJ] = c.num("waterjet.nozzle_area", 0.0, 10.0, strict_lo=True)
    P[pc.P_UDES] = c.num("waterjet.design_speed_kn", 0.0, 80.0, strict_lo=True) * KNOT
    if P[pc.P_UDES] > speeds[-1]:
        raise c._err("waterjet.design_speed_kn", "is beyond the Savitsky resistance table "
                     "(resistance.savitsky_speeds_kn)")
    P[pc.P_ETAREV] = c.num("waterjet.astern_efficiency", 0.0, 1.0)
    P[pc.P_XT], P[pc.P_YT], P[pc.P_ZT] = c.vec("waterjet.position", 3)


def _fill_resistance(P: np.ndarray, c: _Cfg, speeds: np.ndarray, speed_step: float, rtab: np.ndarray) -> None:
    """The resistance table's grid, and the astern resistance."""
    P[pc.P_RTAB_U0], P[pc.P_RTAB_DU] = speeds[0], speed_step
    # astern: displacement-mode quadratic through the slowest table point, times a factor
    P[pc.P_RAST] = c.num("resistance.astern_factor", 0.0, 10.0) * rtab[0] / speeds[0] ** 2


def _fill_actuators(P: np.ndarray, c: _Cfg) -> None:
    """Impeller ramp (paper 2.5: rpm changes linearly) and the bucket's rate and limit."""
    P[pc.P_NRAMP] = 1.0 / c.num("waterjet.impeller_ramp_time", 0.0, 120.0, strict_lo=True)
    P[pc.P_DRATE] = math.radians(c.num("waterjet.bucket_rate_deg_s", 0.0, 360.0, strict_lo=True))
    P[pc.P_DMAX] = math.radians(c.num("waterjet.bucket_max_deg", 0.0, 60.0, strict_lo=True))


def _polynomials(c: _Cfg) -> np.ndarray:
    """hydrodynamics.polynomials: Eq 13 quadratics (Tables 3, 4, 6), Table 5 quartics (C_L, C_M)."""
    C = np.zeros((pc.C_NPOLY, 5))
    for key, row in _POLY_ROWS.items():
        n_max = 5 if key in ("C_L", "C_M") else 3
        coef = c.vec(f"hydrodynamics.polynomials.{key}", min_n=1, max_n=n_max)
        C[row, :len(coef)] = coef
    return C


def _attachments(c: _Cfg) -> Dict[str, np.ndarray]:
    att_node = c.lookup("attachments")
    if not isinstance(att_node, dict) or not att_node:
        raise c._err("attachments", "must map attachment names to [x, y, z] body points")
    return {str(k): c.vec(f"attachments.{k}", 3) for k in att_node}


def load(path: str, name: Optional[str] = None, initial_state: Optional[VesselState] = None) -> PlaningHull:
    """Load a planing-hull ship file directly (the common loader is ship_file.load_ship)."""
    import yaml
    with open(path, "r", encoding="utf-8") as fh:
        cfg = yaml.safe_load(fh)
    return PlaningHull.from_config(cfg, path, name=name, initial_state=initial_state)


def fit_pitch_coupling(model: PlaningHull, speeds: Sequence[float], degree: int = 2):
    """The paper's M_w tuning (its 2.4) done systematically: for each speed (m/s) find the
    prime M_w' = M_w/(0.5 rho L^3 U) that makes the steady trim equal Savitsky's trim, then
    fit a polynomial in U. Returns (speeds, M_w' values, coefficients a0..a_degree)."""
    from scipy.optimize import brentq
    P, C = model.P, model.C.copy()
    C[pc.C_MW, :] = 0.0
    b, A, diag = np.zeros(6), np.zeros((6, 6)), np.zeros(pc.D_ND)
    vals = []
    for U in speeds:
        th = -savitsky.steady_state(model.hull, U).trim
        n = model.throttle_for_speed(U)
        x = np.zeros(12)
        x[4], x[6], x[8] = th, U, U * math.tan(th)

        def heave(z):
            x[2] = z
            pc.forces(x, P, C, model.rtab, n, 0.0, model._no_wrench, model._current, diag, b, A)
            return b[2]
        heave(brentq(heave, -P[pc.P_D0], P[pc.P_D0], xtol=1e-12))
        # b[4] is the pitch moment without M_w; M_w w must cancel it
        vals.append(-b[4] / (0.5 * P[pc.P_RHO] * P[pc.P_LREF] ** 3 * U * x[8]))
    coef = np.polynomial.polynomial.polyfit(np.asarray(speeds), np.asarray(vals), degree)
    return np.asarray(speeds), np.asarray(vals), coef
