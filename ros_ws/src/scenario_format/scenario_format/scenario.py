"""The scenario format: one YAML file names everything a run needs. Validated before any node
starts; every error names the file, the key and what was expected.

    name: default_demo
    duration: 240.0            # s of simulated time
    exchange_rate: 50.0        # Hz, vessel <-> rope exchange
    mode: lockstep             # lockstep (as fast as possible) | realtime (paced on the wall clock)
    environment: {current: [0.0, 0.0], water_density: 1025.0, gravity: 9.80665}
    # or with wind, a current field and depth (sea_environment/environment.py has the format):
    # environment: {wind: {speed_kn: 25, from_deg: 270}, depth: 14.0,
    #               current: {speed_kn: 1.5, towards_deg: 90, tidal_period_s: 44712},
    #               waves: {hs: 2.0, tp: 8.0, from_deg: 200, spreading_s: 10, seed: 3}}
    vessels:
      - name: tug              # ROS namespace
        ship_file: harbour_tug.yaml
        initial: {x: 0.0, y: 0.0, heading_deg: 0.0, speed: 0.0}
        # manned: true         # a person gives every order (console, page, send_command); the script none
    ropes:
      - name: towline
        rope_file: table1.yaml
        end_a: tug/towing_hook  # "<vessel>/<attachment>", or "fixed" / "free" with end_a_position
        end_b: barge/bow_bollard
        layout: winch           # straight | slack | winch (wound on end a's winch)
        equilibrium: true       # settled to static equilibrium before step 0 (default false: as laid)
    contacts:                   # a tug pushing: its fender against another vessel's hull (hull_contact)
      - name: push_aft
        fender: tug2/bow_fender # "<vessel>/<attachment>"
        hull: ship              # the vessel pushed on (outline from its ship file)
        # radius: 0.5  stiffness: 2.0e6  damping: 4.0e5  friction: 0.3   (m, N/m, N s/m, -)
    interactions:               # passing-ship loads between two hulls (Wang 1975), one interaction_node for all
      - between: [ship, moored] # two vessels; name: optional (default <a>_<b>_interaction)
      - between: [ship]         # one vessel and a vertical bank: [x, y] points (m), the water on the left
        bank: [[0.0, -60.0], [2000.0, -60.0]]
    events:
      - {time: 0.0, vessel: tug, engine_order: 0.8}
      - {time: 60.0, vessel: tug, steering_deg: 20.0}
      - {time: 0.0, rope: towline, payout_rate: 1.0}
      # triggered by state (IMO trials): armed once every event listed before it has fired
      - {when: {vessel: tug, heading_change_deg: 10.0, since: 60.0}, vessel: tug, steering_deg: -20.0}
      - {when: {vessel: tug, speed_below: 0.5}, vessel: tug, engine_order: 0.0}
"""
from __future__ import annotations

import datetime as _dt
import math
import os
import re
from typing import Any, Dict, List, Literal, Optional, Union

from pydantic import BaseModel, ConfigDict, Field, PrivateAttr, ValidationError, field_validator, model_validator
from typing_extensions import Annotated

from sim_contract.equipment import DEFAULT_UTC_START, NMEA_UDP_PORT, check_mmsi, parse_utc
from sim_contract.geo import DEFAULT_ORIGIN, KNOT
from sim_contract.node_params import CONTACT_NODE, CURRENT_EAST, NMEA_OUT, ROPE_NODE, VESSEL_NODE
from sea_environment.environment import DepthGridSpec, EnvironmentSpec
from sim_math import data_files
from sim_math.input_files import YamlInputError, load_yaml


class ScenarioError(ValueError):
    """A scenario that cannot run; the message names the file and the key."""


class _Strict(BaseModel):
    # strict: "1" and true are not numbers; no NaN or inf anywhere (the nodes refuse them)
    model_config = ConfigDict(extra="forbid", frozen=True, strict=True, allow_inf_nan=False)


# The nodes' parameter ranges (sim_contract.node_params): a value outside them makes the node
# refuse to start, so the scenario refuses it first.
_V, _R, _C = VESSEL_NODE, ROPE_NODE, CONTACT_NODE
MAX_COORD = _V["initial_x"].hi        # m, initial_x / initial_y
MAX_CURRENT = CURRENT_EAST.hi         # m/s per component, current_east / current_north


def _within(param, default=..., **bounds):
    """A field whose range is the node parameter's (in the same unit)."""
    return Field(default, ge=param.lo, le=param.hi, **bounds)


def _deg_within(param, default=0.0):
    """A field in degrees of a node parameter in radians: its range, rounded inwards to 0.01 deg."""
    return Field(default, ge=math.ceil(math.degrees(param.lo) * 100) / 100,
                 le=math.floor(math.degrees(param.hi) * 100) / 100)
Coord = Annotated[float, Field(ge=-MAX_COORD, le=MAX_COORD)]
Point3 = Annotated[List[Coord], Field(min_length=3, max_length=3)]


class Environment(EnvironmentSpec):
    """wind, current (uniform [east, north] m/s or a field), depth: sea_environment.environment
    (its docstring has the format); water density and gravity for every node."""
    water_density: float = Field(1025.0, gt=900.0, lt=1100.0)
    gravity: float = Field(9.80665, gt=9.0, lt=10.5)

    @property
    def is_uniform(self) -> bool:
        """Only a uniform current: the nodes' current_east / current_north carry it all."""
        return (self.wind is None and self.depth is None and isinstance(self.current, list)
                and (self.waves is None or self.waves.hs == 0.0))   # hs 0: a calm sea, as without waves


