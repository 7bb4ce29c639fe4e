"""A tug's fender against a hull (hull_contact.fender), without ROS.

Truths used:
- geometry: the signed distance to a rectangle and to the S-175's outline, by hand;
- an elastic impact of two free bodies (damping and friction off), stepped as the lockstep network
  steps it (force from step k's state acts over k+1 -> k+2): kinetic energy after the impact equals
  the energy before (no energy added), momentum is exchanged exactly, and the largest compression
  is the analytic v0 sqrt(m_eff / k) of a linear spring;
- friction: a fender sliding along the hull fast (v >> slip speed) feels mu F_n against the slip;
- pushing: an ASD tug pushing a free S-175 at rest on its side settles where the contact force
  equals the tug's delivered thrust minus its own resistance (the ship file's resistance table
  at the tug's speed, by hand), within 2 %, and the fender's compression is F / k.
"""
import math
import os

import numpy as np
import pytest

from hull_contact.fender import FenderContact, FenderSpec, PlanarPose, contact_from_ship_files, outline_distance
from sim_math.hull_plan import HullDimensions, waterline_outline

SHIPS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "ros_ws", "src", "tug_dynamics", "ships")
BOX = np.array([[-10.0, -5.0], [10.0, -5.0], [10.0, 5.0], [-10.0, 5.0]])


@pytest.mark.parametrize("q, dist, normal", [((12.0, 0.0), 2.0, (1, 0)), ((0.0, -7.5), 2.5, (0, -1)),
                                             ((13.0, 9.0), 5.0, (0.6, 0.8)), ((9.0, 0.0), -1.0, (1, 0)),
                                             ((0.0, 4.0), -1.0, (0, 1))])
def test_signed_distance_to_a_rectangle(q, dist, normal):
    d, n, nearest = outline_distance(BOX, np.array(q))
    assert d == pytest.approx(dist, abs=1e-12)
    np.testing.assert_allclose(n, normal, atol=1e-12)
    np.testing.assert_allclose(nearest + d * n, q, atol=1e-12)


def test_ship_outline_is_convex_and_has_the_ship_files_size():
    d = HullDimensions(175.0, 25.4, 9.5, 5.0, "ship")
    o = waterline_outline(d)
    e = np.roll(o, -1, axis=0) - o
    cross = e[:, 0] * np.roll(e, -1, axis=0)[:, 1] - e[:, 1] * np.roll(e, -1, axis=0)[:, 0]
    assert np.all(cross >= -1e-9)                       # convex, counter-clockwise
    assert o[:, 0].max() - o[:, 0].min() == pytest.approx(175.0)
    assert o[:, 1].max() == pytest.approx(12.7)
    # midships beam-on: a point 3 m off the side is 3 m away, the normal points to port
    dist, n, _ = outline_distance(o, np.array([0.0, 15.7]))
    assert dist == pytest.approx(3.0, abs=1e-9) and n == pytest.approx([0.0, 1.0], abs=1e-9)


def _free_flight(pose: PlanarPose, accel: np.ndarray, dt: float) -> PlanarPose:
    """Exact motion of a free body under a constant force over dt (no water, no rotation)."""
    return PlanarPose(pose.x + dt * pose.vx + 0.5 * dt * dt * accel[0], pose.y + dt * pose.vy + 0.5 * dt * dt * accel[1],
                      pose.heading, pose.vx + dt * accel[0], pose.vy + dt * accel[1], 0.0)


def _impact(dt: float, predict: bool, v0: float = 0.5, m_tug: float = 7.5e5, m_hull: float = 3.0e6,
            k: float = 2.0e6, angle: float = 0.0):
    """A tug (fender point at its reference point) running at v0 into a box hull at rest, stepped
    like the lockstep network. Returns (energy after / before, max compression, momentum drift,
    analytic max compression)."""
    spec = FenderSpec(radius=0.5, stiffness=k, damping=0.0, friction=0.0, predict_half_step=predict)
    contact = FenderContact(spec, np.zeros(2), BOX)
    c, s = math.cos(angle), math.sin(angle)
    start = np.array([12.0, 0.0])
    tug = PlanarPose(c * start[0] - s * start[1], s * start[0] + c * start[1], angle, -v0 * c, -v0 * s)
    hull = PlanarPose(0.0, 0.0, angle)
    force = contact.force(tug, hull, 0.5 * dt).force_on_hull   # the step-0 output acts over 0 -> 1
    p0 = m_tug * np.array([tug.vx, tug.vy])
    peak = 0.0
    for _ in range(int(20.0 / dt)):
        nxt = contact.force(tug, hull, 1.5 * dt)                # from step k, acts over k+1 -> k+2
        peak = max(peak, nxt.penetration)
        tug, hull = _free_flight(tug, -force / m_tug, dt), _free_flight(hull, force / m_hull, dt)
        force = nxt.force_on_hull
    energy = 0.5 * m_tug * (tug.vx ** 2 + tug.vy ** 2) + 0.5 * m_hull * (hull.vx ** 2 + hull.vy ** 2)
    momentum = m_tug * np.array([tug.vx, tug.vy]) + m_hull * np.array([hull.vx, hull.vy])
    m_eff = m_tug * m_hull / (m_tug + m_hull)
    return energy / (0.5 * m_tug * v0 ** 2), peak, np.linalg.norm(momentum - p0), v0 * math.sqrt(m_eff / k)


