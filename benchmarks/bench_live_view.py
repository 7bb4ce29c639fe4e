"""Live-view cost (issue 16): real-time factor of the default demo (lockstep, every node its own
process, recorded) without the live view and with `--live`: no client, one browser on the
instructor station, one and ten Foxglove-protocol WebSocket clients.

    source scripts/ensure_env.sh && python benchmarks/bench_live_view.py [--duration 120] [--repeats 3]
        [--configs none,live,poll,browser,browser19,burn0.4,ws1,ws10]

- The browser: Debian's headless Chromium (/usr/bin/chromium, driven by Playwright as
  tests/ros/test_instructor_station.py does, software WebGL) loads the instructor station
  (the runner's page, on a free port: `-p live_view:http_port:=...`) as soon as the page
  answers, while the nodes are still starting, and shows the run with the default follow
  camera. It runs on the same two cores as the simulation: at the simulation's priority, and
  (row "nice 19") at the lowest, the nearest this machine comes to a bridge's set-up, where the
  page is on another display machine. Chromium without a GPU renders WebGL in software
  (SwiftShader); the benchmark's Chromium composites in software too (--disable-gpu-compositing,
  a third less CPU than compositing through SwiftShader).
- Two rows without a browser tell its parts apart: "poll", a process that GETs /api/state every
  100 ms as the page does (the runner's side of the page), and "burn0.4", no live view and a
  synthetic load of 0.4 of a core at nice 19 (busy, then asleep, in 100 ms cycles): what any
  other work of the browser's size costs the lockstep on these two cores.
- The WebSocket clients (live_view.probe, subscribed to every channel, reading all along) run
  in a separate process (this script with --clients), so their CPU is measured apart from the
  runner's.
- Measured per run: the real-time factor the runner prints; the CPU (user + system, over the
  runner's whole life, start-up included) of the runner process (conductor, recorder and the
  live view node with its threads), of the clients' process and of the browser's processes
  (all Chromium processes); the live view sender's achieved rate while the simulation ran and
  the foxglove-sdk threads' CPU (the node's shutdown log); what the first client or the page
  received.

The configurations run --repeats times, rounds interleaved (the machine's speed drifts within
minutes); the table gives medians. Before each run the benchmark waits for an idle machine, and
it runs again (up to --retries times; the last one is kept whatever the load) a run during which
other processes used more than --max-foreign cores (the machine's busy time from /proc/stat less
this benchmark's processes); the table gives their load. Prints a markdown table (as in docs/benchmarks.md).
"""
import argparse
import asyncio
import json
import os
import re
import resource
import socket
import statistics
import subprocess
import sys
import tempfile
import threading
import time
import urllib.request

ROW = re.compile(r"simulated in (?P<wall>[\d.]+) s wall \((?P<rtf>[\d.]+)x real time")
SENDER = re.compile(r"sender: (?P<hz>[\d.]+) Hz achieved .*?longest gap (?P<gap>\d+) ms, "
                    r"(?P<ms>[\d.]+) ms CPU a round\)"
                    r"; foxglove-sdk threads: (?P<tokio>[\d.]+) s CPU")
SAMPLER = re.compile(r"instructor station: (?P<n>\d+) samples, (?P<ms>[\d.]+) ms CPU each")
CHROMIUM = "/usr/bin/chromium"
# tests/ros/test_instructor_station.py's (WebGL in software: SwiftShader), and Chromium's software
# compositor rather than compositing through SwiftShader too (a third less of the browser's CPU)
BROWSER_ARGS = ["--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist",
                "--disable-dev-shm-usage", "--disable-gpu-compositing"]
TICK = os.sysconf("SC_CLK_TCK")


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


