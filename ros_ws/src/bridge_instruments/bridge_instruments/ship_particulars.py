"""A vessel's dimensions as bridge equipment reports them (AIS type 5), ROS-free.

They come from the vessel's ship file with the scenario's `ship_overrides` for that vessel
merged over it, the way the vessel node builds its model and its hull (tug_dynamics.ship_file),
so a scenario that lengthens or widens a hull gets the same length and beam on the ECDIS as in
the simulation. The scenario is read with scenario_runner.scenario's own loader.
"""
from __future__ import annotations

import os
from typing import Dict, Optional, Tuple

from sim_plumbing.scene import HullDimensions


def hull_dimensions(ship_file: str, overrides: Optional[dict] = None) -> HullDimensions:
    """Length, beam, draft and kind of the hull a ship file (a path, or a name in the installed
    ships directory) describes, with `overrides` (a scenario's ship_overrides) merged over it.
    ValueError naming the file for one that is missing or has no hull dimensions."""
    import yaml
    from tug_dynamics.ship_file import _deep_merge, ships_dir  # the merge load_ship applies
    path = ship_file
    if not os.path.isabs(path) and not os.path.isfile(path):
        path = os.path.join(ships_dir(), path)
    if not os.path.isfile(path):
        raise ValueError(f"ship file '{ship_file}' not found (looked in {os.path.dirname(path)})")
    with open(path) as f:
        cfg = yaml.safe_load(f)
    if not isinstance(cfg, dict):
        raise ValueError(f"{path}: not a ship file (top level is not a mapping)")
    if overrides:
        if not isinstance(overrides, dict):
            raise ValueError(f"{path}: ship_overrides must be a mapping, got {type(overrides).__name__}")
        cfg = _deep_merge(cfg, overrides)
    try:
        return HullDimensions.from_ship_config(cfg)
    except (KeyError, TypeError) as exc:
        raise ValueError(f"{path}: no hull dimensions ({exc})" +
                         (" after the scenario's ship_overrides" if overrides else "")) from None


def scenario_ships(scenario: str) -> Dict[str, Tuple[str, dict]]:
    """vessel -> (its ship file, resolved as the runner resolves it; its ship_overrides or {}) of a
    scenario file. ValueError (the loader's message: file, key, value) for one that does not load."""
    from scenario_runner.scenario import ScenarioError, load_scenario, resolve
    try:
        sc = load_scenario(scenario, check_files=False)
    except ScenarioError as exc:
        raise ValueError(str(exc)) from None
    return {v.name: (resolve("tug_dynamics", "ships", v.ship_file, scenario), dict(v.ship_overrides or {}))
            for v in sc.vessels}
