"""Hull interaction for 6 vessels (issue 33): what the interaction of every pair adds to a step.

    source scripts/ensure_env.sh && python benchmarks/bench_interaction.py [--duration 30] [--repeats 2]

Six vessels (three S-175s and three harbour tugs, in three lanes 60 m apart, all at 6 kn) and
the 15 pairs between them (30 directed Wang loads each step). Two measurements, printed as the
markdown table of docs/benchmarks.md:

- model: the physics of one simulation step without ROS: the six vessels' Vessel.step (with the
  environment attached, as the vessel node does) against the interaction node's work for the 15
  pairs (InteractionSet.loads: each state carried on, the Wang arguments and both vessels' loads
  in one compiled call), timed side by side in blocks, interleaved, median of the blocks;
- run: run_scenario on the generated scenario without and with the 15 `interactions` entries
  (one interaction node for all of them), both layouts, no recording: CPU ms per step of all processes as the runner measures it (median
  of --repeats runs, interleaved).

Timings are not asserted anywhere (the machine's speed drifts by a factor of two); the ratios of
one run go in docs/benchmarks.md.
"""
from __future__ import annotations

import argparse
import itertools
import math
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np
import yaml

HERE = os.path.dirname(os.path.abspath(__file__))
for package in ("tug_dynamics", "sim_math", "sea_environment", "hull_contact", "sim_contract", "sim_plumbing"):
    sys.path.insert(0, os.path.join(HERE, "..", "ros_ws", "src", package))

CPU = re.compile(r"CPU per step, all processes: (?P<cpu>[\d.]+) ms")
KNOTS_6 = 3.0867
FLEET = [("ship1", "s175_003.yaml", 0.0, 0.0, 0.33), ("ship2", "s175_003.yaml", 0.0, 60.0, 0.33),
         ("ship3", "s175_003.yaml", 0.0, 120.0, 0.33), ("tug1", "harbour_tug.yaml", 150.0, 0.0, 0.5),
         ("tug2", "harbour_tug.yaml", 150.0, 60.0, 0.5), ("tug3", "harbour_tug.yaml", 150.0, 120.0, 0.5)]


def fleet_scenario(name: str, interactions: bool, duration: float, rate: float) -> dict:
    sc = {"name": name, "description": "six vessels at 6 kn in three lanes (bench_interaction)",
          "duration": duration, "exchange_rate": rate,
          "vessels": [{"name": n, "ship_file": f, "initial": {"x": x, "y": y, "heading_deg": 0.0,
                                                               "speed": KNOTS_6, "engine_order": order}}
                      for n, f, x, y, order in FLEET]}
    if interactions:
        sc["interactions"] = [{"between": [a[0], b[0]]} for a, b in itertools.combinations(FLEET, 2)]
    return sc


def _block(fn, n):
    t0 = time.perf_counter()
    for _ in range(n):
        fn()
    return (time.perf_counter() - t0) / n * 1e6


def model_costs(dt: float, n: int = 200, repeats: int = 7):
    """us per step: the six vessels, the 15 pairs' interaction work in deep water, and at h = 20 m."""
    from tug_dynamics.hull_interaction import SectionalAreaCurve
    from tug_dynamics.interaction_set import InteractionSet, PairEntry, PlanarState
    from tug_dynamics.ship_file import load_ship, ship_config
    from tug_dynamics.environment_loads import VesselInEnvironment
    from sea_environment.environment import Environment
    env = Environment.from_mapping({"wind": {"speed_kn": 15.0, "from_deg": 250.0},
                                    "current": {"speed_kn": 1.0, "towards_deg": 80.0}, "depth": 20.0})
    from tug_dynamics.vessel import VesselState
    vessels = []
    for _, f, x, y, order in FLEET:
        state = VesselState.at_rest(x, y)
        state.linear_velocity_body[0] = KNOTS_6
        v = load_ship(f, initial_state=state)
        VesselInEnvironment(v, env)         # from now on every step feels the environment
        vessels.append(v)
    hulls = {n: SectionalAreaCurve.from_ship_config(ship_config(f)[1]) for n, f, *_ in FLEET}
    pairs = [PairEntry(f"{a[0]}_{b[0]}", a[0], b[0]) for a, b in itertools.combinations(FLEET, 2)]
    states = {n: PlanarState(x, y, 0.0, KNOTS_6, 0.0) for n, _, x, y, _ in FLEET}

    def vessel_step():
        for v in vessels:
            v.step(dt, [])

    def interactions_at(depth):
        interactions = InteractionSet(hulls, pairs, depth=depth)

        def interaction_step():
            interactions.loads(states, 1.5 * dt)
        return interaction_step

    fns = (vessel_step, interactions_at(math.inf), interactions_at(20.0))
    for fn in fns:
        _block(fn, 50)
    times = {fn: [] for fn in fns}
    for _ in range(repeats):
        for fn in fns:
            times[fn].append(_block(fn, n))
    return tuple(float(np.median(times[fn])) for fn in fns)


def run_cpu_ms(path: str, duration: float, layout: str, tmp: str) -> float:
    cmd = ["ros2", "run", "scenario_runner", "run_scenario", path, "--duration", str(duration), "--quiet",
           "--layout", layout, "--no-record", "--output", os.path.join(tmp, "bench.mcap")]
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=3600)
    if out.returncode != 0:
        sys.exit(f"benchmark run failed: {' '.join(cmd)}\n{out.stderr[-2000:]}")
    return float(CPU.search(out.stdout)["cpu"])


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--duration", type=float, default=30.0, help="simulated seconds per run")
    p.add_argument("--rate", type=float, default=20.0, help="exchange rate, Hz")
    p.add_argument("--repeats", type=int, default=2, help="runs per configuration (the table gives medians)")
    p.add_argument("--layouts", default="one_process,processes")
    p.add_argument("--model-only", action="store_true")
    a = p.parse_args(argv)
    vessels_us, deep_us, shallow_us = model_costs(1.0 / a.rate)
    print("| six vessels, 15 pairs | us per step | ratio to the vessels' step |\n|---|---|---|")
    print(f"| model: six Vessel.step with environment (h = 20 m, wind, current) | {vessels_us:.0f} | 1 |")
    for label, us in (("deep water", deep_us), ("h = 20 m", shallow_us)):
        print(f"| model: the 15 pairs' interaction (30 Wang loads, {label}) | {us:.0f} | {us / vessels_us:.2f} |")
    if a.model_only:
        return
    with tempfile.TemporaryDirectory() as tmp:
        paths = {}
        for with_pairs in (False, True):
            name = f"bench_fleet_{'pairs' if with_pairs else 'alone'}"
            paths[with_pairs] = os.path.join(tmp, name + ".yaml")
            with open(paths[with_pairs], "w") as f:
                yaml.safe_dump(fleet_scenario(name, with_pairs, a.duration, a.rate), f)
        layouts = a.layouts.split(",")
        cpu = {(lay, w): [] for lay in layouts for w in (False, True)}
        for _ in range(a.repeats):
            for key in cpu:
                cpu[key].append(run_cpu_ms(paths[key[1]], a.duration, key[0], tmp))
        print("\n| run, no recording, median of %d | CPU ms per step, all processes | with the 15 pairs | added |"
              % a.repeats)
        print("|---|---|---|---|")
        for lay in layouts:
            alone, both = statistics.median(cpu[(lay, False)]), statistics.median(cpu[(lay, True)])
            print(f"| six vessels, layout {lay} | {alone:.2f} | {both:.2f} | {100.0 * (both / alone - 1.0):+.0f} % |")


if __name__ == "__main__":
    main()
