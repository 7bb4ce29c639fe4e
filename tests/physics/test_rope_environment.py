"""The rope chain in a varying environment (issue 18, rope side): a current and a wind
sampled per element by the caller (RopeChain.set_environment), and the seabed as a contact
surface with friction along and across the rope (MoorDyn's seabed model). No ROS.

Truths (independent of the model's output):
* a floating rope without attachments in a current ends up moving with it: quadratic drag
  decays the relative velocity as v0 / (1 + k v0 t), k = (1/2 rho C_D D f) / (mu + m_a), so
  after t it is below 1 / (k t) whatever v0 (bound computed in the test);
* in a sheared current u = (a y, 0, 0) each element moves with the current at its own
  centre (the field's value there), not with a mean current;
* the first acceleration of a rope at rest in air across a wind W is the air drag over the
  mass, (1/2 rho_a C_D D W^2) / mu (Eq 10-11);
* a cable lying on a flat seabed and pulled slowly along its axis carries the
  friction-limited tension of the closed form dT/ds = mu_axial w (w: submerged weight per
  metre), T(s) = mu w s from the free end, and rests on the seabed with the penetration of
  its contact spring, w / (kbot D).
"""
import math
import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "ros_ws", "src", "rope_model"))

from rope_model import RopeChain, RopeParamsError, default_rope_path, load_rope_params  # noqa: E402
from rope_model.params import SeabedParams  # noqa: E402

TABLE1 = load_rope_params(default_rope_path())
DT = 0.02


def _relative_speed_bound(p, t):
    """1 / (k t): the largest normal relative speed left after t seconds of quadratic drag
    on a floating rope (immersed fraction 0.857 at the Archimedes draft of Table 1, any
    fraction f <= 1 only makes the drag per mass larger than the bound assumes: the bound
    uses the drag of the immersed fraction and the mass with its added mass)."""
    area = math.pi * p.radius ** 2
    f = p.mass_per_length / (p.water_density * area)  # floating: immersed fraction
    k = 0.5 * p.water_density * p.drag_normal * p.diameter * f / (
        p.mass_per_length + p.added_mass_coefficient * p.water_density * area * f)
    return 1.0 / (k * t)


def _archimedes_draft(p):
    """Centre height of a floating circular section: immersed segment fraction = mu / (rho A)
    (bisection on the circle segment area)."""
    f = p.mass_per_length / (p.water_density * math.pi * p.radius ** 2)
    lo, hi = -1.0, 1.0  # z / R
    for _ in range(60):
        zz = 0.5 * (lo + hi)
        frac = (math.acos(zz) - zz * math.sqrt(1.0 - zz * zz)) / math.pi
        lo, hi = (zz, hi) if frac > f else (lo, zz)
    return 0.5 * (lo + hi) * p.radius


def _still_air_factor(p):
    """A floating rope carried by a current U through still air moves at U / (1 + r): water
    drag on the immersed fraction f, rho_w f (U - v)^2, equals air drag on the rest,
    rho_a (1 - f) v^2 (same C_D and D), r = sqrt(rho_a (1 - f) / (rho_w f))."""
    f = p.mass_per_length / (p.water_density * math.pi * p.radius ** 2)
    return 1.0 / (1.0 + math.sqrt(p.air_density * (1.0 - f) / (p.water_density * f)))


def _floating_rope(n=11, along=(0.0, 1.0, 0.0)):
    """Table 1 rope (floats: 878 kg/m^3) laid straight at its draft, ends free."""
    d = np.asarray(along, float)
    z = _archimedes_draft(TABLE1)  # -0.0150 m
    p_a = np.array([0.0, 0.0, z])
    return RopeChain.straight(TABLE1, p_a, p_a + TABLE1.length * d, n_elements=n, end_a="free",
                              end_b="free")


def test_floating_rope_moves_with_a_uniform_current():
    c = np.array([0.5, 0.0, 0.0])  # across the rope (laid along y)
    t_end = 40.0
    ropes = []
    for form in ("uniform", "per element"):
        rope = _floating_rope()
        for _ in range(int(round(t_end / DT))):
            cur = c if form == "uniform" else np.tile(c, (rope.n_elements, 1))
            rope.set_environment(current=cur)
            rope.step(DT)
        ropes.append(rope)
    bound = _relative_speed_bound(TABLE1, t_end)  # 3.3 mm/s
    terminal = _still_air_factor(TABLE1) * c  # the still air above holds it back 7 mm/s
    for rope in ropes:
        V = rope.velocities
        assert np.abs(V[:, :2] - terminal[:2]).max() < bound, V - terminal
        assert np.abs(V[:, 2]).max() < 1e-3  # afloat: no sinking, no lift
    # with the wind blowing along with the current, exactly the current
    rope = _floating_rope()
    for _ in range(int(round(t_end / DT))):
        rope.set_environment(current=c, wind=c)
        rope.step(DT)
    assert np.abs(rope.velocities - c).max() < bound
    # a (3,) current and the same current given per element are one and the same (bit for bit:
    # the (3,) form is broadcast to the elements, then one and the same compiled step runs)
    assert np.array_equal(ropes[0].positions, ropes[1].positions)
    # the uniform form is the old `current` property
    assert np.array_equal(ropes[0].current, c)
    # and it drifted with the current, not just sped up: mean displacement = c t less the
    # start-up lag (the relative speed integrates to at most ln(1 + k v0 t) / k: 20 m here)
    moved = ropes[0].positions[:, 0].mean()
    assert c[0] * t_end - 20.0 < moved < c[0] * t_end


