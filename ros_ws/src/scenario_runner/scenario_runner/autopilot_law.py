"""Control law of the example autopilot (scenario_runner/autopilot.py), free of ROS.

Conventions (README): world frame `map` is ENU, yaw 0 = bow east, positive counter-clockwise
(REP-103); a positive steering angle turns the vessel to port (positive yaw rate at headway);
engine order in [-1, 1]. Angles in rad, speeds in m/s, times in s.

Three pieces, combined by AutopilotLaw:

HeadingController
    steering = kp e + ki I - kd r,  e = wrap(psi_ordered - psi) in [-pi, pi),  r = yaw rate
    (derivative on the measurement: a step in the ordered heading gives no derivative kick).
    Clamped to +-max_steering. Anti-windup: the error is integrated only while |e| is below
    integral_band (a large turn is flown on P and D) and not while the output is saturated
    in the direction the error pushes; ki I is further limited to +-integral_limit.

SpeedController
    engine = (U_o / U_full)^n + kp e + ki I,  e = U_o - U  (U_o ordered speed through the water)
    (feed-forward of the steady engine order for U_o plus PI), clamped to [min_engine,
    max_engine]. Anti-windup as above: integration only while |e| < integral_band (not while
    the vessel accelerates) and not into saturation; ki I limited to +-integral_limit.

LosGuidance
    Line-of-sight guidance along the legs of a waypoint list: on the leg p0 -> p1 with path
    angle chi_p = atan2(y1 - y0, x1 - x0) and cross-track error e (positive: the vessel is to
    the left of the leg, looking along it), the ordered heading is
    psi_d = chi_p - atan(e / lookahead).
    The next leg becomes active when the along-track distance reaches the leg length minus the
    acceptance radius (or the vessel is within that radius of p1). After the last waypoint the
    extension of the last leg is followed (finished = True).
"""
from __future__ import annotations

import dataclasses
import math
from typing import Dict, List, Optional, Sequence, Tuple

from sim_contract.node_params import Param, ParamTable

TWO_PI = 2.0 * math.pi


def wrap_angle(a: float) -> float:
    """a wrapped to [-pi, pi)."""
    return (a + math.pi) % TWO_PI - math.pi


def clamp(value: float, lo: float, hi: float) -> float:
    return lo if value < lo else hi if value > hi else value


class HeadingController:
    """PID on the wrapped heading error, damping on the measured yaw rate. Output: steering, rad."""

    def __init__(self, kp: float, ki: float, kd: float, max_steering: float,
                 integral_band: float = math.radians(10.0), integral_limit: Optional[float] = None):
        if max_steering <= 0.0:
            raise ValueError(f"max_steering={max_steering}: must be positive")
        self.kp, self.ki, self.kd = kp, ki, kd
        self.max_steering = max_steering
        self.integral_band = integral_band
        self.integral_limit = 0.5 * max_steering if integral_limit is None else integral_limit
        self.integral = 0.0  # int e dt, rad s
        self.error = 0.0
        self.saturated = False

    def reset(self) -> None:
        self.integral = 0.0

    def _output(self, error: float, yaw_rate: float, integral: float) -> float:
        return self.kp * error + self.ki * integral - self.kd * yaw_rate

    def update(self, heading_ordered: float, heading: float, yaw_rate: float, dt: float) -> float:
        """Steering angle (rad, positive to port) after dt s (dt = 0: no integration)."""
        e = wrap_angle(heading_ordered - heading)
        self.error = e
        if dt > 0.0 and self.ki > 0.0:
            if abs(e) < self.integral_band:
                candidate = self.integral + e * dt
                # ki I stays within +-integral_limit
                bound = self.integral_limit / self.ki
                candidate = clamp(candidate, -bound, bound)
                raw = self._output(e, yaw_rate, candidate)
                pushing_out = (raw > self.max_steering and e > 0.0) or (raw < -self.max_steering and e < 0.0)
                if not pushing_out:
                    self.integral = candidate
            else:
                # far from the ordered heading (a large turn): let the old integral decay
                self.integral *= math.exp(-dt / 10.0)
        raw = self._output(e, yaw_rate, self.integral)
        out = clamp(raw, -self.max_steering, self.max_steering)
        self.saturated = out != raw
        return out


