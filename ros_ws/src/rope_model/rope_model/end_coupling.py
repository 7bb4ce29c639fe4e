"""A rope end's force linearised for the vessel it is pinned to (ROS-free).

The rope and the vessels step in parallel (sim_plumbing.stepping): a vessel applies over its step
k+1 -> k+2 the force the rope computed over k -> k+1. Held constant, that force is one exchange
late, and a spring k = EA/L acting one period h late is a negative damper k h: a towline of 40 m
of 40 mm wire (k = 1.6e6 N/m) pumps 8e4 N s/m into an ASD tug at 20 Hz against the 4e4 its
propellers damp (studies/coupling-stability/REPORT.md, sections 1 and 3). So the rope publishes
with each end's mean force the end state it belongs to and its derivatives, and the vessel
follows the force along its own motion inside its step:

    F(t) = F0 + K (p(t) - p_ref) + C (v(t) - v_ref)

(tug_dynamics.vessel.ExternalWrench). The other end's motion over the coming step is predicted
here: it moves on at its velocity, dF_X/dx_Y = -K_XX for a line whose force depends on the chord.

The linearisation of a line between its two attachments (world axes, e the unit force direction
at the end, T the end tension, l the chord, L the deployed unstretched length):

    K = -k_ax e e^T - (T / l) (I - e e^T)
    k_ax = 1 / (L / EA + (w_perp L)^2 L / (12 T^3))

the axial stiffness of the elastic line in series with the sag compliance of a shallow elastic
catenary (Irvine 1981, Cable Structures, ch. 2; w_perp the line's weight per length across the
chord, submerged where the line is under water), and the string's geometric stiffness across it.
Damping C = -c_ax e e^T, c_ax = 2 zeta_axial sqrt(EA mu) / (N + 1): the N + 1 connection dampers of
the chain (Eq 14) in series. A slack or parted line has K = C = 0; a winch rendering or slipping
adds the drum law's compliance (its speed G (T - T_set): a damper 1/G in series, k / (1 + k G h)
over a step h).

The study checked k_ax against the settled element chain (dT/dchord) within 1 % from 10 to 494 kN
(results_jacobian_check.txt); tests/physics/test_rope_coupling.py checks it again.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from rope_model.chain import RopeChain

SLACK_TENSION = 1.0   # N: below this the line is slack and couples nothing

# The exchange rate a rope needs (the scenario check): omega h of its stiffest vessel-rope mode.
# With the coupling above a damped bollard pull stays damped up to omega h = 0.58 and loses it at
# 0.72; below that rate the rope's own state is wrong whatever the vessel does (its end drive
# overshoots the vessel's path by a h^2 / 2, a tension error of about (omega h)^2 / 2), and the
# recorded energy of a snatch between free bodies overshoots by about (omega h)^2: 4 % at 0.2,
# 25 % at 0.5 (studies/coupling-stability/REPORT.md section 6).
REFUSE_OMEGA_H = 0.5
WARN_OMEGA_H = 0.2


def exchange_omega(ea: float, length: float, mobility_a: float, mobility_b: float) -> float:
    """omega (rad/s) of the stiffest vessel-rope mode: omega^2 = (EA / L)(lambda_a + lambda_b),
    lambda the ends' largest horizontal mobilities (1/kg; 0 for a fixed end)."""
    return math.sqrt(ea / length * (mobility_a + mobility_b))


class EndCoupling(NamedTuple):
    """One end's coupling for the coming step (world axes)."""
    force: np.ndarray               # (3,) N, on the attachment
    reference_position: np.ndarray  # (3,) m
    reference_velocity: np.ndarray  # (3,) m/s
    stiffness: np.ndarray           # (3, 3) dF/dx, N/m
    damping: np.ndarray             # (3, 3) dF/dv, N s/m


ZERO3x3 = np.zeros((3, 3))


def axial_stiffness(rope: RopeChain, tension: float, chord_unit: np.ndarray) -> float:
    """k_ax (N/m) of the deployed line at end tension `tension` (module docstring)."""
    p = rope.params
    L = rope.unstretched_length
    submerged = float(np.mean(rope.X[:, 2] < 0.0))          # share of the line under water
    w = p.mass_per_length * p.gravity - submerged * p.water_density * p.gravity * math.pi * p.radius ** 2
    w_perp = abs(w) * math.sqrt(max(0.0, 1.0 - float(chord_unit[2]) ** 2))
    compliance = L / p.ea + (w_perp * L) ** 2 * L / (12.0 * tension ** 3)
    return 1.0 / compliance


def line_derivatives(rope: RopeChain, end: str, force: np.ndarray, h: float):
    """(K, C) of end `end` ('a' or 'b') for the end force `force` and exchange period h; zeros for
    a slack or parted line."""
    T = float(np.linalg.norm(force))
    pa, pb = rope.att_pos[0], rope.att_pos[1]
    chord = float(np.linalg.norm(pb - pa))
    if T < SLACK_TENSION or chord < 1e-6 or not np.all(rope.conn_ok):
        return ZERO3x3, ZERO3x3
    e = force / T                                   # from the attachment into the line
    ee = np.outer(e, e)
    k_ax = axial_stiffness(rope, T, (pb - pa) / chord)
    if end == "a" and rope.winch and rope.winch_state in ("rendering", "recovering", "slipping"):
        k_ax = k_ax / (1.0 + k_ax * rope.winch_gain * h)   # the drum law's damper in series
    p = rope.params
    c_ax = 2.0 * p.damping_ratio_axial * math.sqrt(p.ea * p.mass_per_length) / (rope.n_elements + 1)
    K = -k_ax * ee - (T / chord) * (np.eye(3) - ee)
    return K, -c_ax * ee


def end_couplings(rope: RopeChain, drives: dict, h: float, averaged: bool) -> dict:
    """{end: EndCoupling} for the ends in `drives` ({end: (x0, v)}: each pinned end's position at
    the start of the rope's step just taken and the velocity it was driven with over it).

    averaged: the force is the mean over that step and belongs to the drive's mean state
    x0 + v h / 2; the other end moves on by v_other h over the step it will act over. Step 0
    (averaged False): the force at the laid-out state x0, the other end moving on by v h / 2."""
    out = {}
    for end, (x0, v) in drives.items():
        force = rope.mean_end_force(end) if averaged else rope.end_force(end)
        K, C = line_derivatives(rope, end, force, h)
        lead = h if averaged else 0.5 * h
        other = "b" if end == "a" else "a"
        if other in drives:                          # the other end predicted over the coming step
            force = force - K @ (lead * np.asarray(drives[other][1], float))
        x0 = np.asarray(x0, float)
        v = np.asarray(v, float)
        out[end] = EndCoupling(np.asarray(force, float), x0 + 0.5 * h * v if averaged else x0.copy(),
                               v.copy(), K, C)
    return out