def _number(value, key: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ValueError(f"{key}: expected a finite number, got {value!r}")
    return float(value)


class InitialState(_Strict):
    """Also accepted where a person types them (converted here, before anything else sees them):
    heading_true_deg (compass, deg true, clockwise from north) for heading_deg, speed_kn for
    speed, and latitude / longitude (WGS-84 deg, converted with the scenario's origin in
    Scenario) for x / y."""
    x: Coord = 0.0  # m east
    y: Coord = 0.0  # m north
    heading_deg: float = Field(0.0, ge=-360.0, le=360.0)  # 0 = bow east, counter-clockwise positive (REP-103)
    speed: float = _within(_V["initial_speed"], 0.0)  # m/s surge
    # Orders held from the start with the engine and rudder already there (e.g. "turn from
    # 9 kn at half ahead"); 0 keeps the model's own start.
    engine_order: float = _within(_V["initial_engine_order"], 0.0)
    steering_deg: float = Field(0.0, ge=-90.0, le=90.0)

    @model_validator(mode="before")
    @classmethod
    def _human_units(cls, data):
        if not isinstance(data, dict):
            return data
        data = dict(data)
        for human, si, convert in (("heading_true_deg", "heading_deg", lambda h: 90.0 - h),
                                   ("speed_kn", "speed", lambda kn: kn * KNOT)):
            if human in data:
                if si in data:
                    raise ValueError(f"give {si} or {human}, not both")
                value = _number(data.pop(human), human)
                if human == "heading_true_deg" and not 0.0 <= value <= 360.0:
                    raise ValueError(f"heading_true_deg: expected 0-360 deg true, got {value!r}")
                data[si] = convert(value)
        return data


class Motion(_Strict):
    """Prescribed motion of a tug, in the initial frame (x along initial.heading_deg): the tug tracks
    of section 4 of Yoon, Lee, Park, Kim, "Dynamic Modeling and Simulation of a Towing Rope using
    Multiple Finite Element Method". The vessel starts as the law says at t = 0 (start())."""
    type: Literal["constant_speed", "sinusoidal_sway", "acceleration", "turn"]
    speed: float = _within(_V["motion_speed"])  # m/s, U or U_max
    amplitude: float = _within(_V["motion_amplitude"], 0.0)  # m
    period: float = _within(_V["motion_period"], 0.0)  # s
    acceleration: float = _within(_V["motion_acceleration"], 0.0)  # m/s^2
    heading: Literal["track", "fixed"] = "track"
    turn_rate_deg: float = _deg_within(_V["motion_turn_rate"])  # deg/s, positive to port
    turn_start: float = _within(_V["motion_turn_start"], 0.0)  # s
    turn_duration: float = _within(_V["motion_turn_duration"], 0.0)  # s

    @model_validator(mode="after")
    def _complete(self):
        if self.type == "turn" and (self.turn_rate_deg == 0 or self.turn_duration <= 0):
            raise ValueError("turn needs a non-zero turn_rate_deg and a positive turn_duration")
        if self.type == "sinusoidal_sway" and self.period <= 0:
            raise ValueError("sinusoidal_sway needs a positive period")
        if self.type == "acceleration" and self.acceleration <= 0:
            raise ValueError("acceleration needs a positive acceleration")
        return self

    def start(self):
        """(surge speed m/s, heading relative to the track's x axis rad) of the law at t = 0, from
        the law itself (tug_dynamics.prescribed): e.g. the seed 000 sway (2 kn, 10 m, 50 s) starts
        at 1.624 m/s, 50.7 deg off its mean course (atan2(A 2 pi / T, U))."""
        from tug_dynamics.prescribed import MotionLaw
        law = MotionLaw(self.type, speed=self.speed, amplitude=self.amplitude, period=self.period,
                        acceleration=self.acceleration, heading=self.heading,
                        turn_rate=math.radians(self.turn_rate_deg), turn_start=self.turn_start,
                        turn_duration=self.turn_duration)
        _, (vx, vy), _ = law.track(0.0)
        if self.heading == "track" and math.hypot(vx, vy) > 1e-9:
            return math.hypot(vx, vy), math.atan2(vy, vx)
        return vx, 0.0


class VesselSpec(_Strict):
    name: str = Field(pattern=r"^[A-Za-z][A-Za-z0-9_]*$")
    ship_file: str
    initial: InitialState = InitialState()
    motion: Optional[Motion] = None
    # Merged over the ship file (e.g. {towline_simple: {enabled: true, gamma_max_deg: 20}}).
    ship_overrides: Optional[Dict[str, Any]] = None
    # true: a person (console, instructor page, send_command) or an outside controller gives every
    # order; the script gives this vessel none (an event for it is refused). docs/scenarios.md
    manned: bool = False


class RopeSpec(_Strict):
    name: str = Field(pattern=r"^[A-Za-z][A-Za-z0-9_]*$")
    rope_file: str = "table1.yaml"
    end_a: str
    end_b: str
    end_a_position: Optional[Point3] = None
    end_b_position: Optional[Point3] = None
    layout: Literal["straight", "slack", "winch"] = "straight"
    # true: the rope node settles the laid-out rope to static equilibrium for the ends' positions and
    # velocities at t = 0 before step 0 (RopeChain.settle), so the run starts without a spurious load
    equilibrium: bool = False
    deployed_length: Optional[float] = Field(None, gt=0.0, le=_R["deployed_length"].hi)  # also <= the rope file's
    # layout straight only: lay the whole rope straight even though its ends start closer than its
    # length (the slack then lies folded along the chord); without it such a layout is refused
    allow_slack: bool = False
    n_elements: Optional[int] = Field(None, ge=1, le=_R["n_elements"].hi)  # None: the rope file's


class ContactSpec(_Strict):
    """A tug's fender against another vessel's hull (hull_contact: spring-dashpot with friction
    against the hull's waterline outline from its ship file). Defaults and ranges: the contact
    node's (sim_contract.node_params.CONTACT_NODE)."""
    name: str = Field(pattern=r"^[A-Za-z][A-Za-z0-9_]*$")
    fender: str      # "<vessel>/<attachment>": the pushing vessel and its fender point
    hull: str        # the vessel pushed on
    radius: float = _within(_C["radius"], _C["radius"].default)           # m, fender thickness
    stiffness: float = _within(_C["stiffness"], _C["stiffness"].default)  # N/m
    damping: float = _within(_C["damping"], _C["damping"].default)        # N s/m
    friction: float = _within(_C["friction"], _C["friction"].default)


class InteractionSpec(_Strict):
    """Between two vessels, the `loads` named: "wang", Wang's (1975) passing-ship loads on each
    from the other (tug_dynamics.hull_interaction); "wash", the first vessel's propeller or
    azimuth-thruster jets on the second's hull side (tug_dynamics.propeller_wash: still water,
    the second's side a flat box side). Or with a `bank` the image-method bank suction on one
    vessel (tug_dynamics.bank_effect; a sloped bank as the vertical wall of the same d2b). Computed every step from the odometry (and the wash
    source's thrust) by the run's one hull_contact interaction_node (all the entries together,
    each vessel's loads summed); deep water, or the environment's depth when it is one number."""
    between: List[str] = Field(min_length=1, max_length=2)   # the two vessels, or one with a bank
    name: Optional[str] = Field(None, pattern=r"^[A-Za-z][A-Za-z0-9_]*$")   # default <a>_<b>_interaction
    # a bank (image method, tug_dynamics.bank_effect): polyline points [x, y] (m, world), water on the left;
    # or "depth": the banks and channel edges of the environment's depth grid, across the ship every step
    bank: Optional[Union[Literal["depth"], List[List[float]]]] = None
    # the bank's underwater slope, m across per m down from the line (its waterline) to the depth; 0: a vertical
    # wall. A slope acts as the vertical wall of the same d2b (Lataire, Vantorre & Eloot 2009)
    bank_slope: float = Field(0.0, ge=0.0, le=100.0)
    # two vessels: "wang" (each on the other), "wash" (the first's jets on the second's side), or both
    loads: List[Literal["wang", "wash"]] = Field(default_factory=lambda: ["wang"], min_length=1, max_length=2)
    # the wash's impingement coefficient C_w (tug_dynamics.propeller_wash): 1 the ideal plate (an upper bound)
    wash_impingement: float = Field(1.0, ge=0.0, le=1.0)

    @property
    def entry_name(self) -> str:
        """The name its events carry (`interaction_off` / `interaction_on`)."""
        return self.name or ("_".join(self.between) + ("_bank" if self.bank else "_interaction"))

    @property
    def felt_by(self) -> List[str]:
        """The vessels it puts a load on."""
        if self.bank or "wang" in self.loads:
            return list(self.between)
        return self.between[1:]


class Trigger(_Strict):
    """A vessel's state that fires an event (IMO trials: "when the heading has changed by 10 deg,
    put the rudder over"). Evaluated on the state at the start of each step (the step's
    odometry); exactly one condition:
      heading_change_deg: the heading (yaw, + to port) has changed by this much (signed) since
        the time `since` (s, default 0): + port / counter-clockwise, - starboard;
      speed_below / speed_above: speed over ground below / above this, m/s;
      surge_below: headway u (body x over ground) below this, m/s (a crash stop: 0.0)."""
    vessel: str
    heading_change_deg: Optional[float] = Field(None, ge=-3600.0, le=3600.0)
    since: float = Field(0.0, ge=0.0)
    speed_below: Optional[float] = Field(None, ge=0.0, le=40.0)
    speed_above: Optional[float] = Field(None, ge=0.0, le=40.0)
    surge_below: Optional[float] = Field(None, ge=-40.0, le=40.0)

    @model_validator(mode="after")
    def _one_condition(self):
        given = [k for k in CONDITIONS if getattr(self, k) is not None]
        if len(given) != 1:
            raise ValueError(f"a trigger gives exactly one of {', '.join(CONDITIONS)}; got "
                             f"{', '.join(given) if given else 'none'}")
        if self.heading_change_deg == 0.0:
            raise ValueError("heading_change_deg 0 would fire at once: give the change (+ port, - starboard)")
        if "since" in self.model_fields_set and self.heading_change_deg is None:
            raise ValueError("since is the reference time of heading_change_deg only")
        return self

    def describe(self) -> str:
        if self.heading_change_deg is not None:
            return f"{self.vessel} heading changed {self.heading_change_deg:+g} deg since {self.since:g} s"
        key = next(k for k in CONDITIONS if getattr(self, k) is not None)
        return f"{self.vessel} {key.replace('_', ' ')} {getattr(self, key):g} m/s"


CONDITIONS = ("heading_change_deg", "speed_below", "speed_above", "surge_below")


class Event(_Strict):
    time: Optional[float] = Field(None, ge=0.0)  # s; or `when` (a Trigger), not both
    when: Optional[Trigger] = None
    vessel: Optional[str] = None
    rope: Optional[str] = None
    engine_order: Optional[float] = Field(None, ge=-1.0, le=1.0)
    steering_deg: Optional[float] = Field(None, ge=-90.0, le=90.0)
    anchor: Optional[Literal["let_go", "heave_up"]] = None
    payout_rate: Optional[float] = Field(None, ge=-10.0, le=10.0)  # m/s; winches run below 2 m/s

    @model_validator(mode="after")
    def _one_target(self):
        if (self.time is None) == (self.when is None):
            raise ValueError("an event gives exactly one of 'time' (s) or 'when' (a state trigger)")
        if (self.vessel is None) == (self.rope is None):
            raise ValueError("an event names exactly one of 'vessel' or 'rope'")
        vessel_keys = [self.engine_order, self.steering_deg, self.anchor]
        if self.vessel is not None and (self.payout_rate is not None or all(v is None for v in vessel_keys)):
            raise ValueError("a vessel event gives engine_order, steering_deg and/or anchor (not payout_rate)")
        if self.rope is not None and (self.payout_rate is None or any(v is not None for v in vessel_keys)):
            raise ValueError("a rope event gives payout_rate only")
        return self


class AutopilotSpec(_Strict):
    """An outside controller as a lockstep participant (scenario_runner autopilot, or another
    executable speaking the step protocol): it reads the vessel's state of step k and sends
    the command the vessel applies from step k+1."""
    name: str = Field(pattern=r"^[A-Za-z][A-Za-z0-9_]*$")  # ROS namespace of the controller
    vessel: str
    # a package and an executable name, never a path (looked up in lib/<package>/ like `ros2 run`)
    package: str = Field("scenario_runner", pattern=r"^[A-Za-z0-9_]+$")
    executable: str = Field("autopilot", pattern=r"^[A-Za-z0-9_.-]+$")
    params: Dict[str, Any] = Field(default_factory=dict)  # ROS parameters of the controller


class GeoOrigin(_Strict):
    """WGS-84 position of the map origin (x = y = 0) and ellipsoid height of the water there.
    Default: the Port of Rotterdam, in the Maasmond (sim_contract.geo.DEFAULT_ORIGIN)."""
    latitude: float = Field(DEFAULT_ORIGIN.latitude, ge=-85.0, le=85.0)  # deg north
    longitude: float = Field(DEFAULT_ORIGIN.longitude, ge=-180.0, le=180.0)  # deg east
    height: float = Field(DEFAULT_ORIGIN.height, ge=-1e3, le=1e4)  # m


class NmeaOutput(_Strict):
    vessel: str  # the own vessel whose bridge this destination is
    host: str = Field("127.0.0.1", min_length=1, max_length=253)  # checked by the node: reported, not fatal
    port: int = Field(NMEA_UDP_PORT, ge=1, le=65535)


class NmeaSpec(_Strict):
    """Starts `bridge_instruments nmea_out` beside the run: NMEA 0183 of each output's vessel and
    AIS of every other vessel over UDP (README, "Bridge instruments")."""
    outputs: List[NmeaOutput] = Field(min_length=1)
    rate: float = _within(NMEA_OUT["rate"], NMEA_OUT["rate"].default)  # Hz of simulation time
    utc_start: str = DEFAULT_UTC_START  # UTC of t = 0 (ISO 8601, whole hundredths of a second)
    static_every: int = _within(NMEA_OUT["static_every"], NMEA_OUT["static_every"].default)  # AIS type 5 every n-th
    mmsi: Dict[str, int] = Field(default_factory=dict)  # vessel -> MMSI (default 244990001, 244990002, ...)
    gear_ratios: Dict[str, Annotated[float, Field(gt=0.0, le=100.0)]] = Field(default_factory=dict)  # engine/shaft rpm


class Recording(_Strict):
    enabled: bool = True
    path: Optional[str] = None  # default: output/<scenario name>.mcap; the command line wins


class Scenario(_Strict):
    name: str = Field(pattern=r"^[A-Za-z0-9_][A-Za-z0-9_.-]*$", max_length=100)  # names output files: no paths
    description: str = ""
    duration: float = Field(gt=0.0, le=1e7)  # s (1e7 s: 115 days)
    exchange_rate: float = Field(50.0, ge=1.0, le=1000.0)
    mode: Literal["lockstep", "realtime"] = "lockstep"
    environment: Environment = Environment()
    vessels: List[VesselSpec] = Field(default_factory=list)
    ropes: List[RopeSpec] = Field(default_factory=list)
    contacts: List[ContactSpec] = Field(default_factory=list)
    interactions: List[InteractionSpec] = Field(default_factory=list)
    autopilots: List[AutopilotSpec] = Field(default_factory=list)
    events: List[Event] = Field(default_factory=list)
    recording: Recording = Recording()
    origin: GeoOrigin = GeoOrigin()
    nmea: Optional[NmeaSpec] = None
    _path: str = PrivateAttr("")   # the file it was read from (load_scenario), for relative paths
    _warnings: List[str] = PrivateAttr(default_factory=list)   # what the run should say before it starts

    @property
    def warnings(self) -> List[str]:
        """Things the checks let through but a user should hear before the run (e.g. an exchange
        rate close to what a rope's stiffness allows)."""
        return list(self._warnings)

    @model_validator(mode="before")
    @classmethod
    def _geographic_positions(cls, data):
        """vessels[].initial.latitude / longitude -> x / y (ENU metres about `origin`, pymap3d)."""
        if not isinstance(data, dict) or not isinstance(data.get("vessels"), list):
            return data
        origin = data.get("origin", {})
        origin = GeoOrigin.model_validate(origin) if isinstance(origin, dict) else GeoOrigin()
        vessels = []
        for i, v in enumerate(data["vessels"]):
            init = v.get("initial") if isinstance(v, dict) else None
            if isinstance(init, dict) and ("latitude" in init or "longitude" in init):
                key = f"vessels[{i}].initial"
                if "latitude" not in init or "longitude" not in init:
                    raise ValueError(f"{key}: give both latitude and longitude")
                if "x" in init or "y" in init:
                    raise ValueError(f"{key}: give x / y or latitude / longitude, not both")
                init = dict(init)
                lat, lon = _number(init.pop("latitude"), f"{key}.latitude"), _number(init.pop("longitude"),
                                                                                    f"{key}.longitude")
                if not (-85.0 <= lat <= 85.0 and -180.0 <= lon <= 180.0):
                    raise ValueError(f"{key}: latitude {lat!r} / longitude {lon!r} out of range")
                from sim_contract.geo import Origin, geodetic_to_enu
                init["x"], init["y"], _ = geodetic_to_enu(lat, lon, Origin(*origin.model_dump().values()))
                v = dict(v, initial=init)
            vessels.append(v)
        return dict(data, vessels=vessels)

    @field_validator("exchange_rate")
    @classmethod
    def _integer_period(cls, v: float) -> float:
        ns = 1e9 / v
        if abs(ns - round(ns)) > 1e-6:
            raise ValueError(f"{v} Hz gives a period of {ns} ns; choose a rate whose period is whole nanoseconds")
        return v

    @property
    def steps(self) -> int:
        return int(round(self.duration * self.exchange_rate))


def _key_path(loc) -> str:
    out = ""
    for part in loc:
        if isinstance(part, str) and _UNION_BRANCH.search(part):
            continue   # pydantic's name of a Union member (list[...], constrained-float, CurrentFieldSpec)
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out += ("." if out else "") + str(part)
    return out


_UNION_BRANCH = re.compile(r"\[|^constrained-|^function-|^[A-Z][A-Za-z0-9]*Spec$|^float$|^int$")


def _explain(err: dict) -> str:
    if err["type"] == "extra_forbidden":
        return f"unknown key (misspelt?), value {err['input']!r}"
    if err["type"] == "missing":
        return "required key is missing"
    return f"{err['msg']}, got {err['input']!r}"


def load_scenario(path: str, check_files: bool = True) -> Scenario:
    """Read and validate a scenario; with check_files also load every ship and rope file, check
    the rope lengths and ends against them, and find every autopilot executable. Everything a
    node would refuse at start-up is refused here, as ScenarioError naming file, key and value."""
    if not os.path.isfile(path):
        raise ScenarioError(f"scenario file '{path}' not found")
    try:
        data = load_yaml(path)  # duplicate keys are errors; messages carry the line
    except YamlInputError as exc:
        raise ScenarioError(f"{path}: {exc}") from None
    if not isinstance(data, dict):
        raise ScenarioError(f"{path}: expected a mapping of scenario keys at the top level, got {type(data).__name__}")
    try:
        sc = Scenario.model_validate(data)
    except ValidationError as exc:
        lines = [f"{path}: key '{_key_path(e['loc']) or '(top)'}': {_explain(e)}" for e in exc.errors()]
        raise ScenarioError("\n".join(lines)) from None
    sc._path = os.path.abspath(path)
    _check_references(path, sc)
    if check_files:
        _check_files(path, sc)
    return sc


_RUNNER_PARAMS = ("vessel", "exchange_rate", "lockstep", "use_sim_time")  # scenario_runner.run_nodes.node_specs sets these


def _check_runner_params(path: str, i: int, a: AutopilotSpec) -> None:
    """A controller's parameters that the runner sets from the scenario. (The example
    autopilot's own parameters are checked by its table: scenario_runner.autopilot_law.)"""
    for name in a.params:
        if name in _RUNNER_PARAMS:
            raise ScenarioError(f"{path}: key 'autopilots[{i}].params.{name}': set by the runner (from the "
                                "scenario), not a parameter to give")


def _check_references(path: str, sc: Scenario) -> None:
    """Names unique, and every name a key refers to defined (the order of the checks is the order
    of the messages a scenario with several faults gets: the first)."""
    vessels = [v.name for v in sc.vessels]
    _check_names(path, sc, vessels)
    _check_contacts(path, sc, vessels)
    _check_interaction_names(path, sc, vessels)
    _check_rope_ends(path, sc, vessels)
    _check_prescribed_starts(path, sc)
    driven = _check_autopilots(path, sc, vessels)
    if sc.nmea is not None:
        _check_nmea(path, sc.nmea, vessels, sc.duration)
    if sc.steps < 1:
        raise ScenarioError(f"{path}: key 'duration': {sc.duration} s is less than one step at "
                            f"{sc.exchange_rate:g} Hz (exchange_rate)")
    for i, r in enumerate(sc.ropes):
        if r.deployed_length is not None and r.layout == "straight":
            # the node ignores it: a straight rope is laid with the rope file's length
            raise ScenarioError(f"{path}: key 'ropes[{i}].deployed_length': only for layout slack or winch "
                                f"(layout is straight: the rope file's length is laid out)")
        if r.allow_slack and r.layout != "straight":
            raise ScenarioError(f"{path}: key 'ropes[{i}].allow_slack': only for layout straight (layout "
                                f"{r.layout} lays its slack out itself)")
    _check_events(path, sc, vessels, driven)


def _check_names(path: str, sc: Scenario, vessels: List[str]) -> None:
    """Vessels, ropes, contacts and autopilots are ROS namespaces: each name once."""
    ropes = [r.name for r in sc.ropes]
    for kind, names in (("vessels", vessels), ("ropes", ropes)):
        dup = {n for n in names if names.count(n) > 1}
        if dup:
            raise ScenarioError(f"{path}: key '{kind}': duplicate name(s) {sorted(dup)}")
    pilots = [a.name for a in sc.autopilots]
    if len(set(pilots)) != len(pilots):
        raise ScenarioError(f"{path}: key 'autopilots': duplicate name(s)")
    contacts = [c.name for c in sc.contacts] + [i.entry_name for i in sc.interactions]
    groups = [set(vessels), set(ropes), set(pilots), set(contacts)]
    if sc.interactions:       # the interaction node's namespace (sim_contract.topics.INTERACTIONS)
        taken = sorted(n for g in groups[:3] + [{c.name for c in sc.contacts}] for n in g if n == "interactions")
        if taken:
            raise ScenarioError(f"{path}: name 'interactions' is the interaction node's namespace in a run with "
                                "'interactions': rename that vessel, rope, contact or autopilot")
    clash = {n for i, a in enumerate(groups) for b in groups[i + 1:] for n in a & b}
    if clash or len(set(contacts)) != len(contacts):
        raise ScenarioError(f"{path}: names {sorted(clash or {n for n in contacts if contacts.count(n) > 1})} are "
                            "used twice among vessels, ropes, contacts and autopilots (namespaces must differ)")


def _check_interaction_names(path: str, sc: Scenario, vessels: List[str]) -> None:
    for i, pair in enumerate(sc.interactions):
        for vessel in pair.between:
            if vessel not in vessels:
                raise ScenarioError(f"{path}: key 'interactions[{i}].between': vessel '{vessel}' is not in 'vessels' "
                                    f"({vessels})")
        if bool(pair.bank) != (len(pair.between) == 1):
            raise ScenarioError(f"{path}: key 'interactions[{i}].between': {pair.between} with "
                                f"{'a bank' if pair.bank else 'no bank'}: two vessels, or one vessel and a 'bank'")
        if "bank_slope" in pair.model_fields_set and (not pair.bank or pair.bank == "depth"):
            raise ScenarioError(f"{path}: key 'interactions[{i}].bank_slope': only with a 'bank' line (a depth "
                                "grid has its own slopes)")
        if pair.bank == "depth" and not isinstance(sc.environment.depth, DepthGridSpec):
            raise ScenarioError(f"{path}: key 'interactions[{i}].bank': 'depth' takes the banks of the environment's "
                                "depth grid, and 'environment.depth' is not a grid")
        if pair.bank:
            if pair.loads != ["wang"] and "loads" in pair.model_fields_set:
                raise ScenarioError(f"{path}: key 'interactions[{i}].loads': a bank has no loads to choose "
                                    "(its suction only)")
            continue
        if "wash_impingement" in pair.model_fields_set and "wash" not in pair.loads:
            raise ScenarioError(f"{path}: key 'interactions[{i}].wash_impingement': only with 'wash' in its loads")
        if len(set(pair.loads)) != len(pair.loads):
            raise ScenarioError(f"{path}: key 'interactions[{i}].loads': {pair.loads} names one twice")
        if pair.between[0] == pair.between[1]:
            raise ScenarioError(f"{path}: key 'interactions[{i}].between': '{pair.between[0]}' twice (a pair of two "
                                "vessels)")


def _check_contacts(path: str, sc: Scenario, vessels: List[str]) -> None:
    for i, c in enumerate(sc.contacts):
        parts = c.fender.split("/")
        if len(parts) != 2 or not all(parts):
            raise ScenarioError(f"{path}: key 'contacts[{i}].fender': expected '<vessel>/<attachment>', got {c.fender!r}")
        for key, vessel in (("fender", parts[0]), ("hull", c.hull)):
            if vessel not in vessels:
                raise ScenarioError(f"{path}: key 'contacts[{i}].{key}': vessel '{vessel}' is not in 'vessels' ({vessels})")
        if parts[0] == c.hull:
            raise ScenarioError(f"{path}: key 'contacts[{i}].hull': '{c.hull}' carries the fender itself")


def _check_rope_ends(path: str, sc: Scenario, vessels: List[str]) -> None:
    for i, r in enumerate(sc.ropes):
        for end in ("a", "b"):
            spec = getattr(r, f"end_{end}")
            key = f"ropes[{i}].end_{end}"
            if spec in ("fixed", "free"):
                if getattr(r, f"end_{end}_position") is None:
                    raise ScenarioError(f"{path}: key 'ropes[{i}].end_{end}_position': required for a {spec} end")
                continue
            parts = spec.split("/")
            if len(parts) != 2 or not all(parts):
                raise ScenarioError(f"{path}: key '{key}': expected '<vessel>/<attachment>', 'fixed' or 'free', "
                                    f"got {spec!r}")
            if parts[0] not in vessels:
                raise ScenarioError(f"{path}: key '{key}': vessel '{parts[0]}' is not in 'vessels' ({vessels})")
        if r.layout == "winch" and r.end_a == "free":
            raise ScenarioError(f"{path}: key 'ropes[{i}].layout': a winch layout needs end a attached")


def _check_prescribed_starts(path: str, sc: Scenario) -> None:
    """A prescribed vessel starts as its law says: an initial speed that says otherwise is refused.
    It takes no orders, so it cannot be manned."""
    for i, v in enumerate(sc.vessels):
        if v.motion is not None and v.manned:
            raise ScenarioError(f"{path}: key 'vessels[{i}].manned': '{v.name}' follows a prescribed motion "
                                f"({v.motion.type}) and takes no orders")
        if v.motion is not None and "speed" in v.initial.model_fields_set:
            surge = v.motion.start()[0]
            if abs(v.initial.speed - surge) > 1e-3:
                raise ScenarioError(f"{path}: key 'vessels[{i}].initial.speed': {v.initial.speed:g} m/s contradicts "
                                    f"the prescribed motion ({v.motion.type}), which starts at {surge:.4f} m/s; "
                                    f"give {surge:.4f} or leave the key out")


def _check_autopilots(path: str, sc: Scenario, vessels: List[str]) -> Dict[str, str]:
    """{vessel: its autopilot}: one autopilot a vessel at most."""
    driven: Dict[str, str] = {}
    for i, a in enumerate(sc.autopilots):
        if a.vessel not in vessels:
            raise ScenarioError(f"{path}: key 'autopilots[{i}].vessel': '{a.vessel}' is not in 'vessels' ({vessels})")
        if a.vessel in driven:
            raise ScenarioError(f"{path}: key 'autopilots[{i}].vessel': '{a.vessel}' already has an autopilot")
        if any(v.manned for v in sc.vessels if v.name == a.vessel):
            raise ScenarioError(f"{path}: key 'autopilots[{i}].vessel': '{a.vessel}' is manned (vessels[].manned: "
                                "true): its orders come from outside the scenario, not from a scenario autopilot")
        driven[a.vessel] = a.name
        _check_runner_params(path, i, a)
    return driven


def _check_nmea(path: str, nmea: "NmeaSpec", vessels: List[str], duration: float) -> None:
    for i, o in enumerate(nmea.outputs):
        if o.vessel not in vessels:
            raise ScenarioError(f"{path}: key 'nmea.outputs[{i}].vessel': '{o.vessel}' is not in 'vessels' "
                                f"({vessels})")
    for key, table in (("mmsi", nmea.mmsi), ("gear_ratios", nmea.gear_ratios)):
        for name in table:
            if name not in vessels:
                raise ScenarioError(f"{path}: key 'nmea.{key}.{name}': '{name}' is not in 'vessels' ({vessels})")
    for name, m in nmea.mmsi.items():
        if check_mmsi(m):
            raise ScenarioError(f"{path}: key 'nmea.mmsi.{name}': {check_mmsi(m)}")
    if len(set(nmea.mmsi.values())) != len(nmea.mmsi):
        raise ScenarioError(f"{path}: key 'nmea.mmsi': two vessels with one MMSI")
    try:
        start = parse_utc(nmea.utc_start)
    except ValueError as exc:
        raise ScenarioError(f"{path}: key 'nmea.utc_start': expected an ISO 8601 UTC time such as "
                            f"2026-06-01T08:00:00Z: {exc}") from None
    try:  # every sentence's time, utc_start + t, must be a date
        start + _dt.timedelta(seconds=duration)
    except OverflowError:
        raise ScenarioError(f"{path}: key 'nmea.utc_start': {nmea.utc_start!r} plus the run's {duration:g} s is "
                            f"past the year 9999") from None


def _check_events(path: str, sc: Scenario, vessels: List[str], driven: Dict[str, str]) -> None:
    ropes = [r.name for r in sc.ropes]
    for i, ev in enumerate(sc.events):
        if ev.vessel is not None and ev.vessel not in vessels:
            raise ScenarioError(f"{path}: key 'events[{i}].vessel': '{ev.vessel}' is not in 'vessels' ({vessels})")
        if ev.vessel in driven:
            raise ScenarioError(f"{path}: key 'events[{i}].vessel': '{ev.vessel}' is steered by autopilot "
                                f"'{driven[ev.vessel]}'; give its orders as the autopilot's params")
        manned = next((j for j, v in enumerate(sc.vessels) if v.name == ev.vessel and v.manned), None)
        if manned is not None:
            raise ScenarioError(f"{path}: key 'events[{i}].vessel': '{ev.vessel}' is manned "
                                f"(vessels[{manned}].manned: true): the script gives it no orders; remove the event "
                                f"or the key 'vessels[{manned}].manned'")
        prescribed = next((v for v in sc.vessels if v.name == ev.vessel and v.motion is not None), None)
        if prescribed is not None:
            raise ScenarioError(f"{path}: key 'events[{i}].vessel': '{ev.vessel}' follows a prescribed motion "
                                f"({prescribed.motion.type}): orders would have no effect")
        if ev.rope is not None:
            if ev.rope not in ropes:
                raise ScenarioError(f"{path}: key 'events[{i}].rope': '{ev.rope}' is not in 'ropes' ({ropes})")
            if next(r for r in sc.ropes if r.name == ev.rope).layout != "winch":
                raise ScenarioError(f"{path}: key 'events[{i}].payout_rate': rope '{ev.rope}' has no winch "
                                    "(layout: winch)")
        if ev.time is not None and ev.time > sc.duration:
            raise ScenarioError(f"{path}: key 'events[{i}].time': {ev.time} s is after the end ({sc.duration} s)")
        if ev.when is not None:
            if ev.when.vessel not in vessels:
                raise ScenarioError(f"{path}: key 'events[{i}].when.vessel': '{ev.when.vessel}' is not in 'vessels' "
                                    f"({vessels})")
            if ev.when.since > sc.duration:
                raise ScenarioError(f"{path}: key 'events[{i}].when.since': {ev.when.since} s is after the end "
                                    f"({sc.duration} s)")


def resolve(package: str, subdir: str, name: str, scenario_path: str) -> str:
    """A data file named in a scenario: relative to the scenario file, else in the package's data."""
    return data_files.resolve(package, subdir, name, relative_to=scenario_path)


def installed_executable(package: str, executable: str) -> Optional[str]:
    """Where `ros2 run package executable` finds it: lib/<package>/<executable> under the first
    prefix of AMENT_PREFIX_PATH that has it; None if none does."""
    for prefix in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep):
        cand = os.path.join(prefix, "lib", package, executable)
        if prefix and os.access(cand, os.X_OK):
            return cand
    return None


