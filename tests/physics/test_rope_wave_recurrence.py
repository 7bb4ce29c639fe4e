"""The rope's wave sampling by recurrence (kernels.sample_waves with the rope's wave cache): the
phasors and depth factors of each element advanced from the last exchange step's instead of
evaluated anew. No ROS.

Truth: the direct evaluation, waves.wave_kinematics_wet at each element centre (itself checked
against the numpy WaveField in test_rope_waves.py); the recurrence must give the same sampled
kinematics (the SWV / SWA / SETA columns) within 1e-10 of their scale at every step of a long
run, whatever the rope does (moving ends, a winch paying out links, jumps, deep and dry
elements, a changed sea), and the same run twice must be the same bit for bit.
"""
import math
import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "ros_ws", "src", "rope_model"))

from rope_model import RopeChain, default_rope_path, load_rope_params  # noqa: E402
from rope_model import kernels as K  # noqa: E402
from sea_environment.environment import Environment  # noqa: E402
from sea_environment.sampler import P_TIME, EnvironmentSampler, wave_offset  # noqa: E402
from sea_environment.waves import WaveField, wave_kinematics_wet  # noqa: E402

TABLE1 = load_rope_params(default_rope_path())
SEA = {"hs": 3.0, "tp": 7.0, "from_deg": 300.0, "spreading_s": 6.0, "components": 150, "seed": 11,
       "ramp_time": 5.0}
WAVE_COLS = slice(K.SWV, K.SETA + 1)
# the columns' groups and the scale each is judged against: velocity, acceleration, elevation
GROUPS = ((0, 3), (3, 6), (6, 7))
DT = 0.02


def _direct(S, n_el, env, t):
    """(N, 7) u, v, w, ax, ay, az, eta of wave_kinematics_wet at the element centres of S."""
    at = wave_offset(env)
    scratch = np.empty(2 * K.wave_components(env))
    out = np.empty((n_el, 7))
    for j in range(n_el):
        eta, u, v, w, ax, ay, az = wave_kinematics_wet(env, at, S[j, K.SX], S[j, K.SX + 1], S[j, K.SX + 2],
                                                        t, scratch)
        out[j] = u, v, w, ax, ay, az, eta
    return out


def _ends(t):
    """End a (the winch) and end b moving at about 1 m/s along x, heaving and swaying."""
    xb = 40.0 + t + 0.8 * max(0.0, min(t, 40.0) - 10.0)      # end b runs ahead while paying out
    return ((np.array([t, 0.3 * math.sin(0.2 * t), 1.5 + 0.8 * math.sin(0.9 * t)]),
             np.array([1.0, 0.06 * math.cos(0.2 * t), 0.72 * math.cos(0.9 * t)])),
            (np.array([xb, 2.0 * math.sin(0.1 * t), 1.0 + 0.5 * math.cos(0.7 * t)]),
             np.array([1.0 + (0.8 if 10.0 < t < 40.0 else 0.0), 0.2 * math.cos(0.1 * t), -0.35 * math.sin(0.7 * t)])))


def _towline_run(depth, steps, check=True):
    """Table 1's rope on a winch (45 m out, 5 links) between ends moving as _ends, in a
    150-component sea (cos-2s) with a current; the winch pays out at 1.5 m/s from 10 s to 40 s
    (45 m: five new links). Returns the sampled wave columns per step, the largest deviation
    from the direct evaluation per column group (scaled by the group's largest value) and the
    rope."""
    spec = {"waves": SEA, "current": [0.4, -0.2]}
    if depth is not None:
        spec["depth"] = depth
    env = EnvironmentSampler(Environment.from_mapping(spec)).data
    rope = RopeChain.wound_on_winch(TABLE1, (0.0, 0.0, 1.5), (40.0, 0.0, 1.0), deployed_length=45.0)
    rope.attach_environment(env)
    # room for the 5 links only: the winch's sixth makes the rope allocate a larger cache
    rope._wave_cache = K.new_wave_cache(5, 150)[:K.WC_FIXED + K.WC_ELEM * 5]
    dev, scale, sampled = np.zeros(3), np.zeros(3), []
    for k in range(steps):
        (pa, va), (pb, vb) = _ends(k * DT)
        rope.set_end_kinematics("a", pa, va)
        rope.set_end_kinematics("b", pb, vb)
        if k == 500:
            rope.set_payout_rate(1.5)
        if k == 2000:
            rope.set_payout_rate(0.0)
        S0, n0, t_mid = rope._S.copy(), rope.n_elements, env[P_TIME] + 0.5 * DT
        rope.step(DT)
        got = rope._S[:rope.n_elements, WAVE_COLS].copy()
        sampled.append(got)
        if check and rope.n_elements == n0:      # a link added in the step moves the rows
            ref = _direct(S0, n0, env, t_mid)
            for g, (lo, hi) in enumerate(GROUPS):
                dev[g] = max(dev[g], np.abs(got[:, lo:hi] - ref[:, lo:hi]).max())
                scale[g] = max(scale[g], np.abs(ref[:, lo:hi]).max())
    return sampled, dev / np.where(scale > 0.0, scale, 1.0), rope


