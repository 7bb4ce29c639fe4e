#!/usr/bin/env python3
"""Benchmark: rope_model vs MoorDyn on the Table 1 rope (issue 3). Not a test.

Same line in both codes: 100 m, d 0.05 m, 1.725 kg/m, EA 1.046e6 N, axial damping ratio
0.5, Cd 1.2 on d*l, Cf 0.015 on pi*d*l, Ca 1, submerged (ends 100 m apart at z = -50 m in
500 m of water; the rope is buoyant, so the static shape is an upward arch: "sag" below is
the mid-span rise). MoorDyn's static initial-condition solver does not converge for this
line in air at N = 200, hence submerged. End a
fixed, end b moved by the "tug": x_b = 98 + 2 cos(2 pi t / 10) (a 2 m surge, slackening and
re-tensioning the rope). Exchange period 0.02 s for both (the rope node's period). MoorDyn
runs RK2 (its default) with the largest step from a ladder (0.02 s down, steps that divide
the exchange period) that stays finite for the whole run; rope_model runs its default
sub-step (0.01 s, two per exchange) and 0.02 s (one), or the --substep values. Both timed
loops do the same per exchange step: set the moving end, step, read the end force (norm
with math, not numpy) and the mid-span height.

Reported per N = 11, 50, 200: static mid-span sag of each (matched accuracy = within 1 %
of each other), simulated seconds per wall second over 60 s, the RMS difference of the
mid-span height histories between the two codes and against rope_model with a 10x smaller
step, the peak end tension, and the warm-start time to the first step
(fresh interpreter, numba cache present). Rates use the process CPU time (best of
--repeat runs), which equals wall time on an idle core and is robust on a shared machine.
Prints a markdown table per rope_model sub-step (the MoorDyn runs are shared).
--stability prints rope_model's stability map instead; --environment the cost of the
per-element current, wind and seabed (issue 18) against the calm rope (rope_model only).

Usage: PYTHONPATH=ros_ws/src/rope_model python benchmarks/bench_rope.py [--seconds 60]
"""
import argparse
import contextlib
import math
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "ros_ws", "src", "rope_model"))
sys.path.insert(0, os.path.join(HERE, "..", "ros_ws", "src", "sea_environment"))

from rope_model import RopeChain, default_rope_path, load_rope_params  # noqa: E402

# MoorDyn takes the tangential drag on the surface pi*d*l (CdAx); Eq (10) uses d*l: match
# MoorDyn here so that both codes model the same line
P = load_rope_params(default_rope_path()).replace(tangential_area_factor=math.pi)
Z0 = float(os.environ.get("BENCH_Z0", "-50.0"))  # line depth (z up)
DT_X = 0.02  # exchange period


def tug(t):
    ph = 2.0 * math.pi * t / 10.0
    return (98.0 + 2.0 * math.cos(ph), 0.0, Z0), (-2.0 * math.sin(ph) * 2.0 * math.pi / 10.0, 0.0, 0.0)