class SpeedController:
    """Feed-forward + PI on the speed error. Output: engine order."""

    def __init__(self, kp: float, ki: float, speed_full_ahead: float, min_engine: float = 0.0,
                 max_engine: float = 1.0, integral_limit: float = 0.5, exponent: float = 1.4,
                 integral_band: float = 0.5):
        if not min_engine < max_engine:
            raise ValueError(f"engine limits [{min_engine}, {max_engine}]: need min < max")
        if speed_full_ahead <= 0.0:
            raise ValueError(f"speed_full_ahead={speed_full_ahead}: must be positive")
        self.kp, self.ki = kp, ki
        self.speed_full_ahead = speed_full_ahead
        self.exponent = exponent
        self.integral_band = integral_band
        self.min_engine, self.max_engine = min_engine, max_engine
        self.integral_limit = integral_limit
        self.integral = 0.0  # int e dt, m
        self.error = 0.0
        self.saturated = False

    def reset(self) -> None:
        self.integral = 0.0

    def feedforward(self, speed_ordered: float) -> float:
        """Engine order for a steady speed: (U / U_full)^exponent, odd in U."""
        ratio = speed_ordered / self.speed_full_ahead
        return math.copysign(abs(ratio) ** self.exponent, ratio)

    def _output(self, speed_ordered: float, error: float, integral: float) -> float:
        return self.feedforward(speed_ordered) + self.kp * error + self.ki * integral

    def update(self, speed_ordered: float, speed: float, dt: float) -> float:
        e = speed_ordered - speed
        self.error = e
        if dt > 0.0 and self.ki > 0.0 and abs(e) < self.integral_band:
            bound = self.integral_limit / self.ki
            candidate = clamp(self.integral + e * dt, -bound, bound)
            raw = self._output(speed_ordered, e, candidate)
            pushing_out = (raw > self.max_engine and e > 0.0) or (raw < self.min_engine and e < 0.0)
            if not pushing_out:
                self.integral = candidate
        raw = self._output(speed_ordered, e, self.integral)
        out = clamp(raw, self.min_engine, self.max_engine)
        self.saturated = out != raw
        return out


def parse_waypoints(values: Sequence[float]) -> List[Tuple[float, float]]:
    """[x1, y1, x2, y2, ...] -> [(x1, y1), ...]; at least two distinct consecutive points."""
    values = [float(v) for v in values]
    if len(values) % 2:
        raise ValueError(f"track: {len(values)} numbers, expected pairs x1, y1, x2, y2, ...")
    if len(values) < 4:
        raise ValueError("track: need at least two waypoints (x1, y1, x2, y2)")
    if not all(math.isfinite(v) for v in values):
        raise ValueError(f"track: non-finite coordinate in {values}")
    points = list(zip(values[0::2], values[1::2]))
    for i, (a, b) in enumerate(zip(points, points[1:])):
        if math.hypot(b[0] - a[0], b[1] - a[1]) < 1e-6:
            raise ValueError(f"track: waypoints {i + 1} and {i + 2} coincide at {a}")
    return points


class LosGuidance:
    """Line-of-sight guidance along a list of waypoints (map frame, m)."""

    def __init__(self, waypoints: Sequence[Tuple[float, float]], lookahead: float, acceptance_radius: float):
        if len(waypoints) < 2:
            raise ValueError("LOS guidance needs at least two waypoints")
        if lookahead <= 0.0:
            raise ValueError(f"lookahead={lookahead}: must be positive")
        self.waypoints = [(float(x), float(y)) for x, y in waypoints]
        self.lookahead = lookahead
        self.acceptance_radius = max(0.0, acceptance_radius)
        self.leg = 0  # active leg: waypoints[leg] -> waypoints[leg + 1]
        self.finished = False
        self.cross_track = 0.0
        self.along_track = 0.0

    def geometry(self, x: float, y: float, leg: int) -> Tuple[float, float, float, float]:
        """(path angle, along-track distance, cross-track error, leg length) on a leg."""
        (x0, y0), (x1, y1) = self.waypoints[leg], self.waypoints[leg + 1]
        dx, dy = x1 - x0, y1 - y0
        length = math.hypot(dx, dy)
        chi = math.atan2(dy, dx)
        c, s = dx / length, dy / length
        along = (x - x0) * c + (y - y0) * s
        cross = -(x - x0) * s + (y - y0) * c  # positive: left of the leg (port side looking along it)
        return chi, along, cross, length

    def update(self, x: float, y: float) -> float:
        """Ordered heading, rad in [-pi, pi)."""
        last = len(self.waypoints) - 2
        while True:
            chi, along, cross, length = self.geometry(x, y, self.leg)
            x1, y1 = self.waypoints[self.leg + 1]
            reached = along >= length - self.acceptance_radius or math.hypot(x - x1, y - y1) < self.acceptance_radius
            if reached and self.leg < last:
                self.leg += 1
                continue
            if reached and self.leg == last:
                self.finished = True
            break
        self.along_track, self.cross_track = along, cross
        return wrap_angle(chi - math.atan2(cross, self.lookahead))


