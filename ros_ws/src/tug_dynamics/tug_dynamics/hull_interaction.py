"""Hull-hull interaction of two slender ships on parallel courses: Wang's (1975) slender-body
theory for the surge force, sway force and yaw moment a passing ship induces on another, in deep
or (by the method of images) finite depth. ROS-free; numba kernel, callable from Python.

Wang, S. (1975) Dynamic effects of ship passage on moored vessels, J. Waterways, Harbors and
Coastal Eng. Div., ASCE 101(WW3), 247-258; as restated in the passing-ship literature (the
original was not available here; e.g. Seelig 2001, NFESC TR-6027-OCN). docs/confined-water.md
gives the derivation. Ship 2 (speed U along ship 1's x axis, midship at stagger xi ahead of and
separation eta to port of ship 1's midship) is a line of sources of strength U dS2/dx; the
linearised unsteady pressure of its potential on ship 1 gives, with R^2 = (xi - x1 + x2)^2 +
eta^2 + (2 n h)^2 summed over the bottom images n (n = 0 only in deep water):

    X1 = rho U^2 / pi   sum_n  int int S1'(x1) S2'(x2) (xi - x1 + x2) / R^3  dx2 dx1
    Y1 = rho U^2 eta / pi  sum_n int int S1'(x1) S2'(x2) / R^3  dx2 dx1
    N1 = rho U^2 eta / pi  sum_n int int [S1(x1) + x1 S1'(x1)] S2'(x2) / R^3  dx2 dx1

S(x) is a hull's underwater sectional area: here Wang's parabola S = S_m (1 - (2x/L)^2), with
S_m = 3 V / (2 L) so that it holds the ship file's displaced volume V. Forces on ship 1 in its
body frame (REP-103: x forward, y port; N positive bow to port). S2' is linear, so the inner
integral is in closed form (the bottom images beyond IMAGE_COUNT each side as their integral over
depth); the outer one uses composite Gauss-Legendre nodes on ship 1 fixed per hull pair, so a
pair costs about a microsecond in deep water.

Limits: parallel courses (the formulas have no heading difference); potential flow at low
Froude number (no waves, no viscous wake); slender hulls (length much larger than beam); within
0.1 % of adaptive quadrature of the integrals down to a separation of 0.1 L of ship 1
(tests/physics/test_hull_interaction.py); Wang's moored-ship pressure: the force on ship 1 scales
with the passing ship's speed squared, whatever ship 1's own speed (the cross terms of two
moving hulls, Tuck & Newman 1974, are not in it). A tug beside a ship is two slender bodies and
the same formulas apply (surge/sway/yaw on the tug from the ship and on the ship from the tug);
the theory knows nothing of the bow wave, the tug's propeller or a heading difference, so at a
ship's bow at close range it gives the suction's order of magnitude, not a validated value.
"""
from __future__ import annotations

import math
import numbers
from typing import Optional, Tuple

import numpy as np
from numba import njit

DEFAULT_NODES = 24       # Gauss-Legendre nodes on ship 1 (6 panels of 4); ship 2 in closed form
NODES_PER_PANEL = 4
MIN_SEPARATION_SQUARED = 1e-4   # m^2: the kernel's floor for hulls in line (ends apart)
IMAGE_COUNT = 3          # bottom images each side summed exactly; the rest as their integral


