"""The scenario format: one YAML file names everything a run needs. Validated before any node
starts; every error names the file, the key and what was expected.

    name: default_demo
    duration: 240.0            # s of simulated time
    exchange_rate: 50.0        # Hz, vessel <-> rope exchange
    mode: lockstep             # lockstep (as fast as possible) | realtime (paced on the wall clock)
    environment: {current: [0.0, 0.0], water_density: 1025.0, gravity: 9.80665}
    vessels:
      - name: tug              # ROS namespace
        ship_file: harbour_tug.yaml
        initial: {x: 0.0, y: 0.0, heading_deg: 0.0, speed: 0.0}
    ropes:
      - name: towline
        rope_file: table1.yaml
        end_a: tug/towing_hook  # "<vessel>/<attachment>", or "fixed" / "free" with end_a_position
        end_b: barge/bow_bollard
        layout: winch           # straight | slack | winch (wound on end a's winch)
    events:
      - {time: 0.0, vessel: tug, engine_order: 0.8}
      - {time: 60.0, vessel: tug, steering_deg: 20.0}
      - {time: 0.0, rope: towline, payout_rate: 1.0}
"""
from __future__ import annotations

import math
import os
from typing import Any, Dict, List, Literal, Optional, Tuple

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator


class ScenarioError(ValueError):
    """A scenario that cannot run; the message names the file and the key."""


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class Environment(_Strict):
    current: Tuple[float, float] = (0.0, 0.0)  # east, north, m/s
    water_density: float = Field(1025.0, gt=900.0, lt=1100.0)
    gravity: float = Field(9.80665, gt=9.0, lt=10.5)


class InitialState(_Strict):
    x: float = 0.0  # m east
    y: float = 0.0  # m north
    heading_deg: float = 0.0  # 0 = bow east, counter-clockwise positive (REP-103)
    speed: float = Field(0.0, ge=-30.0, le=40.0)  # m/s surge
    # Orders held from the start with the engine and rudder already there (e.g. "turn from
    # 9 kn at half ahead"); 0 keeps the model's own start.
    engine_order: float = Field(0.0, ge=-1.0, le=1.0)
    steering_deg: float = Field(0.0, ge=-90.0, le=90.0)


class Motion(_Strict):
    """Prescribed motion (seed 000 section 4 tug tracks), in the initial frame."""
    type: Literal["constant_speed", "sinusoidal_sway", "acceleration", "turn"]
    speed: float = Field(ge=0.0, le=40.0)  # m/s, U or U_max
    amplitude: float = Field(0.0, ge=0.0)  # m
    period: float = Field(0.0, ge=0.0)  # s
    acceleration: float = Field(0.0, ge=0.0)  # m/s^2
    heading: Literal["track", "fixed"] = "track"
    turn_rate_deg: float = 0.0  # deg/s, positive to port
    turn_start: float = Field(0.0, ge=0.0)  # s
    turn_duration: float = Field(0.0, ge=0.0)  # s

    @model_validator(mode="after")
    def _complete(self):
        if self.type == "turn" and (self.turn_rate_deg == 0 or self.turn_duration <= 0):
            raise ValueError("turn needs a non-zero turn_rate_deg and a positive turn_duration")
        if self.type == "sinusoidal_sway" and self.period <= 0:
            raise ValueError("sinusoidal_sway needs a positive period")
        if self.type == "acceleration" and self.acceleration <= 0:
            raise ValueError("acceleration needs a positive acceleration")
        return self


class VesselSpec(_Strict):
    name: str = Field(pattern=r"^[A-Za-z][A-Za-z0-9_]*$")
    ship_file: str
    initial: InitialState = InitialState()
    motion: Optional[Motion] = None
    # Merged over the ship file (e.g. {towline_simple: {enabled: true, gamma_max_deg: 20}}).
    ship_overrides: Optional[Dict[str, Any]] = None


class RopeSpec(_Strict):
    name: str = Field(pattern=r"^[A-Za-z][A-Za-z0-9_]*$")
    rope_file: str = "table1.yaml"
    end_a: str
    end_b: str
    end_a_position: Optional[Tuple[float, float, float]] = None
    end_b_position: Optional[Tuple[float, float, float]] = None
    layout: Literal["straight", "slack", "winch"] = "straight"
    deployed_length: Optional[float] = Field(None, gt=0.0)
    n_elements: Optional[int] = Field(None, ge=1, le=2000)


class Event(_Strict):
    time: float = Field(ge=0.0)
    vessel: Optional[str] = None
    rope: Optional[str] = None
    engine_order: Optional[float] = Field(None, ge=-1.0, le=1.0)
    steering_deg: Optional[float] = Field(None, ge=-90.0, le=90.0)
    anchor: Optional[Literal["let_go", "heave_up"]] = None
    payout_rate: Optional[float] = None

    @model_validator(mode="after")
    def _one_target(self):
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
    package: str = "scenario_runner"
    executable: str = "autopilot"
    params: Dict[str, Any] = Field(default_factory=dict)  # ROS parameters of the controller


class Recording(_Strict):
    enabled: bool = True
    path: Optional[str] = None  # default: output/<scenario name>.mcap; the command line wins


class Scenario(_Strict):
    name: str
    description: str = ""
    duration: float = Field(gt=0.0)
    exchange_rate: float = Field(50.0, ge=1.0, le=1000.0)
    mode: Literal["lockstep", "realtime"] = "lockstep"
    environment: Environment = Environment()
    vessels: List[VesselSpec] = Field(default_factory=list)
    ropes: List[RopeSpec] = Field(default_factory=list)
    autopilots: List[AutopilotSpec] = Field(default_factory=list)
    events: List[Event] = Field(default_factory=list)
    recording: Recording = Recording()

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
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out += ("." if out else "") + str(part)
    return out


