"""Ropes in waves (issue 31 item 3): the element chain feels the linear sea of the run
(sea_environment.waves) through the environment's packed data. No ROS.

Truths (independent of the model's output):
* Morison's equation (Morison et al. 1950; DNV-RP-C205 6.2) on an element held at rest in a
  regular deep-water Airy wave, computed here by hand from the closed-form kinematics
  u = a omega e^{k z'} cos(theta), w = a omega e^{k z'} sin(theta), z' = z - eta (Wheeler 1970):
  normal drag 1/2 rho C_D D l |u_n| u_n, tangential drag 1/2 rho C_f tfac D l |u_t| u_t,
  inertia rho V ((1 + C_a) a_n + a_t), plus weight and buoyancy;
* a neutrally buoyant submerged rope in a long regular wave moves with the water particles:
  its velocity amplitude is a omega e^{k z} (the orbital speed at its depth);
* a rope floating on the surface across the crests of a long wave rides it: its heave
  amplitude is the wave amplitude (a section 0.05 m across a 100 m wave follows the surface);
* a light elastic line snatched by a heavy mass moving at v peaks at v sqrt(k M), k = EA / L
  (energy: 1/2 M v^2 = 1/2 T^2 / k); so does a towline whose ends heave in antiphase, with v
  their relative speed when it comes taut (and a lumped tug-line-tow model solved by scipy);
* a sea of Hs 0 is the calm sea bit for bit; the same seed gives the same motion.
"""
import copy
import math
import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "ros_ws", "src", "rope_model"))

from rope_model import RopeChain, default_rope_path, load_rope_params  # noqa: E402
from rope_model import kernels as K  # noqa: E402
from sea_environment.environment import Environment  # noqa: E402
from sea_environment.sampler import P_TIME, EnvironmentSampler  # noqa: E402

TABLE1 = load_rope_params(default_rope_path())
G = 9.80665


def _regular(height, period, from_deg=270.0, ramp=0.0):
    """A regular deep-water wave; from 270 deg (west) it travels towards +x (east)."""
    return Environment.from_mapping({"waves": {"hs": height, "tp": period, "from_deg": from_deg,
                                               "spectrum": "regular", "ramp_time": ramp}})


def _airy(a, omega, x, z, t, g=G):
    """Deep-water Airy kinematics towards +x, phase 0 (a crest at x = 0 at t = 0), Wheeler
    stretched: (eta, u, w, ax, az)."""
    k = omega * omega / g
    th = k * x - omega * t
    eta = a * math.cos(th)
    e = math.exp(k * (z - eta))
    return (eta, a * omega * e * math.cos(th), a * omega * e * math.sin(th),
            a * omega ** 2 * e * math.sin(th), -a * omega ** 2 * e * math.cos(th))


@pytest.mark.parametrize("axis", ["across", "along"])
def test_held_element_feels_the_morison_force_of_the_airy_kinematics(axis):
    """The force on one element at rest, 3 m below the still surface, in a 2 m / 7 s wave,
    against the hand calculation: 1e-6 relative (the kernel's force is evaluated directly,
    no time integration: the only differences are rounding and the waves' summation)."""
    p = TABLE1
    a, period, t = 1.0, 7.0, 2.3
    omega = 2.0 * math.pi / period
    d = np.array([0.0, 1.0, 0.0]) if axis == "across" else np.array([1.0, 0.0, 0.0])
    x0 = np.array([4.0, 0.0, -3.0])
    rope = RopeChain.straight(p, x0, x0 + 50.0 * d, n_elements=5, end_a="free", end_b="free")
    env = EnvironmentSampler(_regular(2.0 * a, period)).data
    env[P_TIME] = t
    rope.attach_environment(env)
    rope._pack()
    K.sample_environment(rope._S, rope._io, env, 0.0, rope._wave_cache)   # the waves at t (dt 0: no half step)
    par = K._read_params(rope._io, 1.0)                    # h = 1: the right-hand side is F
    for j in range(rope.n_elements):
        terms = K._element_terms(K._element_state(rope._S, j), par)
        force = np.array(terms[6:9])
        l = rope.L[j]
        xc, _yc, zc = rope.X[j]
        e = rope.E[j]
        eta, u, w, ax, az = _airy(a, omega, xc, zc, t)
        uw = np.array([u, 0.0, w])
        aw = np.array([ax, 0.0, az])
        rho, D = p.water_density, p.diameter
        vol = math.pi * (0.5 * D) ** 2 * l
        ut = uw @ e
        un = uw - ut * e
        at = aw @ e
        an = aw - at * e
        drag = (0.5 * rho * p.drag_normal * D * l * np.linalg.norm(un) * un
                + 0.5 * rho * p.drag_tangential * p.tangential_area_factor * D * l * abs(ut) * ut * e)
        inertia = rho * vol * ((1.0 + p.added_mass_coefficient) * an + at * e)
        weight = np.array([0.0, 0.0, -p.mass_per_length * l * G + rho * vol * G])
        expected = drag + inertia + weight
        dynamic = drag + inertia
        assert np.linalg.norm(dynamic) > 0.05 * np.linalg.norm(weight)   # the waves do matter here
        err = np.linalg.norm(force - expected) / np.linalg.norm(dynamic)
        assert err < 1e-6, (j, force, expected)


