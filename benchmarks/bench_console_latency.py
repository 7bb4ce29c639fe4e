"""Console latency (issue 17, item 5): from a key press in the terminal console to the order
applied by the vessel, in a paced (realtime) run at 50 Hz.

    source scripts/ensure_env.sh && flock /tmp/bench.lock python benchmarks/bench_console_latency.py \
        [--presses 250] [--runs 1]

The default demo (tug, barge, towline; every node its own process, recorded) is run paced in
real time (mode: realtime, its events after t = 0 left out so that only the console orders the
tug). The console (`ros2 run bridge_instruments console tug`) runs in a pseudo-terminal
(pexpect), as a person would use it; the benchmark presses engine and helm keys at random
intervals of 0.12-0.2 s (so the presses fall at every phase of the 20 ms step), cycling
w, d, s, a (each press changes exactly one order). Its own ROS node listens to /clock,
/tug/command and /tug/status. Per press:

- key -> command: wall time from writing the key to the pty until the console's VesselCommand
  arrives at the benchmark (Textual's input, the console's handler, DDS);
- key -> applied: the vessel applies an order from the first step whose status carries it: the
  status stamped s shows the order used from step s-1, which the runner starts at wall time
  start + (s-1) T. Latency = (s-1) T - (the key's wall time - start), with start taken from
  /clock (the lower envelope of arrival time - clock stamp). In steps of T = 20 ms and in ms;
- key -> status seen: wall time until that status reaches a subscriber (what a screen shows).

Prints a markdown table (p50 / p95 / p99 / max) and the runner's realtime summary line. The
goal is a p99 under two steps from key to applied.
"""
import argparse
import math
import os
import random
import subprocess
import sys
import tempfile
import threading
import time

STEP_S = 0.02  # 50 Hz
KEYS = ["w", "d", "s", "a"]  # engine +0.1, helm 5 deg starboard, engine -0.1, helm 5 deg port


def scenario(tmp: str, duration: float) -> str:
    import yaml
    from ament_index_python.packages import get_package_share_directory
    share = get_package_share_directory("scenario_runner")
    sc = yaml.safe_load(open(f"{share}/scenarios/default_demo.yaml"))
    sc.update(name="console_latency", mode="realtime", duration=duration, exchange_rate=1.0 / STEP_S)
    sc["events"] = [e for e in sc["events"] if e["time"] == 0.0]
    path = os.path.join(tmp, "console_latency.yaml")
    with open(path, "w") as f:
        yaml.safe_dump(sc, f)
    return path


class Listener:
    """/clock, /tug/command and /tug/status with their arrival times (time.monotonic)."""

    def __init__(self):
        import rclpy
        from rclpy.qos import QoSProfile, ReliabilityPolicy
        from rosgraph_msgs.msg import Clock
        from tug_msgs.msg import VesselCommand, VesselStatus
        from sim_plumbing import ros_common as rc
        rclpy.init()
        self.rclpy = rclpy
        self.node = rclpy.create_node("console_latency_bench")
        self.clock_offset = math.inf  # min over /clock of (arrival - clock stamp): wall time of sim time 0
        self.commands, self.status = [], []
        self.node.create_subscription(Clock, "/clock", self._on_clock,
                                      QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT))
        self.node.create_subscription(VesselCommand, "/tug/command", self._on_command, rc.COMMAND_SUB_QOS)
        self.node.create_subscription(VesselStatus, "/tug/status", self._on_status, rc.STATE_QOS)
        self.executor = rclpy.executors.SingleThreadedExecutor()
        self.executor.add_node(self.node)
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._spin, daemon=True)
        self.thread.start()

    @staticmethod
    def _t(stamp) -> float:
        return stamp.sec + stamp.nanosec * 1e-9

    def _on_clock(self, m) -> None:
        self.clock_offset = min(self.clock_offset, time.monotonic() - self._t(m.clock))

    def _on_command(self, m) -> None:
        self.commands.append((time.monotonic(), m.engine_order, m.steering_angle))

    def _on_status(self, m) -> None:
        self.status.append((time.monotonic(), round(self._t(m.header.stamp) / STEP_S), m.engine_order,
                            m.steering_angle_ordered))

    def _spin(self) -> None:
        while not self.stop.is_set():
            self.executor.spin_once(timeout_sec=0.05)

    def close(self) -> None:
        self.stop.set()
        self.thread.join(2.0)
        self.node.destroy_node()
        self.rclpy.try_shutdown()


def percentiles(values):
    import numpy as np
    a = np.asarray(values, float)
    return [float(np.percentile(a, p)) for p in (50, 95, 99)] + [float(a.max())]


