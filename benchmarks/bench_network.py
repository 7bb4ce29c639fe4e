"""Node-network benchmark (issue 6): real-time factor of the default demo in lockstep with every
node in its own process and with all nodes in one process, for both rclpy executors; step
round-trip latency (p50, p99); CPU per step of all processes; paced real time with its
lateness (p99) and overruns.

    source scripts/ensure_env.sh && python benchmarks/bench_network.py [--duration 60] [--repeats 3]

Every configuration runs --repeats times, the rounds interleaved (the machine's speed drifts
within minutes), and the table gives the median of each column. Prints a markdown table (as in
docs/benchmarks.md). "CPU per step" is what the runner measures itself: user + system time of the runner
and every node process from step 0 to the last step (start-up excluded), divided by the steps.
"""
import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile

ROW = re.compile(r"simulated in (?P<wall>[\d.]+) s wall \((?P<rtf>[\d.]+)x real time, (?P<steps>\d+) steps")
RT = re.compile(r"round trip: p50 (?P<p50>[\d.]+) ms, p99 (?P<p99>[\d.]+) ms")
CPU = re.compile(r"CPU per step, all processes: (?P<cpu>[\d.]+) ms")
LATE = re.compile(r"realtime: (?P<over>\d+) overrun step\(s\)(?: \((?P<which>[^)]*)\))?; lateness p99 (?P<late>[\d.]+) ms")


def run(scenario, duration, layout, executor, record, tmp):
    env = dict(os.environ, TUGSIM_EXECUTOR=executor)
    cmd = ["ros2", "run", "scenario_runner", "run_scenario", scenario, "--duration", str(duration), "--quiet",
           "--layout", layout, "--output", os.path.join(tmp, "bench.mcap")]
    if not record:
        cmd.append("--no-record")
    out = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=3600)
    if out.returncode != 0:
        sys.exit(f"benchmark run failed: {' '.join(cmd)}\n{out.stderr}")
    m, r, c = ROW.search(out.stdout), RT.search(out.stdout), CPU.search(out.stdout)
    late = LATE.search(out.stdout)
    return dict(rtf=float(m["rtf"]), p50=float(r["p50"]), p99=float(r["p99"]), cpu_ms=float(c["cpu"]),
                over=int(late["over"]) if late else None, late=float(late["late"]) if late else None)


def median_row(results):
    keys = results[0].keys()
    return {k: (statistics.median(r[k] for r in results) if results[0][k] is not None else None) for k in keys}


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--duration", type=float, default=60.0, help="simulated seconds per run")
    p.add_argument("--repeats", type=int, default=3, help="runs per configuration (the table gives medians)")
    p.add_argument("--scenario", default="default_demo.yaml")
    args = p.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        # paced real time: a copy of the scenario with mode realtime
        import yaml
        from ament_index_python.packages import get_package_share_directory
        src = os.path.join(get_package_share_directory("scenario_runner"), "scenarios", args.scenario)
        sc = yaml.safe_load(open(src))
        sc.update(mode="realtime", name=sc["name"] + "_paced")
        paced = os.path.join(tmp, "paced.yaml")
        with open(paced, "w") as f:
            yaml.safe_dump(sc, f)
        configs = [(f"lockstep, {layout}, {executor} executor, {'recording' if record else 'no recording'}",
                    (args.scenario, args.duration, layout, executor, record))
                   for layout in ("processes", "one_process") for executor in ("events", "single")
                   for record in (True, False)]
        configs.append(("realtime (paced), processes, events executor, recording",
                        (paced, min(args.duration, 30.0), "processes", "events", True)))
        results = {label: [] for label, _ in configs}
        for _ in range(args.repeats):
            for label, cfg in configs:
                results[label].append(run(*cfg, tmp))
        rows = [(label, median_row(results[label])) for label, _ in configs]
    print(f"| {args.scenario}, {args.duration:g} s simulated at 50 Hz, median of {args.repeats} | real-time factor | "
          "round trip p50 ms | "
          "round trip p99 ms | CPU ms per step, all processes | realtime: overruns, lateness p99 ms |")
    print("|---|---|---|---|---|---|")
    for label, r in rows:
        late = f"{r['over']:g}, {r['late']:.2f}" if r["over"] is not None else "-"
        print(f"| {label} | {r['rtf']:.1f}x | {r['p50']:.2f} | {r['p99']:.2f} | {r['cpu_ms']:.2f} | {late} |")


if __name__ == "__main__":
    main()