@dataclasses.dataclass
class AutopilotConfig:
    """Gains and limits; the defaults suit the harbour tug (harbour_tug.yaml: 24 m, 35 deg rudder,
    12 kn at full ahead), tuned with tests/physics/test_autopilot_law.py."""
    mode: str = "heading"               # heading | track
    heading: float = 0.0                # ordered heading, rad (mode heading)
    speed_control: bool = True          # True: PI on speed; False: fixed engine_order
    speed: float = 3.0                  # ordered speed through the water, m/s
    engine_order: float = 0.5           # fixed engine order when speed_control is False
    waypoints: Sequence[Tuple[float, float]] = ()  # mode track
    lookahead: float = 60.0             # LOS lookahead distance, m
    acceptance_radius: float = 40.0     # waypoint switching radius, m
    heading_kp: float = 2.5             # rad steering per rad heading error
    heading_ki: float = 0.05            # rad steering per rad s
    heading_kd: float = 10.0            # rad steering per rad/s yaw rate (s)
    heading_integral_band: float = math.radians(10.0)
    heading_integral_limit: float = math.radians(10.0)
    max_steering: float = math.radians(35.0)
    speed_kp: float = 0.2               # engine order per m/s speed error
    speed_ki: float = 0.02              # engine order per m
    speed_full_ahead: float = 6.17      # speed at engine order 1 (feed-forward), m/s
    speed_exponent: float = 1.4         # feed-forward engine = (speed / speed_full_ahead)^exponent
    speed_integral_band: float = 0.5    # m/s
    speed_integral_limit: float = 0.5
    min_engine_order: float = 0.0
    max_engine_order: float = 1.0

    MODES = ("heading", "track")

    def check(self) -> None:
        if self.mode not in self.MODES:
            raise ValueError(f"mode={self.mode!r}: expected one of {self.MODES}")
        if self.mode == "track" and len(self.waypoints) < 2:
            raise ValueError("mode track needs at least two waypoints (parameter track)")
        if not -1.0 <= self.min_engine_order < self.max_engine_order <= 1.0:
            raise ValueError(f"engine limits [{self.min_engine_order}, {self.max_engine_order}]: "
                             "need -1 <= min < max <= 1")
        for name in ("heading", "speed", "engine_order", "lookahead", "heading_kp", "heading_ki", "heading_kd",
                     "max_steering", "speed_kp", "speed_ki", "speed_full_ahead"):
            if not math.isfinite(getattr(self, name)):
                raise ValueError(f"{name}={getattr(self, name)!r} is not finite")


@dataclasses.dataclass
class Measurement:
    """What the law needs from odometry (and status)."""
    x: float          # m, map (east)
    y: float          # m, map (north)
    yaw: float        # rad, REP-103
    yaw_rate: float   # rad/s, body z
    speed: float      # m/s, speed through the water (or surge speed)

    def finite(self) -> bool:
        return all(math.isfinite(v) for v in (self.x, self.y, self.yaw, self.yaw_rate, self.speed))


@dataclasses.dataclass
class Output:
    engine_order: float
    steering_angle: float     # rad, positive to port
    heading_ordered: float    # rad
    heading_error: float      # rad
    cross_track: float = 0.0  # m (mode track)
    leg: int = 0              # active leg (mode track)
    finished: bool = False    # past the last waypoint (mode track)