def test_sheared_current_each_element_moves_with_its_own_current():
    a = 0.004  # 1/s: current east = a * north, 0 .. 0.4 m/s along the rope (laid north)
    t_end = 30.0
    rope = _floating_rope(n=21)
    for _ in range(int(round(t_end / DT))):
        y = rope.element_centres()[:, 1]
        cur = np.zeros((rope.n_elements, 3))
        cur[:, 0] = a * y
        rope.set_environment(current=cur)
        rope.step(DT)
    y = rope.element_centres()[:, 1]
    u_local = a * y * _still_air_factor(TABLE1)  # still air: 1.4 % behind (see above)
    V = rope.velocities
    # each element: within the drag relaxation bound (4.4 mm/s at 30 s) plus what the rope's
    # inextensibility forces on it, the shear along its rotated axis (a y sin(a t) < 5 mm/s)
    bound = _relative_speed_bound(TABLE1, t_end) + a * TABLE1.length * math.sin(a * t_end)
    assert np.abs(V[:, 0] - u_local).max() < bound, V[:, 0] - u_local
    # the velocity profile is the field's: slope a within 5 % (a mean current has slope 0)
    slope = np.polyfit(y, V[:, 0], 1)[0]
    assert abs(slope - a * _still_air_factor(TABLE1)) < 0.05 * a, slope


def test_wind_drag_on_a_rope_in_air():
    """First step of a straight rope at rest high in the air, no gravity, wind across it:
    acceleration = air drag / mass. Zero wind gives no motion (today's still air)."""
    p = TABLE1.replace(gravity=0.0)
    W = 15.0  # m/s, north, across the rope (laid east)
    a_true = 0.5 * p.air_density * p.drag_normal * p.diameter * W * W / p.mass_per_length
    for wind, expect in ((np.array([0.0, W, 0.0]), a_true), (None, 0.0)):
        rope = RopeChain.straight(p, (0, 0, 50), (100, 0, 50), n_elements=11, end_a="free",
                                  end_b="free")
        rope.set_environment(wind=wind)
        h = 0.001
        rope.step(h)
        acc = rope.velocities / h
        assert np.allclose(acc[:, 1], expect, rtol=2e-3, atol=1e-9), acc[:, 1]
        assert np.abs(acc[:, [0, 2]]).max() < 1e-6 * max(a_true, 1.0)
    # wind per element: only the elements in the wind are pushed
    rope = RopeChain.straight(p, (0, 0, 50), (100, 0, 50), n_elements=10, end_a="free",
                              end_b="free")
    wind = np.zeros((10, 3))
    wind[5:, 1] = W
    rope.set_environment(wind=wind)
    rope.step(0.001)
    v = rope.velocities[:, 1]
    assert np.all(v[6:] > 0.9 * a_true * 0.001) and np.all(np.abs(v[:4]) < 0.1 * a_true * 0.001)


# ------------------------------------------------------------------ seabed
DEPTH = 20.0
HEAVY = TABLE1.replace(mass_per_length=12.0)  # a sinking line: 6100 kg/m^3 (wire rope)


def _submerged_weight(p):
    return (p.mass_per_length - p.water_density * math.pi * p.radius ** 2) * p.gravity


