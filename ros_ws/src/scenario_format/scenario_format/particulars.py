"""A run's particulars, computed once: what the topics do not carry but the analysis, the bridge
equipment and the instructor station need (ROS-free).

From a scenario: each vessel's ship file and length (the L of the IMO criteria), each rope's file,
ends and breaking load (N; None for a model without one). The runner records them in the MCAP
metadata record PARTICULARS_METADATA, so a recording carries them without its scenario; the
analysis and the instructor's replay read them back with `particulars_of_recording`.

A vessel's dimensions as bridge equipment reports them (AIS type 5) come from its ship file with
the scenario's `ship_overrides` for that vessel merged over it, the way the vessel node builds its
model and its hull (tug_dynamics.ship_file.ship_config), so a scenario that lengthens a hull gets
the same length and beam on the ECDIS as in the simulation.
"""
from __future__ import annotations

import json
import math
import os
from typing import Dict, Optional, Tuple

from rope_model.models import load_params
from scenario_format.scenario import Scenario, ScenarioError, load_scenario, resolve
from sim_math.data_files import resolve as resolve_data_file
from sim_math.hull_plan import HullDimensions
from tug_dynamics.ship_file import ShipFileError, load_ship, ship_config

PARTICULARS_METADATA = "tugsim"  # MCAP metadata record: {"particulars": JSON of particulars()}
_KEY = "particulars"


def scenario_path(name: str) -> str:
    """A path as given, or a bare name in the scenario library (scenario_runner/scenarios)."""
    return resolve_data_file("scenario_runner", "scenarios", name)


def particulars(path: str, sc: Scenario) -> dict:
    """The particulars of the scenario `sc` read from `path` (its files were checked by
    load_scenario): {"scenario", "vessels": {name: {ship_file, length}}, "ropes": {name:
    {rope_file, end_a, end_b, breaking_load}}, and with a sea "waves": environment.waves with its
    ramp time resolved (s)}."""
    vessels = {}
    for v in sc.vessels:
        ship = resolve("tug_dynamics", "ships", v.ship_file, path)
        vessels[v.name] = {"ship_file": os.path.basename(ship),
                           "length": float(load_ship(ship, name=v.name, overrides=v.ship_overrides).length)}
    ropes = {}
    for r in sc.ropes:
        rope = resolve("rope_model", "ropes", r.rope_file, path)
        load = getattr(load_params(rope), "breaking_load", None)
        ropes[r.name] = {"rope_file": os.path.basename(rope), "end_a": r.end_a, "end_b": r.end_b,
                         "breaking_load": None if load is None or not math.isfinite(load) else float(load)}
    out = {"scenario": os.path.basename(path), "vessels": vessels, "ropes": ropes}
    w = sc.environment.waves
    if w is not None and w.hs > 0.0:   # the sea the run was in: analyze's sea statistics need it
        out["waves"] = {**w.model_dump(), "ramp_time": 3.0 * w.tp if w.ramp_time is None else w.ramp_time}
    return out


def recording_metadata(path: str, sc: Scenario) -> Dict[str, Dict[str, str]]:
    """The MCAP metadata records that carry the particulars: {name: {key: text}}."""
    return {PARTICULARS_METADATA: {_KEY: json.dumps(particulars(path, sc))}}


def particulars_from_metadata(metadata: Dict[str, Dict[str, str]]) -> dict:
    """The particulars from a recording's metadata records ({name: {key: text}}); {} for a
    recording without them (rosbag2, older files). ValueError naming the record if unreadable."""
    text = (metadata.get(PARTICULARS_METADATA) or {}).get(_KEY)
    if text is None:
        return {}
    try:
        value = json.loads(text)
    except ValueError as exc:
        raise ValueError(f"metadata '{PARTICULARS_METADATA}' key '{_KEY}' is not readable ({exc})") from None
    if not isinstance(value, dict):
        raise ValueError(f"metadata '{PARTICULARS_METADATA}' key '{_KEY}' is not readable "
                         f"(a JSON {type(value).__name__}, not an object)")
    return value


