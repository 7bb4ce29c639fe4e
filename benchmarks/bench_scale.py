"""Scale benchmark (issue 20 item 3): 1, 2, 4, 6, 8 tows in one sea, every node its own process
on this machine; lockstep real-time factor, CPU per step of all processes and step round trip
against the number of tows, a linear fit of the CPU per step, and the largest number of tows
held in paced real time at 50 Hz without an overrun.

    source scripts/ensure_env.sh && python benchmarks/bench_scale.py [--tows 1,2,4,6,8]
        [--duration 60] [--paced-duration 30] [--repeats 1] [--plot docs/bench_scale.png]
        [--one-process 4,8] [--pyspy 8 --pyspy-bin /path/to/py-spy] [--json out.json] [--merge old.json]

- The scenarios are generated from the default demo (default_demo.yaml: the harbour tug, the
  full-scale seed 002 barge, the Table 1 rope from the tug's winch, settled before step 0, the
  demo's engine orders): tow i is the demo's tow moved 300 m north (tug_i, barge_i, towline_i),
  so the tows share the sea, the step protocol and the runner, nothing else. Exchange at 50 Hz,
  recorded (--no-record: not), written into a temporary folder.
- Each N runs twice through the real runner (`ros2 run scenario_runner run_scenario`): lockstep
  for --duration simulated seconds and paced (mode realtime) for --paced-duration. The runner's
  summary gives the real-time factor, the step round trip (SimStep out to the last StepDone in),
  the CPU per step of all processes (user + system of the runner and every node process from
  step 0 to the last step, over the steps), each node's mean compute time (its StepDone's
  compute_time: model step and publishing, wall) and, paced, the overruns (steps that finished
  after their deadline) and the lateness p99.
- From outside, the benchmark reads every thread of the runner and its nodes in /proc twice
  during the stepping (at the first progress report past 5 % and past 70 % of the steps: the
  runner's progress bar on stderr) and splits the CPU per step by process (runner, tugs, barges,
  ropes) and thread (the Python main thread; Fast DDS's shared-memory receive, event and other
  threads; others).
- --one-process N,...: the same runs with `--layout one_process` (every node in the runner's
  process, on its executor), for comparison.
- --merge FILE: an earlier run's --json fills the rows this run does not measure (e.g. re-run
  only the rows another session's load disturbed; `--tows ""` re-prints and re-plots).
- Other processes' load (the machine's busy time from /proc/stat less this benchmark's and its
  children's) is given per run; before each run the benchmark waits (up to 60 s) for an idle
  machine, and a paced run with an overrun during which other processes used more than
  --max-foreign cores is run again (up to --retries times).
- --pyspy N: one more lockstep run of N tows, sampled by `py-spy record --pid <runner>
  --subprocesses --nonblocking` (py-spy from PATH, or --pyspy-bin; attached between the two
  snapshots, so the start-up is not in it); its active samples (running, or runnable and waiting for a
  core) are split by process kind and by
  what the innermost Python frame is doing (model physics, CDR encoding, rclpy publish, the
  executor's C++ spin under its Python caller, the step protocol, the recorder). Samples only:
  that run's timings are not used.

Prints markdown tables (those of docs/benchmarks.md) and the fit; writes the plot (matplotlib) and, with
--json, every number.
"""
import argparse
import copy
import json
import os
import re
import resource
import signal
import statistics
import subprocess
import sys
import tempfile
import threading
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_live_view import busy_cpu, descendants, wait_quiet  # noqa: E402 - the same /proc helpers

ROW = re.compile(r"simulated in (?P<wall>[\d.]+) s wall \((?P<rtf>[\d.]+)x real time, (?P<steps>\d+) steps")
RT = re.compile(r"round trip: p50 (?P<p50>[\d.]+) ms, p99 (?P<p99>[\d.]+) ms")
CPU = re.compile(r"CPU per step, all processes: (?P<cpu>[\d.]+) ms")
LATE = re.compile(r"realtime: (?P<over>\d+) overrun step\(s\)(?: \((?P<which>[^)]*)\))?; lateness p99 (?P<late>[\d.]+) ms")
COMPUTE = re.compile(r"compute per step: (?P<list>.*)")
PROGRESS = re.compile(r"(\d+)/(\d+) \[")
TICK = os.sysconf("SC_CLK_TCK")
SPACING = 300.0  # m between the tows, north
PERIOD_MS = 20.0  # 50 Hz
ROLES = ("runner", "tug", "barge", "rope")


# -- scenarios -------------------------------------------------------------------------------
def template() -> dict:
    import yaml
    from ament_index_python.packages import get_package_share_directory
    path = os.path.join(get_package_share_directory("scenario_runner"), "scenarios", "default_demo.yaml")
    with open(path) as f:
        return yaml.safe_load(f)