class SectionalAreaCurve:
    """A hull's underwater sectional area, Wang's parabola S(x) = S_m (1 - (2x/L)^2), x from
    midship, positive forward; zero at both ends."""

    def __init__(self, length: float, midship_area: float, beam: float, draft: Optional[float] = None):
        """draft: the hull's (a bank's weights use it, bank_effect); None: midship_area / beam, the
        draft of a box midship section."""
        for name, value in (("length", length), ("midship_area", midship_area), ("beam", beam), ("draft", draft)):
            if value is None and name == "draft":
                continue
            if isinstance(value, bool) or not isinstance(value, numbers.Real) or not (math.isfinite(value)
                                                                                     and value > 0.0):
                raise ValueError(f"sectional area curve: {name} must be finite and > 0, got {value!r}")
        self.length, self.midship_area, self.beam = float(length), float(midship_area), float(beam)
        self.draft = float(draft) if draft is not None else self.midship_area / self.beam

    @staticmethod
    def from_ship_config(cfg: dict) -> "SectionalAreaCurve":
        """Wang's parabola holding the ship file's displaced volume (hull mass / water density)."""
        if cfg.get("model") == "planing_6dof":
            raise ValueError(f"ship file {cfg.get('name', '?')!r}: a planing hull is not a slender displacement "
                             "hull (Wang's theory does not apply)")
        hull = cfg["hull"]
        length, beam, draft = float(hull["length"]), float(hull["beam"]), float(hull["draft"])
        rho = float(cfg.get("water_density", 1025.0))
        volume = float(hull["mass"]) / rho if hull.get("mass") else 0.7 * length * beam * draft
        return SectionalAreaCurve(length, 1.5 * volume / length, beam, draft)

    @property
    def volume(self) -> float:
        return 2.0 / 3.0 * self.midship_area * self.length

    def area(self, x: np.ndarray) -> np.ndarray:
        xi = np.clip(2.0 * np.asarray(x, float) / self.length, -1.0, 1.0)
        return self.midship_area * (1.0 - xi * xi)

    def slope(self, x: np.ndarray) -> np.ndarray:
        """dS/dx (zero off the hull)."""
        x = np.asarray(x, float)
        return np.where(np.abs(x) <= 0.5 * self.length, -8.0 * self.midship_area * x / self.length ** 2, 0.0)


def composite_gauss(length: float, nodes: int) -> Tuple[np.ndarray, np.ndarray]:
    """Nodes and weights of a composite Gauss-Legendre rule over [-L/2, L/2]."""
    if nodes < NODES_PER_PANEL or nodes % NODES_PER_PANEL:
        raise ValueError(f"nodes must be a positive multiple of {NODES_PER_PANEL}, got {nodes!r}")
    g, w = np.polynomial.legendre.leggauss(NODES_PER_PANEL)
    panels = nodes // NODES_PER_PANEL
    h = length / panels
    left = -0.5 * length + h * np.arange(panels)
    x = (left[:, None] + 0.5 * h * (g[None, :] + 1.0)).ravel()
    return x, np.tile(0.5 * h * w, panels)


@njit(cache=True)
def _inner_3d(u0, u1, e2, alpha, beta):
    """int over u in [u0, u1] of (alpha + beta u) / (u^2 + e2)^(3/2), and of the same times u."""
    s0 = math.sqrt(u0 * u0 + e2)
    s1 = math.sqrt(u1 * u1 + e2)
    k = alpha * (u1 / s1 - u0 / s0) / e2 - beta * (1.0 / s1 - 1.0 / s0)
    root = math.sqrt(e2)
    ku = -alpha * (1.0 / s1 - 1.0 / s0) + beta * (math.asinh(u1 / root) - math.asinh(u0 / root) - u1 / s1 + u0 / s0)
    return k, ku


@njit(cache=True)
def _tail_antiderivative(u, e2, z, alpha, beta):
    """Antiderivatives in u of (alpha + beta u) T and (alpha + beta u) u T, T = (1 - z / w) / (u^2 + e2),
    w = sqrt(u^2 + e2 + z^2): the images beyond the exact ones, as their integral over depth."""
    eta = math.sqrt(e2)
    w = math.sqrt(u * u + e2 + z * z)
    at = math.atan(u / eta) - math.atan(u * z / (eta * w))
    lg = math.log(w + z)                    # = ln(u^2 + e2) / 2 - ln((w - z) / (w + z)) / 2
    k = alpha * at / eta + beta * lg
    ku = alpha * lg + beta * (u - eta * math.atan(u / eta) - z * math.asinh(u / math.sqrt(e2 + z * z))
                              + eta * math.atan(u * z / (eta * w)))
    return k, ku


