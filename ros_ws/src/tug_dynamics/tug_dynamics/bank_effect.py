"""Bank suction on a ship running parallel to a vertical bank (a quay wall, a sheet-piled
channel edge), by the method of images with Wang's (1975) slender-body kernel
(tug_dynamics.hull_interaction). ROS-free.

The bank's no-flux condition is met by the ship's mirror image, a ship of the same hull at
separation 2 d moving with it at the same speed; the bank's sway force and yaw moment on the ship
are the image's on the ship: Wang's integrals at stagger 0, separation 2 d (bottom images as in
hull_interaction for finite depth):

    Y_bank = rho U^2 (2d) / pi  sum_n int int S'(x1) S'(x2) / [(x2 - x1)^2 + 4 d^2 + (2 n h)^2]^(3/2)
    N_bank = rho U^2 (2d) / pi  sum_n int int [S(x1) + x1 S'(x1)] S'(x2) / [...]^(3/2)

Far from the bank (2 d >> L, deep water) Y_bank -> 3 rho U^2 V^2 / (16 pi d^4), V the displaced
volume: the suction falls off as the fourth power of the distance.

Limits: a vertical bank is a mirror, a sloping bank or a berm is not (they act here as the vertical
wall of the same d2b, below: equivalent_wall_distance, loads_along's slope, loads_in_depth); a
parallel course (the image of a ship at an angle to the bank is not parallel to it); potential
flow at low Froude number. Wang's parabola is fore-and-aft symmetric, so N_bank is zero: the
bow-away moment measured on real hulls (from the fuller stern and the propeller's suction, as in
the empirical models of Norrbin 1974 and Lataire & Vantorre 2008) is not in this model, nor the
repulsion measured in very shallow water (Lataire, Vantorre & Eloot 2009: below 15-20 % under-keel
clearance the ship is pushed away from the bank).

The second part of this module is the bank geometry of that empirical model (Lataire, Vantorre &
Eloot 2009, Eqs 1-22): d2b and m_eq of any bank cross-section (BankGeometry), and through it a
sloped bank or a depth field's banks as the vertical wall of the same d2b.
"""
from __future__ import annotations

import math
from typing import List, Sequence, Tuple

import numpy as np

from tug_dynamics.hull_interaction import DEFAULT_NODES, HullPair, SectionalAreaCurve


class BankLine:
    """A straight vertical bank through two points (world frame, m); the water lies on its left
    (counter-clockwise side) as seen from `start` looking at `end`."""

    def __init__(self, start: Sequence[float], end: Sequence[float]):
        pts = [float(v) for v in (*start, *end)]
        if len(pts) != 4 or not all(math.isfinite(v) for v in pts):
            raise ValueError(f"bank line: start and end must be two finite (x, y) points, got {start!r}, {end!r}")
        dx, dy = pts[2] - pts[0], pts[3] - pts[1]
        length = math.hypot(dx, dy)
        if length <= 0.0:
            raise ValueError(f"bank line: start {start!r} and end {end!r} are the same point")
        self.origin = (pts[0], pts[1])
        self.direction = (dx / length, dy / length)

    def distance(self, x: float, y: float) -> float:
        """Distance (m) from (x, y) to the bank, positive on the water side."""
        ux, uy = self.direction
        return ux * (y - self.origin[1]) - uy * (x - self.origin[0])

    def side(self, yaw: float) -> float:
        """+1 when the bank lies to port of a ship heading `yaw` (ENU, rad), -1 to starboard."""
        ux, uy = self.direction
        # the bank is on the right of the water side: port of the ship if the ship heads against it
        return 1.0 if (math.cos(yaw) * ux + math.sin(yaw) * uy) < 0.0 else -1.0


def _segments_cross(p1, p2, q1, q2) -> bool:
    """Whether the closed segments p1-p2 and q1-q2 share a point (collinear overlaps included)."""
    def orient(a, b, c):
        v = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
        return (v > 0.0) - (v < 0.0)

    def on(a, b, c):   # c on segment a-b, given collinear
        return min(a[0], b[0]) <= c[0] <= max(a[0], b[0]) and min(a[1], b[1]) <= c[1] <= max(a[1], b[1])
    o1, o2, o3, o4 = orient(p1, p2, q1), orient(p1, p2, q2), orient(q1, q2, p1), orient(q1, q2, p2)
    if o1 != o2 and o3 != o4:
        return True
    return ((o1 == 0 and on(p1, p2, q1)) or (o2 == 0 and on(p1, p2, q2)) or (o3 == 0 and on(q1, q2, p1))
            or (o4 == 0 and on(q1, q2, p2)))