# -- CPU from /proc --------------------------------------------------------------------------
def cpu_of(pid: int) -> float:
    """CPU seconds (user + system) of a process, its threads included; 0 once gone."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            fields = f.read().rpartition(")")[2].split()
        return (int(fields[11]) + int(fields[12])) / TICK
    except (OSError, ValueError, IndexError):
        return 0.0


def busy_cpu() -> float:
    """CPU seconds the whole machine has been busy (every process, /proc/stat)."""
    with open("/proc/stat") as f:
        v = [int(x) for x in f.readline().split()[1:]]
    return (sum(v[:8]) - v[3] - v[4]) / TICK  # user nice system idle iowait irq softirq steal


def wait_quiet(limit: float = 0.15, timeout: float = 90.0) -> float:
    """Wait (up to timeout s) until the machine is idle: less than limit cores busy over 1 s
    (other people's work on these two cores would be measured as the live view's); returns the
    busy cores of the last second."""
    deadline = time.monotonic() + timeout
    while True:
        b0, t0 = busy_cpu(), time.monotonic()
        time.sleep(1.0)
        load = (busy_cpu() - b0) / (time.monotonic() - t0)
        if load < limit or time.monotonic() > deadline:
            return load


def descendants(root: int) -> list:
    children = {}
    for name in os.listdir("/proc"):
        if not name.isdigit():
            continue
        try:
            with open(f"/proc/{name}/stat") as f:
                ppid = int(f.read().rpartition(")")[2].split()[1])
        except (OSError, ValueError, IndexError):
            continue
        children.setdefault(ppid, []).append(int(name))
    out, todo = [], [root]
    while todo:
        for c in children.get(todo.pop(), []):
            out.append(c)
            todo.append(c)
    return out


def comm(pid: int) -> str:
    try:
        with open(f"/proc/{pid}/comm") as f:
            return f.read().strip()
    except OSError:
        return ""


class Browser:
    """Headless Chromium through Playwright; its processes' CPU from /proc."""

    def __init__(self):
        from playwright.sync_api import sync_playwright
        self._pw = sync_playwright().start()
        self.browser = self._pw.chromium.launch(executable_path=CHROMIUM, headless=True, args=BROWSER_ARGS)

    def pids(self, driver: bool = False) -> list:
        """Chromium's processes (and Playwright's driver, a Node.js process)."""
        names = ("chromium", "chrome") + (("node",) if driver else ())
        return [p for p in descendants(os.getpid()) if comm(p).startswith(names)]

    def renice(self, nice: int) -> None:
        """Every thread of every Chromium process at this niceness (Linux: a thread's own; a page
        opened later forks its renderer from the zygote, and threads started later inherit it)."""
        for p in self.pids():
            try:
                tasks = os.listdir(f"/proc/{p}/task")
            except OSError:
                continue
            for tid in tasks:
                try:
                    os.setpriority(os.PRIO_PROCESS, int(tid), nice)
                except OSError:
                    pass

    def cpu(self, driver: bool = False) -> dict:
        return {p: cpu_of(p) for p in self.pids(driver)}

    def close(self) -> None:
        self.browser.close()
        self._pw.stop()


# -- the clients' process ------------------------------------------------------------------
def clients_main(port: int, n: int) -> None:
    """--clients: n probes subscribed to every channel, reading until the server goes away;
    prints JSON: messages to the first client, the simulation time of its first message data,
    the time broadcasts it saw while the simulation time advanced and over how long (wall)."""
    from live_view.probe import OP_TIME, Probe

    class Counting(Probe):
        """Keeps no history (reads like a viewer): counts the messages, notes the simulation time of
        the first one and the wall time of each time broadcast that advanced."""

        def __init__(self, url):
            super().__init__(url)
            self.count, self.first_log_time, self.advanced, self.last_time = 0, None, [], None

        async def receive(self, timeout):
            ok = await super().receive(timeout)
            for msgs in self.messages.values():
                self.count += len(msgs)
                if self.first_log_time is None and msgs:
                    self.first_log_time = msgs[0][0]
            self.messages = {}
            for t in self.times:
                if t != self.last_time:
                    self.advanced.append(time.monotonic())
                self.last_time = t
            self.times = []
            return ok

    async def main():
        probes = [Counting(f"ws://127.0.0.1:{port}") for _ in range(n)]
        for p in probes:
            await p.connect(timeout=120)
            await p.wait_for_topics(["/tug/odom", "/tf"], timeout=120)
            await p.subscribe_all()
        print("subscribed", flush=True)

        async def read(p):
            while True:
                try:
                    await p.receive(1.0)
                except Exception:  # noqa: BLE001 - the server went away at the end of the run
                    return
        await asyncio.gather(*(read(p) for p in probes))
        first = probes[0]
        adv = first.advanced[1:]  # the first broadcast is the time already there at connection
        rate = (len(adv) - 1) / (adv[-1] - adv[0]) if len(adv) > 2 and adv[-1] > adv[0] else None
        print(json.dumps({"messages": first.count, "first_log_time": first.first_log_time, "time_rate": rate}),
              flush=True)
    asyncio.run(main())