def _load_error(exc: Exception) -> str:
    # loaders' own errors already name their file and key; anything else gets its type named
    if isinstance(exc, (ValueError, FileNotFoundError)):
        return str(exc)
    return f"{type(exc).__name__}: {exc}"


def _end_point(path: str, sc: Scenario, r: RopeSpec, end: str, points: Dict[str, Dict[str, Any]]):
    """World position of a rope end at the start (vessel initial pose + attachment), or None."""
    spec = getattr(r, f"end_{end}")
    if "/" not in spec:
        return getattr(r, f"end_{end}_position")
    vessel, point = spec.split("/")
    v = next(v for v in sc.vessels if v.name == vessel)
    ax, ay, az = points[vessel][point]
    yaw = heading_rad(v) + (v.motion.start()[1] if v.motion is not None else 0.0)
    c, s = math.cos(yaw), math.sin(yaw)
    return [v.initial.x + c * ax - s * ay, v.initial.y + s * ax + c * ay, az]


def _check_files(path: str, sc: Scenario) -> None:
    from rope_model.models import MODELS, load_params as load_rope_params
    from tug_dynamics.ship_file import load_ship
    from tug_dynamics.seakeeping import waves_refused
    waves = sc.environment.waves
    points: Dict[str, Dict[str, Any]] = {}
    models: Dict[str, Any] = {}
    for i, v in enumerate(sc.vessels):
        key = f"vessels[{i}].ship_file"
        ship = resolve("tug_dynamics", "ships", v.ship_file, path)
        if not os.path.isfile(ship):
            raise ScenarioError(f"{path}: key '{key}': ship file '{v.ship_file}' not found (looked for {ship})")
        try:
            models[v.name] = load_ship(ship, name=v.name, overrides=v.ship_overrides)
            points[v.name] = {k: [float(c) for c in p] for k, p in models[v.name].attachments.items()}
        except Exception as exc:  # noqa: BLE001 - whatever stops the vessel node stops the run here
            what = "ship file (with ship_overrides)" if v.ship_overrides else "ship file"
            raise ScenarioError(f"{path}: key '{key}': {what} '{v.ship_file}' is not usable:\n"
                                f"  {_load_error(exc)}") from None
        refused = waves_refused(models[v.name], ship) if waves is not None and waves.hs > 0.0 else ""
        if refused:
            raise ScenarioError(f"{path}: key 'environment.waves': vessel '{v.name}' ({key} '{v.ship_file}') cannot "
                                f"take waves:\n  {refused}")
    for i, r in enumerate(sc.ropes):
        key = f"ropes[{i}]"
        rope = resolve("rope_model", "ropes", r.rope_file, path)
        if not os.path.isfile(rope):
            raise ScenarioError(f"{path}: key '{key}.rope_file': rope file '{r.rope_file}' not found "
                                f"(looked for {rope})")
        try:
            raw = load_yaml(rope)  # duplicate keys, and bad YAML with its line
            params = load_rope_params(rope)
        except Exception as exc:  # noqa: BLE001 - whatever stops the rope node stops the run here
            raise ScenarioError(f"{path}: key '{key}.rope_file': rope file '{r.rope_file}' is not usable:\n"
                                f"  {_load_error(exc) if not isinstance(exc, YamlInputError) else f'{rope}: {exc}'}"
                                ) from None
        if not raw:  # the loader would take every default: surely not what was meant
            raise ScenarioError(f"{path}: key '{key}.rope_file': rope file '{r.rope_file}' is empty ({rope})")
        model = raw.get("model", MODELS[0]) if isinstance(raw, dict) else MODELS[0]
        length = float(params.length)
        for end in ("a", "b"):
            spec = getattr(r, f"end_{end}")
            if "/" in spec:
                vessel, point = spec.split("/")
                if point not in points[vessel]:
                    raise ScenarioError(f"{path}: key '{key}.end_{end}': vessel '{vessel}' has no attachment "
                                        f"'{point}' (it has {sorted(points[vessel])})")
        if r.deployed_length is not None and r.deployed_length > length:
            raise ScenarioError(f"{path}: key '{key}.deployed_length': {r.deployed_length:g} m is longer than "
                                f"the rope ({length:g} m in {r.rope_file})")
        if model == "fd_cable":
            # rope_model.models.CableAdapter: end a towed, end b hanging free, laid straight
            if r.end_a == "free" or r.end_b != "free":
                raise ScenarioError(f"{path}: key '{key}.end_b': an fd_cable rope ({r.rope_file}) has end a on a "
                                    f"vessel (or fixed) and end b 'free', got end_a {r.end_a!r}, end_b {r.end_b!r}")
            if r.layout != "straight":
                raise ScenarioError(f"{path}: key '{key}.layout': an fd_cable rope ({r.rope_file}) starts from its "
                                    f"steady state: use layout straight, got {r.layout!r}")
            if r.equilibrium:
                raise ScenarioError(f"{path}: key '{key}.equilibrium': an fd_cable rope ({r.rope_file}) starts "
                                    "from its steady tow already; the settle phase is for element-chain ropes")
            if r.n_elements is not None and r.n_elements < 3:
                raise ScenarioError(f"{path}: key '{key}.n_elements': an fd_cable rope needs at least 3 nodes, "
                                    f"got {r.n_elements}")
        elif r.layout == "straight":
            _check_straight_span(path, sc, i, r, params, points)
            pa, pb = _end_point(path, sc, r, "a", points), _end_point(path, sc, r, "b", points)
            if pa is not None and pb is not None and math.dist(pa, pb) < 1e-6:
                raise ScenarioError(f"{path}: key '{key}.end_b': both ends start at {[round(c, 3) for c in pa]}: "
                                    "a straight rope needs two distinct end points")
        if model != "fd_cable":
            _check_exchange_rate(path, sc, i, r, params, models)
    for i, c in enumerate(sc.contacts):
        _check_contact(path, sc, i, c)
    for i, pair in enumerate(sc.interactions):
        _check_interaction(path, sc, i, pair)
    depth = sc.environment.depth
    if isinstance(depth, DepthGridSpec):
        from sea_environment.bathymetry import DepthGrid
        try:
            DepthGrid.load(depth_grid_path(depth, path))
        except ValueError as exc:
            raise ScenarioError(f"{path}: key 'environment.depth.grid': {exc}") from None
    for i, a in enumerate(sc.autopilots):
        if installed_executable(a.package, a.executable) is None:
            raise ScenarioError(f"{path}: key 'autopilots[{i}].executable': {a.package}/{a.executable} not found on "
                                "AMENT_PREFIX_PATH (misspelt, or the workspace is not built / sourced?)")


