"""The study file: a base scenario, axes over its values, seeds, and the measures to take (ROS-free).

    name: tow_length_engine_order
    scenario: default_demo.yaml          # beside this file, else in the scenario library
    duration: 160.0                      # s simulated of each run (run_scenario --duration; default: all)
    sea_window: [60.0, 160.0]            # analyze --sea-window: the sea statistics' window
    axes:                                # combined as a grid (every value with every value)
      - key: ropes[towline].deployed_length     # a scenario value by dotted path
        values: [90.0, 95.0, 100.0]
      - key: events[16].engine_order            # list items by index, or by name: vessels[tug]
        range: {start: 0.35, stop: 0.55, step: 0.1}   # or {start, stop, num}; stop included
      - key: environment.wind.speed_kn
        random: {distribution: uniform, low: 5.0, high: 25.0, count: 4, seed: 1}
    seeds: {key: environment.waves.seed, count: 20, first: 0}   # Monte Carlo: every configuration 20 times
    measures:                            # name: dotted path in analyze's summary (summary.json)
      peak_tension: ropes.towline.tension_a_max
      significant_tension: ropes.towline.sea_end_a.tension_significant
    extremes: {measure: peak_tension, duration: 10800.0}   # Gumbel fit over seeds, MPM in 3 h

Everything is checked before any run starts: an unknown key, an empty range, an axis over a value
the scenario does not have (each value of each axis is put into the scenario and the scenario
checked as run_scenario checks it), a measure of a vessel or rope the scenario lacks. The error
(StudyError) names the study file and the key.
"""
from __future__ import annotations

import copy
import hashlib
import itertools
import json
import math
import os
import re
from dataclasses import dataclass, field
from typing import Any, Dict, List, Literal, Optional, Tuple, Union

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from scenario_format.particulars import scenario_path
from scenario_format.scenario import ScenarioError, load_scenario
from sim_math.input_files import YamlInputError, load_yaml


class StudyError(ValueError):
    """A study that cannot run; the message names the file and the key."""


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, strict=True, allow_inf_nan=False)


class RangeSpec(_Strict):
    """start, stop (included when a step lands on it) and either step or num (evenly spaced)."""
    start: float
    stop: float
    step: Optional[float] = None
    num: Optional[int] = None

    @model_validator(mode="after")
    def _step_or_num(self):
        if (self.step is None) == (self.num is None):
            raise ValueError("a range gives exactly one of 'step' or 'num'")
        if self.step == 0.0:
            raise ValueError("step 0 never reaches stop")
        return self

    def values(self) -> List[float]:
        if self.num is not None:
            return [float(v) for v in np.linspace(self.start, self.stop, self.num)] if self.num > 0 else []
        count = math.floor((self.stop - self.start) / self.step + 1e-9) + 1  # <= 0: the step leads away from stop
        return [round(self.start + i * self.step, 12) for i in range(max(count, 0))]


class RandomSpec(_Strict):
    """count draws from numpy's default_rng(seed): uniform in [low, high), normal (mean, std), or
    integers in [low, high)."""
    distribution: Literal["uniform", "normal", "integers"]
    count: int = Field(ge=0)
    seed: int = Field(ge=0)
    low: Optional[float] = None
    high: Optional[float] = None
    mean: Optional[float] = None
    std: Optional[float] = Field(None, ge=0.0)

    @model_validator(mode="after")
    def _parameters(self):
        wanted = ("mean", "std") if self.distribution == "normal" else ("low", "high")
        given = [k for k in ("low", "high", "mean", "std") if getattr(self, k) is not None]
        if sorted(given) != sorted(wanted):
            raise ValueError(f"a {self.distribution} draw gives {' and '.join(wanted)}; got {', '.join(given) or 'none'}")
        if self.distribution != "normal" and not self.low < self.high:
            raise ValueError(f"low {self.low:g} must be below high {self.high:g}")
        return self

    def values(self) -> List[Any]:
        rng = np.random.default_rng(self.seed)
        if self.distribution == "uniform":
            return [float(v) for v in rng.uniform(self.low, self.high, self.count)]
        if self.distribution == "normal":
            return [float(v) for v in rng.normal(self.mean, self.std, self.count)]
        return [int(v) for v in rng.integers(math.ceil(self.low), math.ceil(self.high), self.count)]


Value = Union[bool, int, float, str]