def one_run(presses: int, tmp: str, seed: int):
    import pexpect
    path = scenario(tmp, duration=presses * 0.16 + 25.0)
    out = os.path.join(tmp, "latency.mcap")
    run = subprocess.Popen(["ros2", "run", "scenario_runner", "run_scenario", path, "--output", out, "--quiet"],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    listener = Listener()
    env = dict(os.environ, TERM="xterm-256color", PYTHONUNBUFFERED="1")
    con = pexpect.spawn("ros2", ["run", "bridge_instruments", "console", "tug", "--scenario", path], env=env,
                        dimensions=(30, 160), encoding="utf-8", codec_errors="replace", timeout=120)
    con.delaybeforesend = None  # pexpect sleeps 50 ms before every send by default: not the console's
    keys = []
    reading = threading.Event()

    def drain():  # the console repaints all the time: keep its pty read so it never blocks on output
        while not reading.is_set() and con.isalive():
            try:
                con.read_nonblocking(65536, timeout=0.05)
            except pexpect.TIMEOUT:
                pass
            except pexpect.EOF:
                return
    try:
        con.expect(r"rate of turn", timeout=120)
        con.expect(r"t +[1-9]\.\d\d s ", timeout=60)
        drainer = threading.Thread(target=drain, daemon=True)
        drainer.start()
        time.sleep(1.5)  # the console takes up the orders the tug holds (no key for 1 s)
        n_before = len(listener.commands)
        rnd = random.Random(seed)
        for i in range(presses):
            key = KEYS[i % len(KEYS)]
            t_key = time.monotonic()
            con.send(key)
            keys.append(t_key)
            time.sleep(rnd.uniform(0.12, 0.2))
        time.sleep(1.0)
        reading.set()
        drainer.join(2.0)
        con.send("q")
        con.expect(pexpect.EOF, timeout=20)
    finally:
        if con.isalive():
            con.terminate(force=True)
        try:
            stdout, stderr = run.communicate(timeout=presses * 0.2 + 120)
        finally:
            if run.poll() is None:
                run.kill()
        listener.close()
    if run.returncode != 0:
        sys.exit(f"run failed ({run.returncode}):\n{stdout}\n{stderr[-3000:]}")
    commands = listener.commands[n_before:]
    if len(commands) != presses:
        sys.exit(f"{presses} keys pressed but {len(commands)} commands seen on /tug/command")
    start = listener.clock_offset
    status = sorted(listener.status, key=lambda s: s[1])
    to_command, to_applied, to_seen = [], [], []
    for t_key, (t_cmd, engine, helm) in zip(keys, commands):
        key_step = (t_key - start) / STEP_S
        match = next((s for s in status if s[1] >= math.floor(key_step) and abs(s[2] - engine) < 1e-9
                      and abs(s[3] - helm) < 1e-9), None)
        if match is None:
            sys.exit(f"the order of the key at step {key_step:.1f} (engine {engine}, helm {helm}) is in no status")
        to_command.append(1e3 * (t_cmd - t_key))
        to_applied.append(match[1] - 1 - key_step)  # steps
        to_seen.append(1e3 * (match[0] - t_key))
    realtime = next((line.strip() for line in stdout.splitlines() if "realtime:" in line), "")
    return to_command, to_applied, to_seen, realtime


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--presses", type=int, default=250, help="key presses per run (default 250)")
    ap.add_argument("--runs", type=int, default=1, help="runs, results pooled (default 1)")
    ap.add_argument("--seed", type=int, default=17)
    args = ap.parse_args()
    from domain_coordinator import domain_id
    to_command, to_applied, to_seen, notes = [], [], [], []
    with domain_id() as did, tempfile.TemporaryDirectory() as tmp:
        os.environ["ROS_DOMAIN_ID"] = str(did)
        for r in range(args.runs):
            c, a, s, rt = one_run(args.presses, tmp, args.seed + r)
            to_command += c
            to_applied += a
            to_seen += s
            notes.append(rt)
            print(f"run {r + 1}: {len(a)} presses, key -> applied p99 {percentiles(a)[2]:.2f} steps; {rt}",
                  file=sys.stderr)
    n = len(to_applied)
    print(f"default_demo.yaml paced in real time at 50 Hz (T = 20 ms), processes, recorded; {n} key presses "
          f"in {args.runs} run(s), {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}\n")
    print("| key press -> | p50 | p95 | p99 | max |")
    print("|---|---|---|---|---|")
    row = lambda name, v, f: print(f"| {name} | " + " | ".join(f(x) for x in percentiles(v)) + " |")  # noqa: E731
    row("command on /tug/command (console: pty, Textual, publish)", to_command, lambda x: f"{x:.1f} ms")
    row("order applied by the vessel (first step computed with it)", to_applied,
        lambda x: f"{x:.2f} steps ({x * STEP_S * 1e3:.1f} ms)")
    row("status showing it at a subscriber", to_seen, lambda x: f"{x / (STEP_S * 1e3):.2f} steps ({x:.1f} ms)")
    print(f"\nrunner: {'; '.join(notes)}")
    p99 = percentiles(to_applied)[2]
    print(f"goal (p99 key -> applied under 2 steps): {'met' if p99 < 2.0 else 'MISSED'} ({p99:.2f} steps)")


if __name__ == "__main__":
    main()
