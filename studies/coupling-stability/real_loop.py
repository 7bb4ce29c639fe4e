"""The lockstep exchange with the real models, ROS-free: the ASD tug (tug_dynamics, asd_tug.yaml)
at full ahead on 40 m of the 40 mm steel wire (rope_model element chain, steel_wire_40mm.yaml) to
a fixed point, or a wire between two free vessels (engines stopped).

Mimics sim_plumbing/stepping.py: step 0: the rope is laid out from the vessels' step-0
attachments and its step-0 output is end_force (not averaged); step k -> k+1: the rope takes the
attachments stamped k (set_end_kinematics, moved linearly over its step) and publishes
mean_end_force stamped k+1; each vessel applies the rope force stamped k over its step k -> k+1
(vessel_node.compute_step: ExternalWrench constant over the step).

Schemes (see linear_model.py):
  lag      what the nodes do now
  pred     the rope is driven one step ahead: set_end(x_k + h v_k, v_k) (its mean force is the
           spring at the predicted middle of the step it acts over: fender.py's lead 1.5 dt).
           Breaks the element chain: the end then jumps by ~h^2 a every step, inconsistent with
           its velocity, and the end connection piles up a spurious stretch (rope_shift_check.py)
  predJ    the same prediction done on the force instead: the rope is driven as now and
           publishes Fbar + Jx (h v_k) (+ the other end's term), held over the vessel's step
  jac      the rope also publishes its end Jacobian (rope_jacobian below) and the reference end
           state of its step (xhat = x_{k-1} + v_{k-1} h/2, vhat = v_{k-1}); the vessel applies
           F = Fbar + Jx (x_att(t) - xhat) + Jv (v_att(t) - vhat) inside its step. Emulated here
           by sub-stepping the vessel (n_sub from omega_J h_sub <= 0.05, the force of each
           sub-step at its predicted middle); in the design it goes into the RK4 stages.
  jac_pred jac, and the rope shifts the other end's reference one step ahead (its own
           prediction of the other end over the step the force acts over)
  jac_now  jac, and the vessel takes the other vessel's attachment of step k (x_b,k + v_b,k s)
"""
from __future__ import annotations

import os
import copy
import dataclasses
import math
import sys
import time

import numpy as np

from rope_model.chain import RopeChain
from rope_model.params import load_rope_params
from tug_dynamics.ship_file import load_ship
from tug_dynamics.vessel import Command, ExternalWrench, VesselState

SHIPS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "ros_ws", "src") + "/" + "tug_dynamics/ships/"
ROPES = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "ros_ws", "src") + "/" + "rope_model/ropes/"
TF = 9806.65


def rotx(vessel):
    """World x velocity of the vessel's reference point."""
    s = vessel.state
    return math.cos(s.rpy[2]) * s.linear_velocity_body[0] - math.sin(s.rpy[2]) * s.linear_velocity_body[1]


def rope_jacobian(rope: RopeChain, end: str):
    """dF/dx (3x3) and dF/dv (3x3) of the force the rope exerts on attachment `end`, world:
    axial tangent stiffness along the end's line of pull (elastic chain in series with the
    sag compliance of a shallow elastic catenary, Irvine 1981) and the string's geometric
    stiffness T / chord across it; axial damping of the connection dampers in series."""
    p = rope.params
    i = 0 if end == "a" else 1
    F = rope.mean_end_force(end)
    T = float(np.linalg.norm(F))
    pa, pb = rope.att_pos[0], rope.att_pos[1]
    chord = float(np.linalg.norm(pb - pa))
    L0 = rope.unstretched_length
    if T < 1.0 or chord < 1e-6:
        return np.zeros((3, 3)), np.zeros((3, 3)), T
    e = F / T                                        # from the attachment towards the rope
    d = (pb - pa) / chord
    w = p.mass_per_length * p.gravity                # weight per length (in air; wetted: less)
    w_perp = w * math.sqrt(max(0.0, 1.0 - d[2] ** 2))
    compliance = L0 / p.ea + (w_perp * L0) ** 2 * L0 / (12.0 * T ** 3)
    k_ax = 1.0 / compliance
    ee = np.outer(e, e)
    Jx = -k_ax * ee - (T / chord) * (np.eye(3) - ee)
    n = rope.n_elements
    c_ax = math.sqrt(p.ea * p.mass_per_length) * 2 * p.damping_ratio_axial / (n + 1)   # ~ c_conn / (N+1)
    Jv = -c_ax * ee
    return Jx, Jv, T


class Body:
    """A vessel and the attachment the rope is on; or a fixed point (vessel None)."""

    def __init__(self, vessel, attachment, fixed_point=None):
        self.vessel, self.att, self.fixed = vessel, attachment, fixed_point

    def kin(self):
        if self.vessel is None:
            return self.fixed.copy(), np.zeros(3)
        return self.vessel.attachment_kinematics(self.att)

    def surge_mass(self):
        return 7.925e5 if self.vessel is None else getattr(self, "m", 7.925e5)