def _neutral_params():
    """Table 1's rope with the density of sea water (it neither sinks nor floats)."""
    p = TABLE1
    return p.replace(mass_per_length=p.water_density * math.pi * (0.5 * p.diameter) ** 2)


def test_neutrally_buoyant_rope_moves_with_the_water_particles():
    """A 20 m rope across the crests 6 m down in a 2 m / 10 s wave (156 m long), no current,
    free ends, grown from calm by the sea's 20 s ramp: after the ramp its horizontal and
    vertical speeds have the orbital amplitude a omega e^{k z} within 3 % (the rope rides a
    0.7 m orbit, e^{k z} varies +-2.6 % over it; measured: -0.8 % and -0.9 %)."""
    p = _neutral_params()
    a, period, z0 = 1.0, 10.0, -6.0
    omega = 2.0 * math.pi / period
    k = omega * omega / G
    rope = RopeChain.straight(p, np.array([0.0, -10.0, z0]), np.array([0.0, 10.0, z0]),
                              n_elements=10, end_a="free", end_b="free")
    rope.attach_environment(EnvironmentSampler(_regular(2.0 * a, period, ramp=20.0)).data)
    dt = 0.05
    vx, vz, z = [], [], []
    for i in range(int(45.0 / dt)):
        rope.step(dt)
        if rope.time > 25.0 + 1e-9:          # two whole periods
            vx.append(rope.V[5, 0])
            vz.append(rope.V[5, 2])
            z.append(rope.X[5, 2])
    expected = a * omega * math.exp(k * z0)
    for v in (vx, vz):
        amp = 0.5 * (max(v) - min(v))
        assert amp == pytest.approx(expected, rel=0.03)
    # The orbit's centre sinks slowly (0.33 m in 45 s, measured): linear Morison loads use the
    # local acceleration du/dt, not the particle's Du/Dt = du/dt + grad(|u|^2 / 2), whose
    # second-order upward part k (a omega)^2 e^{2kz} = 0.1 % of g the rope then lacks; drag
    # balances it at a few cm/s. Bounded here so a real imbalance would show.
    assert abs(np.mean(z) - z0) < 0.5


def test_floating_rope_rides_the_waves():
    """Table 1's rope (878 kg/m^3: floats) across the crests of a 1 m / 8 s wave: its elements'
    immersion is judged against the local surface, so they heave with it; the heave amplitude
    of the middle element is the wave amplitude within 5 % and it stays at the surface (centre
    within 0.1 m of eta; measured: +0.3 %, at most 0.020 m from eta, its calm draft 0.015 m)."""
    a, period = 0.5, 8.0
    rope = RopeChain.straight(TABLE1, np.array([0.0, -30.0, -0.015]), np.array([0.0, 30.0, -0.015]),
                              n_elements=11, end_a="free", end_b="free")
    env = _regular(2.0 * a, period, ramp=16.0)
    rope.attach_environment(EnvironmentSampler(env).data)
    dt = 0.05
    z, gap = [], []
    for i in range(int(40.0 / dt)):
        rope.step(dt)
        if rope.time > 24.0:
            x, y, zc = rope.X[5]
            z.append(zc)
            gap.append(zc - env.wave_elevation(rope.time, x, y))
    assert 0.5 * (max(z) - min(z)) == pytest.approx(a, rel=0.05)
    assert max(abs(g) for g in gap) < 0.1