class BankPolyline:
    """A vertical bank along a polyline of (x, y) points (world frame, m), the water on its left
    (as BankLine, segment by segment). Refused (ValueError naming the point or segments): fewer
    than two points, a non-finite coordinate, two equal consecutive points, and a line that crosses
    or touches itself (a bank line must not enclose or fold over the water)."""

    def __init__(self, points: Sequence[Sequence[float]]):
        pts: List[Tuple[float, float]] = []
        for i, p in enumerate(points):
            if len(p) != 2 or not all(isinstance(c, (int, float)) and math.isfinite(c) for c in p):
                raise ValueError(f"bank line: point {i} must be two finite numbers (x, y), got {p!r}")
            pts.append((float(p[0]), float(p[1])))
        if len(pts) < 2:
            raise ValueError(f"bank line: needs at least two points, got {len(pts)}")
        self.lines = []
        for i in range(len(pts) - 1):
            if pts[i] == pts[i + 1]:
                raise ValueError(f"bank line: points {i} and {i + 1} are the same point {pts[i]!r}")
            self.lines.append(BankLine(pts[i], pts[i + 1]))
        for i in range(len(pts) - 1):
            for j in range(i + 2, len(pts) - 1):
                if _segments_cross(pts[i], pts[i + 1], pts[j], pts[j + 1]):
                    raise ValueError(f"bank line crosses itself: segment {i} {pts[i]!r}-{pts[i + 1]!r} meets "
                                     f"segment {j} {pts[j]!r}-{pts[j + 1]!r}")
        for i in range(len(pts) - 2):      # a segment doubling back over the previous one
            if _segments_cross(pts[i], pts[i + 1], pts[i + 1], pts[i + 2]) and self._folds(pts, i):
                raise ValueError(f"bank line crosses itself: segment {i + 1} {pts[i + 1]!r}-{pts[i + 2]!r} "
                                 f"doubles back over segment {i}")
        self.points = pts

    @staticmethod
    def _folds(pts, i) -> bool:
        (ax, ay), (bx, by), (cx, cy) = pts[i], pts[i + 1], pts[i + 2]
        cross = (bx - ax) * (cy - by) - (by - ay) * (cx - bx)
        dot = (bx - ax) * (cx - bx) + (by - ay) * (cy - by)
        return cross == 0.0 and dot < 0.0

    def nearest(self, x: float, y: float) -> Tuple[float, float, float]:
        """(distance, px, py): the distance (m) from (x, y) to the nearest point (px, py) of the line."""
        best = (math.inf, 0.0, 0.0)
        for (ax, ay), (bx, by) in zip(self.points, self.points[1:]):
            dx, dy = bx - ax, by - ay
            t = min(1.0, max(0.0, ((x - ax) * dx + (y - ay) * dy) / (dx * dx + dy * dy)))
            px, py = ax + t * dx, ay + t * dy
            d = math.hypot(x - px, y - py)
            if d < best[0]:
                best = (d, px, py)
        return best

    def water_side(self, x: float, y: float) -> bool:
        """Whether (x, y) is on the water side of the nearest segment (left of its direction)."""
        d_best, side = math.inf, True
        for line, (ax, ay), (bx, by) in zip(self.lines, self.points, self.points[1:]):
            dx, dy = bx - ax, by - ay
            t = min(1.0, max(0.0, ((x - ax) * dx + (y - ay) * dy) / (dx * dx + dy * dy)))
            d = math.hypot(x - ax - t * dx, y - ay - t * dy)
            if d < d_best:
                d_best, side = d, line.distance(x, y) >= 0.0
        return side


# a depth field's banks: the depth sampled across the ship this far out (horizontal reaches, Eq 2;
# the weight there is e^-7.5 of the ship's) at this many points a side
REACH_SAMPLED = 2.5
DEPTH_SAMPLES = 41