def advance_vessel(body: Body, h, force_fn, omega_j):
    """Step body's vessel over h with the rope force force_fn(x_att, v_att, s) (world), held
    over sub-steps at each sub-step's predicted middle; n_sub from omega_j h_sub <= 0.05."""
    n = max(1, int(math.ceil(omega_j * h / 0.05))) if omega_j > 0 else 1
    hs = h / n
    point = body.vessel.attachments[body.att]
    work = 0.0
    for j in range(n):
        x, v = body.vessel.attachment_kinematics(body.att)
        f = np.asarray(force_fn(x + 0.5 * hs * v, v, (j + 0.5) * hs), float)
        body.vessel.step(hs, [ExternalWrench(f, point)])
        work += float(f @ (body.vessel.attachment_kinematics(body.att)[0] - x))
    return work


def _set_up(case, n_elements, length, stretch, ship, attachment):
    """The bodies (bollard: the tug at full ahead and a fixed point; else two free ASD tugs,
    engines stopped) and the rope laid straight between them and settled, its ends on the
    attachments; (params, a, b, rope, ends with a vessel)."""
    params = dataclasses.replace(load_rope_params(ROPES + "steel_wire_40mm.yaml"), length=length)
    tug = load_ship(SHIPS + ship, name="tug")
    if case == "bollard":
        tug.settle_command(Command(1.0, 0.0))            # full ahead, rpm already up (worst case)
        a = Body(tug, attachment)
        pa, _ = a.kin()
        b = Body(None, None, fixed_point=pa - np.array([length, 0.0, 0.0]))
    else:                                                # two free ASD tugs, engines stopped
        tug2 = load_ship(SHIPS + "asd_tug.yaml", name="tug2",
                         initial_state=VesselState.at_rest(-(length + 8.0 + 14.5) - stretch, 0.0, 0.0))
        a = Body(tug, "winch_aft")
        b = Body(tug2, "bow_staple")
    pa, va = a.kin()
    pb, vb = b.kin()
    rope = RopeChain.straight(params, pa, pb, n_elements=n_elements, end_a="pinned",
                              end_b="pinned" if b.vessel is not None else "fixed")
    ends = [e for e, body in (("a", a), ("b", b)) if body.vessel is not None]
    rope.settle(va, vb)                                  # the rope node's equilibrium:=true
    for e, body in (("a", a), ("b", b)):
        if body.vessel is not None:
            rope.set_end_kinematics(e, *body.kin())
    return params, a, b, rope, ends


