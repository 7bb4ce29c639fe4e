"""A hull in the sea (tug_dynamics.seakeeping, issue 31 item 2): the compiled response against
its numpy oracle, the superposition's kinematics against small-angle hand kinematics, the drift
wrench against the total-reflection closed form, and a free barge drifting down-wave. No ROS."""
import math
import os

import numpy as np
import pytest

from sea_environment.waves import G, WaveField
from tug_dynamics.seakeeping import VesselInWaves, hydro_data_path
from tug_dynamics.ship_file import load_ship, ships_dir
from tug_dynamics.vessel import BodyPoints, VesselState

RHO = 1025.0


def _ship(name):
    return os.path.join(ships_dir(), name + ".yaml")


def _sea(ship, field):
    return VesselInWaves.for_ship(_ship(ship), field)


@pytest.mark.parametrize("t", [5.0, 80.0])   # inside the ramp (r' != 0) and after it
def test_compiled_response_equals_its_numpy_oracle(t):
    field = WaveField.irregular(2.5, 8.0, 0.3, spreading_s=10.0, components=180, seed=7, ramp_time=30.0)
    resp = _sea("harbour_tug", field).response
    for x, y, psi, u in ((0.0, 0.0, 0.0, 0.0), (120.0, -40.0, 2.5, 3.0), (-300.0, 55.0, -1.2, -0.5)):
        fast, ref = resp.evaluate(x, y, psi, u, t), resp.evaluate_numpy(x, y, psi, u, t)
        for a, b in zip(fast, ref):
            np.testing.assert_allclose(a, b, rtol=1e-11, atol=1e-13)
        assert fast.elevation == pytest.approx(float(field.elevation(x, y, t)), rel=1e-11, abs=1e-12)



def test_compiled_response_follows_a_turning_hull_through_every_heading_cell():
    """The compiled response keeps each component's two table rows until its heading cell
    changes (wave_response._evaluate's working rows): a hull turning a full circle one way and
    back, in steps smaller and larger than a cell and across 0 / 2 pi, against the numpy
    oracle, which gathers from the table every time."""
    field = WaveField.irregular(2.0, 7.0, 0.3, spreading_s=10.0, components=150, seed=11, ramp_time=0.0)
    resp = _sea("harbour_tug", field).response
    cell = 2.0 * math.pi / resp.table.shape[1]
    psis = np.concatenate([np.arange(0.0, 2.0 * math.pi + cell, 0.3 * cell),
                           np.arange(2.0 * math.pi, -2.0 * math.pi, -1.7 * cell), [1e-15, -1e-15, 0.5 * cell]])
    for n, psi in enumerate(psis):
        t = 0.05 * n
        fast, ref = resp.evaluate(10.0, -3.0, float(psi), 2.0, t), resp.evaluate_numpy(10.0, -3.0, float(psi), 2.0, t)
        for a, b in zip(fast, ref):
            np.testing.assert_allclose(a, b, rtol=1e-11, atol=1e-12)