def scale_scenario(base: dict, n: int, mode: str) -> dict:
    """n copies of the default demo's tow, 300 m apart north; the vessel and rope names get _i."""
    sc = {k: v for k, v in base.items() if k not in ("vessels", "ropes", "events")}
    sc.update(name=f"scale_{n}_{mode}", mode=mode, exchange_rate=50.0,
              description=f"{n} tow(s) of the default demo side by side, {SPACING:g} m apart ({mode})")
    vessels, ropes, events = [], [], []
    names = {v["name"] for v in base["vessels"]} | {r["name"] for r in base["ropes"]}
    for i in range(1, n + 1):
        ren = {name: f"{name}_{i}" for name in names}
        for v in base["vessels"]:
            v = copy.deepcopy(v)
            v["name"] = ren[v["name"]]
            v["initial"]["y"] = float(v["initial"].get("y", 0.0)) + SPACING * (i - 1)
            vessels.append(v)
        for r in base["ropes"]:
            r = copy.deepcopy(r)
            r["name"] = ren[r["name"]]
            for end in ("end_a", "end_b"):
                vessel, sep, att = r[end].partition("/")
                if sep:
                    r[end] = f"{ren[vessel]}/{att}"
            ropes.append(r)
        for ev in base.get("events", []):
            ev = copy.deepcopy(ev)
            for key in ("vessel", "rope"):
                if key in ev:
                    ev[key] = ren[ev[key]]
            if "when" in ev and "vessel" in ev["when"]:
                ev["when"]["vessel"] = ren[ev["when"]["vessel"]]
            events.append(ev)
    sc.update(vessels=vessels, ropes=ropes, events=events)
    return sc


def write_scenarios(tows, folder: str) -> dict:
    import yaml
    base = template()
    paths = {}
    for n in tows:
        for mode in ("lockstep", "realtime"):
            path = os.path.join(folder, f"scale_{n}_{mode}.yaml")
            with open(path, "w") as f:
                yaml.safe_dump(scale_scenario(base, n, mode), f, sort_keys=False)
            paths[n, mode] = path
    return paths


# -- CPU by process and thread, from /proc -----------------------------------------------------
def role_of(pid: int) -> str:
    try:
        with open(f"/proc/{pid}/cmdline", "rb") as f:
            cmd = f.read().replace(b"\0", b" ").decode(errors="replace")
    except OSError:
        return "other"
    if "run_scenario" in cmd:
        return "runner"
    if "rope_node" in cmd:
        return "rope"
    if "vessel_node" in cmd:
        m = re.search(r"__ns:=/([A-Za-z]+)", cmd)
        return m.group(1) if m else "vessel"
    return "other"


def thread_class(pid: int, tid: int, comm: str) -> str:
    if tid == pid:
        return "main thread (Python)"
    if comm.startswith("dds.shm"):
        return "Fast DDS shm receive"
    if comm.startswith("dds.ev"):
        return "Fast DDS event"
    if comm.startswith("dds."):
        return "Fast DDS other"
    return "other threads"


def tree_threads(root: int, roles: dict) -> dict:
    """(pid, tid) -> (role, thread class, CPU s) of every thread of root and its descendants."""
    out = {}
    for pid in [root] + descendants(root):
        if pid not in roles:
            roles[pid] = role_of(pid)
        try:
            tids = os.listdir(f"/proc/{pid}/task")
        except OSError:
            continue
        for t in tids:
            try:
                with open(f"/proc/{pid}/task/{t}/stat") as f:
                    head, _, rest = f.read().rpartition(")")
                fields = rest.split()
                comm = head.partition("(")[2]
            except (OSError, ValueError):
                continue
            tid = int(t)
            out[pid, tid] = (roles[pid], thread_class(pid, tid, comm), (int(fields[11]) + int(fields[12])) / TICK)
    return out


def split_per_step(a: dict, b: dict, steps: int) -> dict:
    """(role, thread class) -> ms of CPU per step between two tree_threads snapshots."""
    out = {}
    for key, (role, cls, cpu) in b.items():
        before = a.get(key, (role, cls, 0.0))[2]
        out[role, cls] = out.get((role, cls), 0.0) + 1e3 * (cpu - before) / steps
    return out