def test_snatch_of_a_light_line_on_a_heavy_mass():
    """End a fixed, end b on a 10 t point mass moving away at 1 m/s just as the straight
    50 m line (EA 5 MN: k = 1e5 N/m, 0.5 kg/m) comes taut, in air without gravity (the wave
    field plays no part): the peak tension is v sqrt(k M) = 31.6 kN within 3 % (the line's own
    mass, 0.25 % of M, and its axial damping lower it by well under 1 %; measured 31.44 kN,
    -0.6 %). The mass is moved by
    the mean end force of each 2 ms exchange step (momentum-consistent coupling)."""
    p = TABLE1.replace(length=50.0, mass_per_length=0.5, axial_stiffness=5e6, breaking_load=1e6,
                       gravity=0.0)
    M, v0, L = 1e4, 1.0, 50.0
    pa, pb = np.array([0.0, 0.0, 20.0]), np.array([L, 0.0, 20.0])
    rope = RopeChain.straight(p, pa, pb, n_elements=11)
    pos, vel = pb.copy(), np.array([v0, 0.0, 0.0])
    rope.set_end_kinematics("b", pos, vel)
    dt = 0.002
    peak = 0.0
    for i in range(int(1.2 / dt)):
        rope.step(dt)
        f = rope.mean_end_force("b")          # on the attachment, i.e. on the mass
        vel = vel + f / M * dt
        pos = pos + vel * dt
        rope.set_end_kinematics("b", pos, vel)
        peak = max(peak, float(np.max(rope.tensions)))
    expected = v0 * math.sqrt(p.ea / L * M)
    assert peak == pytest.approx(expected, rel=0.03)
    assert vel[0] < 0.0                         # the mass was thrown back


def _lumped_antiphase_peak(k, M, C, a, omega):
    """The same snatch as a lumped system (scipy, no rope code): the tow's heave z under its
    spring C and the line k (tension only) to the prescribed fairlead a sin(omega t)."""
    from scipy.integrate import solve_ivp

    def rhs(t, y):
        stretch = a * math.sin(omega * t) - y[0]
        return [y[1], (k * max(stretch, 0.0) - C * y[0]) / M]
    sol = solve_ivp(rhs, (0.0, 0.8), [0.0, -a * omega], max_step=1e-4, rtol=1e-10, atol=1e-12)
    return float(np.max(k * (a * np.sin(omega * sol.t) - sol.y[0])))


def test_snatch_of_a_towline_whose_ends_heave_in_antiphase():
    """A 50 m line (EA 50 MN: k = 1e6 N/m, 0.5 kg/m, in air, no gravity) from a tug's fairlead
    heaving 1 m at 8 s (prescribed: the tug is far heavier) down to a 10 t tow heaving freely
    on its own hydrostatic spring C = M omega^2 in antiphase. The line is straight at its
    unstretched length just as both ends cross their mean positions, so it comes taut with the
    relative speed v = 2 a omega = 1.57 m/s. The peak is the elastic closed form v sqrt(k M) =
    157.1 kN within 3 %, and the lumped tug-line-tow system solved by scipy (156.6 kN: C and the
    fairlead's slowing change it by -0.3 %) within 2 % (the rope's axial damping and own mass
    lower it; measured 154.8 kN, -1.5 % and -1.2 %)."""
    M, a, period, L, k = 1e4, 1.0, 8.0, 50.0, 1e6
    omega = 2.0 * math.pi / period
    C = M * omega * omega
    p = TABLE1.replace(length=L, mass_per_length=0.5, axial_stiffness=k * L, breaking_load=1e8, gravity=0.0)
    z0, dt = 30.0, 0.002
    fairlead = lambda t: (np.array([0.0, 0.0, z0 + L + a * math.sin(omega * t)]),     # noqa: E731
                          np.array([0.0, 0.0, a * omega * math.cos(omega * t)]))
    zb, vb = z0, -a * omega
    pa, va = fairlead(0.0)
    rope = RopeChain.straight(p, pa, np.array([0.0, 0.0, zb]), n_elements=11)
    rope.V[:, 2] = vb + (va[2] - vb) * (rope.X[:, 2] - zb) / L    # the line moves with its ends
    rope.set_end_kinematics("a", pa, va)
    rope.set_end_kinematics("b", (0.0, 0.0, zb), (0.0, 0.0, vb))
    peak, t = 0.0, 0.0
    while t < 0.8:
        rope.step(dt)
        t += dt
        f = rope.mean_end_force("b")[2]           # the line's pull on the tow, upwards
        vb += (f - C * (zb - z0)) / M * dt
        zb += vb * dt
        rope.set_end_kinematics("a", *fairlead(t))
        rope.set_end_kinematics("b", (0.0, 0.0, zb), (0.0, 0.0, vb))
        peak = max(peak, f)
    assert peak == pytest.approx(2.0 * a * omega * math.sqrt(k * M), rel=0.03)
    assert peak == pytest.approx(_lumped_antiphase_peak(k, M, C, a, omega), rel=0.02)
    assert vb > 0.0                                # the line threw the tow back up


