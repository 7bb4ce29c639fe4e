"""Propeller wash: a tug's jet meeting another hull, and the push or pull the tug then delivers.
ROS-free; numba kernel, callable from Python. docs/confined-water.md ("Propeller wash") gives the
derivation.

Jet (Blaauw & van de Kaa 1978, the "Dutch method" of PIANC WG 180 (2015) for bed protection):

    efflux      V0 = sqrt(T / (rho pi D0^2 / 4))     (axial momentum theory: the jet carries T)
                D0 = D ducted, D / sqrt(2) open       (open: the actuator disc's far-wake contraction,
                                                       which makes V0 = sqrt(8/pi) n D sqrt(K_T)
                                                       = 1.596 n D sqrt(K_T), Fuehrer & Roemisch's 1.59)
    established V(x, r) = 2.8 V0 (D0 / x) exp(-15.4 r^2 / x^2)         for x >= x_e = 2.8 D0
    establishing V(x, r) = V0 exp(-15.4 r^2 / x_e^2)                   for 0 < x < x_e

x along the jet from the propeller, r from its axis. The zone of flow establishment is simplified
here: centre-line velocity V0 and the width held at its value at x_e (where the established law
gives V0), so the momentum flux is the same in both zones. With these constants the jet carries
4 * 2.8^2 / 30.8 = 1.018 T; the wash below uses the fraction of the jet's momentum flux, so a jet
wholly stopped by a wall takes exactly T.

Wash on a hull: the other hull's side is a vertical plane rectangle (length along the hull, from
the waterline to its draft). The free surface is a mirror for the jet's momentum flux (the part
above it folded back below). Where the jet crosses the plane the hull takes the jet's normal
momentum (a frictionless flat plate; the fluid leaves along it: the textbook jet-on-plate
F = rho Q V sin(psi)), times a named impingement coefficient C_w (1: the ideal plate):

    F_wash = C_w T sin^2(psi) int_side  (a / pi) exp(-a r^2)  dA,   a = 30.8 / max(x, x_e)^2

psi is the jet's angle to the hull side (90 deg: straight at it; negative: leaving it). A jet
heading at the hull pushes the hull away from the tug; a jet leaving it along the hull (a tug
pushing at a shallow angle) is taken to attach to the side (Coanda) and the same normal momentum
becomes suction that pulls the hull toward the tug (fully attached: an upper bound). Either way
the wash force opposes what the tug delivers.

Limits: still water and a ship at rest (no current sweeping the jet); the jet's swirl, the tug's
own hull in the jet and the bilge's curvature are not modelled; the hull side is flat; the part
of the jet passing under the keel or beyond the ends is lost to the hull.
"""
from __future__ import annotations

import math
import numbers
from typing import Tuple

import numpy as np
from numba import njit

CENTRELINE_DECAY = 2.8          # V_max / V0 = 2.8 D0 / x (Blaauw & van de Kaa 1978)
RADIAL_SPREAD = 15.4            # V / V_max = exp(-15.4 r^2 / x^2) (Blaauw & van de Kaa 1978)
OPEN_CONTRACTION = 1.0 / math.sqrt(2.0)   # D0 / D of an open propeller (actuator-disc far wake)
PANELS = 8                      # Gauss-Legendre panels along the hull, 4 nodes each
SCAN_POINTS = 129               # coarse scan that finds where the jet meets the hull side
NEGLIGIBLE = 1e-12              # relative integrand below which the side is out of the jet

GAUSS_X, GAUSS_W = np.polynomial.legendre.leggauss(4)


def _check_positive(name: str, value: float, allow_zero: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value) \
            or value < 0.0 or (value == 0.0 and not allow_zero):
        bound = ">= 0" if allow_zero else "> 0"
        raise ValueError(f"propeller wash: {name} must be finite and {bound}, got {value!r}")
    return float(value)


def efflux_diameter(diameter: float, ducted: bool) -> float:
    """D0 (m): the propeller diameter if ducted, the contracted far wake D / sqrt(2) if open."""
    d = _check_positive("diameter", diameter)
    return d if ducted else d * OPEN_CONTRACTION


def efflux_velocity(thrust: float, diameter: float, ducted: bool = True, water_density: float = 1025.0) -> float:
    """V0 (m/s) from the thrust by axial momentum theory, T = rho (pi D0^2 / 4) V0^2."""
    t = _check_positive("thrust", thrust, allow_zero=True)
    rho = _check_positive("water_density", water_density)
    d0 = efflux_diameter(diameter, ducted)
    return math.sqrt(4.0 * t / (rho * math.pi * d0 * d0))


