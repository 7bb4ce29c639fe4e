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
    closing_speed: float = 0.0    # m/s, d(penetration)/dt where the force was evaluated


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
        self.hull_beam = float(np.ptp(self.outline[:, 1]))   # m, for divergence()
        # 1/m_fender + 1/m_hull at the contact (contact_mobility; contact_from_ship_files sets it):
        # nan leaves the impulse test of divergence() out
        self.mobility = math.nan

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
        return ContactResult(True, -gap, gap, fn, float(math.hypot(*ft_vec)), -on_fender, point, nearest_body,
                             closing)

    def divergence(self, r: ContactResult, dt: float) -> Optional[str]:
        """What makes the force `r` (to act over one exchange step dt) unphysical, or None. The
        exchange has diverged when:
        - a value is not finite;
        - the penetration exceeds the fender (radius) plus a quarter of the hull's beam: the fender
          point is deep inside the other hull, vessels passing through each other;
        - the force's impulse over one step, F_n dt mobility (the change of the relative normal
          speed it makes, self.mobility = 1/m_fender + 1/m_hull there), exceeds what any passive fender
          can do: reverse the approach (2 |v_n|) and release all the energy its spring holds
          (omega d, omega^2 = k mobility). A contact within exchange_limits changes it by at most
          omega h omega d + b |v_n| < omega d / 2 + |v_n|."""
        values = (r.penetration, r.normal_force, r.closing_speed, *r.force_on_hull)
        if not all(math.isfinite(v) for v in values):
            return (f"contact force not finite (normal force {r.normal_force!r} N, penetration {r.penetration!r} m)")
        limit = self.spec.radius + 0.25 * self.hull_beam
        if r.penetration > limit:
            return (f"penetration {r.penetration:.3g} m exceeds the fender ({self.spec.radius:g} m) plus a quarter "
                    f"of the hull's beam ({self.hull_beam:g} m): {limit:.3g} m")
        mobility = self.mobility
        dv = r.normal_force * dt * mobility
        passive = 2.0 * abs(r.closing_speed) + math.sqrt(self.spec.stiffness * mobility) * r.penetration
        if dv > passive:   # False for a nan mobility
            return (f"normal force {r.normal_force:.4g} N would change the relative speed by {dv:.3g} m/s in one "
                    f"step of {dt:g} s (effective mass {1.0 / mobility:.4g} kg), more than a passive fender can "
                    f"({passive:.3g} m/s: twice the closing speed {r.closing_speed:.3g} m/s plus its spring's "
                    f"release from {r.penetration:.3g} m)")
        return None


# --- what the lockstep exchange can carry ---------------------------------------------------
#
# The contact is exchanged between the two vessel nodes: the force computed from the state of
# step k (springs at the predicted middle of its step, 1.5 h on) acts, constant, over k+1 -> k+2.
# Closed, along the normal, with lam = 1/m_fender + 1/m_hull the relative mobility there (free
# bodies), the relative penetration x, its rate v and the exchanged force f obey
#     v_{k+1} = v_k + h lam f_k,   x_{k+1} = x_k + h v_k + h^2 lam f_k / 2,
#     f_{k+1} = -k (x_k + 1.5 h v_k) - c v_k,
# whose characteristic polynomial is z^3 - 2 z^2 + (1 + 2a + b) z - (a + b) with
#     a = (omega h)^2 = k h^2 lam,   b = c h lam.
# The Jury conditions reduce to a > 0, a + b < 1 and (a + b)^2 < b: the exchange is stable iff
#     a < sqrt(b) - b.
# Hence: omega h < 1/2 (a < 1/4, the largest sqrt(b) - b, at b = 1/4) whatever the damping; and
# for a stiffness within that, the damping inside ((1 - r)^2 / 4, (1 + r)^2 / 4), r = sqrt(1 - 4a):
# above it the lagged damper overshoots (b < 1 for a spring-less damper), below it the prediction's
# small energy gain, about a^2 / 2 per step, is not damped away. tests/physics/test_hull_contact.py
# checks the growth of the map and of stepped contacts against this.
STIFFNESS_BOUND_OMEGA_H = 0.5


def stable_damping_range(a: float) -> Tuple[float, float]:
    """(b_lo, b_hi): the b = c h lam between which a spring of a = k h^2 lam is exchanged stably
    (empty, (nan, nan), for a >= 1/4)."""
    if not 0.0 <= a < 0.25:
        return math.nan, math.nan
    r = math.sqrt(1.0 - 4.0 * a)
    return (1.0 - r) ** 2 / 4.0, (1.0 + r) ** 2 / 4.0


def exchange_limits(stiffness: float, damping: float, dt: float, mobility: float) -> dict:
    """The contact's stiffness and damping against what the exchange at step dt (s) carries, for
    the relative mobility `mobility` (1/kg) at the contact: {'stiffness': k_max for any damping
    (omega h = 1/2, reached at 'best_damping'), 'stiffness_here': the largest stiffness for this
    damping (0 if none), 'damping': (c_min, c_max) for this stiffness (nan when k >= k_max),
    'stable': bool, 'omega_h', 'b'}."""
    hl = dt * mobility
    a, b = stiffness * dt * hl, damping * hl
    b_lo, b_hi = stable_damping_range(a)
    return {"stiffness": STIFFNESS_BOUND_OMEGA_H ** 2 / (dt * hl), "best_damping": 0.25 / hl,
            "stiffness_here": max(0.0, math.sqrt(b) - b) / (dt * hl) if b < 1.0 else 0.0,
            "damping": (b_lo / hl, b_hi / hl), "stable": a < 0.25 and b_lo < b < b_hi, "omega_h": math.sqrt(a), "b": b}