def test_cable_pulled_along_the_seabed_carries_the_friction_limited_tension():
    p = HEAVY
    sb = p.seabed
    w = _submerged_weight(p)  # 97.9 N/m
    n = 20
    z0 = -DEPTH + p.radius  # lying on the seabed
    rope = RopeChain.straight(p, (0, 0, z0), (p.length, 0, z0), n_elements=n, end_a="pinned",
                              end_b="free")
    rope.set_environment(seabed_depth=DEPTH)
    u = 0.05  # m/s, pull speed (5 x the friction's slip speed: fully sliding)
    t_ramp, t_end = 2.0, 20.0
    x = 0.0
    T_sum = np.zeros(n + 1)
    pen_max = 0.0
    samples = 0
    for k in range(int(round(t_end / DT))):
        t = k * DT
        v = -u * min(1.0, t / t_ramp)  # end a pulled away from the rope (towards -x)
        rope.set_end_kinematics("a", (x, 0.0, z0), (v, 0.0, 0.0))
        rope.set_environment(seabed_depth=DEPTH)
        rope.step(DT)
        x += v * DT
        if t >= 15.0:  # steady sliding: average over the last 5 s
            T_sum += rope.tensions
            samples += 1
            under = -DEPTH - (rope.positions[:, 2] - p.radius)  # penetration of the underside
            pen_max = max(pen_max, float(np.abs(under).max()))
    T = T_sum / samples
    # the whole cable slides with the pull
    assert np.allclose(rope.velocities[:, 0], -u, atol=0.1 * u)
    # closed form T(s) = mu w s, s from the free end b; connection c is at s = L - c l
    s = p.length * (1.0 - np.arange(n + 1) / n)
    T_true = sb.friction_axial * w * s
    inner = slice(1, n)  # connection N (the free end) carries nothing
    err = np.abs(T[inner] - T_true[inner]) / T_true[inner]
    assert err.max() < 0.02, err  # measured 0.15 % (N = 20, 10 ms sub-steps)
    # at the pulled end the whole friction, mu w L, within 3 % (measured -1.1 %)
    assert abs(T[0] - T_true[0]) < 0.03 * T_true[0], (T[0], T_true[0])
    # resting on the seabed: penetration about w / (kbot D) = 0.65 mm, small vs the diameter
    pen_true = w / (sb.stiffness * p.diameter)
    assert pen_max < 2.0 * pen_true + 1e-4 and pen_max < 0.05 * p.diameter, pen_max


def test_cable_on_the_seabed_held_by_friction_below_the_limit():
    """Pulled across the rope (transverse friction) with less than the friction limit the
    cable stays where it is (creeps at most at the slip speed), with more it slides."""
    p = HEAVY.replace(seabed=SeabedParams(friction_axial=0.25, friction_transverse=0.6))
    w = _submerged_weight(p)
    n = 10
    z0 = -DEPTH + p.radius
    limit = p.seabed.friction_transverse * w * p.length  # transverse limit of the whole cable
    moved = []
    for frac in (0.5, 1.5):
        rope = RopeChain.straight(p, (0, 0, z0), (p.length, 0, z0), n_elements=n, end_a="free",
                                  end_b="free")
        rope.set_environment(seabed_depth=DEPTH)
        # a uniform sideways push: a current across the rope whose drag per metre on the
        # rope at rest, 1/2 rho C_D D U^2 (fully immersed), is this fraction of the friction
        q = frac * limit / p.length  # N/m across the rope
        U = math.sqrt(q / (0.5 * p.water_density * p.drag_normal * p.diameter))
        for _ in range(int(round(10.0 / DT))):
            rope.set_environment(current=(0.0, U, 0.0), seabed_depth=DEPTH)
            rope.step(DT)
        moved.append(float(np.abs(rope.velocities[:, 1]).max()))
    assert moved[0] < p.seabed.slip_speed  # held: creeping below the slip speed
    assert moved[1] > 5.0 * p.seabed.slip_speed  # slides


# ------------------------------------------------------------------ bad input
def test_bad_environment_raises_a_clear_value_error():
    rope = _floating_rope(n=5)
    x0 = rope.positions
    cur = np.zeros((5, 3))
    cur[3, 1] = math.nan
    cases = [
        (dict(current=cur), r"current: must be finite, got nan at element 3"),
        (dict(current=np.zeros((4, 3))), r"current: expected shape \(3,\) or \(N, 3\) = \(5, 3\).*\(4, 3\)"),
        (dict(current=(1.0, 2.0)), r"current: expected shape"),
        (dict(wind=(0.0, math.inf, 0.0)), r"wind: must be finite, got inf"),
        (dict(seabed_depth=-5.0), r"seabed_depth: expected a positive depth.*got -5.0"),
        (dict(seabed_depth=[10.0, 10.0, 0.0, 10.0, 10.0]), r"seabed_depth:.*got 0.0 at element 2"),
        (dict(seabed_depth=math.nan), r"seabed_depth:.*got nan"),
        (dict(seabed_depth=np.full(6, 10.0)), r"seabed_depth: expected a number or shape \(N,\) = \(5,\)"),
    ]
    rope.set_environment(current=(0.1, 0.0, 0.0), seabed_depth=30.0)
    for kw, msg in cases:
        with pytest.raises(ValueError, match=msg):
            rope.set_environment(**kw)
        # nothing changed by a refused call
        assert np.array_equal(rope.current, [0.1, 0.0, 0.0])
        assert np.all(rope.seabed_depth == 30.0)
    rope.set_environment(seabed_depth=math.inf)  # inf: no seabed, accepted
    rope.step(DT)
    assert np.all(np.isfinite(rope.positions)) and rope.positions.shape == x0.shape


