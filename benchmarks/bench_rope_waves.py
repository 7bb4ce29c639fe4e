#!/usr/bin/env python3
"""Benchmark: what a sea of 150 components adds to the element-chain rope's exchange step
(issue 31's speed goal: under 25 % at N = 11-200). Not a test.

The rope: Table 1's 100 m line hanging slack between two points 1 m above the surface 98 m
apart (its middle in the water), end b surging 2 m at 10 s, the default sub-step (two per
0.02 s exchange step), the same current in every case. Three environments, stepped in turn
(calm, waves, waves direct; blocks of --block steps, --repeat rounds; CPU time of the process,
best block per case, which equals wall time on an idle core and is robust on a shared machine):
  calm:          no waves key;
  waves:         JONSWAP Hs 2 m, Tp 7 s, cos-2s, 150 components (the recurrence of
                 kernels.sample_waves, its phasors advanced from the last step's);
  waves direct:  the same sea evaluated directly at every element every step (the rope's wave
                 cache too small, so sample_waves falls back to waves.wave_kinematics_wet: the
                 cost before the recurrence).
Prints us per exchange step and the ratios waves / calm and direct / calm per N (a table per
--components: 150, the issue's 100-200, by default); --micro also
the cost per element and component of sample_waves alone, recurrence against direct.

Usage: PYTHONPATH=<the ros_ws/src packages> python benchmarks/bench_rope_waves.py
    [--n 11,50,200] [--components 150] [--block 200] [--repeat 5] [--micro]
"""
import argparse
import math
import os
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
for pkg in ("rope_model", "sea_environment", "sim_math"):
    sys.path.insert(0, os.path.join(HERE, "..", "ros_ws", "src", pkg))

from rope_model import RopeChain, default_rope_path, load_rope_params  # noqa: E402
from rope_model import kernels as K  # noqa: E402
from sea_environment.environment import Environment  # noqa: E402
from sea_environment.sampler import P_TIME, EnvironmentSampler, wave_offset  # noqa: E402

P = load_rope_params(default_rope_path())
DT = 0.02
SEA = {"hs": 2.0, "tp": 7.0, "from_deg": 250.0, "spreading_s": 8.0, "components": 150, "seed": 1}
CASES = ("calm", "waves", "waves direct")


def _environment(case, components=150):
    spec = {"current": [0.3, 0.1]}
    if case != "calm":
        spec["waves"] = dict(SEA, components=components)
    return EnvironmentSampler(Environment.from_mapping(spec)).data


def _rope(n, case, components):
    rope = RopeChain.slack(P, np.array([0.0, 0.0, 1.0]), np.array([98.0, 0.0, 1.0]), n_elements=n)
    rope.attach_environment(_environment(case, components))
    if case == "waves direct":
        rope._wave_cache = np.zeros((1, 1))     # does not fit: the direct evaluation
    return rope


def _block(rope, steps):
    """CPU seconds per exchange step over `steps` steps (end b surging)."""
    t0 = time.process_time()
    for _ in range(steps):
        ph = 2.0 * math.pi * rope.time / 10.0
        rope.set_end_kinematics("b", (98.0 + 2.0 * math.cos(ph), 0.0, 1.0),
                                (-0.4 * math.pi * math.sin(ph), 0.0, 0.0))
        rope.step(DT)
    return (time.process_time() - t0) / steps


def step_table(ns, block, repeat, components):
    print(f"rope exchange step (dt {DT} s, 2 sub-steps), us per step (best of {repeat} blocks of "
          f"{block}); sea of {components} components")
    print("| N | calm | waves (recurrence) | waves direct | waves / calm | direct / calm |")
    print("|---|---|---|---|---|---|")
    for n in ns:
        ropes = {c: _rope(n, c, components) for c in CASES}
        for c in CASES:
            _block(ropes[c], 50)            # compile, settle into the run
        best = {c: math.inf for c in CASES}
        for _ in range(repeat):
            for c in CASES:                 # alternating: a load change hits every case alike
                best[c] = min(best[c], _block(ropes[c], block))
        us = {c: 1e6 * best[c] for c in CASES}
        print(f"| {n} | {us['calm']:.1f} | {us['waves']:.1f} | {us['waves direct']:.1f} | "
              f"{us['waves'] / us['calm']:.3f} | {us['waves direct'] / us['calm']:.3f} |")


def micro(n_elements=50, steps=400, repeat=5):
    """ns per element and component of sample_waves alone: the elements drift 2 cm per step
    (the recurrence) against the direct evaluation (the same positions)."""
    env = _environment("waves")
    at, nc = wave_offset(env), K.wave_components(env)
    rope = RopeChain.slack(P, np.array([0.0, 0.0, 1.0]), np.array([98.0, 0.0, 1.0]), n_elements=n_elements)
    S = rope._S.copy()
    wc = K.new_wave_cache(n_elements, nc)
    x0 = S[:n_elements, K.SX].copy()

    def run(direct):
        t0 = time.process_time()
        for k in range(steps):
            S[:n_elements, K.SX] = x0 + 0.02 * k
            t = 100.0 + DT * k
            if direct:
                K._sample_waves_direct(S, env, at, t, nc)
            else:
                K.sample_waves(S, env, t, wc)
        return (time.process_time() - t0) / (steps * n_elements * nc)

    run(True), run(False)
    d = min(run(True) for _ in range(repeat))
    r = min(run(False) for _ in range(repeat))
    adv, dirn = wc[K.WC_HEADER, K.H_ADVANCED], wc[K.WC_HEADER, K.H_DIRECT]
    print(f"sample_waves alone, N = {n_elements}, {nc} components: direct {1e9 * d:.2f} ns, recurrence "
          f"{1e9 * r:.2f} ns per element-component ({d / r:.1f} x; {adv / (adv + dirn):.1%} of the "
          f"element-steps advanced, the rest refreshed directly)")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", default="11,50,200", help="element counts, comma separated")
    ap.add_argument("--block", type=int, default=200, help="exchange steps per timed block")
    ap.add_argument("--repeat", type=int, default=5, help="rounds of blocks (best taken)")
    ap.add_argument("--components", default="150", help="wave components, comma separated (a table each)")
    ap.add_argument("--micro", action="store_true", help="also time sample_waves alone")
    a = ap.parse_args()
    if a.micro:
        micro()
    for components in (int(v) for v in a.components.split(",")):
        step_table([int(v) for v in a.n.split(",")], a.block, a.repeat, components)


if __name__ == "__main__":
    main()