def _check_exchange_rate(path: str, sc: Scenario, i: int, r: "RopeSpec", params, models: Dict[str, Any]) -> None:
    """The exchange period h against the stiffest vessel-rope mode, omega^2 = (EA / L) (lambda_a +
    lambda_b), lambda the largest horizontal mobility of each end's attachment (0: fixed, or a
    prescribed motion): refused above omega h = REFUSE_OMEGA_H, a warning above WARN_OMEGA_H
    (rope_model.end_coupling, where the bound comes from)."""
    from rope_model.end_coupling import REFUSE_OMEGA_H, WARN_OMEGA_H, exchange_omega
    mobility, masses = [], []
    for end in ("a", "b"):
        spec = getattr(r, f"end_{end}")
        if spec == "free":
            return                                  # no spring between two ends to resolve
        lam = 0.0
        if "/" in spec:
            vessel, point = spec.split("/")
            v = next(v for v in sc.vessels if v.name == vessel)
            if v.motion is None:
                lam = models[vessel].point_mobility(models[vessel].attachments[point])
            masses.append(f"{spec} (effective mass {1.0 / lam:,.0f} kg)" if lam > 0 else f"{spec} (prescribed)")
        else:
            masses.append("a fixed point")
        mobility.append(lam)
    length = float(r.deployed_length or params.length)
    omega = exchange_omega(params.ea, length, *mobility)
    h = 1.0 / float(sc.exchange_rate)
    if omega * h <= WARN_OMEGA_H:
        return
    what = (f"rope '{r.name}' ({r.rope_file}: EA/L = {params.ea / length:.3g} N/m on {length:g} m between "
            f"{masses[0]} and {masses[1]}) has its stiffest vessel-rope mode at omega = {omega:.3g} rad/s")
    if omega * h > REFUSE_OMEGA_H:
        raise ScenarioError(f"{path}: key 'exchange_rate': {sc.exchange_rate:g} Hz is too slow for {what}: the "
                            f"exchange needs omega h <= {REFUSE_OMEGA_H:g}, i.e. exchange_rate >= "
                            f"{math.ceil(omega / REFUSE_OMEGA_H * 10) / 10:g} Hz (omega h = {omega * h:.2f} now)")
    sc._warnings.append(f"exchange_rate {sc.exchange_rate:g} Hz: {what}, omega h = {omega * h:.2f}: the rope's "
                        f"tension and the recorded energy are off by about (omega h)^2 = {(omega * h) ** 2:.0%}; "
                        f"{math.ceil(omega / WARN_OMEGA_H * 10) / 10:g} Hz or more keeps it under "
                        f"{WARN_OMEGA_H ** 2:.0%}")