@pytest.mark.parametrize("rate, energy_tol", [(50.0, 5e-4), (20.0, 5e-3)])
@pytest.mark.parametrize("angle", [0.0, 2.3])
def test_elastic_impact_adds_no_energy_and_compresses_as_a_linear_spring(rate, energy_tol, angle):
    ratio, peak, drift, analytic = _impact(1.0 / rate, predict=True, angle=angle)
    assert abs(ratio - 1.0) < energy_tol            # measured 1.2e-4 (50 Hz), 1.4e-3 (20 Hz)
    assert peak == pytest.approx(analytic, rel=0.01)  # the fender never bottoms out: 0.27 m of 0.5 m
    assert peak < 0.5
    assert drift < 1e-6 * 0.5 * 7.5e5


def test_without_the_half_step_prediction_the_lagged_force_pumps_energy():
    """Why the node predicts: evaluated on the lagged state the spring gains > 10 % per impact at 50 Hz."""
    ratio, _peak, _drift, _analytic = _impact(0.02, predict=False)
    assert ratio > 1.10


def test_friction_opposes_sliding_with_mu_times_the_normal_force():
    spec = FenderSpec(radius=0.5, stiffness=2.0e6, damping=0.0, friction=0.3)
    contact = FenderContact(spec, np.zeros(2), BOX)
    # fender pressed 0.1 m into the top side, sliding along +x at 2 m/s (40 x the slip speed)
    r = contact.force(PlanarPose(0.0, 5.4, 0.0, 2.0, 0.0), PlanarPose(0.0, 0.0, 0.0))
    assert r.normal_force == pytest.approx(2.0e6 * 0.1)
    on_fender = -r.force_on_hull
    assert on_fender[1] == pytest.approx(r.normal_force)                  # pushed out of the hull (+y)
    assert on_fender[0] == pytest.approx(-0.3 * r.normal_force / math.sqrt(1 + (0.05 / 2.0) ** 2), rel=1e-9)
    # the hull turning under a fender at rest is sliding too: the friction drags the fender along
    r2 = contact.force(PlanarPose(0.0, 5.4, 0.0), PlanarPose(0.0, 0.0, 0.0, yaw_rate=-0.4))
    assert -r2.force_on_hull[0] == pytest.approx(0.3 * r2.normal_force, rel=1e-3)  # hull moves +x there


def test_contact_is_frame_invariant():
    """Moving and turning both vessels together turns the force with them."""
    spec = FenderSpec()
    contact = FenderContact(spec, np.array([1.0, 0.0]), BOX)
    base = contact.force(PlanarPose(10.2, 1.0, math.pi, -0.3, 0.1, 0.01), PlanarPose(0.0, 0.0, 0.0, 0.0, 0.0, 0.002))
    a = 0.7
    c, s = math.cos(a), math.sin(a)
    rot = np.array([[c, -s], [s, c]])
    p = rot @ [10.2, 1.0] + [50.0, -20.0]
    v = rot @ [-0.3, 0.1]
    # the hull's origin moved to (50, -20): its velocity field v + w x r is the same body-fixed field
    turned = contact.force(PlanarPose(p[0], p[1], math.pi + a, v[0], v[1], 0.01),
                           PlanarPose(50.0, -20.0, a, 0.0, 0.0, 0.002))
    assert base.in_contact and turned.in_contact
    np.testing.assert_allclose(turned.force_on_hull, rot @ base.force_on_hull, rtol=1e-9)
    np.testing.assert_allclose(turned.hull_point_body, base.hull_point_body, atol=1e-9)


def _pose(model) -> PlanarPose:
    s = model.state
    yaw = s.rpy[2]
    u, v = s.linear_velocity_body[:2]
    c, sn = math.cos(yaw), math.sin(yaw)
    return PlanarPose(s.position[0], s.position[1], yaw, c * u - sn * v, sn * u + c * v, s.angular_velocity_body[2])


def test_a_tug_pushing_a_free_ship_transfers_its_thrust():
    import yaml
    from tug_dynamics.ship_file import load_ship
    from tug_dynamics.vessel import Command, ExternalWrench, VesselState
    tug_file, ship_file = os.path.join(SHIPS, "asd_tug.yaml"), os.path.join(SHIPS, "s175_003.yaml")
    spec = FenderSpec()
    contact, fender = contact_from_ship_files(spec, tug_file, "bow_fender", ship_file)
    ship, tug = load_ship(ship_file), load_ship(tug_file)
    # beam-on at midships against the starboard side, heading north, 0.2 m off
    tug.set_state(VesselState.at_rest(x=0.0, y=-12.7 - spec.radius - fender[0] - 0.2, yaw=math.pi / 2))
    tug.set_command(Command(engine_order=0.5, steering_angle=0.0))
    dt = 0.05
    result = contact.force(_pose(tug), _pose(ship), 0.5 * dt)
    for _ in range(int(700.0 / dt)):
        nxt = contact.force(_pose(tug), _pose(ship), 1.5 * dt)
        force = np.array([*result.force_on_hull, 0.0])
        ship.step(dt, [ExternalWrench(force, np.array([*result.hull_point_body, fender[2]]))])
        tug.step(dt, [ExternalWrench(-force, fender)])
        result = nxt
    u = tug.state.linear_velocity_body[0]
    assert 0.5 < u < 1.0 and abs(ship.state.linear_velocity_body[1] - u) < 1e-3   # pushed sideways together
    thrust = sum(t.thrust * math.cos(t.azimuth) for t in tug.status().thrusters)
    table = yaml.safe_load(open(tug_file))["hull"]["resistance"]
    resistance = float(np.interp(u, table["speed"], table["force"]))
    assert result.normal_force == pytest.approx(thrust - resistance, rel=0.02)   # measured 0.02 %
    assert result.penetration == pytest.approx(result.normal_force / spec.stiffness, rel=0.01)
    assert result.friction_force < 1e-3 * result.normal_force                    # no sliding beam-on
