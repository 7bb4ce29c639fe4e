"""Time one model step for every ship file in tug_dynamics/ships (any model, via load_ship).

    PYTHONPATH=ros_ws/src/tug_dynamics python benchmarks/bench_vessels.py [--dt 0.05] [--update-readme]

Prints a markdown table (median microseconds per Vessel.step call over 2000 calls after a
warm-up, without and with one external wrench, and with one wrench plus the environment: gusty
wind, a tidal sheared current and a bathymetry grid attached through
tug_dynamics.environment_loads, as the vessel node does; the last two timed side by side, their
blocks interleaved); --update-readme writes it between the
<!-- bench:start --> / <!-- bench:end --> markers of ros_ws/src/tug_dynamics/README.md.
"""
from __future__ import annotations

import argparse
import math
import os
import platform
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "ros_ws", "src", "tug_dynamics"))
sys.path.insert(0, os.path.join(HERE, "..", "ros_ws", "src", "sim_math"))
sys.path.insert(0, os.path.join(HERE, "..", "ros_ws", "src", "sea_environment"))

from tug_dynamics.ship_file import list_ship_files, load_ship  # noqa: E402
from tug_dynamics.vessel import Command, ExternalWrench  # noqa: E402
from tug_dynamics.environment_loads import VesselInEnvironment  # noqa: E402
from sea_environment.environment import Environment  # noqa: E402

README = os.path.join(HERE, "..", "ros_ws", "src", "tug_dynamics", "README.md")


def _time_block(vessel, dt, wrenches, n):
    t0 = time.perf_counter()
    for _ in range(n):
        vessel.step(dt, wrenches)
    return (time.perf_counter() - t0) / n * 1e6


def time_steps(vessels, dt, wrenches, n=2000, repeats=5):
    """Median us per step of each vessel, their blocks of n steps interleaved (the machine's
    speed drifts: a ratio between them is only fair when measured side by side)."""
    for v in vessels:
        for _ in range(200):
            v.step(dt, wrenches)
    times = [[] for _ in vessels]
    for _ in range(repeats):
        for v, t in zip(vessels, times):
            t.append(_time_block(v, dt, wrenches, n))
    return [float(np.median(t)) for t in times]


def bench_environment(tmpdir, mean_depth=40.0):
    """Gusty 25 kn wind, a 2 kn tidal stream with shear, a 41 x 41 bathymetry grid (mean_depth
    +- 20 m; bench_rope uses it too, 500 m deep)."""
    grid = os.path.join(tmpdir, "bench_depth.asc")
    with open(grid, "w") as f:
        f.write("ncols 41\nnrows 41\nxllcorner -10000\nyllcorner -10000\ncellsize 500\n")
        for i in range(41):
            f.write(" ".join(f"{mean_depth + 20.0 * math.sin(0.3 * i + 0.2 * j):.2f}" for j in range(41)) + "\n")
    return Environment.from_mapping({
        "wind": {"speed_kn": 25.0, "from_deg": 250.0, "gusts": True, "seed": 1},
        "current": {"speed_kn": 2.0, "towards_deg": 80.0, "shear_per_s": 0.0005, "tidal_period_s": 44712.0},
        "depth": {"grid": grid}})


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dt", type=float, default=0.05, help="step size, s (default 0.05 = 20 Hz)")
    ap.add_argument("--update-readme", action="store_true")
    a = ap.parse_args(argv)
    rows = []
    import tempfile
    tmp = tempfile.mkdtemp()
    env = bench_environment(tmp)
    for path in list_ship_files():
        name = os.path.basename(path)
        try:
            v, in_env = load_ship(path), load_ship(path)
            for model in (v, in_env):
                model.set_command(Command(0.5, math.radians(10.0)))
            point = next(iter(v.attachments.values())) if v.attachments else np.zeros(3)
            w = [ExternalWrench(np.array([1e3, 2e3, 0.0]), np.asarray(point, float))]
            t0, = time_steps([v], a.dt, ())
            if v.windage is not None:
                # the environment attached: every step samples it (inside the model's compiled step)
                # and applies its current, wind, depth factors and bottom friction
                VesselInEnvironment(in_env, env)
                t1, t2 = time_steps([v, in_env], a.dt, w)
                env_cell = f"{t2:.1f} ({100.0 * (t2 - t1) / t1:+.0f} %)"
            else:
                t1, = time_steps([v], a.dt, w)
                env_cell = "(no windage section)"
            sub = getattr(v, "hmax", None)
            nsub = math.ceil(a.dt / sub - 1e-9) if sub else "-"
            rows.append(f"| {name} | {type(v).__name__} | {nsub} | {t0:.1f} | {t1:.1f} | {env_cell} |")
        except Exception as exc:  # noqa: BLE001 - report, keep timing the others
            rows.append(f"| {name} | (not loadable: {type(exc).__name__}: {str(exc)[:60]}) | | | | |")
    table = "\n".join([
        f"Step dt = {a.dt} s; {platform.processor() or platform.machine()}, Python {platform.python_version()}, "
        f"median of 5 x 2000 calls (with and without the environment: interleaved blocks).",
        "",
        "| ship file | model | RK4 sub-steps per call | us / step | us / step, 1 wrench | "
        "us / step, 1 wrench + environment |",
        "|---|---|---|---|---|---|",
        *rows])
    print(table)
    if a.update_readme:
        text = open(README, encoding="utf-8").read()
        start, end = "<!-- bench:start -->", "<!-- bench:end -->"
        i, j = text.index(start) + len(start), text.index(end)
        open(README, "w", encoding="utf-8").write(text[:i] + "\n" + table + "\n" + text[j:])
    return 0


if __name__ == "__main__":
    sys.exit(main())