def _check_contact(path: str, sc: Scenario, i: int, c: ContactSpec) -> None:
    """The fender attachment exists, the fender does not start inside the hull outline, and the
    exchange can carry its stiffness and damping (_check_contact_exchange)."""
    import numpy as np
    from hull_contact.fender import FenderSpec, PlanarPose, contact_from_ship_files
    vessel_name, fender = c.fender.split("/")
    fv = next(v for v in sc.vessels if v.name == vessel_name)
    hv = next(v for v in sc.vessels if v.name == c.hull)
    try:
        contact, _ = contact_from_ship_files(
            FenderSpec(radius=c.radius, stiffness=c.stiffness, damping=c.damping, friction=c.friction),
            resolve("tug_dynamics", "ships", fv.ship_file, path), fender,
            resolve("tug_dynamics", "ships", hv.ship_file, path), fv.ship_overrides, hv.ship_overrides)
    except ValueError as exc:
        raise ScenarioError(f"{path}: key 'contacts[{i}].fender': {exc}") from None
    poses = [PlanarPose(v.initial.x, v.initial.y, heading_rad(v)) for v in (fv, hv)]
    start = contact.force(*poses)
    if start.penetration > c.radius:
        where = np.round(start.point_world, 1).tolist()
        raise ScenarioError(f"{path}: key 'contacts[{i}]': the fender point of {c.fender} starts inside the hull "
                            f"of '{c.hull}' ({start.penetration - c.radius:.2f} m in, near {where}): move the "
                            "vessels apart")
    _check_contact_exchange(path, sc, i, c, contact.mobility)