def slowest_stable_rate(stiffness: float, damping: float, mobility: float) -> float:
    """The exchange rate (Hz) above which the contact is stable: with x = sqrt(h), the margin
    sqrt(b) - b - a = sqrt(c lam) x - c lam x^2 - k lam x^4 is concave in x and starts positive,
    so it has one root; found by bisection (inf when damping is 0: never stable)."""
    if damping <= 0.0:
        return math.inf
    margin = lambda h: math.sqrt(damping * mobility * h) - damping * mobility * h - stiffness * mobility * h * h  # noqa: E731
    lo, hi = 1e-9, 1.0 / (damping * mobility)          # stable at lo, not at hi (b = 1)
    for _ in range(200):
        mid = math.sqrt(lo * hi)
        lo, hi = (mid, hi) if margin(mid) > 0.0 else (lo, mid)
    return 1.0 / lo


def planar_mobility(model, z: float = 0.0, dt: float = 1e-3) -> np.ndarray:
    """The vessel at rest: (4, 3) accelerations (u', v', r', p') per unit force X, Y at (0, 0, z)
    and yaw moment N (body), measured on the model itself by one short step (rigid body, added
    mass and the roll a force at height z brings), the same for every model kind."""
    import copy
    from tug_dynamics.vessel import ExternalWrench, VesselState
    model = copy.deepcopy(model)
    model.set_state(VesselState.at_rest())

    def rates(wrenches):
        m = copy.deepcopy(model)
        m.step(dt, wrenches)
        s = m.state
        return np.array([s.linear_velocity_body[0], s.linear_velocity_body[1], s.angular_velocity_body[2],
                         s.angular_velocity_body[0]]) / dt
    base, unit, out = rates([]), 1.0e4, np.zeros((4, 3))
    point = np.array([0.0, 0.0, z])
    for j in range(3):
        f, n = np.zeros(3), np.zeros(3)
        if j < 2:
            f[j] = unit
        else:
            n[2] = unit
        out[:, j] = (rates([ExternalWrench(f, point, n)]) - base) / unit
    return out


def point_mobility(minv: np.ndarray, x: float, y: float, z: float) -> float:
    """Largest horizontal mobility (1/kg) of the body point (x, y, z) for a force there, from
    planar_mobility(model, z): 1 / the smallest effective mass a contact at that point meets."""
    j_out = np.array([[1.0, 0.0, -y, 0.0], [0.0, 1.0, x, -z]])   # (u, v, r, p) -> point velocity
    j_in = np.array([[1.0, 0.0], [0.0, 1.0], [-y, x]])          # point force -> (X, Y, N) at height z
    g = j_out @ minv @ j_in
    return float(np.linalg.eigvalsh(0.5 * (g + g.T)).max())


def contact_mobility(fender_model, fender_point: np.ndarray, hull_model, hull_outline: np.ndarray) -> float:
    """lam = 1/m_fender + 1/m_hull at the contact, conservative: the fender point's largest
    mobility plus the largest over the hull's outline (the contact may land anywhere on it; the
    largest of a quadratic form over a convex outline is at a vertex), at the fender's height."""
    z = float(fender_point[2]) if len(fender_point) > 2 else 0.0
    fender = point_mobility(planar_mobility(fender_model, z), fender_point[0], fender_point[1], z)
    m_hull = planar_mobility(hull_model, z)
    return fender + max(point_mobility(m_hull, x, y, z) for x, y in hull_outline)


def contact_from_ship_files(spec: FenderSpec, fender_ship: str, fender: str, hull_ship: str,
                            fender_overrides: Optional[dict] = None,
                            hull_overrides: Optional[dict] = None) -> Tuple[FenderContact, np.ndarray]:
    """The contact of attachment `fender` of the ship file fender_ship against the waterline
    outline of hull_ship (each with its ship_overrides merged), and the fender point (body, 3D).
    Raises ValueError naming the file and the attachment when the fender is not there."""
    from sim_math.hull_plan import HullDimensions, waterline_outline
    from tug_dynamics.ship_file import load_ship, ship_config   # the file and merge load_ship reads
    fender_model = load_ship(fender_ship, overrides=fender_overrides)
    points = fender_model.attachments
    if fender not in points:
        raise ValueError(f"ship file {fender_ship}: no attachment '{fender}' for the fender "
                         f"(it has {sorted(points)})")
    point = np.asarray(points[fender], float)
    hull_model = load_ship(hull_ship, overrides=hull_overrides)   # the same checks as the vessel node's
    dims = HullDimensions.from_ship_config(ship_config(hull_ship, hull_overrides)[1])
    contact = FenderContact(spec, point[:2], waterline_outline(dims))
    contact.mobility = contact_mobility(fender_model, point, hull_model, contact.outline)
    return contact, point