class Axis(_Strict):
    key: str = Field(min_length=1)
    values: Optional[List[Value]] = None
    range: Optional[RangeSpec] = None
    random: Optional[RandomSpec] = None

    @model_validator(mode="after")
    def _one_source(self):
        given = [k for k in ("values", "range", "random") if getattr(self, k) is not None]
        if len(given) != 1:
            raise ValueError(f"an axis gives exactly one of values, range or random; got {', '.join(given) or 'none'}")
        return self

    def points(self) -> List[Any]:
        if self.values is not None:
            return list(self.values)
        return (self.range or self.random).values()


class Seeds(_Strict):
    """Every configuration run `count` times with key = first, first + 1, ... (the sea's seed)."""
    key: str = Field(min_length=1)
    count: int = Field(ge=1, le=100000)
    first: int = Field(0, ge=0)


class Extremes(_Strict):
    """The Gumbel fit of a measure's per-run maxima over the seeds of each configuration, and the
    most probable maximum in `duration` s; `record`: s of each run that measure covers (default
    the runs' duration)."""
    measure: str
    duration: float = Field(gt=0.0)
    record: Optional[float] = Field(None, gt=0.0)
    confidence: float = Field(0.95, gt=0.0, lt=1.0)


class Study(_Strict):
    name: str = Field(pattern=r"^[A-Za-z0-9_][A-Za-z0-9_.-]*$", max_length=100)
    description: str = ""
    scenario: str = Field(min_length=1)
    duration: Optional[float] = Field(None, gt=0.0)
    axes: List[Axis] = Field(default_factory=list)
    seeds: Optional[Seeds] = None
    measures: Dict[str, str] = Field(min_length=1)
    extremes: Optional[Extremes] = None
    # analyze's --sea-window T0 T1 (simulation s): the window of the sea statistics (sea_end_a ...)
    sea_window: Optional[List[float]] = Field(None, min_length=2, max_length=2)

    @model_validator(mode="after")
    def _window(self):
        if self.sea_window is not None and not 0.0 <= self.sea_window[0] < self.sea_window[1]:
            raise ValueError(f"sea_window {self.sea_window}: expected [T0, T1] with 0 <= T0 < T1")
        return self


MEASURE_ROOTS = ("ropes", "vessels", "sea", "file")


@dataclass
class PlannedRun:
    """One run of a study: its scenario (a YAML mapping, file names made absolute) and values."""
    run: str                       # stable id from the values: what a resumed study matches on
    configuration: int
    sample: int
    values: Dict[str, Any]         # axis key (and seed key) -> value
    scenario: Dict[str, Any]


@dataclass
class StudyPlan:
    path: str
    study: Study
    scenario_path: str
    runs: List[PlannedRun] = field(default_factory=list)

    @property
    def axis_keys(self) -> List[str]:
        return [a.key for a in self.study.axes]

    @property
    def run_duration(self) -> float:
        """s each run's measures cover: the sea window, else the runs' simulated time."""
        if self.study.sea_window is not None:
            return self.study.sea_window[1] - self.study.sea_window[0]
        return self.study.duration or (float(self.runs[0].scenario["duration"]) if self.runs else math.nan)


# ---------------------------------------------------------------------------------------
# Dotted paths into a scenario mapping
# ---------------------------------------------------------------------------------------
_PART = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*)((?:\[[^\[\]]+\])*)$")


def parse_path(key: str) -> List[Union[str, Tuple[str]]]:
    """'ropes[towline].deployed_length' -> ['ropes', ('towline',), 'deployed_length']: a str is a
    mapping key, a 1-tuple a list item (an index, or the item whose name it is)."""
    out: List[Union[str, Tuple[str]]] = []
    for part in key.split("."):
        m = _PART.match(part)
        if not m:
            raise ValueError(f"'{key}': '{part}' is not a key (name, name[index] or name[item name])")
        out.append(m.group(1))
        out.extend((item,) for item in re.findall(r"\[([^\[\]]+)\]", m.group(2)))
    return out


def _item(items: list, label: str, where: str) -> int:
    if re.fullmatch(r"-?\d+", label):
        i = int(label)
        if not -len(items) <= i < len(items):
            raise ValueError(f"'{where}' has {len(items)} item(s): no [{label}]")
        return i % len(items)
    names = [x.get("name") for x in items if isinstance(x, dict)]
    if label not in names:
        raise ValueError(f"'{where}' has no item named '{label}' (names: {', '.join(map(str, names)) or 'none'})")
    return names.index(label)