# -- one run -----------------------------------------------------------------------------------
def run(path: str, duration: float, tmp: str, record: bool, env: dict, pyspy=None, layout="processes") -> dict:
    """One run through the real runner; the summary's numbers, the CPU split and other load.
    pyspy: (py-spy executable, raw output file): sample the runner and its nodes between the two
    snapshots (the stepping only, not the start-up)."""
    out_file = os.path.join(tmp, "bench.mcap")
    cmd = ["ros2", "run", "scenario_runner", "run_scenario", path, "--duration", f"{duration:g}",
                          "--output", out_file]
    if not record:
        cmd.append("--no-record")
    if layout != "processes":
        cmd += ["--layout", layout]
    res = {"idle_before": wait_quiet(timeout=20.0)}
    busy0, self0, t0 = busy_cpu(), resource.getrusage(resource.RUSAGE_SELF), time.monotonic()
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env)
    err_chunks, snaps, roles, spy = [], {}, {}, []

    def read_progress():  # tqdm on stderr: "...|  123/3000 [..."; snapshots at 10 % and 85 %
        buf = b""
        while True:
            chunk = os.read(proc.stderr.fileno(), 65536)
            if not chunk:
                return
            err_chunks.append(chunk)
            buf = (buf + chunk)[-400:]
            m = None
            for m in PROGRESS.finditer(buf.decode(errors="replace")):
                pass
            if m is None:
                continue
            n, total = int(m.group(1)), int(m.group(2))
            for key, frac in (("a", 0.05), ("b", 0.70)):
                if key not in snaps and n >= frac * total and n < total and ("a" in snaps or key == "a"):
                    snaps[key] = (n, time.monotonic(), tree_threads(proc.pid, roles))
                    if pyspy and key == "a":
                        spy.append(subprocess.Popen(
                            [pyspy[0], "record", "--pid", str(proc.pid), "--subprocesses", "--nonblocking",
                             "--rate", "100", "--format", "raw", "--full-filenames", "--output", pyspy[1]],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE))
                    elif spy and key == "b":
                        spy[0].send_signal(signal.SIGINT)  # py-spy writes its samples on Ctrl-C
                    break

    reader = threading.Thread(target=read_progress, daemon=True)
    reader.start()
    out = proc.stdout.read().decode(errors="replace")
    proc.wait()
    reader.join(timeout=10)
    if spy:
        if spy[0].poll() is None:
            spy[0].send_signal(signal.SIGINT)
        _, spy_err = spy[0].communicate(timeout=60)
        res["pyspy_log"] = spy_err.decode(errors="replace")[-500:]
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    life, busy1, self1 = time.monotonic() - t0, busy_cpu(), resource.getrusage(resource.RUSAGE_SELF)
    err = b"".join(err_chunks).decode(errors="replace")
    ours = (r1.ru_utime + r1.ru_stime - r0.ru_utime - r0.ru_stime
            + self1.ru_utime + self1.ru_stime - self0.ru_utime - self0.ru_stime)
    res.update(life=life, all_cpu=ours, foreign_cores=max(0.0, (busy1 - busy0 - ours) / life))
    res["summary"] = out
    m = ROW.search(out)
    if proc.returncode != 0 or not m:
        sys.exit(f"run failed ({proc.returncode}): {' '.join(cmd)}\n{out}\n{err[-3000:]}")
    r, c, late = RT.search(out), CPU.search(out), LATE.search(out)
    res.update(rtf=float(m["rtf"]), wall=float(m["wall"]), steps=int(m["steps"]), p50=float(r["p50"]),
               p99=float(r["p99"]), cpu_ms=float(c["cpu"]),
               over=int(late["over"]) if late else None, late=float(late["late"]) if late else None,
               which=(late["which"] or "") if late else "")
    comp = COMPUTE.search(out)
    if comp:  # "/tug_1 0.12 ms, /barge_1 0.10 ms, ..." -> role -> mean ms per node
        per = {}
        for name, ms in re.findall(r"/([A-Za-z]+)_\d+/\w+ ([\d.]+) ms", comp["list"]):
            per.setdefault(name, []).append(float(ms))
        res["compute_ms"] = {k: statistics.mean(v) for k, v in per.items()}
    if "a" in snaps and "b" in snaps:
        (na, ta, a), (nb, tb, b) = snaps["a"], snaps["b"]
        res["split"] = {f"{k[0]}|{k[1]}": v for k, v in split_per_step(a, b, nb - na).items()}
        res["window_steps"] = nb - na
        res["processes"] = len({pid for pid, _ in b})
    return res


