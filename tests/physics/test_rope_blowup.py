"""Numerical blow-up is never reported as physics, a genuine overload still parts,
and winch orders are clamped to the rope file's limits (reported to the caller)."""
import math
import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "ros_ws", "src", "rope_model"))

from rope_model import (RopeChain, RopeDivergedError, RopeParams, RopeParamsError,  # noqa: E402
                        default_rope_path, load_rope_params)
from rope_model.models import ChainAdapter  # noqa: E402

TABLE1 = load_rope_params(default_rope_path())


def test_ea_1e12_file_is_refused(tmp_path):
    text = open(default_rope_path()).read().replace("axial_stiffness: null", "axial_stiffness: 1.0e+12")
    f = tmp_path / "stiff.yaml"
    f.write_text(text)
    with pytest.raises(RopeParamsError, match=r"^stiff\.yaml: key 'axial_stiffness': expected a number "
                                              r"in \[1000, 1e\+10\] N or null, got 1000000000000\.0$"):
        load_rope_params(f)


def test_ea_1e12_straight_layout_is_a_layout_error_not_a_parting():
    """The old 'parts at t = 0 at 49,999 kN' was no instability: laid straight between ends
    100.005 m apart, 100 m of rope is stretched 5e-5, i.e. EA x 5e-5 = 50 MN with EA 1e12 N.
    Bypassing the file check (RopeParams directly) this start is refused as bad input."""
    p = RopeParams(axial_stiffness=1.0e12)
    span = math.hypot(100.0, 1.0)
    expect_kn = 1.0e12 * (span - 100.0) / 100.0 / 1e3  # independent: Hooke on the whole rope
    with pytest.raises(ValueError, match="initial layout overloads connection") as ei:
        RopeChain.straight(p, (0, 0, 2), (100, 0, 1))
    got_kn = float(ei.value.args[0].split("tension ")[1].split(" kN")[0])
    assert got_kn == pytest.approx(expect_kn, rel=0.01)


def test_ea_1e12_hanging_rope_is_stable():
    """A-stable implicit integrator: the stiffness alone does not blow up (README, stability)."""
    p = RopeParams(axial_stiffness=1.0e12)
    rope = RopeChain.wound_on_winch(p, (0, 0, 2), (60, 0, 1), deployed_length=62.0)
    for _ in range(50):
        rope.step(0.02)
    assert not rope.events and np.all(np.isfinite(rope.positions))


def test_unclamped_heave_in_of_1e6_m_s_is_a_divergence_not_a_parting():
    """Bypassing the winch limit (RopeParams.replace is the programmatic, unchecked-range
    path): a drum heaving in at 1e6 m/s used to 'part at 1,899,697 kN', the axial damper
    driven at 1e6 m/s with no strain in the rope. Now: RopeDivergedError naming the step and
    the drum connection, no event, the rope keeps its last good state."""
    p = TABLE1.replace(winch_max_heave_speed=1.0e7)
    rope = RopeChain.wound_on_winch(p, (0, 0, 2), (60, 0, 1), deployed_length=62.0)
    rope.step(0.02)
    before = (rope.positions.copy(), rope.lengths.copy(), rope.time)
    assert rope.set_payout_rate(-1.0e6) == []  # within this rope's (absurd) limit
    with pytest.raises(RopeDivergedError) as ei:
        rope.step(0.02)
    err = ei.value
    assert err.step == 2 and err.connection == 0
    assert "exchange step 2" in str(err) and "connection 0" in str(err) and "not a parting" in str(err)
    assert not rope.events
    assert np.array_equal(rope.positions, before[0]) and np.array_equal(rope.lengths, before[1])
    assert rope.time == before[2]


def test_integrator_instability_is_a_divergence_not_a_parting():
    """theta = 0.5 (no numerical damping) with N = 50, EA x 10 and 10 ms sub-steps is outside
    the stability map (README): the unresolved modes grow until the tension reaches the
    breaking load with the rope's strain far below it. That must end as RopeDivergedError,
    never as a PartingEvent (the default theta 0.55 is stable here)."""
    p = TABLE1.replace(axial_stiffness=10.0 * TABLE1.ea, tangential_area_factor=math.pi)
    rope = RopeChain.straight(p, (0, 0, -50), (100, 0, -50), n_elements=50, relaxation=2.0,
                              max_substep=0.02)
    for _ in range(1000):  # settle to the static shape
        rope.step(0.02)
    rope.relaxation = 0.0
    rope.V[:] = 0.0
    rope.W[:] = 0.0
    rope.theta = 0.5
    rope.max_substep = 0.01
    t = 0.0
    with pytest.raises(RopeDivergedError) as ei:
        for _ in range(3000):  # 60 s; it blows up after about 10 s
            x = 98.0 + 2.0 * math.cos(2 * math.pi * t / 10.0)
            v = -0.4 * math.pi * math.sin(2 * math.pi * t / 10.0)
            rope.set_end_kinematics("b", (x, 0, -50), (v, 0, 0))
            rope.step(0.02)
            t += 0.02
    assert not rope.events
    assert "exchange step" in str(ei.value) and ei.value.step > 0