def poller_main(url: str, period: float) -> None:
    """--poller: GET /api/state every period s as the page does (its requests without a browser),
    until the server goes away; prints JSON: the snapshots that changed."""
    import http.client
    from urllib.parse import urlsplit
    u = urlsplit(url)
    got, changed, last = 0, 0, None
    deadline = time.monotonic() + 120
    conn = None
    while True:
        try:
            if conn is None:
                conn = http.client.HTTPConnection(u.hostname, u.port, timeout=5)
            conn.request("GET", "/api/state", headers={"Host": f"localhost:{u.port}"})
            body = conn.getresponse().read()
        except OSError:
            conn = None
            if got or time.monotonic() > deadline:
                break
            time.sleep(0.1)
            continue
        got += 1
        key = re.sub(rb'"sample": \d+, ', b"", body)
        changed += key != last
        last = key
        time.sleep(period)
    print(json.dumps({"snapshots": got, "changed": changed}), flush=True)


def burner_main(cores: float) -> None:
    """--burner: a synthetic load of about `cores` of one core (busy, then asleep, in 100 ms cycles),
    at nice 19, until terminated: what any other work of the browser's size costs the lockstep."""
    os.nice(19)
    while True:
        end = time.monotonic() + 0.1 * cores
        while time.monotonic() < end:
            pass
        time.sleep(0.1 * (1.0 - cores))


# -- one run ---------------------------------------------------------------------------------
def runner_command(duration: float, config: str, tmp: str):
    """The runner's command line, with the live view (on two free ports: WebSocket and the
    instructor station's HTTP) unless config is 'none' or a synthetic load; returns (cmd, port,
    http_port), the ports None without the live view."""
    cmd = ["ros2", "run", "scenario_runner", "run_scenario", "default_demo.yaml", "--duration", str(duration),
           "--quiet", "--output", os.path.join(tmp, "bench.mcap")]
    port = http_port = None
    if config != "none" and not config.startswith("burn"):
        port, http_port = free_port(), free_port()
        cmd += ["--live", "--live-port", str(port), "--ros-args", "-p", f"live_view:http_port:={http_port}"]
    return cmd, port, http_port


def start_runner_cpu_sampler(runner):
    """The run_scenario process's CPU can only be read while it lives (`ros2 run` starts it as
    its child and it is gone when the run ends): a thread reads it every 0.1 s and keeps the
    last value. Returns stop(), to call once the runner ended: that last value, in s."""
    last_cpu = [0.0]
    done = threading.Event()

    def sample():  # the runner's CPU, read until it ends (its last value before it goes)
        pid = None
        while not done.is_set():
            if pid is None:  # `ros2 run` starts run_scenario as its child
                pid = next((p for p in [runner.pid] + descendants(runner.pid) if comm(p) == "run_scenario"), None)
                if pid is None:
                    done.wait(0.05)
                    continue
            c = cpu_of(pid)
            if c:
                last_cpu[0] = c
            done.wait(0.1)
    sampler = threading.Thread(target=sample, daemon=True)
    sampler.start()

    def stop():
        done.set()
        sampler.join()
        return last_cpu[0]
    return stop