def interaction_depth(sc: Scenario) -> float:
    """The depth of the interactions' bottom images: the environment's when it is one number,
    else 0 (deep water; a depth grid is not sampled along the pair)."""
    depth = sc.environment.depth
    return float(depth) if isinstance(depth, (int, float)) and not isinstance(depth, bool) else 0.0


# the effective under-keel clearance (over the draft) below which model tests along banks measure
# repulsion, not suction, with the propeller idle: 15-20 % (Lataire, Vantorre & Eloot 2009, section 4.6)
BANK_REPULSION_CLEARANCE = 0.20


def _check_bank(path: str, sc: Scenario, i: int, pair: InteractionSpec) -> None:
    """The bank line is a polyline that does not cross itself (BankPolyline), and the vessel starts
    on its water side, clear of it by more than its half beam; a warning where the water is too
    shallow for the image method's sign (BANK_REPULSION_CLEARANCE)."""
    from tug_dynamics.bank_effect import BankPolyline
    from tug_dynamics.hull_interaction import SectionalAreaCurve
    from tug_dynamics.ship_file import ship_config
    key = f"{path}: key 'interactions[{i}].bank'"
    try:
        bank = BankPolyline(pair.bank)
    except ValueError as exc:
        raise ScenarioError(f"{key}: {exc}") from None
    v = next(v for v in sc.vessels if v.name == pair.between[0])
    try:
        cfg = ship_config(resolve("tug_dynamics", "ships", v.ship_file, path), v.ship_overrides or None)[1]
        hull = SectionalAreaCurve.from_ship_config(cfg)
    except ValueError as exc:
        raise ScenarioError(f"{path}: key 'interactions[{i}].between': {exc}") from None
    distance = bank.nearest(v.initial.x, v.initial.y)[0]
    land = not bank.water_side(v.initial.x, v.initial.y)
    if land or distance <= 0.5 * hull.beam:
        raise ScenarioError(f"{key}: {v.name} starts at ({v.initial.x:g}, {v.initial.y:g}) m, {distance:.3g} m "
                            f"from the bank line{' on its land side' if land else ''}: it must start on the water "
                            f"side (left of the line's direction), more than its half beam {0.5 * hull.beam:.3g} m off")
    depth, draft = interaction_depth(sc), float(cfg["hull"]["draft"])
    if depth > 0.0 and (depth - draft) / draft < BANK_REPULSION_CLEARANCE:
        # Lataire, Vantorre & Eloot (2009): below 15-20 % effective under-keel clearance the measured
        # sway force pushes a ship (propeller idle) away from the bank; the image method always attracts
        sc._warnings.append(
            f"{key}: {v.name} runs along the bank with an under-keel clearance of {100 * (depth - draft) / draft:.0f} % "
            f"of its draft ({depth:g} m of water, draft {draft:g} m): below {100 * BANK_REPULSION_CLEARANCE:.0f} % "
            "model tests measure the ship pushed away from a bank, while the image method used here draws it in "
            "at any depth; its sway force may have the wrong sign (docs/confined-water.md, Banks)")


