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
from typing import Sequence, Tuple

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
