"""Savitsky's (1964) steady planing state of a prismatic hull, ROS-free.

Yoon & Kang (planing hull) compute their Table 2 (trim, wetted keel/chine lengths, total
resistance vs speed) with Savitsky's short method: all forces act through the centre of
gravity, so the trim is the one that puts the centre of pressure on the LCG. This module
reproduces that so another hull can be added from its particulars.

Savitsky's empirical formulas take the trim tau and deadrise beta in DEGREES; they are
converted here and nothing outside this module sees degrees. The trim returned is
Savitsky's tau, bow-UP positive. In REP-103 (body y to port) a bow-up attitude is a
NEGATIVE pitch, so pitch = -tau (see planing.py).

Limits of the method (Savitsky 1964): 2 deg <= tau <= 15 deg, 10 deg <= beta <= 30 deg,
lambda <= 4, 0.6 <= Cv <= 13. Table 2's 5 and 10 kn rows lie outside (keel wetted length
longer than the boat); they are extrapolations, as in the paper.
"""
from __future__ import annotations

import dataclasses
import math
from typing import Iterable, List


def brentq(*args, **kwargs):
    # scipy.optimize takes 0.6 s to import: only a planing hull's node pays it, not every vessel node
    from scipy.optimize import brentq as scipy_brentq
    return scipy_brentq(*args, **kwargs)


@dataclasses.dataclass(frozen=True)
class HullParticulars:
    """Particulars Savitsky's method needs (SI)."""
    mass: float                 # kg
    chine_beam: float           # b, m
    deadrise_deg: float         # beta, deg (Savitsky's formulas are in degrees)
    lcg_from_transom: float     # m, forward of the transom
    water_density: float = 1025.0
    kinematic_viscosity: float = 1.19e-6   # sea water 15 C (ITTC)
    roughness_allowance: float = 0.0004    # delta C_F, Savitsky's recommended value
    gravity: float = 9.81


@dataclasses.dataclass(frozen=True)
class PlaningState:
    """Steady planing state at one speed (SI; trim in rad, bow-up positive)."""
    speed: float
    trim: float                  # tau, rad, bow up positive (Savitsky)
    mean_wetted_length: float    # lambda * b, m
    keel_wetted_length: float    # L_K, m
    chine_wetted_length: float   # L_C, m (negative: chines dry)
    resistance: float            # N, total (pressure drag + friction)
    friction_drag: float         # N, along the bottom
    lift_coefficient: float      # C_L,beta
    speed_coefficient: float     # C_v
    center_of_pressure: float    # l_p, m forward of the transom

    @property
    def trim_deg(self) -> float:
        return math.degrees(self.trim)


def _cl0_from_clbeta(cl_beta: float, beta_deg: float) -> float:
    # C_Lbeta = C_L0 - 0.0065 beta C_L0^0.6 (deadrise correction), solved for C_L0
    f = lambda c: c - 0.0065 * beta_deg * c ** 0.6 - cl_beta
    hi = cl_beta + 1.0
    return brentq(f, cl_beta, hi, xtol=1e-14)


def _lambda_from_cl0(cl0: float, tau_deg: float, cv: float) -> float:
    # C_L0 = tau^1.1 (0.012 lambda^0.5 + 0.0055 lambda^2.5 / Cv^2); monotone in lambda
    f = lambda lam: tau_deg ** 1.1 * (0.012 * lam ** 0.5 + 0.0055 * lam ** 2.5 / cv ** 2) - cl0
    return brentq(f, 1e-8, 1e4, xtol=1e-13)


def _center_of_pressure(lam: float, cv: float, b: float) -> float:
    # l_p / (lambda b) = 0.75 - 1 / (5.21 Cv^2 / lambda^2 + 2.39)
    return lam * b * (0.75 - 1.0 / (5.21 * cv ** 2 / lam ** 2 + 2.39))


def _lift_balance(hull: HullParticulars, speed: float, tau: float):
    """lambda, Cv, C_Lbeta and l_p for trim tau (rad) from the lift balance."""
    b, g = hull.chine_beam, hull.gravity
    cv = speed / math.sqrt(g * b)
    cl_beta = hull.mass * g / (0.5 * hull.water_density * speed ** 2 * b ** 2)
    cl0 = _cl0_from_clbeta(cl_beta, hull.deadrise_deg)
    lam = _lambda_from_cl0(cl0, math.degrees(tau), cv)
    return lam, cv, cl_beta, _center_of_pressure(lam, cv, b)


def state_at_trim(hull: HullParticulars, speed: float, tau: float) -> PlaningState:
    """Planing state for a given trim tau (rad, bow up) at speed (m/s): lift balance only."""
    if not speed > 0.0:
        raise ValueError(f"Savitsky's method needs a positive speed, got {speed!r} m/s")
    b, beta, g = hull.chine_beam, hull.deadrise_deg, hull.gravity
    tau_deg = math.degrees(tau)
    weight = hull.mass * g
    lam, cv, cl_beta, lp = _lift_balance(hull, speed, tau)
    # keel/chine wetted lengths straddle the mean by the spray-root rise over the deadrise
    half_diff = b * math.tan(math.radians(beta)) / (2.0 * math.pi * math.tan(tau))
    lk = lam * b + half_diff
    lc = lam * b - half_diff
    # mean bottom velocity (bottom pressure slows the flow)
    x = 0.012 * lam ** 0.5 * tau_deg ** 1.1
    vm2 = speed ** 2 * (1.0 - (x - 0.0065 * beta * x ** 0.6) / (lam * math.cos(tau)))
    vm = math.sqrt(max(vm2, 1e-6 * speed ** 2))  # outside the method's range only
    reynolds = vm * lam * b / hull.kinematic_viscosity
    cf = 0.075 / (math.log10(reynolds) - 2.0) ** 2 + hull.roughness_allowance  # ITTC 1957
    wetted_area = lam * b ** 2 / math.cos(math.radians(beta))
    df = 0.5 * hull.water_density * vm ** 2 * wetted_area * cf
    resistance = weight * math.tan(tau) + df / math.cos(tau)
    return PlaningState(speed, tau, lam * b, lk, lc, resistance, df, cl_beta, cv, lp)


def steady_state(hull: HullParticulars, speed: float) -> PlaningState:
    """Savitsky's short method: the trim that puts the centre of pressure at the LCG."""
    def moment(tau):
        return _lift_balance(hull, speed, tau)[3] - hull.lcg_from_transom
    lo, hi = math.radians(0.5), math.radians(30.0)
    try:
        tau = brentq(moment, lo, hi, xtol=1e-10)
    except ValueError:
        raise ValueError(
            f"Savitsky: no trim in 0.5..30 deg balances the lift at the LCG "
            f"({hull.lcg_from_transom} m) at {speed} m/s") from None
    return state_at_trim(hull, speed, tau)


def steady_table(hull: HullParticulars, speeds: Iterable[float]) -> List[PlaningState]:
    return [steady_state(hull, float(s)) for s in speeds]
