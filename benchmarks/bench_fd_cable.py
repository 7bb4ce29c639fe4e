#!/usr/bin/env python3
"""Benchmark of the finite-difference towed cable (seed 001, issue 8). Not a test.

1. Speed: simulated seconds per wall second in the paper's turning case (Table 1 cable,
   ship 1 m/s east in a -1 m/s current, port turn at 0.5 deg/s from the steady tow) for 7,
   50 and 200 nodes, at dt = 0.1 s and at dt = 0.02 s (the rope node's exchange period).
2. Block tri-diagonal solve vs a dense numpy.linalg.solve of the same Newton Jacobian
   (assembled once; the dense time excludes building the dense matrix) for 7, 50, 200 nodes,
   with their relative disagreement.
3. Turning case history at 20 s intervals: top tension, XY of the top and of the free end,
   free-end depth (Table 1 grid, 7 nodes, and a 49-node / dt 0.05 s reference).

BLAS is pinned to one thread so both solvers use one core. Prints markdown tables.
--environment prints the cost of the environment instead (issue 18): the turning case through
the rope node's CableAdapter with bench_vessels' gusty wind, tidal sheared current and
bathymetry grid (480-520 m deep) attached, against the same cable given that current's value
at the origin once (the same physics to within the shear; CPU time, modes interleaved).

Usage: PYTHONPATH=ros_ws/src/rope_model python benchmarks/bench_fd_cable.py [--seconds 100]
       [--environment]
"""
import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import argparse  # noqa: E402
import math  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "ros_ws", "src", "rope_model"))

from rope_model import fd_kernels as FK  # noqa: E402
from rope_model.fd_cable import FdCable, default_cable_path, load_cable_params  # noqa: E402

P = load_cable_params(default_cable_path())
RATE = math.radians(0.5)


def turning(n, dt, seconds, sample=20.0):
    """Run the turning case; returns (wall seconds of the stepping, mean Newton iterations,
    rows (t, T_top, top x, top y, end x, end y, end z))."""
    cable = FdCable(P, (0.0, 0.0, 0.0), (P.tow_speed, 0.0, 0.0), 0.0, n_nodes=n)

    def row(t):
        p = cable.positions
        return (t, cable.tensions[0], p[0, 0], p[0, 1], p[-1, 0], p[-1, 1], p[-1, 2])

    rows = [row(0.0)]
    its = 0
    nsteps = int(round(seconds / dt))
    wall = 0.0
    for k in range(1, nsteps + 1):
        t = k * dt
        psi = RATE * t
        pos = P.tow_speed / RATE * np.array([math.sin(psi), 1.0 - math.cos(psi), 0.0])
        vel = P.tow_speed * np.array([math.cos(psi), math.sin(psi), 0.0])
        t0 = time.perf_counter()
        cable.set_top_kinematics(pos, vel)
        cable.step(dt)
        wall += time.perf_counter() - t0
        its += cable.last_iterations
        if abs(t / sample - round(t / sample)) < 1e-9:
            rows.append(row(t))
    return wall, its / nsteps, np.array(rows)


def best_time(fn, min_total=0.2):
    """Best of 5 repeats of fn, each repeat looping long enough to time it."""
    t0 = time.perf_counter()
    fn()
    one = max(time.perf_counter() - t0, 1e-7)
    loops = max(1, int(min_total / 5 / one))
    best = math.inf
    for _ in range(5):
        t0 = time.perf_counter()
        for _ in range(loops):
            fn()
        best = min(best, (time.perf_counter() - t0) / loops)
    return best


def environment_run(n, dt, seconds, attached, env):
    """CPU us per step of the turning case through CableAdapter, the environment `env`
    attached, or its current at the origin given once."""
    from rope_model.models import CableAdapter
    cable = CableAdapter(default_cable_path(), "straight", (0.0, 0.0, 0.0), None, end_a="vessel",
                         end_b="free", current=(-1.0, 0.0, 0.0), n_elements=n, deployed_length=None,
                         max_substep=dt, velocity_a=(P.tow_speed, 0.0, 0.0))
    if attached:
        cable.attach_environment(env)
    else:
        cable.cable.current = np.array([*env.current.velocity_xy(0.0, 0.0, 0.0), 0.0])
    steps = int(round(seconds / dt))
    t0 = time.process_time()
    for k in range(1, steps + 1):
        psi = RATE * k * dt
        cable.set_end("a", P.tow_speed / RATE * np.array([math.sin(psi), 1.0 - math.cos(psi), 0.0]),
                      P.tow_speed * np.array([math.cos(psi), math.sin(psi), 0.0]))
        cable.step(dt)
    return 1e6 * (time.process_time() - t0) / steps


