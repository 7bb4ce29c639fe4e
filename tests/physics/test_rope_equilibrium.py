"""RopeChain.settle: the rope laid in static equilibrium for its ends' positions and velocities
before step 0 (the scenario key ropes[].equilibrium). Truths computed here: Irvine's elastic
catenary for a rope hanging in air, Hooke's law along the chord for a towline pulled nearly
straight (EA (chord / L - 1)), and the steady state itself (a settled rope whose ends go on at
the velocity it was settled for must not change)."""
import math
import os
import sys

import numpy as np
import pytest
from scipy.optimize import brentq

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "ros_ws", "src", "rope_model"))

from rope_model import RopeChain, default_rope_path, load_rope_params  # noqa: E402

TABLE1 = load_rope_params(default_rope_path())
U5 = 2.5722  # 5 kn


def irvine_horizontal_tension(L0, w, EA, span):
    """Horizontal tension of an elastic catenary, ends at equal height (Irvine)."""
    Va = 0.5 * w * L0

    def x_end(H):
        return H * L0 / EA + H / w * (math.asinh(Va / H) - math.asinh(-Va / H))

    return brentq(lambda H: x_end(H) - span, 1e-3, 1e9, xtol=1e-10)


def test_settled_in_air_is_the_elastic_catenary():
    """Laid straight and 2 % short of its length apart, high in the air, both ends at rest:
    settle() reaches the catenary, mid-span tension = Irvine's H, and resets the clock."""
    span = 0.98 * TABLE1.length
    rope = RopeChain.slack(TABLE1, (0, 0, 100), (span, 0, 100), n_elements=41)
    t_settle = rope.settle()
    assert 0.0 < t_settle < rope.SETTLE_MAX_TIME
    assert rope.time == 0.0 and rope.step_count == 0 and not rope.events
    assert np.abs(rope.velocities).max() < 1e-3
    H = irvine_horizontal_tension(TABLE1.length, TABLE1.mass_per_length * TABLE1.gravity, TABLE1.ea, span)
    assert rope.tensions[20] == pytest.approx(H, rel=0.01)


def _tow(span, settle=True, speed=U5):
    """Table 1 rope between a tug bollard (2 m up) and a barge bow bollard (1 m up) span m
    astern, both moving ahead at speed in still water."""
    a, b = np.array([0.0, 0.0, 2.0]), np.array([-span, 0.0, 1.0])
    rope = RopeChain.straight(TABLE1, a, b)
    if settle:
        rope.settle((speed, 0, 0), (speed, 0, 0))
    return rope, a, b


def _run_on(rope, a, b, seconds, speed=U5, dt=0.02):
    """Ends carried on at speed; returns the end-b tension at every step."""
    v = np.array([speed, 0.0, 0.0])
    out = []
    for k in range(int(round(seconds / dt))):
        rope.set_end_kinematics("a", a + v * k * dt, v)
        rope.set_end_kinematics("b", b + v * k * dt, v)
        rope.step(dt)
        out.append(np.linalg.norm(rope.end_force("b")))
    return np.array(out)


def test_settled_towline_is_hookes_law_along_the_chord():
    """A towline pulled to ~40 kN is nearly straight: its tension is EA (chord / L - 1) within
    1 % (its sag and its own drag are small against that)."""
    span = 103.85
    rope, a, b = _tow(span)
    chord = float(np.linalg.norm(a - b))
    hooke = TABLE1.ea * (chord / TABLE1.length - 1.0)
    assert hooke == pytest.approx(40.3e3, rel=0.01)  # the seed 000 barge's resistance at 5 kn
    assert np.linalg.norm(rope.end_force("b")) == pytest.approx(hooke, rel=0.01)
    assert np.linalg.norm(rope.end_force("a")) == pytest.approx(hooke, rel=0.01)


def test_settled_towline_stays_in_its_steady_state():
    """Settled for ends moving at 5 kn and carried on at 5 kn: the tension stays within 0.5 % of
    its start for 20 s (settle hands the rope the ends' velocity). Laid straight and not settled,
    the same rope starts far from it (the start-up load the settle phase removes)."""
    span = 103.85
    rope, a, b = _tow(span)
    T0 = np.linalg.norm(rope.end_force("b"))
    T = _run_on(rope, a, b, 20.0)
    assert np.abs(T - T0).max() < 0.005 * T0
    raw, a, b = _tow(span, settle=False)
    T_raw = _run_on(raw, a, b, 20.0)
    assert np.abs(T_raw - T0).max() > 0.05 * T0


def test_settling_in_a_current_is_settling_with_moving_ends():
    """Galilean: ends moving at U in still water settle to the same shape and tensions as ends
    at rest in a current -U."""
    span = 101.0
    moving, _, _ = _tow(span, speed=U5)
    still = RopeChain.straight(TABLE1, (0.0, 0.0, 2.0), (-span, 0.0, 1.0), current=(-U5, 0.0, 0.0))
    still.settle()
    np.testing.assert_allclose(moving.tensions, still.tensions, rtol=1e-6, atol=1.0)
    np.testing.assert_allclose(moving.positions, still.positions, atol=1e-6)
    # the settled moving rope carries the ends' velocity, the one in the current is at rest
    np.testing.assert_allclose(moving.velocities, np.tile([U5, 0.0, 0.0], (len(moving.lengths), 1)), atol=1e-12)
    assert np.abs(still.velocities).max() < 1e-12
    assert still.current[0] == -U5  # the real current is given back


def test_settle_refuses_what_has_no_equilibrium():
    rope = RopeChain.wound_on_winch(TABLE1, (0, 0, 2), (-30, 0, 1), deployed_length=40.0)
    rope.set_payout_rate(1.0)
    with pytest.raises(ValueError, match="winch must be stopped"):
        rope.settle()