@pytest.mark.parametrize("text, msg", [
    ("seabed:\n  friction_axial: -0.1\n", r"key 'seabed.friction_axial': expected a number in \[0, 2\]"),
    ("seabed:\n  stiffness: .nan\n", r"key 'seabed.stiffness': expected a number in \[1000, 1e\+09\] Pa/m"),
    ("seabed:\n  frictio_axial: 0.3\n", r"key 'seabed.frictio_axial': unknown key .*friction_axial"),
    ("seabed: 0.5\n", r"key 'seabed': expected a mapping of stiffness"),
    ("seabed:\n  slip_speed: '0.01'\n", r"key 'seabed.slip_speed': expected a number"),
])
def test_bad_seabed_keys_in_the_rope_file(tmp_path, text, msg):
    base = open(default_rope_path()).read()
    f = tmp_path / "bad_rope.yaml"
    f.write_text(base + "\n" + text)
    with pytest.raises(RopeParamsError, match="bad_rope.yaml: " + msg):
        load_rope_params(f)


def test_seabed_keys_in_the_rope_file(tmp_path):
    base = open(default_rope_path()).read()
    f = tmp_path / "rope.yaml"
    f.write_text(base + "\nseabed:\n  friction_axial: 0.7\n  friction_transverse: 1.0\n")
    p = load_rope_params(f)
    assert p.seabed == SeabedParams(friction_axial=0.7, friction_transverse=1.0)
    assert load_rope_params(default_rope_path()).seabed == SeabedParams()
    with pytest.raises(RopeParamsError, match="seabed.slip_speed"):
        TABLE1.replace(seabed=SeabedParams(slip_speed=0.0))


def test_attached_environment_equals_sampling_by_the_caller(tmp_path):
    """attach_environment (the rope samples the fields at its element centres inside its
    compiled step) against the caller sampling them with the fields' numpy / scipy forms and
    set_environment before every step (the rope node's way before): a sheared tidal current, a
    gusty wind on a rope lifted partly out of the water, a bathymetry grid; 100 steps, the two
    ropes agree to round-off and each step's per-element values equal the numpy ones (the
    depth inf where an element cannot reach the shallowest seabed: the kernel's shortcut)."""
    from sea_environment.environment import Environment
    from sea_environment.sampler import EnvironmentSampler
    from test_environment import wavy_grid_file
    grid = wavy_grid_file(tmp_path, 6, 5, (-60, -50), 20, 10.0, 5.0, 0.5, 0.4)
    env = Environment.from_mapping({
        "wind": {"speed_kn": 35.0, "from_deg": 300.0, "gusts": True, "seed": 5},
        "current": {"speed_kn": 1.5, "towards_deg": 20.0, "shear_per_s": 0.004, "tidal_period_s": 600.0},
        "depth": {"grid": str(grid)}})
    ropes = []
    for _ in range(2):
        rope = RopeChain.straight(TABLE1, (0.0, 0.0, 8.0), (40.0, 10.0, -0.5), n_elements=12, end_b="free")
        rope.set_end_kinematics("a", (0.0, 0.0, 8.0), (0.5, 0.2, 0.0))
        ropes.append(rope)
    fused, by_caller = ropes
    fused.attach_environment(EnvironmentSampler(env).data)
    for k in range(100):
        t = k * DT
        c = by_caller.element_centres()
        cur = np.zeros_like(c)
        cur[:, :2] = env.current_velocity(t, c[:, 0], c[:, 1])
        wind = np.zeros_like(c)
        wind[:, :2] = env.wind_velocity(t, c[:, 2])
        depth = np.asarray(env.depth_at(c[:, 0], c[:, 1]), float)
        reach = 0.5 * by_caller.lengths + TABLE1.radius + 5.0
        in_reach = c[:, 2] - reach < -env.depth.grid.values.min()
        depth = np.where(in_reach, depth, math.inf)
        by_caller.set_environment(cur, wind, depth)
        by_caller.step(DT)
        fused.step(DT)
        assert fused.env[:, 0:3] == pytest.approx(cur, abs=1e-9)
        assert fused.env[:, 3:6] == pytest.approx(wind, abs=1e-9)
        assert fused.env[:, 6] == pytest.approx(depth, abs=1e-9)
    assert np.max(np.abs(wind[:, :2])) > 10.0 and np.ptp(cur[:, 0]) > 0.01   # the fields did vary
    assert 0 < np.count_nonzero(in_reach) < len(in_reach)                   # both kinds of element
    assert fused.positions == pytest.approx(by_caller.positions, abs=1e-9)
    assert fused.velocities == pytest.approx(by_caller.velocities, abs=1e-9)