def test_one_compiled_step_equals_its_numpy_steps():
    """VesselInWaves.step (the vessel node's per-step path, one compiled call) against sample,
    total, point_offsets, drift_wrench and status in numpy, and BodyPoints.world of the total
    state: 1e-12 relative, in a moving, heeled, turning state inside and after the ramp."""
    field = WaveField.irregular(2.0, 7.0, 0.4, spreading_s=8.0, components=150, seed=3, ramp_time=20.0)
    sea = _sea("harbour_tug", field)
    points = BodyPoints([[-10.0, 0.0, 2.0], [12.0, 3.0, 1.5], [0.0, -4.0, 0.5]])
    low = VesselState(np.array([35.0, -12.0, 0.1]), np.array([0.03, -0.02, 2.2]), np.array([2.5, 0.3, 0.01]),
                      np.array([0.01, -0.02, 0.03]))
    for t in (7.5, 95.0):
        fast = sea.step(low, t, points)
        sample = sea.sample(low, t)
        total = sea.total(low, sample)
        for a, b in zip((fast.total.position, fast.total.rpy, fast.total.linear_velocity_body,
                         fast.total.angular_velocity_body),
                        (total.position, total.rpy, total.linear_velocity_body, total.angular_velocity_body)):
            np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12)
        p, v = points.world(total)
        np.testing.assert_allclose(fast.positions, p, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(fast.velocities, v, rtol=1e-12, atol=1e-12)
        dp, dv = sea.point_offsets(low, total, points)
        np.testing.assert_allclose(fast.offsets[0], dp, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(fast.offsets[1], dv, rtol=1e-9, atol=1e-12)
        drift = sea.drift_wrench(low, sample)
        np.testing.assert_allclose(fast.drift.force_world, drift.force_world, rtol=1e-12, atol=1e-9)
        np.testing.assert_allclose(fast.drift.moment_world, drift.moment_world, rtol=1e-12, atol=1e-9)
        status = sea.status(low, sample)
        np.testing.assert_allclose(fast.sea_floats, [status.wave_elevation, status.wave_significant_height,
                                                     status.wave_encounter_period, status.wave_encounter_angle,
                                                     status.heave, status.roll, status.pitch], rtol=1e-12, atol=1e-12)


def test_attachment_points_move_with_heave_roll_and_pitch():
    """Small angles: a point (x, y, z) of the body rises by heave + y roll - x pitch (REP-103: roll
    positive starboard down, pitch positive bow down) and moves along by surge - z pitch...; the
    wave-frequency offsets of the published points equal that to second order in the angles."""
    field = WaveField.regular(1.5, 7.0, direction=math.radians(200.0))
    sea = _sea("harbour_tug", field)
    low = VesselState.at_rest(10.0, -5.0, math.radians(30.0))
    points = np.array([[12.0, 0.0, 2.0], [-14.0, 3.5, 1.5], [0.0, -4.0, 0.5]])
    for t in np.linspace(0.0, 14.0, 15):
        sample = sea.sample(low, t)
        d = sample.displacement
        dp, _ = sea.point_offsets(low, sea.total(low, sample), BodyPoints(points))
        c, s = math.cos(low.rpy[2]), math.sin(low.rpy[2])
        for (x, y, z), off in zip(points, dp):
            # body-frame small-angle offset: translation + rotation x r
            body = d[:3] + np.cross(d[3:], [x, y, z])
            world = np.array([c * body[0] - s * body[1], s * body[0] + c * body[1], body[2]])
            assert off[2] == pytest.approx(d[2] + y * d[3] - x * d[4], abs=0.02 + 20 * max(abs(d[3]), abs(d[4])) ** 2)
            angle = max(abs(d[3]), abs(d[4]), abs(d[5]))
            assert np.max(np.abs(off - world)) < 1e-3 + 20.0 * angle ** 2   # |r| angle^2 / 2 and more
    assert np.ptp([sea.sample(low, t).displacement[2] for t in np.linspace(0, 7, 29)]) > 0.5  # it does heave


def test_drift_wrench_in_short_beam_waves_is_the_total_reflection_force():
    """Short regular waves on the beam of the 45 m barge: the mean drift pushes it along the
    waves' travel with 1/2 rho g a^2 L (Faltinsen 1990 ch. 5, a wall-sided hull reflecting all),
    within 10 % (the data's own check is in test_wave_response); world axes, at any heading."""
    a, period = 0.5, 2.0 * math.pi / 2.4
    for heading in (0.0, 1.0, -2.2):
        travel = heading + math.pi / 2.0   # waves running to port of the bow
        sea = _sea("barge_002_full", WaveField.regular(2 * a, period, direction=travel))
        low = VesselState.at_rest(0.0, 0.0, heading)
        w = sea.drift_wrench(low, sea.sample(low, 100.0))
        along = w.force_world @ [math.cos(travel), math.sin(travel), 0.0]
        closed = 0.5 * RHO * G * a * a * 45.0
        assert 0.9 * closed < along < 1.02 * closed, (along, closed)
        across = w.force_world @ [-math.sin(travel), math.cos(travel), 0.0]
        assert abs(across) < 0.05 * closed


def test_a_free_barge_drifts_down_wave_and_a_calm_sea_adds_nothing():
    """The barge at rest in beam seas, stepped with the drift wrench: it moves down-wave (the
    drift's direction; its hull's sway-yaw coupling turns it a little as it goes); with no sea
    the same steps leave it at rest."""
    travel = math.pi / 2.0
    sea = _sea("barge_002_full", WaveField.regular(3.0, 5.0, direction=travel))
    barge = load_ship(_ship("barge_002_full"))
    still = load_ship(_ship("barge_002_full"))
    t = 0.0
    for _ in range(600):
        barge.step(0.1, [sea.drift_wrench(barge.state, sea.sample(barge.state, t))])
        still.step(0.1, [])
        t += 0.1
    assert barge.state.position[1] > 1.0 and abs(barge.state.position[0]) < 0.5 * barge.state.position[1]
    assert np.all(still.state.position == 0.0)


def test_hydro_data_sits_beside_the_ship_file():
    assert hydro_data_path(_ship("asd_tug")) == os.path.join(ships_dir(), "hydro", "asd_tug.npz")
    assert os.path.isfile(hydro_data_path(_ship("s175_003")))


def test_a_sea_alone_needs_no_environment_sampler_and_loses_nothing_without_it():
    """A sea with no wind, depth or current gives a hull's environment sampler nothing to carry
    (the vessel node then attaches none); stepping the S-175 with the still, deep sampler and
    without it, under the same wrenches and orders, gives the same state to rounding."""
    from sea_environment.environment import Environment
    from tug_dynamics.environment_loads import VesselInEnvironment
    from tug_dynamics.vessel import Command, ExternalWrench
    waves = {"hs": 2.0, "tp": 7.0, "from_deg": 90.0}
    assert not Environment.from_mapping({"waves": waves}).acts_on_hulls
    assert Environment.from_mapping({"waves": waves, "current": [0.3, 0.0]}).acts_on_hulls
    assert Environment.from_mapping({"waves": waves, "depth": 30.0}).acts_on_hulls
    assert Environment.from_mapping({"waves": waves, "wind": {"speed_kn": 10.0, "from_deg": 0.0}}).acts_on_hulls
    at_9_knots = VesselState(np.zeros(3), np.zeros(3), np.array([9.0 * 1852.0 / 3600.0, 0.0, 0.0]), np.zeros(3))
    ships = [load_ship(_ship("s175_003"), initial_state=at_9_knots) for _ in range(2)]
    VesselInEnvironment(ships[0], Environment.from_mapping({"waves": waves}))
    for ship in ships:
        ship.set_command(Command(engine_order=0.5, steering_angle=math.radians(20.0)))
    pull = ExternalWrench(force_world=np.array([-2e5, 1e5, 0.0]), point_body=np.array([80.0, 0.0, 5.0]),
                          moment_world=np.zeros(3))
    for _ in range(500):
        for ship in ships:
            ship.step(0.1, [pull])
    a, b = ships[0].state, ships[1].state
    assert np.linalg.norm(a.position) > 100.0 and abs(a.rpy[2]) > 0.2   # it went somewhere, turning
    for x, y in [(a.position, b.position), (a.rpy, b.rpy), (a.linear_velocity_body, b.linear_velocity_body),
                 (a.angular_velocity_body, b.angular_velocity_body)]:
        np.testing.assert_allclose(x, y, rtol=1e-12, atol=1e-9)
