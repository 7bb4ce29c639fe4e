"""Studies benchmark (issue 35): runs per hour of a study on the embedded LocalCluster with 1 and 2
workers, and the overhead per run over a bare run_scenario of the same runs.

    source scripts/ensure_env.sh && python benchmarks/bench_studies.py [--runs 4] [--duration 10]

The study sweeps the default demo's first engine order over --runs values, each run --duration s
simulated. The bare runs are the same scenarios made one after another by run_scenario (one
process layout, a reserved domain), without analyze. Overhead per run = (a 1-worker study's
wall time - the bare runs' wall time) / runs: the cluster's start, analyze, Dask's hand-over.
Prints a markdown table and the 1-minute load average (other work on the machine slows both).
"""
import argparse
import os
import subprocess
import sys
import tempfile
import time

import numpy as np


def study_file(folder: str, runs: int, duration: float) -> str:
    orders = ", ".join(f"{v:.3f}" for v in np.linspace(0.05, 0.6, runs))
    path = os.path.join(folder, "bench.yaml")
    with open(path, "w") as f:
        f.write(f"name: bench\nscenario: default_demo.yaml\nduration: {duration}\n"
                f"axes:\n  - key: events[0].engine_order\n    values: [{orders}]\n"
                f"measures:\n  peak_tension: ropes.towline.tension_a_max\n")
    return path


def bare_runs(plan, folder: str, duration: float) -> float:
    import yaml
    from domain_coordinator import domain_id
    from studies.one_run import run_command
    start = time.monotonic()
    for r in plan.runs:
        path = os.path.join(folder, f"{r.run}.yaml")
        with open(path, "w") as f:
            yaml.safe_dump(r.scenario, f, sort_keys=False)
        with domain_id() as did:
            env = dict(os.environ, ROS_DOMAIN_ID=str(did), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST",
                       TUGSIM_DOMAIN_CHECK_WAIT="0.5")
            subprocess.run(run_command(path, os.path.join(folder, f"{r.run}.mcap"), duration), env=env, check=True,
                           capture_output=True)
    return time.monotonic() - start


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--runs", type=int, default=4)
    p.add_argument("--duration", type=float, default=10.0)
    args = p.parse_args()
    from studies.study import run_study
    from studies.study_file import plan_study
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        path = study_file(folder, args.runs, args.duration)
        plan = plan_study(path, os.path.join(folder, "check"))
        bare = bare_runs(plan, folder, args.duration)
        rows.append(("bare run_scenario, one after another", bare))
        for workers in (1, 2):
            start = time.monotonic()
            result = run_study(path, os.path.join(folder, f"out{workers}"), workers=workers, say=lambda s: None,
                               progress=False)
            assert result.failed == 0, result.table["message"].tolist()
            rows.append((f"study, {workers} worker(s)", time.monotonic() - start))
    print(f"{args.runs} runs of the default demo, {args.duration:g} s each; load average "
          f"{os.getloadavg()[0]:.1f} on {os.cpu_count()} cores\n")
    print("| | wall s | runs per hour |\n|---|---|---|")
    for name, wall in rows:
        print(f"| {name} | {wall:.1f} | {3600 * args.runs / wall:.0f} |")
    print(f"\noverhead per run of a 1-worker study over bare run_scenario: {(rows[1][1] - bare) / args.runs:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
