#!/usr/bin/env python3
"""Benchmark: what one exchange step costs in DDS deliveries (issue 34 item 2). Not a test.

A delivery is one message handed to one DDS reader. For a scenario, per topic: the messages a
step publishes (from a recording of --seconds: the MCAP's message count over the steps) times
the readers the ROS graph shows on that topic once the run steps (read by an observer node the
runner adds to its own executor, so it is no stranger; it reads nothing). The recorder is not
counted (it takes the nodes' messages from their pipes, not from DDS); nor are the private step
channels (a socket write each, no DDS).

Usage (from the repository, environment sourced: source scripts/ensure_env.sh):
    python benchmarks/bench_deliveries.py [--scenario default_demo.yaml] [--seconds 4] [--layout processes]
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile


def _counts_per_step(scenario: str, seconds: float, folder: str, rate: float) -> dict:
    from mcap.reader import make_reader
    out = os.path.join(folder, "counts.mcap")
    subprocess.run(["ros2", "run", "scenario_runner", "run_scenario", scenario, "--duration", str(seconds),
                    "--layout", "one_process", "--quiet", "--output", out], check=True, capture_output=True,
                   cwd=folder, timeout=600)
    with open(out, "rb") as f:
        summary = make_reader(f).get_summary()
    steps = seconds * rate
    return {summary.channels[c].topic: n / steps for c, n in summary.statistics.channel_message_counts.items()}


def _readers(scenario: str, layout: str, folder: str) -> dict:
    """topic -> the readers in the graph at step 50 (the observer itself excluded)."""
    from rclpy.node import Node
    from scenario_format.particulars import scenario_path
    from scenario_format.scenario import load_scenario
    from scenario_runner import conductor as cd
    from sim_plumbing import ros_common as rc
    rc.init_rclpy()
    observer = Node("delivery_count")
    seen = {}

    def on_step(k: int) -> None:
        if k == 50:
            for topic, _types in observer.get_topic_names_and_types():
                seen[topic] = len(observer.get_subscriptions_info_by_topic(topic))
    path = scenario_path(scenario)
    sc = load_scenario(path)
    cd.run(sc, path, os.path.join(folder, "logs"), steps=100, extra_nodes=[observer], layout=layout, on_step=on_step)
    return seen


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", default="default_demo.yaml")
    ap.add_argument("--seconds", type=float, default=4.0, help="recorded seconds for the message counts")
    ap.add_argument("--layout", default="processes")
    args = ap.parse_args()
    from scenario_format.particulars import scenario_path
    from scenario_format.scenario import load_scenario
    rate = load_scenario(scenario_path(args.scenario)).exchange_rate
    with tempfile.TemporaryDirectory() as folder:
        per_step = _counts_per_step(args.scenario, args.seconds, folder, rate)
        readers = _readers(args.scenario, args.layout, folder)
    rows = sorted(((per_step[t] * readers.get(t, 0), t) for t in per_step), reverse=True)
    print(f"| topic | messages per step | readers | deliveries per step |\n|---|---|---|---|")
    for d, t in rows:
        if d > 0:
            print(f"| {t} | {per_step[t]:.2f} | {readers.get(t, 0)} | {d:.2f} |")
    print(f"| **all** | {sum(per_step.values()):.1f} | | **{sum(d for d, _ in rows):.1f}** |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