def particulars_of_recording(mcap_path: str) -> dict:
    """particulars_from_metadata of an MCAP file's metadata records."""
    from mcap.reader import make_reader
    with open(mcap_path, "rb") as f:
        records = {r.name: dict(r.metadata) for r in make_reader(f).iter_metadata()}
    return particulars_from_metadata(records)


def breaking_loads(parts: dict) -> Dict[str, Optional[float]]:
    """Rope name -> breaking load (N, None for a model without one) of a particulars mapping."""
    return {name: r.get("breaking_load") for name, r in (parts.get("ropes") or {}).items()}


def breaking_loads_from(path: str) -> Dict[str, Optional[float]]:
    """Rope name -> breaking load (N) from a recording (.mcap: its particulars) or a scenario
    (a path or a library name). ValueError naming the file for one that does not load."""
    if path.endswith(".mcap"):
        return breaking_loads(particulars_of_recording(path))
    path = scenario_path(path)
    try:
        sc = load_scenario(path)
    except ScenarioError as exc:
        raise ValueError(str(exc)) from None
    return breaking_loads(particulars(path, sc))


def scenario_of_recording(mcap_path: str, name) -> Tuple[Optional[str], Optional[str]]:
    """(path, None) of the scenario a recording's particulars name (`name`), beside the recording,
    else in the scenario library; (None, why) when it is not found."""
    found = resolve_data_file("scenario_runner", "scenarios", os.path.basename(str(name)),
                              relative_to=os.path.abspath(mcap_path))
    if not os.path.isfile(found):
        return None, f"the recording's scenario {name} is not beside it nor in the scenario library"
    return found, None


def environment_of(path: str) -> Tuple[str, Optional[str]]:
    """(the run's environment as the nodes' `environment` parameter text, note) from a scenario (a
    path or a library name) or a recording (.mcap: the scenario its particulars name, beside it
    or in the scenario library, as the analysis finds it: a recording carries its scenario's
    name, not its environment). ("", why) when there is none to read; ValueError naming the file
    for a scenario that does not load."""
    from scenario_format.scenario import environment_parameter
    if path.endswith(".mcap"):
        name = particulars_of_recording(path).get("scenario")
        if not name:
            return "", f"{path}: no particulars naming its scenario (an older or a rosbag2 recording)"
        found, why = scenario_of_recording(path, name)
        if found is None:
            return "", why
        path = found
    else:
        path = scenario_path(path)
    try:
        sc = load_scenario(path, check_files=False)
    except ScenarioError as exc:
        raise ValueError(str(exc)) from None
    return environment_parameter(sc, path), None


def hull_dimensions(ship_file: str, overrides: Optional[dict] = None) -> HullDimensions:
    """Length, beam, draft and kind of the hull a ship file (a path, or a name in the installed
    ships directory) describes, with `overrides` (a scenario's ship_overrides) merged over it.
    ValueError naming the file for one that is missing or has no hull dimensions."""
    path = resolve_data_file("tug_dynamics", "ships", ship_file)
    if not os.path.isfile(path):
        raise ValueError(f"ship file '{ship_file}' not found (looked in {os.path.dirname(path)})")
    if overrides is not None and not isinstance(overrides, dict):
        raise ValueError(f"{path}: ship_overrides must be a mapping, got {type(overrides).__name__}")
    try:
        _, cfg = ship_config(path, overrides or None)
    except ShipFileError as exc:
        raise ValueError(str(exc)) from None
    try:
        return HullDimensions.from_ship_config(cfg)
    except (KeyError, TypeError) as exc:
        raise ValueError(f"{path}: no hull dimensions ({exc})" +
                         (" after the scenario's ship_overrides" if overrides else "")) from None


def scenario_ships(scenario: str) -> Dict[str, Tuple[str, dict]]:
    """vessel -> (its ship file, resolved as the runner resolves it; its ship_overrides or {}) of a
    scenario file. ValueError (the loader's message: file, key, value) for one that does not load."""
    try:
        sc = load_scenario(scenario, check_files=False)
    except ScenarioError as exc:
        raise ValueError(str(exc)) from None
    return {v.name: (resolve("tug_dynamics", "ships", v.ship_file, scenario), dict(v.ship_overrides or {}))
            for v in sc.vessels}