class AutopilotLaw:
    """Heading keeping or LOS track following, plus speed control."""

    def __init__(self, cfg: AutopilotConfig):
        cfg.check()
        self.cfg = cfg
        self.heading_ctl = HeadingController(cfg.heading_kp, cfg.heading_ki, cfg.heading_kd, cfg.max_steering,
                                             cfg.heading_integral_band, cfg.heading_integral_limit)
        self.speed_ctl = SpeedController(cfg.speed_kp, cfg.speed_ki, cfg.speed_full_ahead, cfg.min_engine_order,
                                         cfg.max_engine_order, cfg.speed_integral_limit, cfg.speed_exponent,
                                         cfg.speed_integral_band)
        self.los = LosGuidance(cfg.waypoints, cfg.lookahead, cfg.acceptance_radius) if cfg.mode == "track" else None

    def retune(self, cfg: AutopilotConfig) -> None:
        """New orders, gains or limits while running (ros2 param set): the integrals and the
        active leg carry over, each integral within its new bound. Raises ValueError (and
        changes nothing) for a configuration __init__ would refuse, or another mode or track."""
        if cfg.mode != self.cfg.mode or tuple(cfg.waypoints) != tuple(self.cfg.waypoints):
            raise ValueError("mode and track are fixed while running: restart the autopilot to change them")
        fresh = AutopilotLaw(cfg)
        for old, new in ((self.heading_ctl, fresh.heading_ctl), (self.speed_ctl, fresh.speed_ctl)):
            bound = new.integral_limit / new.ki if new.ki > 0.0 else 0.0
            new.integral = clamp(old.integral, -bound, bound)
            new.error = old.error
        if self.los is not None:
            fresh.los.leg, fresh.los.finished = self.los.leg, self.los.finished
        self.cfg, self.heading_ctl, self.speed_ctl, self.los = cfg, fresh.heading_ctl, fresh.speed_ctl, fresh.los

    def update(self, m: Measurement, dt: float) -> Output:
        """Command from one measurement; dt = time since the previous update (0: no integration)."""
        if not m.finite():
            raise ValueError(f"non-finite measurement {m}")
        dt = max(0.0, dt)
        if self.los is not None:
            psi_d = self.los.update(m.x, m.y)
        else:
            psi_d = wrap_angle(self.cfg.heading)
        steering = self.heading_ctl.update(psi_d, m.yaw, m.yaw_rate, dt)
        if self.cfg.speed_control:
            engine = self.speed_ctl.update(self.cfg.speed, m.speed, dt)
        else:
            engine = clamp(self.cfg.engine_order, self.cfg.min_engine_order, self.cfg.max_engine_order)
        out = Output(engine_order=engine, steering_angle=steering, heading_ordered=psi_d,
                     heading_error=self.heading_ctl.error)
        if self.los is not None:
            out.cross_track, out.leg, out.finished = self.los.cross_track, self.los.leg, self.los.finished
        return out


SPEED_SOURCES = ("status", "odom")
_D = AutopilotConfig()
# The example autopilot's ROS parameters (autopilot.py declares them from this table; the
# scenario's `autopilots[].params` are checked against it before any node starts). Orders, gains
# and limits change while running.
NODE_TABLE = ParamTable(
    "scenario_runner/autopilot",
    Param("vessel", "tug", "Name (ROS namespace) of the vessel this autopilot drives"),
    Param("mode", _D.mode, "Steering: heading (keep parameter heading) or track (follow parameter track)",
          choices=AutopilotConfig.MODES),
    Param("heading", 0.0, "Ordered heading (mode heading), 0 = east, positive counter-clockwise (REP-103)",
          -360.0, 360.0, "deg", live=True),
    # the same order as a person gives it: no default, so that it is used only when given
    Param("heading_true_deg", None, "Ordered heading as a compass heading (mode heading), 0 = north, clockwise; "
          "instead of heading", 0.0, 360.0, "deg true", live=True, kind="double"),
    Param("speed_control", _D.speed_control, "true: PI control of the speed through the water to parameter speed; "
          "false: fixed engine_order"),
    Param("speed", _D.speed, "Ordered speed through the water", -10.0, 20.0, "m/s", live=True),
    Param("engine_order", _D.engine_order, "Fixed engine order when speed_control is false", -1.0, 1.0, live=True),
    Param("track", "", "Waypoints [x1, y1, x2, y2, ...] in map (ENU), m, for mode track (a list of numbers, or the "
          "same as a comma-separated string)", dynamic=True),
    Param("lookahead", _D.lookahead, "Line-of-sight lookahead distance", 1.0, 10000.0, "m", live=True),
    Param("acceptance_radius", _D.acceptance_radius, "The next leg starts this far before a waypoint", 0.0, 10000.0,
          "m", live=True),
    Param("heading_kp", _D.heading_kp, "Heading PID: steering per heading error", 0.0, 100.0, "rad/rad", live=True),
    Param("heading_ki", _D.heading_ki, "Heading PID: steering per integrated error", 0.0, 10.0, "rad/(rad s)",
          live=True),
    Param("heading_kd", _D.heading_kd, "Heading PID: steering per yaw rate (damping)", 0.0, 1000.0, "rad/(rad/s)",
          live=True),
    Param("heading_integral_band_deg", math.degrees(_D.heading_integral_band),
          "Heading error below which the integral acts", 0.0, 180.0, "deg", live=True),
    Param("heading_integral_limit_deg", math.degrees(_D.heading_integral_limit),
          "Largest steering from the integral term", 0.0, 90.0, "deg", live=True),
    Param("max_steering_deg", math.degrees(_D.max_steering), "Largest steering angle ordered (harbour tug: 35)",
          0.1, 90.0, "deg", live=True),
    Param("speed_kp", _D.speed_kp, "Speed PI: engine order per speed error", 0.0, 10.0, "1/(m/s)", live=True),
    Param("speed_ki", _D.speed_ki, "Speed PI: engine order per integrated error", 0.0, 10.0, "1/m", live=True),
    Param("speed_full_ahead", _D.speed_full_ahead, "Speed at engine order 1 (feed-forward; harbour tug: 12 kn)",
          0.1, 50.0, "m/s", live=True),
    Param("speed_exponent", _D.speed_exponent,
          "Feed-forward engine order = (speed / speed_full_ahead)^speed_exponent", 0.2, 5.0, live=True),
    Param("speed_integral_band", _D.speed_integral_band, "Speed error below which the integral acts", 0.0, 50.0,
          "m/s", live=True),
    Param("speed_integral_limit", _D.speed_integral_limit, "Largest engine order from the integral term", 0.0, 2.0,
          live=True),
    Param("min_engine_order", _D.min_engine_order, "Lowest engine order ordered", -1.0, 1.0, live=True),
    Param("max_engine_order", _D.max_engine_order, "Highest engine order ordered", -1.0, 1.0, live=True),
    Param("speed_source", "status", "status: speed through the water from /<vessel>/status; odom: speed over ground "
          "from odometry", choices=SPEED_SOURCES),
    Param("odom_timeout", 2.0, "Free-running: stop commanding when the latest odometry is older than this (wall "
          "time)", 0.1, 3600.0, "s", live=True),
    Param("log_period", 5.0, "Simulated seconds between progress log lines; 0: none", 0.0, 3600.0, "s", live=True),
)
_NUMBER = (int, float)