class BankEffect:
    """Bank suction on one hull, its image pair precomputed."""

    def __init__(self, hull: SectionalAreaCurve, nodes: int = DEFAULT_NODES, water_density: float = 1025.0):
        self.hull = hull
        self.pair = HullPair(hull, hull, nodes, water_density)

    def loads(self, distance: float, speed: float, depth: float = math.inf,
              bank_to_port: bool = True) -> Tuple[float, float]:
        """(Y, N) on the ship (N, N m; body frame, REP-103) at `distance` m from its centreline to
        the bank, moving at `speed` m/s along it; the bank to port (default) or to starboard."""
        if not math.isfinite(distance) or distance < 0.5 * self.hull.beam:
            raise ValueError(f"bank effect: distance {distance!r} m from the centreline to the bank must be "
                             f"finite and at least the half beam {0.5 * self.hull.beam:.3g} m")
        side = 1.0 if bank_to_port else -1.0
        _, y, n = self.pair.loads(0.0, side * 2.0 * distance, speed, depth)
        return y, n

    def loads_along(self, bank: BankPolyline, x: float, y: float, yaw: float, speed: float,
                    depth: float = math.inf, slope: float = 0.0) -> Tuple[float, float]:
        """(Y, N) on a ship at (x, y) heading `yaw` (ENU, rad), `speed` m/s along its axis: the
        nearest point of the bank gives the distance and the side (the ship's course is taken as
        parallel to the bank there: the image method's limit). `slope` > 0: the line is the bank's
        waterline and the bank falls to the depth at `slope` m across per m down; it acts as the
        vertical wall of the same d2b (equivalent_wall_distance)."""
        distance, px, py = bank.nearest(x, y)
        if not bank.water_side(x, y):
            raise ValueError(f"bank effect: the ship at ({x:.1f}, {y:.1f}) m is on the land side of the bank line")
        to_port = -math.sin(yaw) * (px - x) + math.cos(yaw) * (py - y) > 0.0
        if slope > 0.0:
            distance = equivalent_wall_distance(sloped_bank(distance, slope, depth, self.hull.draft),
                                                self.hull.beam, self.hull.draft, speed, depth)
            if math.isinf(distance):
                return 0.0, 0.0
        return self.loads(distance, speed, depth, bank_to_port=to_port)

    def loads_in_depth(self, depth_at, x: float, y: float, yaw: float, speed: float,
                       samples: int = DEPTH_SAMPLES) -> Tuple[float, float]:
        """(Y, N) on a ship at (x, y) heading `yaw`, `speed` m/s along its axis, from the banks of a
        depth field (`depth_at(xs, ys)` -> depths, m; <= 0 dry): its depth sampled across the ship
        at midship out to REACH_SAMPLED horizontal reaches each side gives each side's profile
        (cut at the first dry point), each side acts as its vertical wall of the same weight
        (equivalent_wall_distance) in the depth under the ship, and their image-method pulls add
        (an open side pulls nothing; a symmetric channel cancels). ValueError: the ship aground,
        or a side's equivalent wall within its half beam (the model's limit)."""
        beam, draft = self.hull.beam, self.hull.draft
        depth = float(depth_at(np.array([x]), np.array([y]))[0])
        if not depth > draft:
            raise ValueError(f"bank effect: {depth:.2f} m of water at the ship, no more than its draft {draft:.2f} m")
        reach = REACH_SAMPLED * horizontal_reach(beam, abs(speed), depth)
        across = np.linspace(0.0, reach, samples)
        px, py = -math.sin(yaw), math.cos(yaw)                     # to port, world
        ys = np.concatenate((across, -across[1:]))
        depths = np.asarray(depth_at(x + px * ys, y + py * ys), float)
        total_y = total_n = 0.0
        for side, values in ((1.0, depths[:samples]), (-1.0, np.concatenate(([depth], depths[samples:])))):
            points = []
            for d_across, d in zip(across, values):
                if d <= 0.0:     # dry: the waterline where the depth between the last two samples is 0
                    y_wet, d_wet = points[-1]
                    points.append((y_wet + (float(d_across) - y_wet) * d_wet / (d_wet - float(d)), 0.0))
                    break
                points.append((float(d_across), float(d)))
            wall = equivalent_wall_distance(SideProfile(points), beam, draft, speed, depth)
            if math.isinf(wall):
                continue
            side_y, side_n = self.loads(wall, speed, depth, bank_to_port=side > 0.0)
            total_y += side_y
            total_n += side_n
        return total_y, total_n


