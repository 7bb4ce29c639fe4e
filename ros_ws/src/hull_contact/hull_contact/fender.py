"""A tug's fender against another vessel's hull: a compliant contact in the horizontal plane.

The fender is a point of the pushing vessel (an attachment of its ship file, e.g. the ASD tug's
`bow_fender`) wrapped in a fender of radius `radius` (its thickness); the hull is the other
vessel's waterline outline (sim_math.hull_plan, the plan shape the scene draws, from the ship
file's length and beam), convex. Where the fender surface reaches into the outline by a
penetration d > 0, the contact pushes the two apart (Kelvin-Voigt spring-dashpot, the usual
penalty contact of ship-fender models, e.g. PIANC (2002) "Guidelines for the design of fender
systems", linearised fender reaction):

    F_n = max(0, k d - c dd/dt)                  (normal, from the hull outwards onto the fender)
    F_t = -mu F_n v_t / sqrt(v_t^2 + v_s^2)      (Coulomb friction of rubber on steel, mu 0.3 in
                                                  PIANC 2002 Table 4.2.1, regularised below v_s)

with v_t the sliding speed of the fender along the hull. The hull vessel takes +F at the contact
point on its outline; the fender vessel takes -F at its fender point (equal and opposite, so
momentum is exchanged, never made).

The exchange holds a force constant over a step (dt), and in the lockstep network the force
computed from the state of step k acts over k+1 -> k+2 (the step protocol's one-step lag, as for
the ropes). Evaluated on the state as it is, a spring that closes and reopens within a few steps
gains energy (the force lags the motion). `predict_half_step` evaluates it at the middle of the
step it will act over instead, extrapolating the positions with the velocities (the mid-point
rule: energy is conserved to O((w dt)^2) for a conservative spring; tests/physics/
test_hull_contact.py measures it).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional, Tuple

import numpy as np

from sim_contract.node_params import CONTACT_NODE


@dataclass(frozen=True)
class FenderSpec:
    """Fender properties (SI). Defaults: a 1 m cylindrical rubber tug fender, reaction about
    1 MN at 0.5 m compression (linearised 2 MN/m), mu 0.3 (PIANC 2002): the contact node's
    defaults (sim_contract.node_params.CONTACT_NODE)."""
    radius: float = CONTACT_NODE["radius"].default        # m, fender surface ahead of the fender point
    stiffness: float = CONTACT_NODE["stiffness"].default  # N/m
    damping: float = CONTACT_NODE["damping"].default      # N s/m (0 for the energy test)
    friction: float = CONTACT_NODE["friction"].default    # Coulomb coefficient
    slip_speed: float = 0.05       # m/s, regularisation of the friction law
    predict_half_step: bool = True

    def __post_init__(self):
        for key in ("radius", "stiffness", "damping", "friction", "slip_speed"):
            v = getattr(self, key)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0.0):
                raise ValueError(f"fender {key}: expected a finite number >= 0, got {v!r}")
        if self.stiffness <= 0.0 or self.slip_speed <= 0.0:
            raise ValueError("fender stiffness and slip_speed must be > 0")


@dataclass
class PlanarPose:
    """A vessel's pose and velocity in the horizontal plane of the world (ENU): position (m),
    heading (rad), velocity (m/s, world), yaw rate (rad/s)."""
    x: float
    y: float
    heading: float
    vx: float = 0.0
    vy: float = 0.0
    yaw_rate: float = 0.0

    def advanced(self, dt: float) -> "PlanarPose":
        return PlanarPose(self.x + dt * self.vx, self.y + dt * self.vy, self.heading + dt * self.yaw_rate,
                          self.vx, self.vy, self.yaw_rate)

    def to_world(self, p_body: np.ndarray) -> np.ndarray:
        c, s = math.cos(self.heading), math.sin(self.heading)
        return np.array([self.x + c * p_body[0] - s * p_body[1], self.y + s * p_body[0] + c * p_body[1]])

    def to_body(self, p_world: np.ndarray) -> np.ndarray:
        c, s = math.cos(self.heading), math.sin(self.heading)
        dx, dy = p_world[0] - self.x, p_world[1] - self.y
        return np.array([c * dx + s * dy, -s * dx + c * dy])

    def velocity_at(self, p_world: np.ndarray) -> np.ndarray:
        """Velocity of the body point at p_world: v + w x r."""
        return np.array([self.vx - self.yaw_rate * (p_world[1] - self.y),
                         self.vy + self.yaw_rate * (p_world[0] - self.x)])


def outline_distance(outline: np.ndarray, q: np.ndarray) -> Tuple[float, np.ndarray, np.ndarray]:
    """Signed distance from q to a convex counter-clockwise outline (negative inside), the
    outward unit normal there and the nearest point on the outline (all in the outline's frame)."""
    a = outline
    b = np.roll(outline, -1, axis=0)
    e = b - a
    length2 = np.einsum("ij,ij->i", e, e)
    normals = np.column_stack((e[:, 1], -e[:, 0])) / np.sqrt(length2)[:, None]   # outward (ccw)
    side = np.einsum("ij,ij->i", q - a, normals)
    if np.all(side <= 0.0):                      # inside: the nearest edge is the least negative
        i = int(np.argmax(side))
        return float(side[i]), normals[i], q - side[i] * normals[i]
    t = np.clip(np.einsum("ij,ij->i", q - a, e) / length2, 0.0, 1.0)
    nearest = a + t[:, None] * e
    d = np.hypot(*(q - nearest).T)
    i = int(np.argmin(d))
    n = (q - nearest[i]) / d[i] if d[i] > 1e-12 else normals[i]
    return float(d[i]), n, nearest[i]


@dataclass
class ContactResult:
    in_contact: bool
    penetration: float            # m, >= 0
    gap: float                    # m, signed: fender surface to outline (negative = penetrating)
    normal_force: float           # N, >= 0
    friction_force: float         # N, magnitude
    force_on_hull: np.ndarray     # world (x, y), N; the fender vessel takes -force_on_hull
    point_world: np.ndarray       # contact point on the hull outline, world (x, y)
    hull_point_body: np.ndarray   # the same point in the hull vessel's body (x, y)


class FenderContact:
    """One fender (a point of the fender vessel's body) against one hull outline."""

    def __init__(self, spec: FenderSpec, fender_point_body: np.ndarray, hull_outline: np.ndarray):
        self.spec = spec
        self.fender_point = np.asarray(fender_point_body, float)[:2]
        self.outline = np.asarray(hull_outline, float)
        if self.outline.ndim != 2 or self.outline.shape[1] != 2 or len(self.outline) < 3:
            raise ValueError("hull outline: expected at least 3 points (x, y)")
        if outline_distance(self.outline, self.outline.mean(axis=0))[0] >= 0:
            raise ValueError("hull outline: not counter-clockwise (its centre is not inside)")

    def force(self, fender: PlanarPose, hull: PlanarPose, lead: float = 0.0) -> ContactResult:
        """The contact force from the vessels' state, evaluated `lead` seconds after that state
        when spec.predict_half_step (the middle of the step the force will act over: 0.5 dt for a
        force applied from the state's own step, 1.5 dt in the lockstep network, where the force
        computed from step k acts over k+1 -> k+2)."""
        spec = self.spec
        if spec.predict_half_step and lead > 0.0:
            fender, hull = fender.advanced(lead), hull.advanced(lead)
        p_world = fender.to_world(self.fender_point)
        q = hull.to_body(p_world)
        dist, n_body, nearest_body = outline_distance(self.outline, q)
        gap = dist - spec.radius
        c, s = math.cos(hull.heading), math.sin(hull.heading)
        n = np.array([c * n_body[0] - s * n_body[1], s * n_body[0] + c * n_body[1]])   # world, outwards
        point = hull.to_world(nearest_body)
        if gap >= 0.0:
            zero = np.zeros(2)
            return ContactResult(False, 0.0, gap, 0.0, 0.0, zero, point, nearest_body)
        # relative velocity of the fender against the hull at the contact point, world
        v_rel = fender.velocity_at(p_world) - hull.velocity_at(point)
        closing = -float(v_rel @ n)               # d(penetration)/dt
        fn = max(0.0, spec.stiffness * (-gap) + spec.damping * closing)
        v_t = v_rel - (v_rel @ n) * n
        speed_t = math.hypot(*v_t)
        ft_vec = -spec.friction * fn * v_t / math.sqrt(speed_t * speed_t + spec.slip_speed ** 2)
        on_fender = fn * n + ft_vec
        return ContactResult(True, -gap, gap, fn, float(math.hypot(*ft_vec)), -on_fender, point, nearest_body)


def contact_from_ship_files(spec: FenderSpec, fender_ship: str, fender: str, hull_ship: str,
                            fender_overrides: Optional[dict] = None,
                            hull_overrides: Optional[dict] = None) -> Tuple[FenderContact, np.ndarray]:
    """The contact of attachment `fender` of the ship file fender_ship against the waterline
    outline of hull_ship (each with its ship_overrides merged), and the fender point (body, 3D).
    Raises ValueError naming the file and the attachment when the fender is not there."""
    from sim_math.hull_plan import HullDimensions, waterline_outline
    from tug_dynamics.ship_file import load_ship, ship_config   # the file and merge load_ship reads
    points = load_ship(fender_ship, overrides=fender_overrides).attachments
    if fender not in points:
        raise ValueError(f"ship file {fender_ship}: no attachment '{fender}' for the fender "
                         f"(it has {sorted(points)})")
    point = np.asarray(points[fender], float)
    load_ship(hull_ship, overrides=hull_overrides)   # the same checks as the vessel node's
    dims = HullDimensions.from_ship_config(ship_config(hull_ship, hull_overrides)[1])
    return FenderContact(spec, point[:2], waterline_outline(dims)), point