@njit(cache=True)
def _spread(x, d0):
    """a (1/m^2) of the jet's V^2 profile exp(-a r^2) at distance x (the width frozen before x_e)."""
    xe = CENTRELINE_DECAY * d0
    xx = x if x > xe else xe
    return 2.0 * RADIAL_SPREAD / (xx * xx)


@njit(cache=True)
def jet_velocity(x, r, v0, d0):
    """Axial velocity (m/s) at x (m) downstream of the propeller, r (m) off the axis; 0 upstream."""
    if x <= 0.0:
        return 0.0
    xe = CENTRELINE_DECAY * d0
    if x < xe:
        return v0 * math.exp(-RADIAL_SPREAD * r * r / (xe * xe))
    return CENTRELINE_DECAY * v0 * d0 / x * math.exp(-RADIAL_SPREAD * r * r / (x * x))


@njit(cache=True)
def _strip(u, offset, sin_psi, cos_psi, axis_to_keel, image_to_keel, d0):
    """The intercepted fraction per metre of hull side at u: the depth integral in closed form."""
    x = u * cos_psi + offset * sin_psi
    if x <= 0.0:
        return 0.0
    a = _spread(x, d0)
    h2 = u * u + offset * offset - x * x          # horizontal part of r^2 (z part in the erf)
    if h2 < 0.0:
        h2 = 0.0
    ra = math.sqrt(a)
    # mirror at the surface: the side from depth -draft to 0 and its image from 0 to +draft
    depth = math.erf(ra * image_to_keel) - math.erf(-ra * axis_to_keel)
    return a / math.pi * math.exp(-a * h2) * 0.5 * math.sqrt(math.pi / a) * depth


@njit(cache=True)
def _reach(u, offset, sin_psi, cos_psi, d0):
    """The strip's size without its depth factor (which is at most 2): cheap, for the scan."""
    x = u * cos_psi + offset * sin_psi
    if x <= 0.0:
        return 0.0
    a = _spread(x, d0)
    return math.sqrt(a) * math.exp(-a * max(u * u + offset * offset - x * x, 0.0))


@njit(cache=True)
def intercepted(offset, psi, u_start, u_end, propeller_depth, draft, d0, gx, gw):
    """(int over the hull side of (a/pi) exp(-a r^2) dA, its first moment in u): composite
    Gauss-Legendre in u over where the jet reaches the side (found by a coarse scan), the depth in
    closed form. The moment over the fraction is where along the side the wash acts."""
    s, c = math.sin(psi), math.cos(psi)
    axis_to_keel, image_to_keel = draft - propeller_depth, draft + propeller_depth
    step = (u_end - u_start) / (SCAN_POINTS - 1)
    scan = np.empty(SCAN_POINTS)
    peak = 0.0
    for i in range(SCAN_POINTS):
        scan[i] = _reach(u_start + i * step, offset, s, c, d0)
        peak = max(peak, scan[i])
    if peak <= 0.0:
        return 0.0, 0.0
    lo, hi = SCAN_POINTS, -1
    for i in range(SCAN_POINTS):
        if scan[i] > NEGLIGIBLE * peak:
            lo = min(lo, i)
            hi = max(hi, i)
    ua = max(u_start, u_start + (lo - 1) * step)
    ub = min(u_end, u_start + (hi + 1) * step)
    total = 0.0
    moment = 0.0
    width = (ub - ua) / PANELS
    for p in range(PANELS):
        mid = ua + (p + 0.5) * width
        for k in range(gx.shape[0]):
            u = mid + 0.5 * width * gx[k]
            f = gw[k] * 0.5 * width * _strip(u, offset, s, c, axis_to_keel, image_to_keel, d0)
            total += f
            moment += f * u
    return total, moment


@njit(cache=True)
def intercepted_fraction(offset, psi, u_start, u_end, propeller_depth, draft, d0, gx, gw):
    """int over the hull side of (a/pi) exp(-a r^2) dA (`intercepted`'s first part)."""
    return intercepted(offset, psi, u_start, u_end, propeller_depth, draft, d0, gx, gw)[0]