def set_value(data: Dict[str, Any], key: str, value: Any) -> None:
    """Puts value at the dotted path key of a scenario mapping (in place). Missing mappings on the
    way are made ({} : environment.waves in a calm scenario); a list item must be there."""
    parts = parse_path(key)
    node: Any = data
    where = ""
    for i, part in enumerate(parts):
        last = i == len(parts) - 1
        if isinstance(part, tuple):
            if not isinstance(node, list):
                raise ValueError(f"'{where}' is not a list: no [{part[0]}]")
            j = _item(node, part[0], where)
            if last:
                node[j] = value
            node, where = node[j], f"{where}[{part[0]}]"
            continue
        if not isinstance(node, dict):
            raise ValueError(f"'{where}' is a value, not a mapping: no '{part}' in it")
        if last:
            node[part] = value
        elif part not in node:
            node[part] = [] if isinstance(parts[i + 1], tuple) else {}
        node, where = node[part], f"{where}.{part}" if where else part


def get_value(data: Any, key: str) -> Any:
    """The value at a dotted path of a mapping (analyze's summary); KeyError when it is not there."""
    node = data
    for part in parse_path(key):
        if isinstance(part, tuple):
            if not isinstance(node, list):
                raise KeyError(key)
            try:
                node = node[_item(node, part[0], key)]
            except ValueError:
                raise KeyError(key) from None
        elif isinstance(node, dict) and part in node:
            node = node[part]
        else:
            raise KeyError(key)
    return node


def absolute_files(data: Any, base_dir: str) -> Any:
    """The mapping with every string that names a file beside the base scenario made absolute:
    the runs' scenarios are written elsewhere, and their ship and rope files must still resolve."""
    if isinstance(data, dict):
        return {k: absolute_files(v, base_dir) for k, v in data.items()}
    if isinstance(data, list):
        return [absolute_files(v, base_dir) for v in data]
    if isinstance(data, str) and data and not os.path.isabs(data) and os.path.isfile(os.path.join(base_dir, data)):
        return os.path.abspath(os.path.join(base_dir, data))
    return data


def run_id(values: Dict[str, Any]) -> str:
    return hashlib.sha256(json.dumps(values, sort_keys=True).encode()).hexdigest()[:16]


# ---------------------------------------------------------------------------------------
# Loading and planning
# ---------------------------------------------------------------------------------------
def _explain(err: dict) -> str:
    if err["type"] == "extra_forbidden":
        return f"unknown key (misspelt?), value {err['input']!r}"
    if err["type"] == "missing":
        return "required key is missing"
    return f"{err['msg']}, got {err['input']!r}"


def _key_path(loc) -> str:
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        elif not re.match(r"^(bool|int|float|str)$", str(part)):
            out += ("." if out else "") + str(part)
    return out or "(top)"


def load_study(path: str) -> Study:
    """The study file read and checked against the format (not yet against its scenario)."""
    if not os.path.isfile(path):
        raise StudyError(f"study file '{path}' not found")
    try:
        data = load_yaml(path)
    except YamlInputError as exc:
        raise StudyError(f"{path}: {exc}") from None
    if not isinstance(data, dict):
        raise StudyError(f"{path}: expected a mapping of study keys at the top level, got {type(data).__name__}")
    try:
        return Study.model_validate(data)
    except ValidationError as exc:
        raise StudyError("\n".join(f"{path}: key '{_key_path(e['loc'])}': {_explain(e)}" for e in exc.errors())) from None


def _scenario_file(path: str, study: Study) -> str:
    local = os.path.join(os.path.dirname(os.path.abspath(path)), study.scenario)
    return local if os.path.isfile(local) else scenario_path(study.scenario)


def _check_scenario(data: Dict[str, Any], folder: str, shown_as: str) -> None:
    """load_scenario on the mapping (as run_scenario checks its file); ScenarioError, its
    messages naming the file `shown_as` (the base scenario) instead of the written copy."""
    import yaml
    file = os.path.join(folder, "check.yaml")
    with open(file, "w", encoding="utf-8") as f:
        yaml.safe_dump(data, f, sort_keys=False)
    try:
        load_scenario(file)
    except ScenarioError as exc:
        raise ScenarioError(str(exc).replace(file, shown_as)) from None