def environment_table(seconds, repeat=5):
    import tempfile
    sys.path.insert(0, HERE)
    sys.path.insert(0, os.path.join(HERE, "..", "ros_ws", "src", "sea_environment"))
    from bench_vessels import bench_environment
    env = bench_environment(tempfile.mkdtemp(), mean_depth=500.0)
    print("| nodes | dt (s) | current given once: CPU us per step | environment attached: CPU us per step (cost) |")
    print("|---:|---:|---:|---:|")
    for n, dt in ((7, 0.1), (7, 0.02), (50, 0.1), (50, 0.02)):
        environment_run(n, dt, 1.0, True, env)  # compile / load the numba cache
        runs = {True: [], False: []}
        for _ in range(repeat):  # interleaved: the machine's speed drifts
            for attached in (False, True):
                runs[attached].append(environment_run(n, dt, seconds, attached, env))
        once, att = min(runs[False]), min(runs[True])
        print(f"| {n} | {dt:g} | {once:.0f} | {att:.0f} ({100 * (att / once - 1):+.1f} %) |", flush=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=100.0, help="simulated time per speed run")
    ap.add_argument("--environment", action="store_true", help="the cost of the environment (issue 18)")
    args = ap.parse_args()
    if args.environment:
        environment_table(args.seconds)
        return

    turning(7, 0.1, 1.0)  # compile / load the numba cache outside the timings

    print("### Speed: turning case (Table 1 cable, port turn 0.5 deg/s)\n")
    print("| nodes | dt (s) | simulated s / wall s | mean Newton iterations / step |")
    print("|---:|---:|---:|---:|")
    for n in (7, 50, 200):
        for dt in (0.1, 0.02):
            secs = args.seconds if not (n == 200 and dt == 0.02) else min(args.seconds, 40.0)
            wall, its, _ = turning(n, dt, secs)
            print(f"| {n} | {dt:g} | {secs / wall:.1f} | {its:.2f} |")

    print("\n### Block tri-diagonal vs dense solve of the Newton Jacobian (one core)\n")
    print("| nodes | unknowns | block solve (ms) | dense solve (ms) | dense / block | "
          "relative difference |")
    print("|---:|---:|---:|---:|---:|---:|")
    for n in (7, 50, 200):
        cable = FdCable(P, (0, 0, 0), (1, 0, 0), 0.0, n_nodes=n)
        for k in range(1, 6):
            psi = RATE * k
            cable.set_top_kinematics((math.sin(psi) / RATE, (1 - math.cos(psi)) / RATE, 0),
                                     (math.cos(psi), math.sin(psi), 0))
            cable.step(1.0)
        cable.set_top_kinematics((5.0, 0.5, 0.0), (0.9, 0.3, 0.05))
        A, D, C, r = cable.linear_system(0.1)
        M = FK.blocks_to_dense(A, D, C)
        rv = r.ravel()
        xb = FK.block_tridiag_solve(A, D, C, r)
        xd = np.linalg.solve(M, rv).reshape(r.shape)
        tb = best_time(lambda: FK.block_tridiag_solve(A, D, C, r))
        td = best_time(lambda: np.linalg.solve(M, rv))
        diff = np.linalg.norm(xb - xd) / np.linalg.norm(xd)
        print(f"| {n} | {10 * n} | {tb * 1e3:.4f} | {td * 1e3:.4f} | {td / tb:.0f} | {diff:.1e} |")

    print("\n### Turning case history (top = towing point; end = free end; world ENU, m)\n")
    for n, dt in ((7, 0.1), (49, 0.05)):
        _, _, rows = turning(n, dt, 100.0)
        print(f"{n} nodes, dt = {dt:g} s:\n")
        print("| t (s) | top tension (N) | top x | top y | end x | end y | end z |")
        print("|---:|---:|---:|---:|---:|---:|---:|")
        for t, T, tx, ty, ex, ey, ez in rows:
            print(f"| {t:.0f} | {T:.1f} | {tx:.2f} | {ty:.2f} | {ex:.2f} | {ey:.2f} | {ez:.2f} |")
        print()


if __name__ == "__main__":
    main()