# -- py-spy ----------------------------------------------------------------------------------
ACTIVITIES = [  # (label, test on the innermost Python frame "function (file:line)"), first match wins
    ("model physics", lambda f: any(s in f for s in ("tug_dynamics/", "rope_model/", "sim_math/",
                                                      "sea_environment/", "numba/"))
     and "_node.py" not in f),
    ("CDR encode / decode", lambda f: "sim_plumbing/cdr.py" in f or "serialization" in f),
    ("rclpy publish", lambda f: "publish" in f and "rclpy/" in f),
    # the EventsExecutor is C++: its take, dispatch and Fast DDS reads show as the Python frame
    # that called spin_once (ros_common.spin_forever in a node, Session.wait_for in the runner)
    ("executor spin (C++ take, dispatch, DDS)", lambda f: "rclpy/executors.py" in f
     or f.startswith(("spin", "wait_for ", "wait_for_states ")) or "events_executor" in f),
    ("recorder", lambda f: "recorder.py" in f or "mcap" in f or "record_feed" in f),
    ("step protocol (stepping.py, conductor)", lambda f: "stepping.py" in f or "conductor.py" in f
     or "ros_common.py" in f and "die_with_parent" not in f),
    ("node glue (vessel_node / rope_node)", lambda f: "_node.py" in f),
]


def classify(frames) -> str:
    """The activity of a sample: the innermost frame that names one (numpy under the rope model
    is model physics, the C++ executor under spin_forever is the executor)."""
    for frame in reversed(frames):
        for label, test in ACTIVITIES:
            if test(frame):
                return label
    return "other Python"


def pyspy_profile(path: str, duration: float, tmp: str, record: bool, env: dict, pyspy: str) -> dict:
    raw = os.path.join(tmp, "pyspy.txt")
    res = run(path, duration, tmp, record, env, pyspy=(pyspy, raw))
    table, samples = {}, {}
    with open(raw) as f:
        for line in f:
            stack, _, count = line.rstrip("\n").rpartition(" ")
            if not stack:
                continue
            frames = stack.split(";")
            procs = [i for i, fr in enumerate(frames) if re.match(r"process \d+:", fr)]
            role = "other"
            if procs:  # nested "process <pid>:"<command line>"" frames, the innermost is the sampled one
                cmd = frames[procs[-1]]
                frames = frames[procs[-1] + 1:] or ["(process start)"]
                role = ("runner" if "run_scenario" in cmd else "rope" if "rope_node" in cmd else
                        (re.search(r"__ns:=/([A-Za-z]+)", cmd) or [None, "vessel"])[1] if "vessel_node" in cmd
                        else "other")
            leaf = frames[-1]
            key = (role, classify(frames))
            table[key] = table.get(key, 0) + int(count)
            samples[role] = samples.get(role, 0) + int(count)
            leaf_key = (role, leaf)
            table.setdefault("leaves", {})
            table["leaves"][leaf_key] = table["leaves"].get(leaf_key, 0) + int(count)
    leaves = table.pop("leaves", {})
    top = {}
    for (role, leaf), n in sorted(leaves.items(), key=lambda kv: -kv[1]):
        top.setdefault(role, [])
        if len(top[role]) < 6:
            top[role].append((leaf, n))
    return {"n": int(re.search(r"scale_(\d+)_", path).group(1)), "duration": duration, "run": res,
            "by_activity": {f"{k[0]}|{k[1]}": v for k, v in table.items()}, "samples": samples,
            "top": top}


# -- table, fit, plot --------------------------------------------------------------------------
def med(values):
    values = [v for v in values if v is not None]
    return statistics.median(values) if values else None


def fit(xs, ys):
    import numpy as np
    x, y = np.asarray(xs, float), np.asarray(ys, float)
    slope, intercept = np.polyfit(x, y, 1)
    pred = slope * x + intercept
    ss_res, ss_tot = float(((y - pred) ** 2).sum()), float(((y - y.mean()) ** 2).sum())
    return float(slope), float(intercept), 1.0 - ss_res / ss_tot if ss_tot > 0 else 1.0