def _check_interaction(path: str, sc: Scenario, i: int, pair: InteractionSpec) -> None:
    """Both hulls are slender displacement hulls (Wang's parabola from their ship files) and do not
    start inside each other (HullPair.check at the start positions, each seen from the other)."""
    from tug_dynamics.hull_interaction import pair_from_ship_configs
    from tug_dynamics.ship_file import ship_config
    if pair.bank == "depth":
        return     # the grid's banks, sampled across the ship in the run (its grounding: the vessel's)
    if pair.bank:
        _check_bank(path, sc, i, pair)
        return
    a, b = (next(v for v in sc.vessels if v.name == n) for n in pair.between)
    key = f"{path}: key 'interactions[{i}].between'"
    try:
        configs = [ship_config(resolve("tug_dynamics", "ships", v.ship_file, path), v.ship_overrides or None)[1]
                   for v in (a, b)]
        if "wash" in pair.loads:
            from tug_dynamics.interaction_set import propulsors_of
            try:
                propulsors_of(configs[0])
            except ValueError as exc:
                raise ScenarioError(f"{path}: key 'interactions[{i}].loads': wash of '{a.name}' "
                                    f"({a.ship_file}): {exc}") from None
        if "wang" not in pair.loads:
            return
        for own, other, cfgs in ((a, b, configs), (b, a, configs[::-1])):
            c, s = math.cos(heading_rad(own)), math.sin(heading_rad(own))
            dx, dy = other.initial.x - own.initial.x, other.initial.y - own.initial.y
            pair_from_ship_configs(*cfgs).check(c * dx + s * dy, -s * dx + c * dy, 0.0,
                                                interaction_depth(sc) or math.inf)
    except ValueError as exc:
        raise ScenarioError(f"{key}: {a.name} and {b.name} at their initial positions: {exc}") from None


