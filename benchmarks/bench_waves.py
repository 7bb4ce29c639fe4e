#!/usr/bin/env python3
"""Benchmark: what the waves add to a node's step (issue 31's speed goal). Not a test.

Runs the head-seas tow (scenario tow_head_seas: harbour tug, 45 m barge, Table 1 towline;
JONSWAP Hs 2 m, Tp 7 s, cos-2s, 150 components) and its calm twin (the same file with hs 0: no
wave field anywhere) through run_scenario, --layout one_process, for --seconds of simulated
time, the two in turn --repeat times, at each towline discretisation of --elements (the rope's
n_elements). Reads each node's compute time per step (what the node spends from taking a step's
inputs to publishing its outputs: the model step plus the message work, as reported by the runner
from the nodes' StepDone) and prints, per node, the medians calm and in waves and their ratio.
The vessel node's wave work is the compiled response (tug_dynamics.wave_response: RAO
superposition and drift, one pass over the components), the superposition on the published state
and the attachment offsets; the rope's is the Airy kinematics at every element every sub-step
(sea_environment.waves, compiled into the rope kernel).

Usage (from the repository, environment sourced: source scripts/ensure_env.sh):
    python benchmarks/bench_waves.py [--seconds 60] [--repeat 2] [--elements 10,50]
"""
from __future__ import annotations

import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile

import yaml

LINE = re.compile(r"compute per step: (.*)")
ENTRY = re.compile(r"(/[\w/]+) ([\d.]+) ms")


def _scenario_path(name: str) -> str:
    from scenario_format.particulars import scenario_path
    return scenario_path(name)


def _variant(folder: str, hs: float, elements: int) -> str:
    doc = yaml.safe_load(open(_scenario_path("tow_head_seas")))
    doc["environment"]["waves"]["hs"] = hs
    doc["ropes"][0]["n_elements"] = elements
    doc["name"] = f"bench_{'waves' if hs else 'calm'}_{elements}"
    path = os.path.join(folder, doc["name"] + ".yaml")
    with open(path, "w") as f:
        yaml.safe_dump(doc, f)
    return path


def _compute_times(path: str, seconds: float, folder: str, layout: str) -> dict:
    proc = subprocess.run(["ros2", "run", "scenario_runner", "run_scenario", path, "--duration", str(seconds),
                           "--layout", layout, "--quiet", "--no-record"],
                          capture_output=True, text=True, timeout=3600, cwd=folder)
    if proc.returncode != 0:
        sys.exit(f"run_scenario {path} failed (exit {proc.returncode}):\n{proc.stdout[-2000:]}{proc.stderr[-2000:]}")
    match = LINE.search(proc.stdout)
    if not match:
        sys.exit(f"no 'compute per step' line in run_scenario's output:\n{proc.stdout[-2000:]}")
    return {node: float(ms) for node, ms in ENTRY.findall(match.group(1))}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=60.0, help="simulated seconds per run (default 60)")
    ap.add_argument("--repeat", type=int, default=2, help="runs of each, in turn (default 2)")
    ap.add_argument("--elements", default="10,50", help="towline n_elements to time (default 10,50)")
    ap.add_argument("--layout", default="one_process", choices=("one_process", "groups", "processes"),
                    help="run_scenario's node layout (default one_process)")
    args = ap.parse_args()
    print(f"| towline elements | node | calm ms/step | waves ms/step | waves / calm |\n|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as folder:
        for n in (int(e) for e in args.elements.split(",")):
            paths = {"calm": _variant(folder, 0.0, n), "waves": _variant(folder, 2.0, n)}
            times = {"calm": [], "waves": []}
            for _ in range(args.repeat):
                for kind in ("calm", "waves"):
                    times[kind].append(_compute_times(paths[kind], args.seconds, folder, args.layout))
            for node in sorted(times["calm"][0]):
                calm = statistics.median(t[node] for t in times["calm"])
                waves = statistics.median(t[node] for t in times["waves"])
                print(f"| {n} | {node} | {calm:.3f} | {waves:.3f} | {waves / calm:.2f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