def plot(rows, cpu_fit, wall_fit, held, path, single=()):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.ticker
    import matplotlib.pyplot as plt
    import numpy as np
    ns = [r["n"] for r in rows]
    x = np.linspace(0, max(ns) * 1.05, 50)
    fig, ax = plt.subplots(2, 2, figsize=(11, 8))
    a = ax[0, 0]
    a.plot(ns, [r["lock"]["cpu_ms"] for r in rows], "o", label="lockstep, CPU per step (all processes)")
    a.plot(x, cpu_fit[0] * x + cpu_fit[1], "-", color="C0",
           label=f"fit {cpu_fit[1]:.2f} + {cpu_fit[0]:.2f} N ms (R$^2$ {cpu_fit[2]:.3f})")
    paced = [r for r in rows if r.get("paced")]
    a.plot([r["n"] for r in paced], [r["paced"]["cpu_ms"] for r in paced], "s", color="C1",
           label="paced 50 Hz, CPU per step")
    a.plot(ns, [PERIOD_MS / r["lock"]["rtf"] for r in rows], "^", color="C2",
           label="lockstep, wall per step")
    a.plot(x, wall_fit[0] * x + wall_fit[1], "--", color="C2", label=f"fit {wall_fit[1]:.2f} + {wall_fit[0]:.2f} N ms")
    if single:
        a.plot([r["n"] for r in single], [r["paced"]["cpu_ms"] for r in single], "D", color="C4",
               label="paced 50 Hz, CPU per step, one process")
    a.axhline(PERIOD_MS, color="k", lw=0.8, ls=":")
    a.axhline(2 * PERIOD_MS, color="grey", lw=0.8, ls=":")
    a.text(max(ns) * 1.05, PERIOD_MS + 0.5, "20 ms: one step at 50 Hz", fontsize=8, ha="right")
    a.text(max(ns) * 1.05, 2 * PERIOD_MS + 0.5, "40 ms: both cores for a 50 Hz step", fontsize=8, ha="right")
    a.set(xlabel="tows (tug + barge + rope each)", ylabel="ms per step", title="Cost per step", xticks=ns,
          ylim=(0, max(2 * PERIOD_MS + 5, 1.1 * max(r["lock"]["cpu_ms"] for r in rows))))
    a.legend(fontsize=7, loc="upper left", bbox_to_anchor=(0.0, 0.9))
    a = ax[0, 1]
    a.plot(ns, [r["lock"]["rtf"] for r in rows], "o-")
    a.axhline(1.0, color="k", lw=0.8, ls=":")
    for r in rows:
        a.annotate(f"{r['lock']['rtf']:.1f}x", (r["n"], r["lock"]["rtf"]), textcoords="offset points", xytext=(4, 4),
                   fontsize=8)
    a.set(xlabel="tows", ylabel="real-time factor", title="Lockstep real-time factor", yscale="log", xticks=ns)
    a.yaxis.set_major_formatter(matplotlib.ticker.FormatStrFormatter("%gx"))
    a.yaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    a = ax[1, 0]
    a.plot(ns, [r["lock"]["p50"] for r in rows], "o-", label="lockstep p50")
    a.plot(ns, [r["lock"]["p99"] for r in rows], "o--", label="lockstep p99")
    a.plot([r["n"] for r in paced], [r["paced"]["p50"] for r in paced], "s-", label="paced p50")
    a.plot([r["n"] for r in paced], [r["paced"]["p99"] for r in paced], "s--", label="paced p99")
    if single:
        a.plot([r["n"] for r in single], [r["paced"]["p99"] for r in single], "D:", color="C4",
               label="paced p99, one process")
    a.axhline(PERIOD_MS, color="k", lw=0.8, ls=":")
    a.set(xlabel="tows", ylabel="ms", title="Step round trip (SimStep out to last StepDone in)", xticks=ns)
    a.legend(fontsize=8)
    a = ax[1, 1]
    steps = paced[0]["paced"].get("steps") or 0
    w = 0.35 if single else 0.8
    a.bar([r["n"] - (w / 2 if single else 0) for r in paced], [r["paced"]["over"] for r in paced], width=w,
          color="C3", alpha=0.6, label=f"overrun steps (of {steps:.0f})")
    for r in paced:
        a.annotate(f"{r['paced']['over']:.0f}", (r["n"] - (w / 2 if single else 0), r["paced"]["over"]),
                   ha="center", va="bottom", fontsize=8)
    if single:
        a.bar([r["n"] + w / 2 for r in single], [r["paced"]["over"] for r in single], width=w, color="C4",
              alpha=0.6, label="overrun steps, one process")
        for r in single:
            a.annotate(f"{r['paced']['over']:.0f}", (r["n"] + w / 2, r["paced"]["over"]), ha="center", va="bottom",
                       fontsize=8)
    a.set(xlabel="tows", ylabel="overrun steps",
          title="Paced 50 Hz: overruns; held without one: " + (f"up to {held} tow(s)" if held else "none"),
          xticks=ns, yscale="symlog")
    a.set_ylim(0, max(10, 3 * max(r["paced"]["over"] for r in list(paced) + list(single))))
    b = a.twinx()
    b.plot([r["n"] for r in paced], [r["paced"]["late"] for r in paced], "ko-", label="lateness p99")
    b.set_ylabel("lateness p99, ms (processes)")
    b.set_yscale("symlog", linthresh=1.0)
    h1, l1 = a.get_legend_handles_labels()
    h2, l2 = b.get_legend_handles_labels()
    a.legend(h1 + h2, l1 + l2, loc="upper left", fontsize=8)
    fig.suptitle("Tows in one sea at 50 Hz, recorded, on 2 cores: every node its own process"
                 + (" (purple: all in one process, --layout one_process)" if single else ""), fontsize=11)
    fig.tight_layout()
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    fig.savefig(path, dpi=110)


