#!/usr/bin/env python3
"""Benchmark: a harbour in real time on two cores (issue 34's acceptance). Not a test.

Through the real runner (`ros2 run scenario_runner run_scenario`, recorded), with bench_scale's
measurement (its scenarios: n copies of the default demo's tow, 300 m apart; its summary
parsing, CPU of all processes, other processes' load):

1. paced at 50 Hz, --steps (1500) steps, --repeats (3) each: the berthing scenario
   (harbour_berthing_s175.yaml) and 8 tows in the default layout, 4 tows with every node its own
   process (--layout processes): overruns (steps finished after their deadline) and lateness p99;
2. lockstep, the default demo: real-time factor in the default layout against --layout
   one_process (runs in turn, --repeats each; the ratio of medians);
3. lockstep, 1, 2, 4 and 8 tows in the default layout: CPU per step per tow.

Usage (from the repository, environment sourced: source scripts/ensure_env.sh):
    python benchmarks/bench_harbour.py [--repeats 3] [--steps 1500] [--only paced,rtf,cpu]
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile

import yaml

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_scale import run, scale_scenario, template  # noqa: E402 - the same runs and parsing

BERTHING = "harbour_berthing_s175.yaml"


def _scenario(folder: str, name: str, doc: dict) -> str:
    path = os.path.join(folder, f"{name}.yaml")
    with open(path, "w") as f:
        yaml.safe_dump(doc, f, sort_keys=False)
    return path


def _berthing(folder: str):
    from scenario_format.particulars import scenario_path
    try:
        doc = yaml.safe_load(open(scenario_path(BERTHING)))
    except (OSError, ValueError):
        return None
    doc["mode"] = "realtime"
    base = os.path.dirname(scenario_path(BERTHING))   # a depth grid named relative to the scenario
    grid = doc.get("environment", {}).get("depth")
    if isinstance(grid, dict) and "grid" in grid and not os.path.isabs(grid["grid"]):
        grid["grid"] = os.path.join(base, grid["grid"])
    return _scenario(folder, "berthing_paced", doc)


def paced(args, folder, env) -> None:
    base = template()
    cases = [("berthing", "groups", _berthing(folder)),
             ("8 tows", "groups", _scenario(folder, "tows8", scale_scenario(base, 8, "realtime"))),
             ("4 tows", "processes", _scenario(folder, "tows4", scale_scenario(base, 4, "realtime")))]
    print(f"| paced 50 Hz, {args.steps} steps, recorded | layout | overruns per run | lateness p99 ms | "
          "CPU per step ms | other load, cores |\n|---|---|---|---|---|---|")
    for name, layout, path in cases:
        if path is None:
            print(f"| {name} | {layout} | (no {BERTHING}) | | | |")
            continue
        runs = [run(path, args.steps / 50.0, folder, True, env, layout=layout) for _ in range(args.repeats)]
        over = ", ".join(str(r["over"]) for r in runs)
        late = ", ".join(f"{r['late']:.2f}" for r in runs)
        other = ", ".join(f"{r['foreign_cores']:.2f}" for r in runs)
        cpu = statistics.median(r["cpu_ms"] for r in runs)
        print(f"| {name} | {layout} | {over} | {late} | {cpu:.2f} | {other} |", flush=True)
        for r in runs:
            if r["which"]:
                print(f"  ({name}: overrun {r['which']})", file=sys.stderr, flush=True)


def rtf(args, folder, env) -> None:
    path = _scenario(folder, "demo_lockstep", {**template(), "mode": "lockstep"})
    got = {"groups": [], "one_process": []}
    for _ in range(args.repeats):
        for layout in got:
            got[layout].append(run(path, args.lockstep_seconds, folder, True, env, layout=layout))
    print(f"\n| default demo, lockstep, {args.lockstep_seconds:g} s, recorded | real-time factor (runs) | median | "
          "CPU per step ms |\n|---|---|---|---|")
    for layout, runs in got.items():
        factors = ", ".join(f"{r['rtf']:.1f}" for r in runs)
        print(f"| {layout} | {factors} | "
              f"{statistics.median(r['rtf'] for r in runs):.1f} | {statistics.median(r['cpu_ms'] for r in runs):.2f} |")
    ratio = statistics.median(r["rtf"] for r in got["groups"]) / statistics.median(r["rtf"] for r in got["one_process"])
    print(f"\ngroups / one_process real-time factor: {ratio:.2f}")


def cpu_per_tow(args, folder, env) -> None:
    base = template()
    print(f"\n| tows, lockstep {args.lockstep_seconds:g} s, groups | real-time factor | CPU per step ms | "
          "CPU per step per tow ms |\n|---|---|---|---|")
    first = None
    for n in (1, 2, 4, 8):
        path = _scenario(folder, f"lock{n}", scale_scenario(base, n, "lockstep"))
        runs = [run(path, args.lockstep_seconds, folder, True, env, layout="groups") for _ in range(args.repeats)]
        cpu = statistics.median(r["cpu_ms"] for r in runs)
        first = first or cpu
        print(f"| {n} | {statistics.median(r['rtf'] for r in runs):.1f} | {cpu:.2f} | {cpu / n:.2f} "
              f"({cpu / n / first:.2f} of 1 tow) |", flush=True)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--steps", type=int, default=1500, help="paced steps per run (default 1500 = 30 s)")
    ap.add_argument("--lockstep-seconds", type=float, default=30.0)
    ap.add_argument("--only", default="paced,rtf,cpu")
    args = ap.parse_args()
    env = dict(os.environ)
    env.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    parts = {"paced": paced, "rtf": rtf, "cpu": cpu_per_tow}
    with tempfile.TemporaryDirectory() as folder:
        for part in args.only.split(","):
            parts[part](args, folder, env)
    return 0


if __name__ == "__main__":
    sys.exit(main())
