"""Several-hosts benchmark (issue 20): the default demo paced in real time with the runner and
every node on its own host (scripts/hosts_harness.py: network namespaces, the runner driving the
nodes with --external all), over links of 0 and 1 ms one-way delay and 0 and 1 % loss, beside
the same run on one host. Reports the runner's own measures: overrun steps, lateness p99, step
round trip p50 / p99. Needs root and nft.

    source scripts/ensure_env.sh && python benchmarks/bench_multi_host.py [--duration 60] [--repeats 3]

Every configuration runs --repeats times, the rounds interleaved (the machine's speed drifts),
and the table gives the median of each column, with the 1-minute load average around the runs
(other work on the machine shows up as overruns). Prints a markdown table. Lateness is how far
behind its wall-clock time a step was sent; an overrun is a step whose answers came after the
next step's time (docs/step-protocol.md). The 1 ms links go through the harness's user-space
switch (this kernel has no netem), which adds about 0.5 ms per packet of its own (ping-pong
round trip over 1 ms links 3.4 ms, over the bridge 0.5 ms).
"""
import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scripts"))
import hosts_harness  # noqa: E402

ROW = re.compile(r"simulated in (?P<wall>[\d.]+) s wall \((?P<rtf>[\d.]+)x real time, (?P<steps>\d+) steps")
RT = re.compile(r"round trip: p50 (?P<p50>[\d.]+) ms, p99 (?P<p99>[\d.]+) ms")
LATE = re.compile(r"realtime: (?P<over>\d+) overrun step\(s\)(?: \((?P<which>[^)]*)\))?; lateness p99 (?P<late>[\d.]+) ms")


def parse(stdout: str) -> dict:
    m, r, late = ROW.search(stdout), RT.search(stdout), LATE.search(stdout)
    return dict(steps=int(m["steps"]), rtf=float(m["rtf"]), p50=float(r["p50"]), p99=float(r["p99"]),
                over=int(late["over"]), late=float(late["late"]))


def runner_cmd(scenario: str, duration: float, out: str, *extra: str):
    return ["ros2", "run", "scenario_runner", "run_scenario", scenario, "--duration", str(duration), "--quiet",
            "--output", out, *extra]


def one_host(scenario, duration, tmp, domain):
    env = dict(os.environ, ROS_DOMAIN_ID=str(domain), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
    out = subprocess.run(runner_cmd(scenario, duration, os.path.join(tmp, "one.mcap")), env=env,
                         capture_output=True, text=True, timeout=3600)
    if out.returncode:
        sys.exit(f"one-host run failed:\n{out.stderr}")
    return parse(out.stdout), None


def hosts_run(scenario, duration, tmp, domain, loss, delay):
    from scenario_runner import run_nodes
    from scenario_format.scenario import load_scenario
    specs = run_nodes.node_specs(load_scenario(scenario), scenario, "")
    with hosts_harness.Hosts(["runner"] + [s.namespace.strip("/") for s in specs], loss_percent=loss,
                             delay_ms=delay) as hosts:
        env = hosts.env(ROS_DOMAIN_ID=str(domain))
        hosts_harness.start_nodes(hosts, specs, env, os.path.join(tmp, "node_logs"))
        out = hosts.run("runner", runner_cmd(scenario, duration, os.path.join(tmp, "hosts.mcap"), "--external", "all"),
                        env=env, capture_output=True, text=True, timeout=3600)
        dropped = sum(hosts.dropped().values())
    if out.returncode:
        sys.exit(f"run over hosts (loss {loss} %, delay {delay} ms) failed:\n{out.stderr}")
    return parse(out.stdout), dropped


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--duration", type=float, default=60.0, help="simulated (= wall) seconds per run")
    p.add_argument("--scenario", default="default_demo.yaml")
    p.add_argument("--domain", type=int, default=77, help="ROS_DOMAIN_ID of the runs")
    p.add_argument("--repeats", type=int, default=1, help="runs per configuration (the table gives medians)")
    args = p.parse_args()
    why = hosts_harness.available()
    if why:
        sys.exit(f"bench_multi_host: {why}")
    import yaml
    from ament_index_python.packages import get_package_share_directory
    src = os.path.join(get_package_share_directory("scenario_runner"), "scenarios", args.scenario)
    sc = yaml.safe_load(open(src))
    sc.update(mode="realtime", name=sc["name"] + "_paced")
    configs = [("one host (loopback, shared memory)", lambda s, t: one_host(s, args.duration, t, args.domain)),
               ("hosts, bridge, 0 % loss", lambda s, t: hosts_run(s, args.duration, t, args.domain, 0.0, 0.0)),
               ("hosts, 1 ms links, 0 % loss", lambda s, t: hosts_run(s, args.duration, t, args.domain, 0.0, 1.0)),
               ("hosts, 1 ms links, 1 % loss", lambda s, t: hosts_run(s, args.duration, t, args.domain, 1.0, 1.0))]
    results = {name: [] for name, _fn in configs}
    loads = []
    with tempfile.TemporaryDirectory() as tmp:
        paced = os.path.join(tmp, "paced.yaml")
        with open(paced, "w") as f:
            yaml.safe_dump(sc, f)
        for _round in range(args.repeats):
            for name, fn in configs:
                r, dropped = fn(paced, tmp)
                r["dropped"] = dropped
                results[name].append(r)
                loads.append(os.getloadavg()[0])
                print(f"{name}: {r} (load {loads[-1]:.1f})", file=sys.stderr, flush=True)
    rows = []
    for name, runs in results.items():
        med = {k: statistics.median(r[k] for r in runs) for k in runs[0] if k != "dropped"}
        dropped = None if runs[0]["dropped"] is None else statistics.median(r["dropped"] for r in runs)
        rows.append((name, med, dropped))
    print(f"\n1-minute load average after the runs: {min(loads):.1f} - {max(loads):.1f} ({os.cpu_count()} CPUs)")
    print(f"\n| {args.scenario}, paced real time, {args.duration:g} s at {sc.get('exchange_rate', 50)} Hz, "
          f"median of {args.repeats} | steps | "
          "overruns | lateness p99 ms | round trip p50 ms | round trip p99 ms | packets dropped |")
    print("|---|---|---|---|---|---|---|")
    for name, r, dropped in rows:
        print(f"| {name} | {r['steps']:.0f} | {r['over']:.0f} | {r['late']:.2f} | {r['p50']:.2f} | {r['p99']:.2f} | "
              f"{'-' if dropped is None else f'{dropped:.0f}'} |")


if __name__ == "__main__":
    main()