def _check_axes(path: str, study: Study, base: Dict[str, Any], folder: str, base_path: str) -> List[List[Any]]:
    """Every value of every axis (and the first and last seed) put into the base scenario alone,
    and that scenario checked; the axes' values."""
    points = []
    axes = list(study.axes) + ([Axis(key=study.seeds.key, values=[study.seeds.first,
                                                                  study.seeds.first + study.seeds.count - 1])]
                               if study.seeds else [])
    for i, axis in enumerate(axes):
        where = f"axes[{i}]" if i < len(study.axes) else "seeds"
        values = axis.points()
        if not values:
            what = "range" if axis.range else ("random" if axis.random else "values")
            raise StudyError(f"{path}: key '{where}.{what}': empty: the axis over '{axis.key}' has no value")
        for value in values:
            data = copy.deepcopy(base)
            try:
                set_value(data, axis.key, value)
                _check_scenario(data, folder, base_path)
            except (ValueError, ScenarioError) as exc:
                raise StudyError(f"{path}: key '{where}.key': '{axis.key}' = {value!r} is not a value the scenario "
                                 f"{study.scenario} can take:\n{exc}") from None
        if i < len(study.axes):
            points.append(values)
    return points


def _check_measures(path: str, study: Study, base: Dict[str, Any]) -> None:
    names = {"ropes": [r.get("name") for r in base.get("ropes", [])],
             "vessels": [v.get("name") for v in base.get("vessels", [])]}
    for name, key in study.measures.items():
        try:
            parts = parse_path(key)
        except ValueError as exc:
            raise StudyError(f"{path}: key 'measures.{name}': {exc}") from None
        if parts[0] not in MEASURE_ROOTS:
            raise StudyError(f"{path}: key 'measures.{name}': '{key}' is not in analyze's summary (it starts with "
                             f"one of {', '.join(MEASURE_ROOTS)})")
        if parts[0] in names and (len(parts) < 3 or parts[1] not in names[parts[0]]):
            raise StudyError(f"{path}: key 'measures.{name}': '{key}': the scenario {study.scenario} has no "
                             f"{parts[0][:-1]} '{parts[1] if len(parts) > 1 else ''}' (its {parts[0]}: "
                             f"{', '.join(names[parts[0]])}); expected {parts[0]}.<name>.<quantity>")
    if study.extremes and study.extremes.measure not in study.measures:
        raise StudyError(f"{path}: key 'extremes.measure': '{study.extremes.measure}' is not one of the measures "
                         f"({', '.join(study.measures)})")


def plan_study(path: str, scratch: str) -> StudyPlan:
    """The study read, its scenario found, every axis value and measure checked (scenarios
    written to `scratch` for the check) and its runs listed: configurations in grid order, each
    with its seeds. StudyError naming file and key."""
    study = load_study(path)
    base_path = _scenario_file(path, study)
    try:
        load_scenario(base_path)
    except ScenarioError as exc:
        raise StudyError(f"{path}: key 'scenario': '{study.scenario}' does not load:\n{exc}") from None
    base = absolute_files(load_yaml(base_path), os.path.dirname(os.path.abspath(base_path)))
    if study.duration is not None and study.duration > float(base["duration"]):
        raise StudyError(f"{path}: key 'duration': {study.duration:g} s is longer than the scenario "
                         f"{study.scenario} ({float(base['duration']):g} s)")
    end = study.duration or float(base["duration"])
    if study.sea_window is not None and study.sea_window[1] > end:
        raise StudyError(f"{path}: key 'sea_window': ends at {study.sea_window[1]:g} s, after the runs do ({end:g} s)")
    os.makedirs(scratch, exist_ok=True)
    points = _check_axes(path, study, base, scratch, base_path)
    _check_measures(path, study, base)
    plan = StudyPlan(path, study, base_path)
    seeds = (list(range(study.seeds.first, study.seeds.first + study.seeds.count)) if study.seeds else [None])
    for c, combo in enumerate(itertools.product(*points)):
        for s, seed in enumerate(seeds):
            values = dict(zip(plan.axis_keys, combo))
            data = copy.deepcopy(base)
            for key, value in values.items():
                set_value(data, key, value)
            if seed is not None:
                values[study.seeds.key] = seed
                set_value(data, study.seeds.key, seed)
            plan.runs.append(PlannedRun(run_id(values), c, s, values, data))
    return plan
