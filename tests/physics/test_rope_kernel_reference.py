"""The compiled rope kernel (kernels.run_substeps) against its plain numpy transcription
(kernels_reference.run_substeps: dense system, numpy.linalg.solve, no numba) on realistic
rope states: a catenary hanging at rest (also with the settling relaxation on), a rope in
tow across a current lying partly on the water, a rope falling onto the water (water
entry), a pay-out from the winch in progress and a rope parting. (The model has no seabed.)

Agreement is measured per quantity as its largest difference over its largest magnitude,
or over a floor far below physical significance (1 mm/s, 1 mrad/s, 1 N) where the quantity
itself is round-off noise (a rope falling flat does not rotate, a slack rope carries
1e-12 N). One sub-step agrees to 1e-11, the velocity change dnu of the solve included
(measured: at most 2e-12; the net force on an element is the small difference of its end
tensions, which the two codes sum in a different order); 200-300 sub-steps through
RopeChain (winch and parting logic included) agree to 1e-9 (measured: at most 5e-11)."""
import copy
import math
import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "ros_ws", "src", "rope_model"))

from rope_model import KNOT, RopeChain, default_rope_path, load_rope_params  # noqa: E402
from rope_model import kernels as K  # noqa: E402
from rope_model import kernels_reference as R  # noqa: E402

TABLE1 = load_rope_params(default_rope_path())
ONE_STEP_RTOL = 1e-11
MANY_STEPS_RTOL = 1e-9
# magnitudes below which a quantity is round-off noise: m, -, m/s, rad/s, m, N
FLOOR = {"X": 1.0, "E": 1.0, "V": 1e-3, "W": 1e-3, "L": 1.0, "tensions": 1.0, "force": 1.0,
         "dnu": 1e-6}


def _rel(a, b, floor):
    a, b = np.asarray(a, float), np.asarray(b, float)
    return np.abs(a - b).max(initial=0.0) / max(np.abs(a).max(initial=0.0), floor)


def _tow(rope):
    """Tug at 2 m/s with a 10 m, 50 s sway (section 4.5)."""
    t = rope.time
    w = 2 * math.pi / 50
    rope.set_end_kinematics("a", (2.0 * t, 10.0 * math.sin(w * t), 2.0),
                            (2.0, 10.0 * w * math.cos(w * t), 0.0))


def _payout(rope):
    """Tug running away at 5 kn from the barge, paying out at 5 kn (section 4.6)."""
    rope.set_end_kinematics("a", (5 * KNOT * rope.time, 0.0, 2.0), (5 * KNOT, 0.0, 0.0))


def catenary_at_rest():
    return RopeChain.slack(TABLE1, (0, 0, 100), (90, 0, 100), n_elements=11), None


def catenary_settling():  # numerical relaxation on (its terms are in the kernel too)
    return RopeChain.slack(TABLE1, (0, 0, 100), (90, 0, 100), n_elements=11,
                           relaxation=2.0), None


def tow_across_current():
    rope = RopeChain.slack(TABLE1, (0, 0, 2), (90, 0, 1), n_elements=11,
                           current=(0.3, 0.5, 0.0))
    for _ in range(150):
        _tow(rope)
        rope.step(0.02)
    return rope, _tow


def _entering_water(rope):
    """Elements entering the water: the water-entry term of Eq (14) is on."""
    return [R.immersion(x[2], e[2], 0.5 * l, TABLE1.radius)[1] * v[2] > 0
            for x, e, l, v in zip(rope.X, rope.E, rope.L, rope.V)]


def falling_onto_water():
    rope = RopeChain.straight(TABLE1, (0, 0, 1), (100, 0, 1), n_elements=11, end_a="free",
                              end_b="free")
    while not any(_entering_water(rope)):  # falls 1 m in 0.45 s
        rope.step(0.005)
    return rope, None


def payout_in_progress():
    rope = RopeChain.wound_on_winch(TABLE1, (0, 0, 2), (0, 0, 1), n_elements=11)
    rope.set_end_kinematics("b", (0, 0, 1), (0, 0, 0))
    rope.set_payout_rate(5 * KNOT)
    for _ in range(100):
        _payout(rope)
        rope.step(0.02)
    return rope, _payout


STATES = [catenary_at_rest, catenary_settling, tow_across_current, falling_onto_water,
          payout_in_progress]


def _inputs(rope):
    rope._pack()
    return rope._S.copy(), rope._F.copy(), rope._io.copy()