# ---- Lataire, Vantorre & Eloot (2009): the bank's geometry as the ship feels it ----------------
# E. Lataire, M. Vantorre, K. Eloot, "Systematic model tests on ship-bank interaction effects",
# Int. Conf. on Ship Manoeuvring in Shallow and Confined Water: Bank Effects, Antwerp 2009 (RINA),
# section 4; equation numbers are the paper's. A bank of any cross-section (vertical wall, slope,
# submerged platform, the bathymetry across a channel) enters the model through two numbers built
# from an exponential weight of every water particle around the ship: the dimensionless distance
# to the bank d2b (Eq 12) and the equivalent blockage m_eq (Eq 11). The paper's sway force and yaw
# moment (Eqs 18, 19) are linear in 1/d2b; their coefficients xi are not in the paper (they are in
# Lataire & Vantorre 2008, 27th Symp. Naval Hydrodynamics), so the loads are not computed here.
# Coordinates: y across the ship from its centreline (>= 0 on the side considered), z down from
# the free surface; a side's water is described by its depth profile d(y).

def horizontal_reach(beam: float, speed: float, depth: float, gravity: float = 9.80665) -> float:
    """Eqs (1)-(2): y_infl = B (5 Fr_h + 5), Fr_h = V / sqrt(g h): beyond it a bank has no
    significant effect."""
    return beam * (5.0 * speed / math.sqrt(gravity * depth) + 5.0)


def weight_factors(y_infl: float, draft: float) -> Tuple[float, float]:
    """Eqs (6)-(7): (a, b) of the weight exp(-(a |y| + b |z|)) (Eqs 5, 8), a = 3 / y_infl,
    b = 1 / (3 T)."""
    if not (y_infl > 0.0 and draft > 0.0):
        raise ValueError(f"bank weights: horizontal reach {y_infl!r} m and draft {draft!r} m must be positive")
    return 3.0 / y_infl, 1.0 / (3.0 * draft)


def _exp_integral(k: float, u: float, v: float) -> float:
    """int_u^v exp(-k y) dy (v may be inf for k > 0)."""
    if math.isinf(v):
        return math.exp(-k * u) / k
    if abs(k * (v - u)) < 1e-12:
        return (v - u) * math.exp(-k * u)
    return -math.exp(-k * u) * math.expm1(-k * (v - u)) / k


def rectangle_weight(a: float, b: float, y1: float, y2: float, z1: float, z2: float) -> float:
    """Eq (9): the weight of the rectangle y1 <= y <= y2, z1 <= z <= z2 (0 <= y1, 0 <= z1; an
    upper bound may be inf)."""
    return _exp_integral(a, y1, y2) * _exp_integral(b, z1, z2)


def ocean_weight(a: float, b: float) -> float:
    """Eq (10): an infinitely wide and deep ocean, both sides: 2 / (a b) = 2 y_infl T."""
    return 2.0 / (a * b)


def ship_weight(a: float, b: float, beam: float, draft: float) -> float:
    """The ship's own section, taken as the rectangle B x T on the centreline (both halves)."""
    return 2.0 * rectangle_weight(a, b, 0.0, 0.5 * beam, 0.0, draft)