@contextlib.contextmanager
def quiet():
    """MoorDyn writes to the C stdout: silence fd 1 and 2."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = os.dup(1), os.dup(2)
    with open(os.devnull, "w") as dn:
        os.dup2(dn.fileno(), 1)
        os.dup2(dn.fileno(), 2)
        try:
            yield
        finally:
            sys.stdout.flush()
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            os.close(saved[0])
            os.close(saved[1])


# ------------------------------------------------------------------ MoorDyn
MD_TEMPLATE = """--------------------- MoorDyn Input File ------------------------------------
Table 1 towing rope (seed 000), benchmark
---------------------- LINE TYPES ----------------------------------------------------------------------
TypeName   Diam    Mass/m     EA     BA/-zeta    EI         Cd     Ca     CdAx    CaAx
(name)     (m)     (kg/m)     (N)    (N-s/-)     (N-m^2)    (-)    (-)    (-)     (-)
rope       {d}     {mu}       {ea}   -{zeta}     0          {cd}   1.0    {cf}    0.0
---------------------- POINTS ---------------------------------------
ID   Attachment  X       Y     Z      Mass   Volume  CdA    Ca
(#)   (word/ID) (m)     (m)   (m)    (kg)   (m^3)   (m^2)  (-)
1     Fixed      0       0     {z}     0      0       0      0
2     Coupled    100     0     {z}     0      0       0      0
---------------------- LINES ----------------------------------------
ID   LineType   AttachA  AttachB  UnstrLen  NumSegs  LineOutputs
(#)   (name)     (ID)     (ID)      (m)       (-)      (-)
1     rope       1        2        {L}        {n}       -
---------------------- OPTIONS -----------------------------------------
0             writeLog
{dt}          dtM
1             disableOutTime
1             disableOutput
{g}           g
{rho}         rho
500           WtrDpth
RK2           tScheme
300           TmaxIC
1e-6          threshIC
---------------------- OUTPUTS -----------------------------------------
------------------------- need this line -------------------------------------
"""


def md_file(n, dt, folder):
    path = os.path.join(folder, f"rope_{n}_{dt:g}.txt")
    with open(path, "w") as fh:
        fh.write(MD_TEMPLATE.format(d=P.diameter, mu=P.mass_per_length, ea=P.ea,
                                    zeta=P.damping_ratio_axial, cd=P.drag_normal,
                                    cf=P.drag_tangential, z=Z0, L=P.length, n=n, dt=dt,
                                    g=P.gravity, rho=P.water_density))
    return path


def md_run(n, dt, seconds, folder):
    """Returns (ok, sag, rate, tensions, warm_start_s)."""
    import moordyn
    t0 = time.perf_counter()
    with quiet():
        s = moordyn.Create(md_file(n, dt, folder))
        x, v = tug(0.0)
        moordyn.Init(s, list(x), list(v))
    line = moordyn.GetLine(s, 1)
    nn = moordyn.GetLineNumberNodes(line)
    pos = np.array([moordyn.GetLineNodePos(line, i) for i in range(nn)])
    sag = np.interp(50.0, pos[:, 0], pos[:, 2]) - Z0
    tens = []
    mids = []
    ok = True
    t = 0.0
    t_first = None
    wall0 = time.process_time()
    try:
        with quiet():
            for k in range(int(round(seconds / DT_X))):
                x, v = tug(t)
                f = moordyn.Step(s, list(x), list(v), t, DT_X)
                if t_first is None:
                    t_first = time.perf_counter() - t0
                t += DT_X
                tens.append(math.hypot(f[0], f[1], f[2]))  # no overflow when diverging
                if n % 2:
                    zm = 0.5 * (moordyn.GetLineNodePos(line, n // 2)[2]
                                + moordyn.GetLineNodePos(line, n // 2 + 1)[2])
                else:
                    zm = moordyn.GetLineNodePos(line, n // 2)[2]
                mids.append(zm)
                if not all(math.isfinite(c) for c in f):
                    ok = False
                    break
    except (RuntimeError, OverflowError):
        ok = False
    wall = time.process_time() - wall0
    with quiet():
        moordyn.Close(s)
    return ok, sag, seconds / wall, np.array(tens), np.array(mids), t_first


def md_best(n, seconds, folder):
    # largest step first; every step divides the exchange period
    for dt in (0.02, 0.01, 0.005, 0.004, 0.0025, 0.002, 0.001, 5e-4, 4e-4, 2.5e-4, 2e-4, 1e-4,
               5e-5):
        ok, *_ = md_run(n, dt, seconds, folder)
        if ok:
            return dt, md_run(n, dt, seconds, folder)  # timed again, clean
    raise RuntimeError(f"MoorDyn: no stable step for N={n}")


# ------------------------------------------------------------------ rope_model
def rope_static(n):
    rope = RopeChain.straight(P, (0, 0, Z0), (100, 0, Z0), n_elements=n, relaxation=2.0,
                              max_substep=0.02)
    for _ in range(1000):  # 20 s of relaxation to the static catenary (not timed)
        rope.step(DT_X)
    rope.relaxation = 0.0
    rope.V[:] = 0.0
    rope.W[:] = 0.0
    return rope


def rope_run(n, seconds, max_substep=0.01):
    rope = rope_static(n)
    rope.max_substep = max_substep
    pts = np.vstack([rope.joint_points(), rope.positions])
    pts = pts[np.argsort(pts[:, 0])]
    sag = np.interp(50.0, pts[:, 0], pts[:, 2]) - Z0
    tens = []
    mids = []
    t = 0.0
    X, E, L = rope.X, rope.E, rope.L
    wall0 = time.process_time()
    for k in range(int(round(seconds / DT_X))):
        x, v = tug(t)
        rope.set_end_kinematics("b", x, v)
        rope.step(DT_X)
        t += DT_X
        tens.append(math.hypot(*rope.end_force("b").tolist()))  # as MoorDyn's
        if n % 2:
            mids.append(X[n // 2, 2])
        else:  # joint between elements n/2-1 and n/2
            mids.append(0.5 * (X[n // 2 - 1, 2] - 0.5 * L[n // 2 - 1] * E[n // 2 - 1, 2]
                               + X[n // 2, 2] + 0.5 * L[n // 2] * E[n // 2, 2]))
    wall = time.process_time() - wall0
    return sag, seconds / wall, np.array(tens), np.array(mids)


# ------------------------------------------------------------------ environment overhead
ENV_MODES = ("calm", "field once", "environment attached", "line pulled, no seabed", "seabed contact")


def _bench_environment():
    """The vessel benchmark's fields, the grid 480-520 m deep (the line never touches)."""
    sys.path.insert(0, HERE)
    from bench_vessels import bench_environment
    return bench_environment(tempfile.mkdtemp(), mean_depth=500.0)


def env_run(n, seconds, max_substep, mode):
    """Sim-s per CPU-s of the benchmark loop with the environment of issue 18:
    calm: as rope_run (uniform zero current, no wind, no seabed);
    field once: a sheared current (N, 3), a wind (N, 3) and a seabed 500 m down (N,) given
        once by set_environment (the kernel's per-element cost: the current and wind columns
        and the seabed reach check, no contact);
    environment attached: the gusty wind, tidal sheared current and bathymetry grid of
        _bench_environment attached (RopeChain.attach_environment): the rope samples them at
        its element centres inside its compiled step, every exchange step (what the rope node
        does: the whole cost of the environment);
    seabed contact: every element on the seabed: a sinking line (12 kg/m) lying on it, end a
        pulled along at 0.05 m/s (the friction test's case), set_environment every step;
    line pulled, no seabed: the same line and loop without seabed and weight (it stays where
        it lies): the baseline of the contact cost."""
    if mode in ("seabed contact", "line pulled, no seabed"):
        contact = mode == "seabed contact"
        # without the seabed: the same line and loop, weightless (it stays where it lies)
        p = P.replace(mass_per_length=12.0, gravity=P.gravity if contact else 0.0)
        z0 = -20.0 + p.radius
        rope = RopeChain.straight(p, (0, 0, z0), (100, 0, z0), n_elements=n, end_b="free",
                                  max_substep=max_substep)
        depth = np.full(n, 20.0 if contact else math.inf)
        zero = np.zeros((n, 3))
        rope.set_environment(seabed_depth=depth)
        t = 0.0
        wall0 = time.process_time()
        for _ in range(int(round(seconds / DT_X))):
            v = -0.05 * min(1.0, t / 2.0)
            rope.set_end_kinematics("a", rope.attachment_position("a"), (v, 0.0, 0.0))
            rope.set_environment(zero, zero, depth)
            rope.step(DT_X)
            t += DT_X
            math.hypot(*rope.end_force("a").tolist())
        return seconds / (time.process_time() - wall0)
    rope = rope_static(n)
    rope.max_substep = max_substep
    if mode == "field once":
        c = rope.element_centres()
        cur = np.zeros((n, 3))
        cur[:, 1] = 0.005 * c[:, 0]  # 0 .. 0.5 m/s across the line
        wind = np.zeros((n, 3))
        wind[:, 0] = 10.0
        rope.set_environment(current=cur, wind=wind, seabed_depth=np.full(n, 500.0))
    elif mode == "environment attached":
        from sea_environment.sampler import EnvironmentSampler
        rope.attach_environment(EnvironmentSampler(_bench_environment()).data)
    X = rope.X
    t = 0.0
    wall0 = time.process_time()
    for _ in range(int(round(seconds / DT_X))):
        x, v = tug(t)
        rope.set_end_kinematics("b", x, v)
        rope.step(DT_X)
        t += DT_X
        math.hypot(*rope.end_force("b").tolist())
        X[n // 2, 2]
    return seconds / (time.process_time() - wall0)


def environment_table(ns, substeps, seconds, repeat):
    print("| N | sub-step (s) | calm: sim-s/CPU-s (us per step) | " +
          "field once | environment attached (sim-s/CPU-s (us per step, cost vs calm)) | line pulled, "
          "no seabed | seabed contact (sim-s/CPU-s (us per step, cost vs the line without "
          "seabed)) |")
    print("|---|---|" + "---|" * len(ENV_MODES))
    for n in ns:
        for h in substeps:
            runs = {m: [] for m in ENV_MODES}
            for _ in range(repeat):      # interleaved: the machine's speed drifts between rounds
                for m in ENV_MODES:
                    runs[m].append(env_run(n, seconds, h, m))
            best = {m: max(r) for m, r in runs.items()}
            us = {m: 1e6 * DT_X / best[m] for m in ENV_MODES}
            ref = {m: "calm" for m in ENV_MODES}
            ref["seabed contact"] = "line pulled, no seabed"
            cells = [f"{best[m]:.0f} ({us[m]:.1f} us, {100 * (us[m] / us[ref[m]] - 1):+.1f} %)"
                     if m != "line pulled, no seabed" else f"{best[m]:.0f} ({us[m]:.1f} us)"
                     for m in ENV_MODES[1:]]
            print(f"| {n} | {h:g} | {best['calm']:.0f} ({us['calm']:.1f} us) | " + " | ".join(cells)
                  + " |", flush=True)


def stability_map(seconds):
    """Runs the benchmark motion with rope_model for a grid of element counts, stiffness
    multipliers and sub-steps; prints the largest sub-step that stays bounded and its error."""
    print("| N | EA | theta | sub-step (s) | result | mid-span RMS error vs theta 0.55, 0.001 s (/rise) |")
    print("|---|---|---|---|---|---|")
    global P
    base = P
    for ea_mul in (1.0, 10.0):
        P = base.replace(axial_stiffness=base.ea * ea_mul)
        for n in (11, 50, 200, 400):
            ref = None
            for theta in (0.55, 0.5):
                for h in (0.001, 0.005, 0.01, 0.02):
                    try:
                        rope = rope_static(n)
                        rope.theta = theta
                        rope.max_substep = h
                        zs, t, peak = [], 0.0, 0.0
                        for _ in range(int(round(seconds / DT_X))):
                            x, v = tug(t)
                            rope.set_end_kinematics("b", x, v)
                            rope.step(DT_X)
                            t += DT_X
                            peak = max(peak, rope.tensions.max())
                            zs.append(rope.X[n // 2, 2])
                        zs = np.array(zs)
                        bounded = peak < 10 * 6.6e3 * ea_mul ** 0.5 and not rope.events
                        res = "bounded" if bounded else f"unbounded (peak {peak / 1e3:.0f} kN)"
                    except Exception as exc:  # RopeDivergedError
                        zs, res = None, f"diverged ({type(exc).__name__})"
                    if h == 0.001 and theta == 0.55:
                        ref = zs
                    err = ""
                    if zs is not None and ref is not None and len(zs) == len(ref):
                        err = f"{100 * np.sqrt(np.mean((zs - ref) ** 2)) / 2.33:.1f} %"
                    print(f"| {n} | {ea_mul:g} x | {theta} | {h:g} | {res} | {err} |", flush=True)
    P = base


WARM = r"""
import time, sys
t0 = time.perf_counter()
sys.path.insert(0, {path!r})
from rope_model import RopeChain, default_rope_path, load_rope_params
p = load_rope_params(default_rope_path())
r = RopeChain.straight(p, (0, 0, -50), (100, 0, -50), n_elements={n})
r.set_end_kinematics("b", (100, 0, -50), (0, 0, 0))
r.step(0.02)
print(time.perf_counter() - t0)
"""


def rope_warm_start(n):
    path = os.path.join(HERE, "..", "ros_ws", "src", "rope_model")
    code = WARM.format(path=os.path.abspath(path), n=n)
    subprocess.run([sys.executable, "-c", code], check=True, capture_output=True)  # fill cache
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True)
    return float(out.stdout.strip().splitlines()[-1])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--n", type=int, nargs="*", default=[11, 50, 200])
    ap.add_argument("--substep", type=float, nargs="*", default=[0.01, 0.02],
                    help="rope_model max sub-step(s) (s), one table each")
    ap.add_argument("--repeat", type=int, default=3, help="timing repeats (best is kept)")
    ap.add_argument("--stability", action="store_true", help="print the rope_model stability map")
    ap.add_argument("--environment", action="store_true",
                    help="print the cost of the environment (per-element current, wind, seabed; "
                         "issue 18) against the calm rope, rope_model only")
    a = ap.parse_args()
    if a.stability:
        stability_map(a.seconds)
        return
    if a.environment:
        environment_table(a.n, a.substep, a.seconds, a.repeat)
        return
    rows = {h: [] for h in a.substep}
    with tempfile.TemporaryDirectory() as folder:
        for n in a.n:
            dt_md, (ok, sag_md, rate_md, t_md, z_md, first_md) = md_best(n, a.seconds, folder)
            runs = {h: rope_run(n, a.seconds, max_substep=h) for h in a.substep}
            rate_r = {h: runs[h][1] for h in a.substep}
            for _ in range(a.repeat - 1):  # best of: the machine is shared
                rate_md = max(rate_md, md_run(n, dt_md, a.seconds, folder)[2])
                for h in a.substep:
                    rate_r[h] = max(rate_r[h], rope_run(n, a.seconds, max_substep=h)[1])
            _, _, t_ref, z_ref = rope_run(n, a.seconds, max_substep=0.001)  # own step error
            warm = rope_warm_start(n)
            for h in a.substep:
                sag_r, _, t_r, z_r = runs[h]
                m = min(len(z_md), len(z_r))
                # mid-span height histories, RMS difference relative to the static sag
                rms = float(np.sqrt(np.mean((z_md[:m] - z_r[:m]) ** 2)) / abs(sag_md))
                rms_ref = float(np.sqrt(np.mean((z_ref - z_r) ** 2)) / abs(sag_md))
                rows[h].append((n, sag_r, sag_md, rate_r[h], rate_md, dt_md, rms, rms_ref, warm,
                                first_md, t_r.max(), t_md.max()))
            print(f"N={n} done", file=sys.stderr, flush=True)
    for h in a.substep:
        print(f"\nrope_model sub-step {h:g} s:\n")
        print("| N | mid-span rise rope_model (m) | rise MoorDyn (m) | difference | rope_model "
              f"sim-s/wall-s (sub-step {h:g} s) | MoorDyn sim-s/wall-s (RK2, dt) | speed ratio | "
              "mid-span height RMS diff between codes (/sag) | rope_model step error "
              f"({h:g} vs 0.001 s, /sag) | peak tension rope_model / MoorDyn (kN) | warm start "
              "to first step: rope_model / MoorDyn (s) |")
        print("|---|---|---|---|---|---|---|---|---|---|---|")
        for (n, sr, sm, rr, rm, dtm, rms, rref, warm, fm, pr, pm) in rows[h]:
            print(f"| {n} | {sr:.4f} | {sm:.4f} | {100 * (sr - sm) / sm:+.2f} % | {rr:.0f} | "
                  f"{rm:.0f} (dt {dtm:g} s) | {rr / rm:.2f} | {100 * rms:.1f} % | "
                  f"{100 * rref:.1f} % | {pr / 1e3:.1f} / {pm / 1e3:.1f} | {warm:.2f} / {fm:.2f} |")


if __name__ == "__main__":
    main()