def _hanging_run(waves, n_steps=150, warm_up=False):
    rope = RopeChain.slack(TABLE1, np.array([0.0, 0.0, 2.0]), np.array([60.0, 0.0, 2.0]), n_elements=11)
    spec = {"current": [0.3, 0.1], "wind": {"speed_kn": 20.0, "from_deg": 200.0, "seed": 2}}
    if waves is not None:
        spec["waves"] = waves
    rope.attach_environment(EnvironmentSampler(Environment.from_mapping(spec)).data)
    if warm_up:   # as the rope node does before the clock: a copy stepped and thrown away
        copy.deepcopy(rope).step(0.02)
    out = []
    for _ in range(n_steps):
        rope.step(0.02)
        out.append(np.concatenate([rope.X.ravel(), rope.V.ravel(), rope.tensions]))
    return np.array(out)


def test_hs_zero_is_the_calm_sea_bit_for_bit():
    """A rope hanging into the calm surface in a current and wind: a waves key of Hs 0 gives
    the same states, bit for bit, as no waves key (and the sampler packs no sea)."""
    calm = _hanging_run(None)
    zero = _hanging_run({"hs": 0.0, "tp": 8.0, "from_deg": 0.0})
    assert np.array_equal(calm, zero)
    assert EnvironmentSampler(Environment.from_mapping({"waves": {"hs": 0.0, "tp": 8.0, "from_deg": 0.0}})
                              ).data.size == EnvironmentSampler(Environment()).data.size


def test_same_seed_same_rope_motion_and_the_sea_matters():
    sea = {"hs": 2.0, "tp": 7.0, "from_deg": 300.0, "spreading_s": 8.0, "components": 120, "seed": 4,
           "ramp_time": 0.5}
    a = _hanging_run(sea)
    b = _hanging_run(sea)
    c = _hanging_run(dict(sea, seed=5))
    calm = _hanging_run(None)
    assert np.array_equal(a, b)
    assert np.array_equal(a, _hanging_run(sea, warm_up=True))   # the node's warm-up touches nothing
    assert not np.array_equal(a, c)
    assert np.abs(a - calm).max() > 0.05      # metres / m/s / N: the waves moved the rope


# ---- the finite-difference towed cable (seed 001) ------------------------------------------------