@pytest.mark.parametrize("make", STATES, ids=[f.__name__ for f in STATES])
def test_one_substep_matches_reference(make):
    rope, _ = make()
    S, F, io = _inputs(rope)
    n = S.shape[0] - 1
    payout = rope.payout_rate if rope.winch else 0.0
    h = 0.01
    S1, F1, io1 = S.copy(), F.copy(), io.copy()
    ws = K.new_workspace(n)
    st_k = K.run_substeps(S1, F1, io1, ws, h, 1, payout, 0.0)
    S2, F2, io2 = S.copy(), F.copy(), io.copy()
    st_r, dnu = R.run_substeps(S2, F2, io2, h, 1, payout, 0.0)
    assert st_k == st_r == K.OK
    assert np.array_equal(F1, F2)
    dnu_k = ws[3, :n, 1, :].ravel()
    checks = {"dnu": (dnu_k, dnu),
              "X": (S1[:n, K.SX:K.SX + 3] - S[:n, K.SX:K.SX + 3],  # its change
                    S2[:n, K.SX:K.SX + 3] - S[:n, K.SX:K.SX + 3]),
              "E": (S1[:n, K.SE:K.SE + 3], S2[:n, K.SE:K.SE + 3]),
              "V": (S1[:n, K.SV:K.SV + 3], S2[:n, K.SV:K.SV + 3]),
              "W": (S1[:n, K.SW:K.SW + 3], S2[:n, K.SW:K.SW + 3]),
              "tensions": (S1[:, K.ST], S2[:, K.ST]),
              "force": (io1[K.IO_FORCE:K.IO_MEAN], io2[K.IO_FORCE:K.IO_MEAN])}
    for name, (a, b) in checks.items():
        err = _rel(a, b, 1e-12 if name == "X" else FLOOR[name])
        assert err <= ONE_STEP_RTOL, f"{name}: {err:.2e}"
    assert np.abs(dnu_k).max() > 0.0


def _reference_kernel(S, F, io, ws, h, n_sub, payout_a, dt):
    return R.run_substeps(S, F, io, h, n_sub, payout_a, dt)[0]


def _compare_runs(rope, drive, steps, dt, monkeypatch):
    """Steps a copy of the rope with the reference kernel, the original with the compiled
    one; returns the largest relative differences over the run."""
    ref = copy.deepcopy(rope)
    worst = {}
    for _ in range(steps):
        for r, kernel in ((rope, None), (ref, _reference_kernel)):
            if drive is not None:
                drive(r)
            with monkeypatch.context() as m:
                if kernel is not None:
                    m.setattr(K, "run_substeps", kernel)
                r.step(dt)
        assert rope.n_elements == ref.n_elements
        assert [(e.connection, e.time) for e in rope.events] == [
            (e.connection, e.time) for e in ref.events]
        for name in ("X", "E", "V", "W", "L", "tensions"):
            err = _rel(getattr(rope, name), getattr(ref, name), FLOOR[name])
            worst[name] = max(worst.get(name, 0.0), err)
        for end in "ab":
            err = _rel(rope.mean_end_force(end), ref.mean_end_force(end), FLOOR["force"])
            worst["end force"] = max(worst.get("end force", 0.0), err)
    return worst


@pytest.mark.parametrize("make, steps", [(tow_across_current, 150), (payout_in_progress, 150),
                                         (falling_onto_water, 150)],
                         ids=["tow_across_current", "payout_in_progress", "falling_onto_water"])
def test_hundreds_of_substeps_match_reference(make, steps, monkeypatch):
    """300 sub-steps (150 exchange steps of 0.02 s, 2 sub-steps each) through RopeChain."""
    rope, drive = make()
    n0 = rope.n_elements
    worst = _compare_runs(rope, drive, steps, 0.02, monkeypatch)
    assert max(worst.values()) <= MANY_STEPS_RTOL, worst
    if make is payout_in_progress:
        assert rope.n_elements > n0  # a link was inserted at the winch


def test_parting_matches_reference(monkeypatch):
    """A free rope stretched apart (sub-step 1 ms) parts at the same connection and time."""
    p = TABLE1.replace(gravity=0.0, breaking_load=12000.0, axial_stiffness=TABLE1.ea,
                       drag_normal=0.0, drag_tangential=0.0)
    rope = RopeChain.straight(p, (0, 0, 100), (100, 0, 100), n_elements=20, end_a="free",
                              end_b="free", max_substep=0.001)
    rope.V[:, 0] = 0.3 * (rope.positions[:, 0] - 50.0)
    for _ in range(25):
        rope.step(0.001)
    assert not rope.events  # it parts at 33 ms
    worst = _compare_runs(rope, None, 200, 0.001, monkeypatch)
    assert rope.events, "the rope did not part"
    assert max(worst.values()) <= MANY_STEPS_RTOL, worst