@njit(cache=True)
def wash_on_hull(thrust, d0, propeller_depth, impingement, px, py, jx, jy, length, beam, draft, gx, gw):
    """The wash's sway force (N) and yaw moment (N m, about midship) on a hull taken as a box (its
    sides the planes y = +-beam/2 from x = -length/2 to +length/2, `draft` deep), from a jet of
    momentum `thrust` (N, >= 0) leaving a propeller at (px, py) in the hull's body axes along the
    unit vector (jx, jy) in those axes. The side facing the propeller takes it (PropellerJet.wash_force
    with psi = the jet's angle to that side, the along-hull coordinate from the propeller's foot);
    a propeller within the hull's beam (ahead of or astern of it) washes no side: (0, 0)."""
    half = 0.5 * beam
    if thrust <= 0.0 or abs(py) <= half:
        return 0.0, 0.0
    side = 1.0 if py > 0.0 else -1.0
    sin_psi = -side * jy                        # the jet's component toward the side
    if sin_psi > 1.0:
        sin_psi = 1.0
    elif sin_psi < -1.0:
        sin_psi = -1.0
    if sin_psi == 0.0:
        return 0.0, 0.0
    psi = math.asin(sin_psi)
    along = 1.0 if jx >= 0.0 else -1.0          # u runs the way the jet's along-hull part points
    u_start = along * (-along * 0.5 * length - px)
    u_end = along * (along * 0.5 * length - px)
    total, moment = intercepted(abs(py) - half, psi, u_start, u_end, propeller_depth, draft, d0, gx, gw)
    if total <= 0.0:
        return 0.0, 0.0
    # heading at the side: pushes the hull away from the propeller; leaving it: suction toward it
    fy = -side * impingement * thrust * sin_psi * abs(sin_psi) * total
    return fy, (px + along * moment / total) * fy


class HullSide:
    """The other hull's flat side as the jet sees it: from u_start to u_end (m) along the hull,
    measured from the foot of the perpendicular from the propeller, positive the way the jet's
    along-hull component points; `draft` (m) below the waterline."""

    def __init__(self, u_start: float, u_end: float, draft: float):
        for name, value in (("u_start", u_start), ("u_end", u_end)):
            if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
                raise ValueError(f"hull side: {name} must be finite, got {value!r}")
        if u_end <= u_start:
            raise ValueError(f"hull side: u_end {u_end!r} must exceed u_start {u_start!r}")
        self.u_start, self.u_end = float(u_start), float(u_end)
        self.draft = _check_positive("draft", draft)


class PropellerJet:
    """One propeller's jet: thrust T (N), diameter D (m), ducted or open, axis depth (m)."""

    def __init__(self, thrust: float, diameter: float, propeller_depth: float, ducted: bool = True,
                 water_density: float = 1025.0, impingement: float = 1.0):
        self.thrust = _check_positive("thrust", thrust, allow_zero=True)
        self.d0 = efflux_diameter(diameter, ducted)
        self.v0 = efflux_velocity(thrust, diameter, ducted, water_density)
        self.depth = _check_positive("propeller_depth", propeller_depth, allow_zero=True)
        self.impingement = _check_positive("impingement", impingement, allow_zero=True)

    def velocity(self, x: float, r: float) -> float:
        return jet_velocity(float(x), float(r), self.v0, self.d0)

    def wash_force(self, side: HullSide, offset: float, psi: float) -> float:
        """Magnitude (N) of the wash's force normal to the hull side, the propeller `offset` m from
        the side's plane, the jet at `psi` rad to it (positive toward it). It pushes the hull along
        the jet's normal component: away from the tug when psi > 0, toward it (suction) when < 0."""
        offset = _check_positive("offset", offset)
        if not math.isfinite(psi) or abs(psi) > 0.5 * math.pi:
            raise ValueError(f"propeller wash: psi must be within [-pi/2, pi/2] rad, got {psi!r}")
        fraction = intercepted_fraction(offset, float(psi), side.u_start, side.u_end, self.depth, side.draft,
                                        self.d0, GAUSS_X, GAUSS_W)
        return self.impingement * self.thrust * math.sin(psi) ** 2 * fraction

    def pull_delivered(self, side: HullSide, offset: float, psi: float) -> Tuple[float, float]:
        """A tug pulling on a line from the hull, its jet straight back along the line at `psi` to the
        side: (force normal to the side, force along the line) delivered, N: T sin psi - F, T - F sin psi."""
        f = self.wash_force(side, offset, psi)
        return self.thrust * math.sin(psi) - f, self.thrust - f * math.sin(psi)

    def push_delivered(self, side: HullSide, lever: float, angle: float) -> float:
        """A tug pushing its bow on the hull with its axis at `angle` rad to the side, the propeller
        `lever` m behind the bow, the jet leaving along the tug's axis: the force normal to the side
        (N), T sin(angle) minus the wash's suction. `side` from the propeller's foot, as HullSide."""
        lever = _check_positive("lever", lever)
        if not math.isfinite(angle) or not 0.0 < angle <= 0.5 * math.pi:
            raise ValueError(f"propeller wash: push angle must be within (0, pi/2] rad, got {angle!r}")
        if angle == 0.5 * math.pi:
            return self.thrust                        # the jet leaves straight away: it misses the hull
        return self.thrust * math.sin(angle) - self.wash_force(side, lever * math.sin(angle), -angle)