def run(scheme, rate, duration, case="bollard", n_elements=30, log_every=None, length=40.0, stretch=0.0,
        smooth=False, ship="asd_tug.yaml", attachment="winch_aft"):
    """smooth: drive each rope end along a continuous path (no jump at the step's start): from
    where the last step left it, x~, at v_k + (x_k - x~) / h, reaching x_k + h v_k; as now
    (False): set_end(x_k, v_k), a jump of ~h^2 a / 2 onto the end connection every step."""
    h = 1.0 / rate
    params, a, b, rope, ends = _set_up(case, n_elements, length, stretch, ship, attachment)
    # step-0 output: the rope's force at the layout (not averaged)
    # (the Jacobian's reference is the step-0 attachment state itself)
    out = {e: dict(F=rope.end_force(e), J=rope_jacobian(rope, e)[:2], xhat=(a if e == "a" else b).kin()[0],
                   vhat=(a if e == "a" else b).kin()[1], Fpred=rope.end_force(e)) for e in ends}
    omega_j = math.sqrt(params.ea / length / 3.0e5)      # generous: sub-steps for the lightest tug
    t_hist, ten, energy, xs = [], [], [], []
    steps = int(round(duration * rate))
    w_vessel = w_rope = 0.0       # work done by the rope on the vessels / by the vessels on the rope
    if case != "bollard":
        energy.append((0.0, rope.kinetic_energy(), rope.elastic_energy(), rope.potential_energy(), 0.0, 0.0,
                       float(rope.momentum()[0])))
    t0 = time.perf_counter()
    for k in range(steps):
        kin = {e: (a if e == "a" else b).kin() for e in ends}          # the attachments stamped k
        # -- the rope's step k -> k+1 (from the attachments stamped k)
        drive = {}
        for e in ends:
            x, v = kin[e]
            if scheme == "pred":
                x = x + h * v
            if smooth and k > 0:
                xt = rope.attachment_position(e)
                v = v + (x - xt) / h
                x = xt
            drive[e] = (x, v)
            rope.set_end_kinematics(e, x, v)
        # -- the vessels' step k -> k+1, with the rope output stamped k
        for e in ends:
            body = a if e == "a" else b
            o = out[e]
            other = "b" if e == "a" else "a"
            if scheme in ("lag", "pred", "predJ") or o["xhat"] is None:
                F = np.asarray(o["F"] if scheme != "predJ" or o["xhat"] is None else o["Fpred"], float)
                x0 = kin[e][0]
                body.vessel.step(h, [ExternalWrench(F, body.vessel.attachments[body.att])])
                w_vessel += float(F @ (body.kin()[0] - x0))
                continue
            Jx, Jv = o["J"]
            Fc = np.array(o["F"], float)
            if other in out and scheme in ("jac_pred", "jac_now"):
                # cross term: dF_e/dx_other = -Jx (a massless line: F_e depends on x_e - x_other)
                oo = out[other]
                if scheme == "jac_pred":
                    Fc = Fc - Jx @ (h * oo["vhat"])
                    cross = None
                else:
                    xo, vo = kin[other]
                    cross = (xo, vo, oo["xhat"], oo["vhat"])
            else:
                cross = None

            def force(x, v, s, Fc=Fc, Jx=Jx, Jv=Jv, o=o, cross=cross):
                f = Fc + Jx @ (x - o["xhat"]) + Jv @ (v - o["vhat"])
                if cross is not None:
                    xo, vo, xh, vh = cross
                    f = f - Jx @ (xo + vo * s - xh) - Jv @ (vo - vh)
                return f
            w_vessel += advance_vessel(body, h, force, omega_j)
        rope.step(h)
        for e in ends:
            w_rope -= float(rope.mean_end_force(e) @ (drive[e][1] * h))   # work done on the rope
        # -- the rope's output stamped k+1
        for e in ends:
            x, v = drive[e]
            out[e] = dict(F=rope.mean_end_force(e), J=rope_jacobian(rope, e)[:2],
                          xhat=x + 0.5 * h * v, vhat=v.copy())
        if scheme == "predJ":
            for e in ends:
                other = "b" if e == "a" else "a"
                Jx = out[e]["J"][0]
                fp = out[e]["F"] + Jx @ (h * out[e]["vhat"])
                if other in out:
                    fp = fp - Jx @ (h * out[other]["vhat"])
                out[e]["Fpred"] = fp
        if rope.events:
            print(f"  {scheme} {rate} Hz: rope parted at t = {rope.events[0].time:.2f} s, "
                  f"{rope.events[0].tension / 1e3:.0f} kN")
            break
        t_hist.append((k + 1) * h)
        ten.append(float(np.linalg.norm(rope.mean_end_force("a"))))
        xs.append([a.kin()[0][0]] + ([b.kin()[0][0]] if b.vessel is not None else []))
        if case != "bollard":
            ke = sum(0.5 * 7.925e5 * float(body.vessel.state.linear_velocity_body[0]) ** 2 for body in (a, b))
            mom = sum(7.925e5 * float(rotx(body.vessel)) for body in (a, b)) + float(rope.momentum()[0])
            energy.append((ke, rope.kinetic_energy(), rope.elastic_energy(), rope.potential_energy(),
                           w_vessel, w_rope, mom))
    wall = time.perf_counter() - t0
    return dict(t=np.array(t_hist), T=np.array(ten), x=np.array(xs), E=np.array(energy), wall=wall,
                parted=bool(rope.events))


def swing(t, T, t_from, t_to):
    sel = (t >= t_from) & (t < t_to)
    if not np.any(sel):
        return math.nan
    return 0.5 * (T[sel].max() - T[sel].min()) / TF


if __name__ == "__main__":
    schemes = sys.argv[1].split(",") if len(sys.argv) > 1 else ["lag", "jac"]
    rates = [float(r) for r in sys.argv[2].split(",")] if len(sys.argv) > 2 else [10.0, 20.0, 50.0]
    dur = float(sys.argv[3]) if len(sys.argv) > 3 else 120.0
    smooth = len(sys.argv) > 4 and sys.argv[4] == "smooth"
    for s in schemes:
        for r in rates:
            res = run(s, r, dur, smooth=smooth)
            t, T = res["t"], res["T"]
            print(f"{s:8s} {r:5g} Hz: surge swing (half peak-to-peak tension) 0-20 s {swing(t, T, 0, 20):6.1f} t, "
                  f"{dur-20:.0f}-{dur:.0f} s {swing(t, T, dur - 20, dur):6.1f} t; max tension "
                  f"{T.max() / 1e3:7.0f} kN; mean last 20 s {T[t >= dur - 20].mean() / TF if np.any(t >= dur - 20) else math.nan:5.1f} t"
                  f"{'  PARTED' if res['parted'] else ''}  ({res['wall']:.1f} s wall)")