def test_genuine_overload_parts_at_the_breaking_load():
    """Table 1 rope between a fixed barge bollard and a tug pulling away at 0.5 m/s: a real
    parting. Independent truth from the file: it parts at the breaking load (16 tf), within
    1 % (the tension rises by EA v / L = 5.2 kN/s, 52 N per 10 ms sub-step, 0.03 %), and at
    the elongation at break (15 %, Table 1): span 115 m within 1 m (the catenary sag under
    16 tf shortens the chord by millimetres)."""
    p = TABLE1
    rope = RopeChain.straight(p, (0, 0, 2), (100, 0, 2), n_elements=11)
    v = 0.5
    t = 0.0
    while not rope.events and t < 60.0:
        rope.set_end_kinematics("a", (-v * t, 0, 2), (-v, 0, 0))
        rope.step(0.02)
        t += 0.02
    assert rope.events, "the rope did not part"
    ev = rope.events[0]
    assert ev.tension == pytest.approx(p.breaking_load, rel=0.01)
    span = 100.0 + v * ev.time
    assert span == pytest.approx(p.length * (1.0 + p.elongation_at_break), abs=1.0)
    rope.step(0.02)  # the pieces go on
    assert np.all(np.isfinite(rope.positions))


# ------------------------------------------------------------------ winch limits
def test_payout_orders_are_clamped_and_reported():
    p = TABLE1
    rope = RopeChain.wound_on_winch(p, (0, 0, 2), (30, 0, 1), deployed_length=40.0)
    notes = rope.set_payout_rate(1.0e9)
    assert notes == ["payout_rate 1e+09 m/s clamped to 3 m/s (winch_max_payout_speed)"]
    assert rope.payout_rate == p.winch_max_payout_speed
    l0 = rope.unstretched_length
    for _ in range(50):  # 1 s
        rope.step(0.02)
    # independent truth: limit x time (the rope is far from its length limits)
    assert rope.unstretched_length - l0 == pytest.approx(3.0 * 1.0, rel=1e-9)
    notes = rope.set_payout_rate(-1.0e6)
    assert notes == ["payout_rate -1e+06 m/s clamped to -3 m/s (winch_max_heave_speed)"]
    l1 = rope.unstretched_length
    for _ in range(50):
        rope.step(0.02)
    assert l1 - rope.unstretched_length == pytest.approx(3.0, rel=1e-9)
    assert not rope.events
    assert rope.set_payout_rate(2.5722) == []  # section 4.6 (5 kn) is within the default
    assert rope.set_payout_rate(-3.0) == []  # the limit itself is not clamped
    for bad in (math.nan, math.inf, -math.inf):
        with pytest.raises(ValueError, match="payout rate must be finite"):
            rope.set_payout_rate(bad)
    assert rope.payout_rate == -3.0  # a rejected order changes nothing


def test_adapter_passes_the_clamp_notes_on():
    a = ChainAdapter(default_rope_path(), "winch", (0, 0, 2), (30, 0, 1), end_a="pinned",
                     end_b="pinned", current=(0, 0, 0), n_elements=None, deployed_length=40.0,
                     max_substep=0.0)
    assert a.set_payout_rate(1.0e9) == ["payout_rate 1e+09 m/s clamped to 3 m/s (winch_max_payout_speed)"]
    assert a.set_payout_rate(0.2) == []
    with pytest.raises(ValueError):
        a.set_payout_rate(math.nan)


def test_winch_limits_from_the_file(tmp_path):
    f = tmp_path / "slow_winch.yaml"
    f.write_text(open(default_rope_path()).read() + "winch_max_payout_speed: 1.5\nwinch_max_heave_speed: 0.5\n")
    p = load_rope_params(f)
    rope = RopeChain.wound_on_winch(p, (0, 0, 2), (30, 0, 1), deployed_length=40.0)
    assert rope.set_payout_rate(2.0) == ["payout_rate 2 m/s clamped to 1.5 m/s (winch_max_payout_speed)"]
    assert rope.set_payout_rate(-1.0) == ["payout_rate -1 m/s clamped to -0.5 m/s (winch_max_heave_speed)"]