def measure(ns, layout, paths, args, tmp, record, env, started, results, attempts) -> None:
    """Lockstep and paced runs of each n in ns, rounds interleaved, into results[layout, n, mode];
    a paced run with an overrun under other processes' load is run again, and of the attempts the
    one with the least other load is kept (all are listed in attempts)."""
    for rnd in range(args.repeats):
        for n in ns:
            res = run(paths[n, "lockstep"], args.duration, tmp, record, env, layout=layout)
            results.setdefault((layout, n, "lockstep"), []).append(res)
            print(f"round {rnd + 1}: {n} tows, {layout}, lockstep: {res['rtf']}x, {res['cpu_ms']} ms CPU/step, round "
                  f"trip {res['p50']}/{res['p99']} ms, other load {res['foreign_cores']:.2f} cores "
                  f"({time.monotonic() - started:.0f} s)", file=sys.stderr, flush=True)
            tried = []
            for attempt in range(1 + args.retries):
                res = run(paths[n, "realtime"], args.paced_duration, tmp, record, env, layout=layout)
                tried.append(res)
                print(f"round {rnd + 1}: {n} tows, {layout}, paced: {res['over']} overruns, lateness p99 {res['late']} "
                      f"ms, round trip {res['p50']}/{res['p99']} ms, {res['cpu_ms']} ms CPU/step, other load "
                      f"{res['foreign_cores']:.2f} cores ({time.monotonic() - started:.0f} s)",
                      file=sys.stderr, flush=True)
                if res["over"] == 0 or res["foreign_cores"] <= args.max_foreign:
                    break
            attempts.setdefault(f"{layout}|{n}", []).extend((r["over"], r["foreign_cores"]) for r in tried)
            results.setdefault((layout, n, "realtime"), []).append(min(tried, key=lambda r: r["foreign_cores"]))


def summarise(ns, layout, results) -> list:
    keys = ("rtf", "cpu_ms", "p50", "p99", "over", "late", "foreign_cores", "processes", "steps")
    rows = []
    for n in ns:
        row = {"n": n}
        for mode, label in (("lockstep", "lock"), ("realtime", "paced")):
            rs = results[layout, n, mode]
            row[label] = {k: med([r.get(k) for r in rs]) for k in keys}
            splits = [r["split"] for r in rs if "split" in r]
            row[label]["split"] = {k: med([s.get(k, 0.0) for s in splits]) for k in splits[0]} if splits else {}
            comps = [r["compute_ms"] for r in rs if "compute_ms" in r]
            row[label]["compute_ms"] = {k: med([c.get(k) for c in comps]) for k in comps[0]} if comps else {}
        rows.append(row)
    return rows


def held_of(rows):
    held = None
    for r in rows:
        if r["paced"]["over"] != 0:
            break
        held = r["n"]
    return held


def print_table(rows, paced_duration):
    print("| tows | processes | lockstep real-time factor | CPU ms per step, all processes | CPU ms per step per tow "
          "| round trip p50 / p99 ms | paced 50 Hz: overruns of steps | paced lateness p99 ms | paced round trip "
          "p50 / p99 ms | paced CPU ms per step | other load, cores (lockstep / paced) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        lk, pc = r["lock"], r["paced"]
        procs = lk["processes"] or 3 * r["n"] + 1
        steps = pc.get("steps") or int(round(paced_duration * 50))
        print(f"| {r['n']} | {procs:.0f} | {lk['rtf']:.1f}x | {lk['cpu_ms']:.2f} | {lk['cpu_ms'] / r['n']:.2f} | "
              f"{lk['p50']:.2f} / {lk['p99']:.2f} | {pc['over']:.0f} of {steps:.0f} | {pc['late']:.2f} | "
              f"{pc['p50']:.2f} / {pc['p99']:.2f} | {pc['cpu_ms']:.2f} | "
              f"{lk['foreign_cores']:.2f} / {pc['foreign_cores']:.2f} |")


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--tows", default="1,2,4,6,8", help="numbers of tows, lockstep and paced (every node a process)")
    p.add_argument("--one-process", default="",
                   help="numbers of tows to run also with --layout one_process (all nodes in the runner's process)")
    p.add_argument("--duration", type=float, default=60.0, help="simulated s of each lockstep run")
    p.add_argument("--paced-duration", type=float, default=30.0, help="simulated (= wall) s of each paced run")
    p.add_argument("--repeats", type=int, default=1, help="rounds (interleaved); the table gives medians")
    p.add_argument("--no-record", action="store_true", help="runs without recording")
    p.add_argument("--max-foreign", type=float, default=0.15,
                   help="a paced run with an overrun while other processes used more cores is run again")
    p.add_argument("--retries", type=int, default=2)
    p.add_argument("--plot", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "docs",
                                                  "bench_scale.png"))
    p.add_argument("--pyspy", type=int, default=0, help="N: profile an N-tow lockstep run with py-spy (0: none)")
    p.add_argument("--pyspy-bin", default="py-spy")
    p.add_argument("--pyspy-duration", type=float, default=60.0, help="simulated s of the profiled run")
    p.add_argument("--json", help="write every number here")
    p.add_argument("--merge", help="a --json file of an earlier run: its runs fill what this one does not measure")
    return p.parse_args()