@njit(cache=True)
def wang_loads(x1, sway_w1, yaw_w1, half_length2, slope2, stagger, eta, depth, images, rho, speed):
    """(X, Y, N) on ship 1: outer Gauss nodes x1 with sway_w1 = w S1', yaw_w1 = w (S1 + x S1');
    ship 2's parabola S2' = -slope2 x2 integrated in closed form, over the direct term and
    `images` bottom images each side (depth 0: deep water), the further images as their integral."""
    sx = 0.0
    sy = 0.0
    sn = 0.0
    e2 = max(eta * eta, MIN_SEPARATION_SQUARED)    # in line (eta 0): Y = N = 0, X stays finite
    for i in range(x1.shape[0]):
        c = stagger - x1[i]                  # u = c + x2
        u0 = c - half_length2
        u1 = c + half_length2
        alpha = slope2 * c
        beta = -slope2
        ky, kx = _inner_3d(u0, u1, e2, alpha, beta)
        if depth > 0.0:
            for n in range(1, images + 1):
                a, b = _inner_3d(u0, u1, e2 + (2.0 * n * depth) ** 2, alpha, beta)
                ky += 2.0 * a
                kx += 2.0 * b
            z = (2.0 * images + 1.0) * depth
            a1, b1 = _tail_antiderivative(u1, e2, z, alpha, beta)
            a0, b0 = _tail_antiderivative(u0, e2, z, alpha, beta)
            ky += (a1 - a0) / depth
            kx += (b1 - b0) / depth
        sx += sway_w1[i] * kx
        sy += sway_w1[i] * ky
        sn += yaw_w1[i] * ky
    k = rho * speed * speed / math.pi
    return k * sx, k * eta * sy, k * eta * sn


class HullPair:
    """Wang's interaction of ship 2 on ship 1, node data precomputed once per pair."""

    def __init__(self, ship1: SectionalAreaCurve, ship2: SectionalAreaCurve, nodes: int = DEFAULT_NODES,
                 water_density: float = 1025.0):
        if not (math.isfinite(water_density) and water_density > 0.0):
            raise ValueError(f"water_density must be finite and > 0, got {water_density!r}")
        self.ship1, self.ship2, self.rho = ship1, ship2, float(water_density)
        self.x1, w1 = composite_gauss(ship1.length, nodes)
        s1p = ship1.slope(self.x1)
        self.sway_w1 = w1 * s1p
        self.yaw_w1 = w1 * (ship1.area(self.x1) + self.x1 * s1p)
        self.half_length2 = 0.5 * ship2.length
        self.slope2 = 8.0 * ship2.midship_area / ship2.length ** 2

    def check(self, stagger: float, separation: float, speed: float, depth: float) -> None:
        for name, value in (("stagger", stagger), ("separation", separation), ("speed", speed)):
            if not math.isfinite(value):
                raise ValueError(f"hull interaction: {name} must be finite, got {value!r}")
        if math.isnan(depth) or depth <= 0.0:
            raise ValueError(f"hull interaction: depth must be > 0 (math.inf for deep water), got {depth!r}")
        overlap_x = abs(stagger) < 0.5 * (self.ship1.length + self.ship2.length)
        if overlap_x and abs(separation) < 0.5 * (self.ship1.beam + self.ship2.beam):
            raise ValueError(f"hull interaction: separation {separation!r} m at stagger {stagger!r} m puts the "
                             f"hulls inside each other (half beams sum to "
                             f"{0.5 * (self.ship1.beam + self.ship2.beam):.3g} m)")

    def images(self, depth: float) -> int:
        """Bottom images summed exactly each side (0 in deep water); the rest as their integral."""
        return 0 if math.isinf(depth) else IMAGE_COUNT

    def loads(self, stagger: float, separation: float, speed: float,
              depth: float = math.inf) -> Tuple[float, float, float]:
        """(X, Y, N) on ship 1 (N, N, N m; body frame, REP-103) with ship 2's midship `stagger` m
        ahead and `separation` m to port, ship 2 moving at `speed` m/s parallel to ship 1."""
        self.check(stagger, separation, speed, depth)
        n = self.images(depth)
        return wang_loads(self.x1, self.sway_w1, self.yaw_w1, self.half_length2, self.slope2, float(stagger),
                          float(separation), float(depth) if n else 0.0, n, self.rho, float(speed))


def pair_from_ship_configs(cfg1: dict, cfg2: dict, nodes: Optional[int] = None) -> HullPair:
    """The pair for two ship files' mappings (ship 1 feels the loads)."""
    rho = float(cfg1.get("water_density", 1025.0))
    return HullPair(SectionalAreaCurve.from_ship_config(cfg1), SectionalAreaCurve.from_ship_config(cfg2),
                    nodes or DEFAULT_NODES, rho)