def _explain(err: dict) -> str:
    if err["type"] == "extra_forbidden":
        return "unknown key (misspelt?)"
    if err["type"] == "missing":
        return "required key is missing"
    return err["msg"]


def load_scenario(path: str, check_files: bool = True) -> Scenario:
    """Read and validate a scenario; with check_files also resolve every ship and rope file and
    check that each rope end names an attachment of its vessel."""
    if not os.path.isfile(path):
        raise ScenarioError(f"scenario file '{path}' not found")
    try:
        with open(path) as f:
            data = yaml.safe_load(f)
    except yaml.YAMLError as exc:
        raise ScenarioError(f"{path}: not valid YAML: {exc}") from None
    if not isinstance(data, dict):
        raise ScenarioError(f"{path}: expected a mapping of scenario keys at the top level")
    try:
        sc = Scenario.model_validate(data)
    except ValidationError as exc:
        lines = [f"{path}: key '{_key_path(e['loc']) or '(top)'}': {_explain(e)}" for e in exc.errors()]
        raise ScenarioError("\n".join(lines)) from None
    _check_references(path, sc)
    if check_files:
        _check_files(path, sc)
    return sc


def _check_references(path: str, sc: Scenario) -> None:
    vessels = [v.name for v in sc.vessels]
    ropes = [r.name for r in sc.ropes]
    for kind, names in (("vessels", vessels), ("ropes", ropes)):
        dup = {n for n in names if names.count(n) > 1}
        if dup:
            raise ScenarioError(f"{path}: key '{kind}': duplicate name(s) {sorted(dup)}")
    pilots = [a.name for a in sc.autopilots]
    if len(set(pilots)) != len(pilots):
        raise ScenarioError(f"{path}: key 'autopilots': duplicate name(s)")
    clash = set(vessels) & set(ropes) | (set(pilots) & (set(vessels) | set(ropes)))
    if clash:
        raise ScenarioError(f"{path}: names {sorted(clash)} are used by a vessel and a rope (namespaces must differ)")
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
    driven = {}
    for i, a in enumerate(sc.autopilots):
        if a.vessel not in vessels:
            raise ScenarioError(f"{path}: key 'autopilots[{i}].vessel': '{a.vessel}' is not in 'vessels' ({vessels})")
        if a.vessel in driven:
            raise ScenarioError(f"{path}: key 'autopilots[{i}].vessel': '{a.vessel}' already has an autopilot")
        driven[a.vessel] = a.name
    for i, ev in enumerate(sc.events):
        if ev.vessel is not None and ev.vessel not in vessels:
            raise ScenarioError(f"{path}: key 'events[{i}].vessel': '{ev.vessel}' is not in 'vessels' ({vessels})")
        if ev.vessel in driven:
            raise ScenarioError(f"{path}: key 'events[{i}].vessel': '{ev.vessel}' is steered by autopilot "
                                f"'{driven[ev.vessel]}'; give its orders as the autopilot's params")
        if ev.rope is not None:
            if ev.rope not in ropes:
                raise ScenarioError(f"{path}: key 'events[{i}].rope': '{ev.rope}' is not in 'ropes' ({ropes})")
            if next(r for r in sc.ropes if r.name == ev.rope).layout != "winch":
                raise ScenarioError(f"{path}: key 'events[{i}].payout_rate': rope '{ev.rope}' has no winch "
                                    "(layout: winch)")
        if ev.time > sc.duration:
            raise ScenarioError(f"{path}: key 'events[{i}].time': {ev.time} s is after the end ({sc.duration} s)")


def resolve(package: str, subdir: str, name: str, scenario_path: str) -> str:
    """A data file named in a scenario: relative to the scenario file, else in the package share."""
    if os.path.isabs(name):
        return name
    local = os.path.join(os.path.dirname(os.path.abspath(scenario_path)), name)
    if os.path.isfile(local):
        return local
    from ament_index_python.packages import get_package_share_directory
    return os.path.join(get_package_share_directory(package), subdir, name)


def _check_files(path: str, sc: Scenario) -> None:
    from rope_model.models import load_params as load_rope_params
    from tug_dynamics.ship_file import load_ship
    attachments = {}
    for i, v in enumerate(sc.vessels):
        ship = resolve("tug_dynamics", "ships", v.ship_file, path)
        if not os.path.isfile(ship):
            raise ScenarioError(f"{path}: key 'vessels[{i}].ship_file': ship file '{v.ship_file}' not found "
                                f"(looked for {ship})")
        try:
            attachments[v.name] = set(load_ship(ship, name=v.name, overrides=v.ship_overrides).attachments)
        except (ValueError, KeyError) as exc:
            raise ScenarioError(f"{path}: key 'vessels[{i}].ship_file': {exc}") from None
    for i, r in enumerate(sc.ropes):
        rope = resolve("rope_model", "ropes", r.rope_file, path)
        if not os.path.isfile(rope):
            raise ScenarioError(f"{path}: key 'ropes[{i}].rope_file': rope file '{r.rope_file}' not found "
                                f"(looked for {rope})")
        try:
            load_rope_params(rope)
        except ValueError as exc:
            raise ScenarioError(f"{path}: key 'ropes[{i}].rope_file': {exc}") from None
        for end in ("a", "b"):
            spec = getattr(r, f"end_{end}")
            if "/" in spec:
                vessel, point = spec.split("/")
                if point not in attachments[vessel]:
                    raise ScenarioError(f"{path}: key 'ropes[{i}].end_{end}': vessel '{vessel}' has no attachment "
                                        f"'{point}' (it has {sorted(attachments[vessel])})")


def heading_rad(v: VesselSpec) -> float:
    return math.radians(v.initial.heading_deg)
