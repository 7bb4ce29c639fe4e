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

Limits: a vertical bank (no slope: a sloping bank or a bank with a shallow berm is not a mirror);
parallel course (the image of a ship at an angle to the bank is not parallel to it); potential
flow at low Froude number. Wang's parabola is fore-and-aft symmetric, so N_bank is zero: the
bow-away moment measured on real hulls (from the fuller stern and the propeller's suction, as in
the empirical models of Norrbin 1974 and Lataire & Vantorre 2008) is not in this model.
"""
from __future__ import annotations

import math
from typing import List, Sequence, Tuple

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
                    depth: float = math.inf) -> Tuple[float, float]:
        """(Y, N) on a ship at (x, y) heading `yaw` (ENU, rad), `speed` m/s along its axis: the
        nearest point of the bank gives the distance and the side (the ship's course is taken as
        parallel to the bank there: the image method's limit)."""
        distance, px, py = bank.nearest(x, y)
        if not bank.water_side(x, y):
            raise ValueError(f"bank effect: the ship at ({x:.1f}, {y:.1f}) m is on the land side of the bank line")
        to_port = -math.sin(yaw) * (px - x) + math.cos(yaw) * (py - y) > 0.0
        return self.loads(distance, speed, depth, bank_to_port=to_port)