class SideProfile:
    """The water depth d(y) on one side of a ship, y >= 0 from its centreline: the points
    (y_i, d_i) joined by straight lines, the last depth held to y = inf (0: the bank's land from
    there on). A vertical wall is two points at one y. Depths may all be inf (deep water)."""

    def __init__(self, points: Sequence[Tuple[float, float]]):
        pts = [(float(y), float(d)) for y, d in points]
        if not pts or pts[0][0] != 0.0:
            raise ValueError(f"side profile: the first point must be at y = 0 (the ship's centreline), got {points!r}")
        for i, (y, d) in enumerate(pts):
            if math.isnan(y) or math.isinf(y) or math.isnan(d) or d < 0.0:
                raise ValueError(f"side profile: point {i} ({y!r}, {d!r}) needs a finite y and a depth >= 0")
            if i and y < pts[i - 1][0]:
                raise ValueError(f"side profile: point {i} at y = {y!r} m lies before point {i - 1} "
                                 f"at y = {pts[i - 1][0]!r} m")
        if any(math.isinf(d) for _, d in pts) and not all(math.isinf(d) for _, d in pts):
            raise ValueError("side profile: an infinite depth must hold everywhere (deep water), not at some points")
        self.points = pts

    def pieces(self, half_beam: float):
        """(y_start, y_end, depth at y_start, slope) of each linear piece, split at the half beam."""
        pts = self.points + [(math.inf, self.points[-1][1])]
        for (ya, da), (yb, db) in zip(pts, pts[1:]):
            if yb <= ya:
                continue            # a vertical step: no width
            slope = 0.0 if math.isinf(yb) or math.isinf(da) else (db - da) / (yb - ya)
            cuts = [ya] + ([half_beam] if ya < half_beam < yb else []) + [yb]
            for u, v in zip(cuts, cuts[1:]):
                yield u, v, (da if math.isinf(da) else da + slope * (u - ya)), slope


def side_weight(profile: SideProfile, a: float, b: float, beam: float, draft: float) -> float:
    """The weight (Eq 9's integral over the water) of one side of the ship: every particle from
    the free surface (under the ship: from its keel) down to the bottom d(y), y from 0 to inf;
    exact for the straight pieces of the profile."""
    total = 0.0
    for u, v, d_u, slope in profile.pieces(0.5 * beam):
        top = draft if u < 0.5 * beam else 0.0
        if math.isinf(d_u):        # deep: the water column from `top` down to infinity
            total += _exp_integral(a, u, v) * math.exp(-b * top) / b
            continue
        # water where d(y) = d_u + slope (y - u) > top: one interval [lo, hi] of [u, v]
        lo, hi = u, v
        if slope == 0.0:
            if d_u <= top:
                continue
        else:
            y_top = u + (top - d_u) / slope           # where the bottom meets `top`
            if slope > 0.0:
                lo = max(u, y_top)
            else:
                hi = min(v, y_top)
            if hi <= lo:
                continue
        # int e^{-a y} (e^{-b top} - e^{-b d(y)}) / b dy, d(y) = (d_u - slope u) + slope y
        total += (math.exp(-b * top) * _exp_integral(a, lo, hi)
                  - math.exp(-b * (d_u - slope * u)) * _exp_integral(a + b * slope, lo, hi)) / b
    return total


def inverse_distance_to_bank(chi_ocean: float, chi_ship: float, chi_port: float, chi_starboard: float) -> float:
    """Eq (12): 1/d2b = 1/2 (chi_ocean - chi_ship) (1/chi_p - 1/chi_s): 0 on the centreline of a
    symmetric channel, negative with the nearer bank to starboard (less water there)."""
    return 0.5 * (chi_ocean - chi_ship) * (1.0 / chi_port - 1.0 / chi_starboard)


def equivalent_blockage(chi_ocean: float, chi_ship: float, chi_port: float, chi_starboard: float) -> float:
    """Eq (11): m_eq = chi_ship / (chi_p + chi_s) - chi_ship / (chi_ocean - chi_ship): 0 in open deep
    water, larger the more of the weighted water the banks and the bottom take away."""
    return chi_ship / (chi_port + chi_starboard) - chi_ship / (chi_ocean - chi_ship)


def propeller_wake_speed(thrust: float, diameter: float, water_density: float = 1025.0) -> float:
    """Eq (13): V_T = sign(T_P) sqrt(|8 T_P / (rho pi D^2)|), the axial speed behind the propeller."""
    return math.copysign(math.sqrt(abs(8.0 * thrust / (water_density * math.pi * diameter ** 2))), thrust)