def start_load(config: str, port, http_port, runner, browser):
    """What the row puts beside the runner: the WebSocket clients ('ws<N>'), the synthetic load
    ('burn<cores>') or the page's requests ('poll'), each in a process of this script so that
    its CPU is measured apart, or the browser's page ('browser<nice>'). Returns (clients
    process or None, page or None)."""
    clients = page = None
    if config.startswith("ws"):
        clients = subprocess.Popen([sys.executable, os.path.abspath(__file__), "--clients", str(port), config[2:]],
                                   stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    elif config.startswith("burn"):
        clients = subprocess.Popen([sys.executable, os.path.abspath(__file__), "--burner", config[4:]],
                                   stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    elif config == "poll":
        clients = subprocess.Popen([sys.executable, os.path.abspath(__file__), "--poller",
                                    f"http://127.0.0.1:{http_port}/", "0.1"],
                                   stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    elif config.startswith("browser"):
        page = open_page(browser, int(config[len("browser"):] or 0), http_port, runner)
    return clients, page


def open_page(browser, nice: int, http_port, runner):
    """The instructor station in the browser at this niceness, opened as soon as the page
    answers (while the nodes are still starting; given up when the runner ends or after 120 s)
    and following the tug."""
    browser.renice(nice)
    url = f"http://localhost:{http_port}/"
    deadline = time.monotonic() + 120
    while True:
        try:
            with urllib.request.urlopen(url + "api/state", timeout=1):
                break
        except OSError:
            if runner.poll() is not None or time.monotonic() > deadline:
                break
            time.sleep(0.1)
    page = browser.browser.new_page(viewport={"width": 1400, "height": 820})
    page.goto(url + "?vessel=tug&camera=follow")
    return page


def read_browser(res: dict, browser, page, b0: dict, d0: dict) -> float:
    """The page's CPU (res["browser_cpu"], Chromium's processes since b0) and what it received
    (res["page"]), then closes it; returns the CPU of Chromium and Playwright's driver since d0,
    which is this benchmark's own and not other processes' load."""
    idle_browser = 0.0
    if browser is not None:
        b1, d1 = browser.cpu(), browser.cpu(driver=True)
        if page is not None:
            res["browser_cpu"] = sum(c - b0.get(p, 0.0) for p, c in b1.items())
        idle_browser = sum(c - d0.get(p, 0.0) for p, c in d1.items())  # Chromium and Playwright's driver
    if page is not None:
        res["page"] = page.evaluate("({updates: instructor.updates, frames: instructor.frames, "
                                    "first_t: instructor.firstT === undefined ? null : instructor.firstT})")
        page.close()
    return idle_browser


def read_clients(res: dict, clients, config: str, r1) -> None:
    """Ends the clients' process (the synthetic load is terminated, the others end with the
    server) and reads its CPU since r1 (res["clients_cpu"]) and its JSON report (res["clients"])."""
    if config.startswith("burn"):
        clients.terminate()
    cout, cerr = clients.communicate(timeout=60)
    r2 = resource.getrusage(resource.RUSAGE_CHILDREN)  # the clients' process has just been waited for
    res["clients_cpu"] = r2.ru_utime + r2.ru_stime - r1.ru_utime - r1.ru_stime
    try:
        res["clients"] = json.loads(cout.strip().splitlines()[-1]) if not config.startswith("burn") else {}
    except (ValueError, IndexError):
        sys.exit(f"the clients failed:\n{cout}\n{cerr[-3000:]}")


def read_runner_summary(res: dict, runner, out: str, err: str) -> None:
    """The runner's printed numbers: real-time factor and stepping wall time (a failed run ends
    the benchmark), the live view sender's rate and CPU, the instructor sampler's cost."""
    m = ROW.search(out)
    if runner.returncode != 0 or not m:
        sys.exit(f"run failed ({runner.returncode}):\n{out}\n{err[-3000:]}")
    res["rtf"], res["wall"] = float(m["rtf"]), float(m["wall"])
    s = SENDER.search(err + out)
    if s:
        res.update(sender_hz=float(s["hz"]), sender_gap=int(s["gap"]), sender_ms=float(s["ms"]),
                   tokio_cpu=float(s["tokio"]))
    s = SAMPLER.search(err + out)
    if s:
        res.update(samples=int(s["n"]), sample_ms=float(s["ms"]))


def run(duration: float, config: str, tmp: str, browser) -> dict:
    """config: 'none' (no live view), 'live' (no client), 'browser', or 'ws<N>'."""
    cmd, port, http_port = runner_command(duration, config, tmp)
    res = {}
    res["idle_before"] = wait_quiet()
    b0 = browser.cpu() if browser is not None else {}
    d0 = browser.cpu(driver=True) if browser is not None else {}
    busy0, self0, t0 = busy_cpu(), resource.getrusage(resource.RUSAGE_SELF), time.monotonic()
    runner = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    stop_sampler = start_runner_cpu_sampler(runner)
    clients, page = start_load(config, port, http_port, runner, browser)
    # the run (the browser's page works in its own processes meanwhile)
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    out, err = runner.communicate()
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    res["all_cpu"] = r1.ru_utime + r1.ru_stime - r0.ru_utime - r0.ru_stime  # the runner and its nodes
    res["runner_cpu"] = stop_sampler()
    life, busy1, self1 = time.monotonic() - t0, busy_cpu(), resource.getrusage(resource.RUSAGE_SELF)
    res["life"] = life
    idle_browser = read_browser(res, browser, page, b0, d0)
    if clients is not None:
        read_clients(res, clients, config, r1)
    # other processes' CPU while the runner lived: the machine's busy time less this benchmark's
    # processes (the clients' all run within the runner's life, as does the page)
    ours = res["all_cpu"] + res.get("clients_cpu", 0.0) + idle_browser + (
        self1.ru_utime + self1.ru_stime - self0.ru_utime - self0.ru_stime)
    res["foreign_cores"] = max(0.0, (busy1 - busy0 - ours) / life)
    read_runner_summary(res, runner, out, err)
    return res


# -- table ---------------------------------------------------------------------------------
CONFIGS = [("no live view", "none"), ("`--live`, no client", "live"),
           ("`--live`, the page's requests without a browser (10 Hz)", "poll"),
           ("`--live`, 1 browser (instructor station)", "browser"),
           ("`--live`, 1 browser at nice 19", "browser19"),
           ("no live view, a synthetic load of 0.4 cores at nice 19", "burn0.4"),
           ("`--live`, 1 WebSocket client", "ws1"), ("`--live`, 10 WebSocket clients", "ws10")]


def med(values):
    values = [v for v in values if v is not None]
    return statistics.median(values) if values else None


def fmt(x, spec, suffix=""):
    return "-" if x is None else f"{x:{spec}}{suffix}"


def main() -> None:
    if len(sys.argv) > 1 and sys.argv[1] == "--clients":
        clients_main(int(sys.argv[2]), int(sys.argv[3]))
        return
    if len(sys.argv) > 1 and sys.argv[1] == "--burner":
        burner_main(float(sys.argv[2]))
        return
    if len(sys.argv) > 1 and sys.argv[1] == "--poller":
        poller_main(sys.argv[2], float(sys.argv[3]))
        return
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--duration", type=float, default=120.0, help="simulated seconds of the default demo")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--configs", default=",".join(c for _, c in CONFIGS),
                    help="which rows (comma-separated; 'none' is always run: the reference)")
    ap.add_argument("--max-foreign", type=float, default=0.1,
                    help="a run during which other processes used more cores than this is run again")
    ap.add_argument("--retries", type=int, default=3, help="at most this many runs again per round and row")
    args = ap.parse_args()
    wanted = set(args.configs.split(",")) | {"none"}
    configs = [c for c in CONFIGS if c[1] in wanted]
    browser = Browser() if any(c.startswith("browser") for c in wanted) else None
    results = {c: [] for _, c in configs}
    discarded = {c: 0 for _, c in configs}
    try:
        with tempfile.TemporaryDirectory() as tmp:
            for r in range(args.repeats):
                for name, c in configs:
                    for attempt in range(1 + args.retries):
                        res = run(args.duration, c, tmp, browser)
                        if res["foreign_cores"] <= args.max_foreign:
                            break
                        discarded[c] += 1
                        print(f"round {r + 1}: {name}: discarded, other processes used {res['foreign_cores']:.2f} "
                              f"cores meanwhile ({res['rtf']}x, sender {res.get('sender_hz')} Hz, longest gap "
                              f"{res.get('sender_gap')} ms)", file=sys.stderr, flush=True)
                    results[c].append(res)
                    print(f"round {r + 1}: {name}: {json.dumps(res)}", file=sys.stderr, flush=True)
    finally:
        if browser is not None:
            browser.close()
    base = med([x["rtf"] for x in results["none"]])
    print(f"default demo, {args.duration:g} s simulated, lockstep, processes, recorded; median of {args.repeats}\n")
    print(f"| default_demo.yaml, {args.duration:g} s simulated | real-time factor | slower than without "
          "| live sender rate (longest gap) | runner process CPU | CPU of the clients, browser or load "
          "| other processes | received |")
    print("|---|---|---|---|---|---|---|---|")
    for name, c in configs:
        rs = results[c]
        rtf = med([x["rtf"] for x in rs])
        hz, gap = med([x.get("sender_hz") for x in rs]), med([x.get("sender_gap") for x in rs])
        other = [x.get("clients_cpu", x.get("browser_cpu")) for x in rs]
        other_s = "-" if med(other) is None else (
            f"{med(other):.1f} s ({med([o / x['life'] for o, x in zip(other, rs) if o is not None]):.2f} cores)")
        if c.startswith("ws"):
            got = f"{int(med([x['clients']['messages'] for x in rs]))} messages"
        elif c == "poll":
            got = f"{int(med([x['clients']['changed'] for x in rs]))} snapshots"
        elif c.startswith("browser"):
            got = (f"{int(med([x['page']['updates'] for x in rs]))} snapshots, "
                   f"{int(med([x['page']['frames'] for x in rs]))} frames")
        else:
            got = "-"
        print(f"| {name} | {rtf:.1f}x | {'-' if c == 'none' else f'{100 * (1 - rtf / base):.1f} %'} | "
              f"{'-' if hz is None else f'{hz:.1f} Hz ({gap:.0f} ms)'} | "
              f"{med([x['runner_cpu'] for x in rs]):.1f} s | {other_s} | "
              f"{med([x['foreign_cores'] for x in rs]):.2f} cores | {got} |")
    print()
    for name, c in configs:
        rs = results[c]
        extra = [f"runner's life {med([x['life'] for x in rs]):.1f} s wall, "
                 f"stepping {med([x['wall'] for x in rs]):.1f} s",
                 f"runner and nodes {med([x['all_cpu'] for x in rs]):.1f} s CPU"]
        if any("tokio_cpu" in x for x in rs):
            extra.append(f"foxglove-sdk threads {med([x.get('tokio_cpu') for x in rs]):.2f} s CPU, sender "
                         f"{med([x.get('sender_ms') for x in rs]):.2f} ms CPU a round")
        if any("sample_ms" in x for x in rs):
            extra.append(f"instructor sampler {med([x.get('samples') for x in rs]):.0f} samples at "
                         f"{med([x.get('sample_ms') for x in rs]):.2f} ms CPU")
        if c.startswith("ws"):
            extra.append(f"first client's first message at t = "
                         f"{med([x['clients']['first_log_time'] for x in rs]) / 1e9:.2f} s simulated, "
                         f"time broadcasts at "
                         f"{fmt(med([x['clients']['time_rate'] for x in rs]), '.1f')} Hz")
        if c.startswith("browser"):
            first = fmt(med([x['page']['first_t'] for x in rs]), '.2f')
            extra.append(f"page's first snapshot at t = {first} s simulated")
        extra.append(f"machine busy before: {max(x['idle_before'] for x in rs):.2f} cores at most; "
                     f"{discarded[c]} run(s) discarded for other processes' load")
        print(f"- {name}: " + "; ".join(extra))

if __name__ == "__main__":
    main()
