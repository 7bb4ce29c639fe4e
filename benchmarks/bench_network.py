"""Node-network benchmark (issue 6): real-time factor of the default demo in lockstep with every
node in its own process and with all nodes in one process, for both rclpy executors; step
round-trip latency (p50, p99); paced real time with its lateness (p99) and overruns.

    source scripts/ensure_env.sh && python benchmarks/bench_network.py [--duration 60]

Prints a markdown table (the README's). Wall-clock numbers depend on the machine's load:
compare rows of one run, not runs of different days.
"""
import argparse
import os
import re
import resource
import subprocess
import sys
import tempfile

ROW = re.compile(r"simulated in (?P<wall>[\d.]+) s wall \((?P<rtf>[\d.]+)x real time, (?P<steps>\d+) steps")
RT = re.compile(r"round trip: p50 (?P<p50>[\d.]+) ms, p99 (?P<p99>[\d.]+) ms")
LATE = re.compile(r"realtime: (?P<over>\d+) overrun step\(s\); lateness p99 (?P<late>[\d.]+) ms")


def run(scenario, duration, layout, executor, record, tmp, extra_env=None):
    env = dict(os.environ, TUGSIM_EXECUTOR=executor, **(extra_env or {}))
    cmd = ["ros2", "run", "scenario_runner", "run_scenario", scenario, "--duration", str(duration), "--quiet",
           "--layout", layout, "--output", os.path.join(tmp, "bench.mcap")]
    if not record:
        cmd.append("--no-record")
    cpu0 = _children_cpu()
    out = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=3600)
    cpu = _children_cpu() - cpu0
    if out.returncode != 0:
        sys.exit(f"benchmark run failed: {' '.join(cmd)}\n{out.stderr}")
    m, r = ROW.search(out.stdout), RT.search(out.stdout)
    late = LATE.search(out.stdout)
    return dict(rtf=float(m["rtf"]), p50=float(r["p50"]), p99=float(r["p99"]), cpu=cpu, steps=int(m["steps"]),
                over=int(late["over"]) if late else None, late=float(late["late"]) if late else None)


def _children_cpu() -> float:
    """CPU seconds (user + system) of every finished descendant (the runner waits for its nodes)."""
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    return ru.ru_utime + ru.ru_stime


def run_cpu_per_step(scenario, duration, layout, executor, record, tmp):
    """run() plus the CPU ms per step of all processes, start-up excluded."""
    short = run(scenario, 2.0, layout, executor, record, tmp)
    res = run(scenario, duration, layout, executor, record, tmp)
    res["cpu_ms"] = 1e3 * (res["cpu"] - short["cpu"]) / (res["steps"] - short["steps"])
    return res


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--duration", type=float, default=60.0, help="simulated seconds per run")
    p.add_argument("--scenario", default="default_demo.yaml")
    args = p.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for layout in ("processes", "one_process"):
            for executor in ("events", "single"):
                for record in (True, False):
                    res = run_cpu_per_step(args.scenario, args.duration, layout, executor, record, tmp)
                    rows.append((f"lockstep, {layout}, {executor} executor, {'recording' if record else 'no recording'}",
                                 res))
        # paced real time: a copy of the scenario with mode realtime
        import yaml
        from ament_index_python.packages import get_package_share_directory
        src = os.path.join(get_package_share_directory("scenario_runner"), "scenarios", args.scenario)
        sc = yaml.safe_load(open(src))
        sc.update(mode="realtime", name=sc["name"] + "_paced")
        paced = os.path.join(tmp, "paced.yaml")
        with open(paced, "w") as f:
            yaml.safe_dump(sc, f)
        rows.append(("realtime (paced), processes, events executor, recording",
                     run_cpu_per_step(paced, min(args.duration, 30.0), "processes", "events", True, tmp)))
    print(f"| {args.scenario}, {args.duration:g} s simulated at 50 Hz | real-time factor | round trip p50 ms | "
          "round trip p99 ms | CPU ms per step, all processes | realtime: overruns, lateness p99 ms |")
    print("|---|---|---|---|---|---|")
    for label, r in rows:
        late = f"{r['over']}, {r['late']:.2f}" if r["over"] is not None else "-"
        print(f"| {label} | {r['rtf']:.1f}x | {r['p50']:.2f} | {r['p99']:.2f} | {r['cpu_ms']:.2f} | {late} |")


if __name__ == "__main__":
    main()