def _scenario_kind(p: Param):
    """(accepted Python type(s), range or choices) of a parameter as a scenario gives it."""
    if p.dynamic:
        return (list, str), None
    if p.ros_type == "bool":
        return bool, None
    if p.ros_type == "string":
        return str, p.choices
    return _NUMBER, (p.lo, p.hi)


# what a scenario may give (the runner sets `vessel` from the scenario's own key)
NODE_PARAMS: Dict[str, tuple] = {p.name: _scenario_kind(p) for p in NODE_TABLE if p.name != "vessel"}


def check_scenario_params(path: str, i: int, a) -> None:
    """The parameters a scenario gives the example autopilot (`a`: its AutopilotSpec, the
    i-th of `autopilots`), checked against NODE_PARAMS and the law's configuration before any
    node starts. ScenarioError naming the file and the key."""
    from scenario_format.scenario import ScenarioError
    if a.package != "scenario_runner" or a.executable != "autopilot":
        return  # another controller: its parameters are its own
    for name, value in a.params.items():
        key = f"autopilots[{i}].params.{name}"
        if name not in NODE_PARAMS:
            raise ScenarioError(f"{path}: key '{key}': unknown parameter of scenario_runner/autopilot (misspelt?); "
                                f"known: {sorted(NODE_PARAMS)}")
        kind, allowed = NODE_PARAMS[name]
        if isinstance(value, bool) and kind is not bool or not isinstance(value, kind):
            raise ScenarioError(f"{path}: key '{key}': wrong type, got {value!r}")
        if kind is _NUMBER and not (math.isfinite(value) and allowed[0] <= value <= allowed[1]):
            raise ScenarioError(f"{path}: key '{key}': must be in [{allowed[0]:g}, {allowed[1]:g}], got {value!r}")
        if kind is str and value not in allowed:
            raise ScenarioError(f"{path}: key '{key}': expected one of {list(allowed)}, got {value!r}")
    p = a.params
    try:
        waypoints = ()
        if p.get("mode", "heading") == "track":
            track = p.get("track", "")
            if isinstance(track, str):
                track = [float(v) for v in track.strip().strip("[]").replace(",", " ").split()]
            if not all(isinstance(v, _NUMBER) and not isinstance(v, bool) for v in track):
                raise ValueError(f"track: expected numbers x1, y1, x2, y2, ..., got {p.get('track')!r}")
            waypoints = parse_waypoints(track)
        AutopilotConfig(mode=p.get("mode", "heading"), waypoints=waypoints,
                        min_engine_order=float(p.get("min_engine_order", 0.0)),
                        max_engine_order=float(p.get("max_engine_order", 1.0))).check()
    except ValueError as exc:
        raise ScenarioError(f"{path}: key 'autopilots[{i}].params': {exc}") from None
