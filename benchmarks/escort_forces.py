#!/usr/bin/env python3
"""Escort (indirect towing) forces of the ASD tug as a function of its drift angle (issue 19 item 4).

The tug is made fast by its bow staple to a ship running at 10 kn; in the steady indirect mode it
moves with the ship at a drift angle beta to the flow (heading beta off the course, r = 0) and its
two azimuth thrusters only hold that angle: both at one azimuth (+-90 deg, thrust athwartships,
the direction that gives the most yaw moment about the staple per unit thrust) and the rpm that
balances the yaw moment. The line force is then whatever balances the hull and thruster forces.

  steering force  F_S: the line force on the ship across its course
  braking force   F_B: the line force on the ship against its course

Two computations, both with the model itself (tug_dynamics: load_ship, the kernel's _deriv_t,
vessel.step):
  1. static: the steady state solved directly: du = dv = dr = dp = 0 for (line force east, north,
     thruster order s, heel) with scipy.optimize.fsolve (s in [-1, 1]: azimuth sign(s) 90 deg,
     rpm |s|; |s| > 1 means the angle cannot be held at this speed);
  2. dynamic: the tug stepped in time (vessel.step, 4 DOF) in a 10 kn current on a line modelled
     as a stiff spring from a fixed point (the ship's stern in the ship's frame) to the staple,
     heading held by a PI loop on the thruster rpm, from rest at the static state; the line force
     after 150 s is compared with the static one (the steady state is reached and held).

Published comparison (see tug_dynamics/README.md, "Escort"): no steering-force-versus-drift
curve with numbers for a comparable ASD tug was found in the sources available here. The
comparison is with published statements: Allan & Molyneux (2004) (maximum forces at yaw angles
up to about 45 deg; hull forces dominate above 8 kn), Hensen (2003) "Tug use in port" (indirect
steering forces 1.5 to 2 times the bollard pull) and Kotug's Rotortug note (towline forces in
excess of 130 % of the bollard pull at yaw angles up to 45 deg).

Usage: python benchmarks/escort_forces.py [--png docs/escort_forces.png] [--no-dynamic]
Prints a markdown table; writes the plot (matplotlib, Agg).
"""
from __future__ import annotations

import argparse
import math
import os
import sys

import numpy as np
from scipy.optimize import fsolve

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
for pkg in ("tug_dynamics", "sim_math", "sea_environment", "sim_plumbing"):
    p = os.path.join(ROOT, "ros_ws", "src", pkg)
    if p not in sys.path:
        sys.path.insert(0, p)

from tug_dynamics import maneuvering as mv  # noqa: E402
from tug_dynamics.ship_file import load_ship  # noqa: E402
from tug_dynamics.vessel import ExternalWrench, ThrusterOrder, VesselState, rotation_body_to_world  # noqa: E402

G = 9.80665
KN = 0.514444
SPEED_KN = 10.0
STAPLE = "bow_staple"
GAINS = (2.0, 0.2, 10.0)   # heading PID on the thruster order, per rad (dynamic_escort)


def _set_thrusters(tug, s):
    """Both units at azimuth sign(s) 90 deg, shaft speed |s| rated (the actual state)."""
    az = math.copysign(0.5 * math.pi, s) if s != 0.0 else 0.5 * math.pi
    states = []
    for cfg in tug.thruster_cfg:
        states.append((az, abs(s) * cfg["rated_rps"]))
    return az, states


def _accel(tug, beta, speed, s, phi, fx, fy):
    """Accelerations (du, dv, dr, dp) of the tug at drift beta (rad), moving at `speed` through
    still water along world east with heading beta (r = 0), thruster order s (azimuth sign(s)
    90 deg, shaft speed |s| rated; the kernel takes |s| > 1 as an over-speed), heel phi (rad) and
    the line force (east, north) N at the staple."""
    az, thr = _set_thrusters(tug, s)
    st = np.zeros_like(tug.s)
    st[mv.S_PSI] = beta
    st[mv.S_PHI] = phi
    st[mv.S_U] = speed * math.cos(beta)
    st[mv.S_V] = -speed * math.sin(beta) / math.cos(phi)   # the heeled body's y: world velocity stays east
    ctrl = tug.ctrl.copy()
    for k, (a, n) in enumerate(thr):
        st[mv.S_THR0 + 2 * k] = n
        st[mv.S_THR0 + 2 * k + 1] = a
        ctrl[mv.C_THR0 + 2 * k] = n
        ctrl[mv.C_THR0 + 2 * k + 1] = a
    pt = tug.attachments[STAPLE]
    d = mv._deriv_t(st, tug.hp, tug.props, tug.ruds, tug.thrs, tug.rv, tug.rf, tug.minv, ctrl,
                    np.array([[fx, fy, 0.0]]), np.array([pt]), np.zeros((1, 3)), tug.out.copy())
    return np.array([d[mv.S_U], d[mv.S_V], d[mv.S_R], d[mv.S_P]])