def _round_in(value: float, up: bool) -> float:
    """value to 3 significant digits, rounded towards the allowed side (a limit quoted in a
    message must itself pass)."""
    if not (math.isfinite(value) and value > 0.0):
        return value
    scale = 10.0 ** (math.floor(math.log10(value)) - 2)
    return (math.ceil if up else math.floor)(value / scale) * scale


def _check_contact_exchange(path: str, sc: Scenario, i: int, c: ContactSpec, mobility: float) -> None:
    """The fender's spring and damper can be exchanged between the two vessel nodes at the
    scenario's rate (hull_contact.fender.exchange_limits, where the bound is derived: omega h <
    1/2 with omega^2 = k lam, and the damping inside the stable range for that stiffness, lam =
    1/m_fender + 1/m_hull the largest relative mobility at the contact). Beyond it the exchanged
    force pumps energy into the contact: the vessels are thrown apart or the run diverges."""
    from hull_contact.fender import exchange_limits, slowest_stable_rate
    h = 1.0 / sc.exchange_rate
    lim = exchange_limits(c.stiffness, c.damping, h, mobility)
    if lim["stable"]:
        return
    where = (f"the effective mass at the contact of {c.fender} on '{c.hull}' is {1.0 / mobility:.3g} kg "
             f"(1/m_fender + 1/m_hull at the fender point and the most mobile point of the hull's outline)")
    rate = f"{sc.exchange_rate:g} Hz (exchange_rate)"
    k_here = _round_in(lim["stiffness_here"], up=False)
    need = slowest_stable_rate(c.stiffness, c.damping, mobility)
    faster = (f"; or exchange_rate above {_round_in(need, up=True):g} Hz for these values" if need <= 1000.0 else
              f"; no exchange_rate up to 1000 Hz carries these values")
    if lim["omega_h"] >= 0.5:
        here = (f"with this damping ({c.damping:g} N s/m) the stiffness must be below {k_here:g} N/m, and "
                if k_here > 0 else "")
        raise ScenarioError(
            f"{path}: key 'contacts[{i}].stiffness': {c.stiffness:g} N/m cannot be exchanged stably at {rate}: {where}, "
            f"so omega = sqrt(k / m) = {lim['omega_h'] / h:.3g} rad/s and omega h = {lim['omega_h']:.3g}; the exchange "
            f"needs omega h < 0.5 whatever the damping: {here}no damping allows more than "
            f"{_round_in(lim['stiffness'], up=False):g} N/m (at {lim['best_damping']:.3g} N s/m) at this rate{faster}")
    c_lo, c_hi = (_round_in(lim["damping"][0], up=True), _round_in(lim["damping"][1], up=False))
    stiffer = f", or a stiffness below {k_here:g} N/m for this damping" if k_here > 0 else ""
    if c.damping >= lim["damping"][1]:
        raise ScenarioError(
            f"{path}: key 'contacts[{i}].damping': {c.damping:g} N s/m cannot be exchanged stably at {rate}: {where}; "
            f"the damper, acting one step late, changes the relative speed per step by c h / m = {lim['b']:.3g} times "
            f"that speed and overshoots (the exchange needs it below 1): with stiffness {c.stiffness:g} N/m the "
            f"damping must be below {c_hi:g} N s/m at this rate (and above {c_lo:g}){stiffer}{faster}")
    raise ScenarioError(
        f"{path}: key 'contacts[{i}].damping': {c.damping:g} N s/m is too little for the exchange at {rate}: {where}; "
        f"the exchanged spring ({c.stiffness:g} N/m, omega h = {lim['omega_h']:.3g}) gains energy every step: with "
        f"that stiffness the damping must be at least {c_lo:g} N s/m (and below {c_hi:g}){stiffer}{faster}; real "
        f"fenders damp far more")


STRAIGHT_SLACK_TOLERANCE = 0.02   # a straight layout's ends at least 98 % of the rope's length apart


def _check_straight_span(path: str, sc: Scenario, i: int, r: RopeSpec, params, points) -> None:
    """A straight layout lays the rope file's whole length between the ends. Accepted when the
    ends start between (1 - STRAIGHT_SLACK_TOLERANCE) L and L (1 + breaking_load / EA) apart: up
    to 2 % of slack (laid straight, a 2 % longer rope would sag about 9 % of the span) or stretched
    at most to its breaking load (beyond it, it parts at t = 0). Shorter spans need allow_slack:
    true; otherwise the message points to the winch or slack layout that lays what was meant."""
    pa, pb = _end_point(path, sc, r, "a", points), _end_point(path, sc, r, "b", points)
    if pa is None or pb is None or math.dist(pa, pb) < 1e-6:
        return                                   # no position, or the ends coincide (checked after)
    span, length = math.dist(pa, pb), float(params.length)
    shortest = (1.0 - STRAIGHT_SLACK_TOLERANCE) * length
    longest = length * (1.0 + params.breaking_load / params.ea)
    key = f"{path}: key 'ropes[{i}].layout'"
    rope = f"the rope ({r.rope_file}) is {length:g} m long"
    if span > longest:
        raise ScenarioError(f"{key}: straight between ends {span:.1f} m apart, but {rope} and reaches at most "
                            f"{longest:.1f} m at its breaking load ({params.breaking_load / 1e3:.4g} kN, EA "
                            f"{params.ea:.4g} N): it would part at t = 0; start the vessels closer or use a longer rope")
    if span >= shortest or r.allow_slack:
        return
    deployed = min(math.ceil(span * (1.0 + STRAIGHT_SLACK_TOLERANCE)), length)
    winch = (f"layout: winch with deployed_length: {deployed:g} (the rest stays on end a's drum), "
             if r.end_a != "free" else "")
    raise ScenarioError(f"{key}: straight between ends {span:.1f} m apart, but {rope}: a straight layout lays all "
                        f"of it out, {length - span:.1f} m folded along the chord. Use {winch}layout: slack (the whole "
                        f"rope hangs as a catenary), or allow_slack: true to lay it straight anyway (a straight layout "
                        f"needs the ends {shortest:.1f} m to {longest:.1f} m apart)")


def has_thrusters(sc: Scenario, v: VesselSpec) -> bool:
    """Whether the vessel's ship file (with its ship_overrides) has azimuth thrusters."""
    path = resolve("tug_dynamics", "ships", v.ship_file, sc._path or "scenario.yaml")
    try:
        data = load_yaml(path)
    except (OSError, YamlInputError):
        return False
    over = v.ship_overrides or {}
    return bool((over.get("thrusters") if "thrusters" in over else (data or {}).get("thrusters")))


def depth_grid_path(depth: DepthGridSpec, scenario_path: str) -> str:
    """A depth grid's path: absolute, or relative to the scenario file."""
    if os.path.isabs(depth.grid):
        return depth.grid
    return os.path.join(os.path.dirname(os.path.abspath(scenario_path)), depth.grid)


def environment_parameter(sc: Scenario, scenario_path: str) -> str:
    """The scenario's environment as the nodes' `environment` parameter (JSON, a YAML subset;
    a depth grid's path made absolute)."""
    import json
    data = sc.environment.model_dump()
    if isinstance(sc.environment.depth, DepthGridSpec):
        data["depth"] = {"grid": depth_grid_path(sc.environment.depth, scenario_path)}
    return json.dumps(data)


def heading_rad(v: VesselSpec) -> float:
    """initial.heading_deg in rad: the heading at t = 0, or for a prescribed vessel the direction of
    its track's x axis (its heading at t = 0 adds the law's track angle, Motion.start)."""
    return math.radians(v.initial.heading_deg)