@pytest.mark.parametrize("depth", [None, 30.0])
def test_recurrence_samples_what_the_direct_evaluation_does_over_a_long_run(depth):
    """3000 exchange steps (60 s) of a towline in deep water and in 30 m: at every step the
    sampled velocity, acceleration and elevation are the direct evaluation's within 1e-10 of
    their scale (measured 1.2e-14 to 1.7e-14); 99 % of the element steps were advanced (not
    evaluated anew), the winch added links (outgrowing the cache) and the cache was refreshed
    every WAVE_REFRESH steps."""
    _sampled, dev, rope = _towline_run(depth, 3000)
    assert np.all(dev < 1e-10), dev
    head = rope._wave_cache[K.WC_HEADER]
    advanced, direct = head[K.H_ADVANCED], head[K.H_DIRECT]
    assert advanced / (advanced + direct) > 0.9
    assert rope.n_elements == 10          # 45 m paid out: five new links
    assert rope._wave_cache.shape[0] > K.WC_FIXED + K.WC_ELEM * 5
    assert head[K.H_COUNT] > 5 * K.WAVE_REFRESH       # the calls since the larger cache came
    assert not rope.events


def test_two_runs_are_the_same_bit_for_bit():
    a, _, ra = _towline_run(None, 800, check=False)
    b, _, rb = _towline_run(None, 800, check=False)
    assert len(a) == len(b) and all(np.array_equal(x, y) for x, y in zip(a, b))
    assert np.array_equal(ra.X, rb.X) and np.array_equal(ra.tensions, rb.tensions)


def _field_env(sea):
    """A sampler-like array: a zeroed header, then the packed sea where P_WAVE_AT says."""
    from sea_environment.sampler import P_WAVE_AT
    env = np.zeros(P_WAVE_AT + 1)
    env[P_WAVE_AT] = env.size
    return np.concatenate([env, sea.packed])


@pytest.mark.parametrize("depth", [math.inf, 25.0])
def test_every_path_of_the_cache_against_the_direct_evaluation(depth):
    """Points driven through every case of the cache against the direct evaluation each call
    (1e-10 of the scale): drifting (advanced), a jump beyond the Taylor bound, above the
    surface, on the way down past the deepest the cache holds (deep water: 400 m) or below the
    bottom (finite depth), a changed step length, a point added (N changed) and a different sea
    in the same cache."""
    seas = [WaveField.irregular(3.0, 8.0, 0.4, spreading_s=5.0, components=120, seed=s, depth=depth,
                                ramp_time=3.0) for s in (1, 2)]
    envs = [_field_env(s) for s in seas]
    rng = np.random.default_rng(7)
    n = 6
    S = np.zeros((n + 2, K.S_COLS))
    S[:n, K.SX] = np.linspace(-20.0, 30.0, n)
    S[:n, K.SX + 2] = [-3.0, -0.5, 0.0, 2.0, -10.0, -1.0]
    wc = K.new_wave_cache(n + 1, 120)
    t, worst = 0.0, 0.0
    for k in range(1500):
        env = envs[0] if k < 1000 else envs[1]
        m = n + 1 if 600 <= k < 700 else n
        if k == 600:
            S[n, K.SX:K.SX + 3] = [5.0, 5.0, -2.0]
        S[:m, K.SX:K.SX + 2] += rng.normal(0.0, 0.02, (m, 2))
        S[:m, K.SX + 2] += rng.normal(0.0, 0.01, m)
        if k % 97 == 0:
            S[1, K.SX] += 3.0                      # a jump
        S[3, K.SX + 2] = 2.0 + 0.5 * math.sin(0.1 * k)                 # above the surface
        S[4, K.SX + 2] = -10.0 - (390.0 if math.isinf(depth) else 16.0) * (0.5 - 0.5 * math.cos(0.01 * k))
        t += DT if k < 300 or k > 400 else 0.013   # the step changes for a while
        view = S[:m + 1]
        K.sample_waves(view, env, t, wc)
        ref = _direct(view, m, env, t)
        got = view[:m, WAVE_COLS]
        for lo, hi in GROUPS:
            sc = max(np.abs(ref[:, lo:hi]).max(), 1e-300)
            worst = max(worst, np.abs(got[:, lo:hi] - ref[:, lo:hi]).max() / sc)
    assert worst < 1e-10
    head = wc[K.WC_HEADER]
    assert head[K.H_ADVANCED] > 5 * head[K.H_DIRECT]
    assert head[K.H_NCOMP] == 120


def test_a_cache_too_small_falls_back_to_the_direct_evaluation():
    """sample_waves with a cache that has no room (for the elements or the components) samples
    exactly what the direct evaluation gives."""
    env = _field_env(WaveField.irregular(2.0, 7.0, 0.0, components=40, seed=3))
    S = np.zeros((4, K.S_COLS))
    S[:3, K.SX] = [0.0, 10.0, 20.0]
    S[:3, K.SX + 2] = -1.0
    for wc in (K.new_wave_cache(3, 20)[:, :20], np.zeros((1, 1))):
        K.sample_waves(S, env, 12.3, wc)
        assert np.array_equal(S[:3, WAVE_COLS], _direct(S, 3, env, 12.3))
