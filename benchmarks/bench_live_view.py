"""Live-view cost (issue 16): real-time factor of the default demo (lockstep, every node its own
process, recorded) without the live view, with `--live` and one client, and with `--live` and
ten clients, each client a Foxglove-protocol WebSocket client subscribed to every channel and
reading all along (live_view.probe, as a browser would).

    source scripts/ensure_env.sh && python benchmarks/bench_live_view.py [--duration 120] [--repeats 3]

The configurations run --repeats times, rounds interleaved (the machine's speed drifts within
minutes); the table gives the median real-time factor, the slowdown against the run without
live view, and the messages the first client received. Prints a markdown table (the README's).
"""
import argparse
import asyncio
import os
import re
import socket
import statistics
import subprocess
import sys
import tempfile
import threading

ROW = re.compile(r"simulated in (?P<wall>[\d.]+) s wall \((?P<rtf>[\d.]+)x real time")


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def clients(port: int, n: int, stop: threading.Event, received: list) -> None:
    from live_view.probe import Probe

    async def main():
        probes = [Probe(f"ws://127.0.0.1:{port}") for _ in range(n)]
        for p in probes:
            await p.connect(timeout=120)
            await p.wait_for_topics(["/tug/odom", "/tf"], timeout=120)
            await p.subscribe_all()

        async def read(p):
            while not stop.is_set():
                try:
                    await p.receive(0.2)
                except Exception:  # noqa: BLE001 - the server went away at the end of the run
                    return
        await asyncio.gather(*(read(p) for p in probes))
        received.append(sum(len(m) for m in probes[0].messages.values()))
        for p in probes:
            try:
                await p.close()
            except Exception:  # noqa: BLE001
                pass
    asyncio.run(main())


def run(duration: float, n_clients: int, tmp: str):
    cmd = ["ros2", "run", "scenario_runner", "run_scenario", "default_demo.yaml", "--duration", str(duration),
           "--quiet", "--output", os.path.join(tmp, "bench.mcap")]
    stop, received, thread = threading.Event(), [], None
    if n_clients:
        port = free_port()
        cmd += ["--live", "--live-port", str(port)]
        thread = threading.Thread(target=clients, args=(port, n_clients, stop, received), daemon=True)
        thread.start()
    out = subprocess.run(cmd, capture_output=True, text=True)
    stop.set()
    if thread is not None:
        thread.join(30)
    m = ROW.search(out.stdout)
    if out.returncode != 0 or not m:
        sys.exit(f"run failed ({out.returncode}):\n{out.stdout}\n{out.stderr[-3000:]}")
    return float(m["rtf"]), (received[0] if received else 0)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--duration", type=float, default=120.0, help="simulated seconds of the default demo")
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    configs = [("no live view", 0), ("--live, 1 client", 1), ("--live, 10 clients", 10)]
    rtf = {c: [] for c, _ in configs}
    msgs = {c: [] for c, _ in configs}
    with tempfile.TemporaryDirectory() as tmp:
        for r in range(args.repeats):
            for name, n in configs:
                x, k = run(args.duration, n, tmp)
                rtf[name].append(x)
                msgs[name].append(k)
                print(f"round {r + 1}: {name}: {x:.1f}x real time, first client received {k} messages",
                      file=sys.stderr)
    base = statistics.median(rtf["no live view"])
    print(f"default demo, {args.duration:g} s simulated, lockstep, processes, recorded; median of {args.repeats}\n")
    print("| configuration | real-time factor | slower than without | messages to the first client |")
    print("|---|---|---|---|")
    for name, _ in configs:
        x = statistics.median(rtf[name])
        print(f"| {name} | {x:.1f}x | {100 * (1 - x / base):+.1f} % | {int(statistics.median(msgs[name]))} |")


if __name__ == "__main__":
    main()