def _line_for(tug, beta, speed, s, phi):
    """The line force (east, north) that makes du = dv = 0 (the accelerations are linear in it),
    and the remaining (dr, dp)."""
    a0 = _accel(tug, beta, speed, s, phi, 0.0, 0.0)
    ax = _accel(tug, beta, speed, s, phi, 1e5, 0.0) - a0
    ay = _accel(tug, beta, speed, s, phi, 0.0, 1e5) - a0
    J = np.array([[ax[0], ay[0]], [ax[1], ay[1]]]) / 1e5
    f = np.linalg.solve(J, -a0[:2])
    a = a0 + (ax * f[0] + ay * f[1]) / 1e5
    return f, a[2:]


def static_escort(tug, beta_deg, speed=SPEED_KN * KN, guess=None):
    """The steady indirect state at drift beta_deg: dict with the line force on the tug (east,
    north, N), the thruster order s, heel (rad), steering and braking force on the ship (N) and
    the line's angle from the course (deg)."""
    beta = math.radians(beta_deg)
    g = np.array([0.0, 0.0]) if guess is None else np.asarray(guess, float)

    def res(x):
        _, r = _line_for(tug, beta, speed, x[0], x[1])
        return [r[0] * 100.0, r[1] * 100.0]

    sol, info, ier, msg = fsolve(res, g, full_output=True, xtol=1e-12)
    s, phi = sol
    (fx, fy), rr = _line_for(tug, beta, speed, s, phi)
    return {"beta_deg": beta_deg, "fx": fx, "fy": fy, "s": s, "heel": phi,
            "residual": float(np.max(np.abs(rr))), "braking": fx, "steering": abs(fy),
            "line_angle_deg": math.degrees(math.atan2(-fy, fx)), "tension": math.hypot(fx, fy)}


def dynamic_escort(tug_file, st, speed=SPEED_KN * KN, duration=150.0, dt=0.05, line_length=40.0):
    """Step the tug (vessel.step) on a spring line from a point running east at `speed` (the
    ship's stern bollard), heading held at beta by a PID loop on the thruster order,
    started at the static state st. Returns the mean line force (east, north) over the last 20 s,
    the heading error (deg) and the thruster order at the end."""
    beta = math.radians(st["beta_deg"])
    tug = load_ship(tug_file)
    pt = tug.attachments[STAPLE]
    # line direction from the staple to the ship's point: along the line force on the tug
    fx, fy = st["fx"], st["fy"]
    e = np.array([fx, fy]) / math.hypot(fx, fy)
    k_line = 2.0e5                                      # N/m: 100 t stretches the spring 5 m
    c_line = 2.0 * math.sqrt(k_line * tug.mass_matrix[0, 0]) * 0.5
    stretch = math.hypot(fx, fy) / k_line
    staple_w = np.array([math.cos(beta) * pt[0], math.sin(beta) * pt[0]])
    anchor = staple_w + e * (line_length + stretch)
    az, thr = _set_thrusters(tug, float(np.clip(st["s"], -1, 1)))
    v0 = np.array([speed * math.cos(beta), -speed * math.sin(beta) / math.cos(st["heel"]), 0.0])
    tug.set_state(VesselState(np.zeros(3), np.array([st["heel"], 0.0, beta]), v0, np.zeros(3)),
                  thrusters=thr)
    s_cmd = float(np.clip(st["s"], -1, 1))
    integ = 0.0
    kp, ki, kd = GAINS                         # per rad of heading error
    # the yaw moment about the staple falls as s rises (thrust to port at the stern turns the bow
    # to starboard): a bow too far to port (err > 0) or turning to port (r > 0) raises s
    forces = []
    p_prev = None
    n = int(round(duration / dt))
    for i in range(n):
        S = tug.state
        psi = S.rpy[2]
        p_w = (S.position + rotation_body_to_world(S.rpy) @ pt)[:2]
        v_w = np.zeros(2) if p_prev is None else (p_w - p_prev) / dt
        p_prev = p_w
        r = S.angular_velocity_body[2]
        d = anchor + np.array([speed * tug.time, 0.0]) - p_w     # the ship's point runs east at `speed`
        L = np.linalg.norm(d)
        u_l = d / L
        ext = L - line_length
        T = max(0.0, k_line * ext - c_line * (float(v_w @ u_l) - speed * u_l[0]))
        F = T * u_l
        err = math.atan2(math.sin(psi - beta), math.cos(psi - beta))
        integ += err * dt
        s_cmd = st["s"] + kp * err + ki * integ + kd * r
        s_cmd = float(np.clip(s_cmd, 0.0, 1.0) if st["s"] > 0 else np.clip(s_cmd, -1.0, 0.0))  # no azimuth flip
        a = math.copysign(0.5 * math.pi, s_cmd) if abs(s_cmd) > 1e-9 else az
        tug.set_thruster_command([ThrusterOrder(k, a, abs(s_cmd)) for k in range(len(tug.thruster_cfg))])
        tug.step(dt, [ExternalWrench(np.array([F[0], F[1], 0.0]), pt.copy())])
        if i >= n - int(20.0 / dt):
            forces.append(F)
    f = np.mean(forces, axis=0)
    return {"fx": f[0], "fy": f[1], "heading_err_deg": math.degrees(err), "s": s_cmd,
            "heel_deg": math.degrees(tug.state.rpy[0])}