def critical_froude(blockage: float) -> float:
    """Eq (21), Schijf (1949): Fr_crit = (2 sin(arcsin(1 - m) / 3))^(3/2), m the conventional
    blockage (ship section over waterway section); the model holds for Fr_h < 0.84 Fr_crit (Eq 22)."""
    if not 0.0 <= blockage < 1.0:
        raise ValueError(f"critical speed: blockage {blockage!r} must be in [0, 1)")
    return (2.0 * math.sin(math.asin(1.0 - blockage) / 3.0)) ** 1.5


class BankGeometry:
    """d2b and m_eq of a ship between two side profiles (Eqs 2, 5-12), with the model's range
    (Eq 20: the weight of each side at least 0.45 of the ship's)."""

    def __init__(self, beam: float, draft: float, speed: float, depth: float,
                 port: SideProfile, starboard: SideProfile, gravity: float = 9.80665):
        self.y_infl = horizontal_reach(beam, speed, depth, gravity)
        a, b = weight_factors(self.y_infl, draft)
        self.chi_ocean = ocean_weight(a, b)
        self.chi_ship = ship_weight(a, b, beam, draft)
        self.chi_port = side_weight(port, a, b, beam, draft)
        self.chi_starboard = side_weight(starboard, a, b, beam, draft)
        if min(self.chi_port, self.chi_starboard) <= 0.0:
            raise ValueError("bank geometry: no water on one side of the ship (it is aground or in the bank)")
        self.inverse_d2b = inverse_distance_to_bank(self.chi_ocean, self.chi_ship, self.chi_port, self.chi_starboard)
        self.m_eq = equivalent_blockage(self.chi_ocean, self.chi_ship, self.chi_port, self.chi_starboard)

    @property
    def within_model_range(self) -> bool:
        """Eq (20): chi_p / chi_ship and chi_s / chi_ship both above 0.45."""
        return min(self.chi_port, self.chi_starboard) / self.chi_ship > 0.45


# a side within this fraction of open water's weight is open water: the sum over a profile's pieces
# carries round-off of ~1e-15, which would otherwise put a wall at 11-12 horizontal reaches or none
OPEN_WATER_TOLERANCE = 1e-12


def _profile_depth(depth: float, draft: float) -> float:
    # deep water: 60 drafts down, where the weight exp(-z / 3T) is e^-20 (the profile must be finite)
    return depth if math.isfinite(depth) and depth > 0.0 else 60.0 * draft


def sloped_bank(waterline: float, slope: float, depth: float, draft: float) -> SideProfile:
    """The bank side of a ship whose centreline is `waterline` m from the bank's waterline, the
    bank falling at `slope` m across per m down to the water's `depth` (inf: deep)."""
    h = _profile_depth(depth, draft)
    toe = waterline - slope * h
    if toe > 0.0:
        return SideProfile([(0.0, h), (toe, h), (waterline, 0.0)])
    return SideProfile([(0.0, waterline / slope), (waterline, 0.0)])   # the ship over the slope


def equivalent_wall_distance(bank_side: SideProfile, beam: float, draft: float, speed: float,
                             depth: float) -> float:
    """The distance from the ship's centreline of the vertical wall (in the same depth) whose side
    of water weighs what the bank's side does (chi_s, Eqs 5-9). With the other side unchanged the
    two have the same 1/d2b (Eq 12), which carries the whole bank geometry in Lataire, Vantorre &
    Eloot's model (their Fig. 17: the sway forces along seven banks, vertical to 1/8 slopes, on one
    line in 1/d2b). The wall's weight is Eq (9)'s rectangle, so the distance is closed form:
    chi_s + chi_ship / 2 = (1 - e^-a y) (1 - e^-b h) / (a b). inf: the side weighs what open water
    does (the bank out of reach)."""
    h = _profile_depth(depth, draft)
    a, b = weight_factors(horizontal_reach(beam, abs(speed), h), draft)
    chi_side = side_weight(bank_side, a, b, beam, draft) + 0.5 * ship_weight(a, b, beam, draft)
    fraction = chi_side * a * b / -math.expm1(-b * h)    # of the open side's weight, 1 - e^-a y
    if fraction >= 1.0 - OPEN_WATER_TOLERANCE:   # open water to round-off (a wall beyond 9 reaches)
        return math.inf
    return -math.log1p(-fraction) / a