def run_rounds(tows, single, args, record, env, started):
    """Every run of this invocation (both layouts, then the py-spy run), on scenarios generated
    into a temporary folder that lives only as long as the runs; returns (results, attempts,
    py-spy profile or None)."""
    results, attempts, prof = {}, {}, None
    with tempfile.TemporaryDirectory() as tmp:
        paths = write_scenarios(sorted(set(tows + single + ([args.pyspy] if args.pyspy else []))), tmp)
        measure(tows, "processes", paths, args, tmp, record, env, started, results, attempts)
        measure(single, "one_process", paths, args, tmp, record, env, started, results, attempts)
        if args.pyspy:
            prof = pyspy_profile(paths[args.pyspy, "lockstep"], args.pyspy_duration, tmp, record, env, args.pyspy_bin)
    return results, attempts, prof


def merge_earlier(args, results, attempts, prof):
    """Fill what this invocation did not measure from an earlier --json (--merge), so that a
    disturbed row can be re-run alone; returns the py-spy profile (this run's, else the earlier
    one's, whose N and duration then go into args for the report)."""
    with open(args.merge) as f:
        old = json.load(f)
    for key, runs in old["runs"].items():
        parts = key.split("|")
        layout, n, mode = ("processes", *parts) if len(parts) == 2 else parts
        results.setdefault((layout, int(n), mode), runs)
    for key, v in old.get("attempts", {}).items():
        attempts.setdefault(key, [tuple(x) for x in v])
    prof = prof or old.get("pyspy")
    if prof and not args.pyspy:
        args.pyspy, args.pyspy_duration = prof.get("n", 0), prof.get("duration", args.pyspy_duration)
    return prof


def report_scaling(rows, tows, args, record):
    """The main table of the processes layout and, with two or more N, the linear fits and the
    largest N held paced; returns (cpu_fit, wall_fit, held) for the plot and the json (None
    with fewer than two N)."""
    rec = "recorded" if record else "not recorded"
    print(f"\nTows in one sea (default demo's tow, {SPACING:g} m apart), every node its own process, {rec}, "
          f"50 Hz; lockstep {args.duration:g} s, paced {args.paced_duration:g} s simulated; "
          f"median of {args.repeats}\n")
    cpu_fit = wall_fit = held = None
    if len(rows) > 1:
        print_table(rows, args.paced_duration)
        cpu_fit = fit(tows, [r["lock"]["cpu_ms"] for r in rows])
        wall_fit = fit(tows, [PERIOD_MS / r["lock"]["rtf"] for r in rows])
        paced_fit = fit(tows, [r["paced"]["cpu_ms"] for r in rows])
        held = held_of(rows)
        print(f"\nLinear fit, lockstep CPU per step of all processes: {cpu_fit[1]:.3f} + {cpu_fit[0]:.3f} N ms "
              f"(R^2 {cpu_fit[2]:.4f}); paced: {paced_fit[1]:.3f} + {paced_fit[0]:.3f} N ms (R^2 {paced_fit[2]:.4f}); "
              f"lockstep wall per step (20 ms / real-time factor): {wall_fit[1]:.3f} + {wall_fit[0]:.3f} N ms "
              f"(R^2 {wall_fit[2]:.4f})")
        print(f"Largest number of tows held in paced real time at 50 Hz without an overrun: "
              f"{held if held is not None else 'none'} (tried {', '.join(map(str, tows))})")
    return cpu_fit, wall_fit, held


def report_attempts(attempts):
    """Every paced attempt, so that a retried row shows what the table's run was chosen from."""
    print("Paced attempts (overruns, other load in cores; the least loaded is in the table): " + "; ".join(
        f"{k.replace('|', ' ')} tows: " + ", ".join(f"{o} ({c:.2f})" for o, c in v) for k, v in attempts.items()))