def holdable_limit(tug, lo=5.0, hi=90.0):
    """The largest drift angle (deg) the thrusters hold at full rpm (|s| = 1), by bisection on
    the static solution (|s| grows with the drift up to there), with its static state."""
    from scipy.optimize import brentq
    guess = [None]

    def f(b):
        st = static_escort(tug, b, guess=guess[0])
        guess[0] = np.array([st["s"], st["heel"]])
        return abs(st["s"]) - 1.0

    if f(hi) < 0.0:
        return hi, static_escort(tug, hi)
    b = brentq(f, lo, hi, xtol=1e-3)
    return b, static_escort(tug, b)


def sweep(tug_file="asd_tug.yaml", betas=None, dynamic=True):
    tug = load_ship(tug_file)
    betas = list(range(0, 91, 5)) if betas is None else betas
    rows = []
    guess = None
    for b in betas:
        st = static_escort(tug, b, guess=guess)
        guess = np.array([st["s"], st["heel"]])
        if dynamic and 0 < b and abs(st["s"]) <= 1.0:
            st["dyn"] = dynamic_escort(tug_file, st)
        rows.append(st)
    return rows


def bollard_pull_ahead(tug_file="asd_tug.yaml"):
    """Both units at 0 deg, rated rpm, at rest: the model's own thrust (N) from the thruster kernel."""
    tug = load_ship(tug_file)
    _, thr = _set_thrusters(tug, 1.0)
    thr = [(0.0, n) for _, n in thr]
    st = tug.s.copy()
    st[:] = 0.0
    ctrl = tug.ctrl.copy()
    for k, (a, n) in enumerate(thr):
        st[mv.S_THR0 + 2 * k] = n
        ctrl[mv.C_THR0 + 2 * k] = n
    X, Y, N, K = mv._thruster_forces(st, tug.thrs, ctrl, tug.hp[mv.H_RHO], 0.0, 0.0, 0.0, tug.out.copy(),
                                     np.zeros_like(st))
    return X


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--png", default=os.path.join(ROOT, "docs", "escort_forces.png"))
    ap.add_argument("--no-dynamic", action="store_true")
    args = ap.parse_args(argv)
    rows = sweep(dynamic=not args.no_dynamic)
    bp = bollard_pull_ahead()
    t = 1000.0 * G
    print(f"ASD tug (asd_tug.yaml, hull form crossflow) in indirect mode at {SPEED_KN:g} kn; "
          f"model bollard pull ahead {bp / t:.1f} t\n")
    print("| drift deg | steering t | braking t | tension t | tension / BP | line angle deg | "
          "thruster order (az +-90) | heel deg | dynamic steering / braking t |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        dyn = r.get("dyn")
        dtxt = (f"{abs(dyn['fy']) / t:.1f} / {dyn['fx'] / t:.1f}" if dyn else "-")
        ok = "" if abs(r["s"]) <= 1.0 else " (beyond full rpm)"
        print(f"| {r['beta_deg']:.0f} | {r['steering'] / t:.1f} | {r['braking'] / t:.1f} | {r['tension'] / t:.1f} | "
              f"{r['tension'] / bp:.2f} | {r['line_angle_deg']:.1f} | {r['s']:+.3f}{ok} | "
              f"{math.degrees(r['heel']):.1f} | {dtxt} |")
    blim, slim = holdable_limit(load_ship("asd_tug.yaml"))
    print(f"\nlargest drift the thrusters hold at full rpm: {blim:.1f} deg: steering {slim['steering'] / t:.1f} t "
          f"({slim['steering'] / bp:.2f} x BP), braking {slim['braking'] / t:.1f} t, line force {slim['tension'] / t:.1f} t "
          f"({slim['tension'] / bp:.2f} x BP), heel {math.degrees(slim['heel']):.1f} deg")
    feas = [r for r in rows if abs(r["s"]) <= 1.0] + [slim]
    pk = max(feas, key=lambda r: r["steering"])
    print(f"peak steering force in indirect mode (thrusters within full rpm) {pk['steering'] / t:.1f} t "
          f"({pk['steering'] / bp:.2f} x bollard pull) at drift {pk['beta_deg']:.1f} deg; braking there "
          f"{pk['braking'] / t:.1f} t")
    un = max(rows, key=lambda r: r["steering"])
    print(f"steering force without the rpm limit (hull alone would allow): peak {un['steering'] / t:.1f} t at "
          f"{un['beta_deg']:.0f} deg (thruster order {abs(un['s']):.2f} of rated rpm needed)")
    if args.png:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        b = np.array([r["beta_deg"] for r in rows])
        fs = np.array([r["steering"] for r in rows]) / t
        fb = np.array([r["braking"] for r in rows]) / t
        ok = np.array([abs(r["s"]) <= 1.0 for r in rows])
        fig, ax = plt.subplots(figsize=(8, 6.5))
        ax.plot(b, fs, "b-", label="steering force (static)")
        ax.plot(b, fb, "r-", label="braking force (static)")
        ax.plot(b, np.array([r["tension"] for r in rows]) / t, "k--", lw=1, label="line force (static)")
        db = [r["beta_deg"] for r in rows if r.get("dyn")]
        ax.plot(db, [abs(r["dyn"]["fy"]) / t for r in rows if r.get("dyn")], "bo", mfc="none",
                label="steering, time-stepped tug on a line")
        ax.plot(db, [r["dyn"]["fx"] / t for r in rows if r.get("dyn")], "ro", mfc="none",
                label="braking, time-stepped tug on a line")
        if not ok.all():
            ax.axvspan(blim, b.max(), color="0.85", alpha=0.5,
                       label=f"beyond {blim:.1f} deg: needs > full rpm to hold the angle")
        ax.axhline(bp / t, color="k", ls=":", lw=1, label=f"bollard pull ahead {bp / t:.1f} t")
        ax.fill_between([0, 90], 1.5 * bp / t, 2.0 * bp / t, color="g", alpha=0.12,
                        label="1.5-2 x BP: indirect line force (Hensen 2003)")
        ax.axvline(45.0, color="g", ls="--", lw=1, label="max force at yaw <= ~45 deg (Allan & Molyneux 2004)")
        ax.set_xlabel("tug drift angle to the flow, deg")
        ax.set_ylabel("force on the ship, t")
        ax.set_title(f"ASD tug escort, indirect mode, {SPEED_KN:g} kn (hull: cross-flow model)")
        ax.set_xlim(0, 90)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=2)
        os.makedirs(os.path.dirname(args.png), exist_ok=True)
        fig.tight_layout()
        fig.savefig(args.png, dpi=110)
        print(f"\nplot: {os.path.relpath(args.png, ROOT)}")
    return rows


if __name__ == "__main__":
    main()