def test_fd_cable_node_feels_the_morison_force_of_the_waves():
    """fd_kernels.node_terms at a node at rest (T = 0, so no stretch factor) with the wave
    particles' velocity u and acceleration a (paper frame) against the hand calculation: the
    fluid force R joins rows 0-2 as -R, R_n = 1/2 rho C_Dn D |u_nb| u_n + (rho A + m_a) a_n (and
    b alike), R_t = 1/2 rho C_Dt pi D |u_t| u_t + rho A a_t; 1e-9 relative."""
    from rope_model import fd_kernels as FK
    from rope_model.fd_cable import _parameter_vector, default_cable_path, load_cable_params
    p = load_cable_params(default_cable_path())
    P = _parameter_vector(p)
    ph, th = 0.4, -0.3
    H = np.zeros(FK.NV, np.complex128)
    H[FK.H_PHI], H[FK.H_THETA] = ph, th
    u = np.array([0.3, -0.5, 0.2])
    a = np.array([-0.2, 0.15, 0.4])
    L0, Lw, g = (np.zeros(FK.NV, np.complex128) for _ in range(3))
    calm = np.zeros(FK.CUR_COLS)
    sea = np.concatenate([u, u, a])
    FK.node_terms(H, H, P, calm, False, L0, g)
    FK.node_terms(H, H, P, sea, False, Lw, g)
    cp, sp, ct, st = math.cos(ph), math.sin(ph), math.cos(th), math.sin(th)
    t = np.array([ct * cp, ct * sp, -st])
    n = np.array([-sp, cp, 0.0])
    b = np.array([st * cp, st * sp, ct])
    rho, D = p.water_density, p.diameter
    area = math.pi * D * D / 4.0
    ma = p.added_mass_coefficient * rho * area
    unb = math.hypot(u @ n, u @ b)
    R = np.array([0.5 * rho * p.drag_tangential * math.pi * D * abs(u @ t) * (u @ t) + rho * area * (a @ t),
                  0.5 * rho * p.drag_normal * D * unb * (u @ n) + (rho * area + ma) * (a @ n),
                  0.5 * rho * p.drag_binormal * D * unb * (u @ b) + (rho * area + ma) * (a @ b)])
    np.testing.assert_allclose((Lw - L0).real[:3], -R, rtol=1e-9, atol=1e-12 * np.abs(R).max())


def _fd_run(waves, steps=24):
    from rope_model.models import CableAdapter
    path = os.path.join(os.path.dirname(default_rope_path()), "cable_001.yaml")
    c = CableAdapter(path, "straight", (0.0, 0.0, 0.0), None, end_a="fixed", end_b="free", current=(0.0, 0.0, 0.0),
                     n_elements=None, deployed_length=None, max_substep=0.0, velocity_a=(1.5, 0.0, 0.0))
    spec = {"current": [0.0, 0.0]}
    if waves is not None:
        spec["waves"] = waves
    c.attach_environment(Environment.from_mapping(spec))
    out = []
    for k in range(1, steps + 1):
        c.set_end("a", (0.75 * k, 0.0, 0.0), (1.5, 0.0, 0.0))
        c.step(0.5)
        out.append(np.concatenate([c.cable.positions.ravel(), c.end_force("a", averaged=False)]))
    return np.array(out)


def test_fd_cable_in_waves_is_reproducible_and_hs_zero_is_calm():
    """The towed cable through the adapter the rope node uses: Hs 0 is the calm run bit for
    bit, the same seed the same run, and the sea moves the cable (its nodes feel the waves)."""
    sea = {"hs": 3.0, "tp": 8.0, "from_deg": 250.0, "components": 100, "seed": 3, "ramp_time": 1.0}
    calm = _fd_run(None)
    assert np.array_equal(calm, _fd_run({"hs": 0.0, "tp": 8.0, "from_deg": 0.0}))
    a, b = _fd_run(sea), _fd_run(sea)
    assert np.array_equal(a, b)
    assert np.abs(a - calm).max() > 0.01


def test_wet_kinematics_are_the_fields_below_the_surface_and_its_surface_values_above():
    """waves.wave_kinematics_wet (what the rope samples) against the field's own kernel: the
    same values (1e-12) at points in the water, and at a point above the surface those at the
    surface (z = eta) rather than zero."""
    from sea_environment.waves import WaveField, wave_kinematics, wave_kinematics_wet
    sea = WaveField.irregular(3.0, 9.0, 0.7, spreading_s=6.0, components=60, seed=8, depth=40.0, ramp_time=5.0)
    w = sea.packed
    scratch = np.empty(2 * 60)
    above = float(sea.elevation(-8.0, 4.0, 60.0)) + 0.3
    for x, y, z, t in ((3.0, -7.0, -2.0, 2.0), (50.0, 11.0, -30.0, 40.0), (-8.0, 4.0, above, 60.0)):
        wet = np.array(wave_kinematics_wet(w, 0, x, y, z, t, scratch))
        ref = np.array(wave_kinematics(w, 0, x, y, z, t))
        if z <= ref[0]:
            np.testing.assert_allclose(wet, ref[:7], rtol=1e-12, atol=1e-12)
        else:
            surf = np.array(wave_kinematics(w, 0, x, y, ref[0], t))
            assert np.abs(surf[1:4]).max() > 0.1
            np.testing.assert_allclose(wet, surf[:7], rtol=1e-12, atol=1e-12)