def report_one_process(srows, single, paced_duration):
    """The same table for --one-process, for comparison with every node a process."""
    print("\nThe same, every node in the runner's process (--layout one_process):\n")
    print_table(srows, paced_duration)
    print(f"\nLargest number held paced without an overrun, one process: {held_of(srows)} "
          f"(tried {', '.join(map(str, single))})")


def report_cpu_split(rows):
    """Where the CPU of a step goes, by process kind and thread, and each node's compute time,
    for the smallest and the largest N (what grows with N)."""
    for label, mode in (("lockstep", "lock"), ("paced", "paced")):
        for r in (rows[:1] + rows[-1:]) if rows else []:
            split = r[mode]["split"]
            if not split:
                continue
            print(f"\nCPU ms per step by process and thread, {label}, {r['n']} tow(s) "
                  f"(from /proc, about 5-70 % of the steps):\n")
            classes = sorted({k.split("|")[1] for k, v in split.items() if v > 0.0005})
            print("| process | " + " | ".join(classes) + " | all |")
            print("|---|" + "---|" * (len(classes) + 1))
            for role in sorted({k.split("|")[0] for k in split}, key=lambda x: (ROLES + (x,)).index(x)):
                vals = [split.get(f"{role}|{c}", 0.0) for c in classes]
                count = 1 if role == "runner" else r["n"]
                print(f"| {role}{'' if count == 1 else f' (x{count})'} | " + " | ".join(f"{v:.3f}" for v in vals)
                      + f" | {sum(vals):.3f} |")
            comp = r[mode]["compute_ms"]
            if comp:
                print("\nmean compute time per node and step (StepDone compute_time: model step and publishing, "
                      "wall): " + ", ".join(f"{k} {v:.3f} ms" for k, v in sorted(comp.items())))


def report_pyspy(prof, n_tows, duration):
    """The py-spy run: what each process kind spends its active samples on (ACTIVITIES), and
    each kind's most sampled innermost frames."""
    print(f"\npy-spy, {n_tows} tows, lockstep, {duration:g} s simulated: share of the active "
          "samples (running, or runnable and waiting for a core) of each process kind by what the innermost "
          "Python frame that names an activity does\n")
    acts = [a for a, _ in ACTIVITIES] + ["other Python"]
    print("| process | samples | " + " | ".join(acts) + " |")
    print("|---|---|" + "---|" * len(acts))
    for role, total in sorted(prof["samples"].items(), key=lambda kv: -kv[1]):
        print(f"| {role} | {total} | " + " | ".join(
            f"{100 * prof['by_activity'].get(f'{role}|{a}', 0) / total:.0f} %" for a in acts) + " |")
    for role, top in prof["top"].items():
        print(f"- {role}: " + "; ".join(f"{leaf} {100 * n / prof['samples'][role]:.0f} %" for leaf, n in top))


def write_json(path, rows, srows, cpu_fit, wall_fit, held, results, attempts, prof):
    """Every number of the report and every run, so that a later --merge can reuse them."""
    with open(path, "w") as f:
        json.dump({"rows": rows, "one_process_rows": srows, "cpu_fit": cpu_fit, "wall_fit": wall_fit,
                   "held": held, "runs": {f"{lay}|{n}|{m}": v for (lay, n, m), v in results.items()},
                   "attempts": attempts, "pyspy": prof}, f, indent=1)


def main():
    args = parse_args()
    tows = [int(t) for t in args.tows.split(",") if t]
    single = [int(t) for t in args.one_process.split(",") if t]
    record = not args.no_record
    env = dict(os.environ)
    env.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    started = time.monotonic()
    results, attempts, prof = run_rounds(tows, single, args, record, env, started)
    if args.merge:
        prof = merge_earlier(args, results, attempts, prof)
    tows = sorted({n for (layout, n, _) in results if layout == "processes"})
    single = sorted({n for (layout, n, _) in results if layout == "one_process"})
    rows = summarise(tows, "processes", results)
    cpu_fit, wall_fit, held = report_scaling(rows, tows, args, record)
    if attempts:
        report_attempts(attempts)
    srows = summarise(single, "one_process", results)
    if srows:
        report_one_process(srows, single, args.paced_duration)
    report_cpu_split(rows)
    if prof:
        report_pyspy(prof, args.pyspy, args.pyspy_duration)
    if len(rows) > 1:
        plot(rows, cpu_fit, wall_fit, held, args.plot, srows)
        print(f"\nplot: {os.path.abspath(args.plot)}")
    elif rows:
        print_table(rows, args.paced_duration)
    print(f"{time.monotonic() - started:.0f} s in all")
    if args.json:
        write_json(args.json, rows, srows, cpu_fit, wall_fit, held, results, attempts, prof)


if __name__ == "__main__":
    main()
