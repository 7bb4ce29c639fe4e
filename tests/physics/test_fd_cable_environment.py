"""The fd cable in the scenario environment (issue 18), through the rope adapter the rope node
uses (rope_model.models.CableAdapter.set_environment).

Truths: Galilean invariance and the analytic critical angle of a towed cable (Park & Jung's
steady tow, test_fd_cable.critical_angle_tow): a cable hanging from a fixed point, with a current
switched on through set_environment, settles to the steady state of the same cable towed through
still water at the current's speed; a uniform current sampled at every node each step changes
nothing; a node below the seabed stops the run naming the node."""
import math
import os

import numpy as np
import pytest

from rope_model.models import CableAdapter, CableOnSeabedError, ModelFailure
from test_fd_cable import CABLE, critical_angle_tow

ROPES = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "ros_ws", "src", "rope_model", "ropes")
PATH = os.path.join(ROPES, "cable_001.yaml")


def _adapter(current, velocity=(0.0, 0.0, 0.0)):
    return CableAdapter(PATH, "straight", (0.0, 0.0, 0.0), None, end_a="fixed", end_b="free", current=current,
                        n_elements=None, deployed_length=None, max_substep=0.0, velocity_a=velocity)


def test_a_current_switched_on_settles_to_the_towed_steady_state():
    U = 1.0
    cable = _adapter((0.0, 0.0, 0.0))
    n = len(cable.element_centres())
    for _ in range(int(400.0 / 0.5)):
        cable.set_environment(current=np.tile([-U, 0.0, 0.0], (n, 1)))
        cable.step(0.5)
    p = CABLE
    angle, _, top = critical_angle_tow(p.weight_in_water, p.water_density, p.diameter, p.drag_normal,
                                       p.drag_tangential, U, p.length)
    assert np.linalg.norm(cable.end_force("a", averaged=False)) == pytest.approx(top, rel=0.02)
    d = cable.cable.positions[-1] - cable.cable.positions[0]
    assert d[0] < 0 and abs(d[1]) < 1e-6 * abs(d[0])               # trails downstream (-x)
    assert math.atan2(-d[2], abs(d[0])) == pytest.approx(angle, abs=math.radians(1.0))


def test_a_uniform_current_sampled_at_every_node_changes_nothing():
    current = np.array([0.3, -0.8, 0.0])
    plain, sampled = _adapter(current, (1.0, 0.0, 0.0)), _adapter(current, (1.0, 0.0, 0.0))
    for k in range(1, 21):
        for c in (plain, sampled):
            c.set_end("a", (0.5 * k, 0.0, 0.0), (1.0, 0.0, 0.0))
        sampled.set_environment(current=np.tile(current, (len(sampled.element_centres()), 1)))
        plain.step(0.5)
        sampled.step(0.5)
    # to rounding: the cable takes the mean of the sampled currents, and the mean of equal
    # numbers need not be that number to the last bit
    np.testing.assert_allclose(sampled.cable.positions, plain.cable.positions, rtol=0, atol=1e-9)


def test_a_sheared_current_acts_as_its_mean_and_the_seabed_stops_the_run():
    cable = _adapter((0.0, 0.0, 0.0))
    n = len(cable.element_centres())
    field = np.column_stack((np.linspace(-1.0, 0.0, n), np.zeros(n), np.zeros(n)))
    cable.set_environment(current=field)
    np.testing.assert_allclose(cable.cable.current, [-0.5, 0.0, 0.0])
    deepest = float(-cable.cable.positions[:, 2].max() + -cable.cable.positions[:, 2].min()) / 2
    with pytest.raises(CableOnSeabedError, match=r"node \d+ .* below the seabed") as err:
        cable.set_environment(seabed_depth=np.full(n, deepest))
    assert isinstance(err.value, ModelFailure)
    cable.set_environment(seabed_depth=np.full(n, 1e4))   # deep enough: nothing happens
