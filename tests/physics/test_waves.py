"""Waves (sea_environment.waves, issue 31 part 1: one sea for all) against independent truths:
the spectrum's variance Hs^2/16 (the definition of Hs), a realised record's Welch spectrum
against the target, the dispersion relation's deep and shallow limits and a root found here by
bisection, the Airy orbit speed a omega, the spatial phase k x between two bodies, Wheeler
stretching at the surface, the ramp, the compiled kernel against numpy, and the scenario's bad
input. No ROS."""
import math
import os

import numpy as np
import pytest
from scipy.optimize import brentq
from scipy.signal import welch

from sea_environment.environment import Environment
from sea_environment.waves import (G, WaveField, dnv_a_gamma, jonswap, jonswap_a_gamma, pierson_moskowitz_shape,
                                   wave_elevation, wave_kinematics, wavenumber)

HS, TP = 3.0, 9.0


# ---- the spectrum -----------------------------------------------------------------------------

@pytest.mark.parametrize("gamma", [1.0, 2.0, 3.3, 7.0])
def test_discretised_m0_is_hs_squared_over_16(gamma):
    """Hs = 4 sqrt(m0): the components' variance sum a^2/2 within 1 % of Hs^2/16 (the range
    [0.5, 5] wp leaves out under 0.25 % of the energy)."""
    f = WaveField.irregular(HS, TP, gamma=gamma, components=150, seed=4)
    assert f.m0 == pytest.approx(HS ** 2 / 16.0, rel=0.01)
    assert f.m0 < HS ** 2 / 16.0          # a truncated spectrum holds less, never more


def test_jonswap_normalisation_against_dnv():
    """The numerical A_gamma against DNV-RP-C205's 1 - 0.287 ln(gamma) (an approximation: within
    0.5 % at gamma 3.3, 2 % at 7); gamma 1 is Pierson-Moskowitz exactly."""
    assert jonswap_a_gamma(3.3) == pytest.approx(dnv_a_gamma(3.3), rel=0.005)
    assert jonswap_a_gamma(7.0) == pytest.approx(dnv_a_gamma(7.0), rel=0.02)
    w = np.linspace(0.2, 3.0, 50)
    assert np.array_equal(jonswap(w, HS, TP, 1.0), pierson_moskowitz_shape(w, HS, TP))
    # the peak is at wp (the shape's maximum, found on a fine grid)
    wf = np.linspace(0.3, 1.5, 120001)
    assert wf[np.argmax(jonswap(wf, HS, TP, 3.3))] == pytest.approx(2 * math.pi / TP, abs=1e-4)


@pytest.mark.parametrize("components", [150, 300])
def test_welch_spectrum_of_a_record_matches_the_target(components):
    """A 3-hour record at one point; scipy's Welch PSD integrated over third-octave bands from
    0.7 to 2.8 fp (95 % of the energy) against the target spectrum's band integrals, and the
    record's variance within 3 % of Hs^2/16.

    A band's error is mostly which side of its edges the nearest components fall (one
    component per bin of 0.03 fp): over 30 seeds the per-band scatter was 3-15 % (std) with 150
    components, 2-7 % with 300 (worst band 25 % and 13 %). So: with 300 components every band
    within 15 %; with the default 150 the mean over the bands within 15 % and each within 25 %."""
    sea = WaveField.irregular(HS, TP, direction=0.3, gamma=3.3, components=components, seed=1)
    dt = 0.5
    t = np.arange(0.0, 3 * 3600.0, dt)
    eta = sea.elevation(12.0, -40.0, t)
    f, pxx = welch(eta, fs=1.0 / dt, nperseg=4096)
    fp = 1.0 / TP
    edges = 0.7 * fp * 2.0 ** (np.arange(0, 7) / 3.0)
    errors = []
    for lo, hi in zip(edges[:-1], edges[1:]):
        sel = (f >= lo) & (f < hi)
        measured = pxx[sel].sum() * (f[1] - f[0])
        wf = np.linspace(2 * math.pi * lo, 2 * math.pi * hi, 2001)
        target = np.trapezoid(sea.spectrum(wf), wf)
        errors.append(measured / target - 1.0)
    errors = np.array(errors)
    print(f"Welch band errors, {components} components:", np.round(errors, 3),
          "variance error", round(np.var(eta) / (HS ** 2 / 16.0) - 1.0, 4))
    if components >= 300:
        assert np.all(np.abs(errors) < 0.15)
    else:
        assert np.mean(np.abs(errors)) < 0.15 and np.all(np.abs(errors) < 0.25)
    assert np.var(eta) == pytest.approx(HS ** 2 / 16.0, rel=0.03)


def test_short_crested_directions_follow_cos2s():
    """cos-2s with s = 10: the circular moments of the realised directions, energy-weighted,
    against the closed form E[cos(theta - theta0)] = s / (s + 1) (Longuet-Higgins et al. 1963)."""
    s, mean = 10.0, 1.1
    f = WaveField.irregular(HS, TP, direction=mean, spreading_s=s, components=400, seed=2)
    d = f.direction - mean
    assert np.mean(np.cos(d)) == pytest.approx(s / (s + 1.0), abs=0.005)
    assert abs(np.mean(np.sin(d))) < 0.01
    long = WaveField.irregular(HS, TP, direction=mean, components=50, seed=2)
    assert np.allclose(long.direction, mean, atol=1e-15)


# ---- reproducibility --------------------------------------------------------------------------

def test_same_seed_same_sea_other_seed_other_sea():
    a = WaveField.irregular(HS, TP, spreading_s=5.0, seed=11)
    b = WaveField.irregular(HS, TP, spreading_s=5.0, seed=11)
    c = WaveField.irregular(HS, TP, spreading_s=5.0, seed=12)
    assert np.array_equal(a.packed, b.packed)
    t = np.linspace(100.0, 400.0, 601)
    ea, ec = a.elevation(5.0, 7.0, t), c.elevation(5.0, 7.0, t)
    assert np.array_equal(ea, b.elevation(5.0, 7.0, t))
    assert abs(np.corrcoef(ea, ec)[0, 1]) < 0.3     # independent seas: uncorrelated records


def test_the_sea_does_not_repeat():
    """Equal bins at their centres would repeat after 2 pi / dw; the random frequencies do not:
    the record one such period later is uncorrelated with the first."""
    n = 150
    f = WaveField.irregular(HS, TP, components=n, seed=5)
    period = 2 * math.pi / ((5.0 - 0.5) * 2 * math.pi / TP / n)   # 300 s for Tp 9 s
    t = np.linspace(0.0, 600.0, 1201)
    r = np.corrcoef(f.elevation(0.0, 0.0, t), f.elevation(0.0, 0.0, t + period))[0, 1]
    assert abs(r) < 0.5


def test_every_node_builds_the_same_sea():
    """Two nodes building their Environment from one parameter text sample one field."""
    text = '{"waves": {"hs": 2.5, "tp": 8.0, "from_deg": 45.0, "spreading_s": 8.0, "seed": 9}, "depth": 30.0}'
    (a, _), (b, _) = Environment.from_parameter(text), Environment.from_parameter(text)
    assert np.array_equal(a.waves.packed, b.waves.packed)
    assert a.waves.depth == 30.0


# ---- dispersion -------------------------------------------------------------------------------

def test_dispersion_limits_and_a_bisected_root():
    w = np.array([0.3, 0.7, 1.0, 2.0, 5.0])
    assert np.allclose(wavenumber(w) * G, w ** 2, rtol=1e-15)                 # deep: w^2 = g k
    assert np.allclose(wavenumber(w, 5000.0), w ** 2 / G, rtol=1e-14)         # kh > 40: deep
    h = 1.0                                                                     # shallow: c = sqrt(g h)
    wl = 2 * math.pi / 120.0
    c = wl / float(wavenumber(wl, h))
    kh = float(wavenumber(wl, h)) * h
    assert c == pytest.approx(math.sqrt(G * h), rel=(kh ** 2) / 6.0 * 1.1)   # c = sqrt(gh)(1 - (kh)^2/6 + ...)
    assert c == pytest.approx(math.sqrt(G * h), rel=2e-4)
    for om, depth in [(0.5, 10.0), (1.0, 10.0), (0.8, 30.0), (2.0, 3.0)]:      # against bisection
        root = brentq(lambda k: om ** 2 - G * k * math.tanh(k * depth), 1e-9, 50.0, xtol=1e-15, rtol=1e-15)
        assert float(wavenumber(om, depth)) == pytest.approx(root, rel=1e-12)


def test_field_uses_the_finite_depth_wavenumber():
    f = WaveField.regular(1.0, 10.0, depth=12.0)
    om = 2 * math.pi / 10.0
    assert om ** 2 == pytest.approx(G * f.k[0] * math.tanh(f.k[0] * 12.0), rel=1e-14)


# ---- Airy kinematics --------------------------------------------------------------------------

def test_deep_water_surface_speed_is_a_omega():
    """Deep water: circular orbits of radius a; at the surface (z = eta, Wheeler z' = 0) the
    speed is a omega at every phase, the horizontal velocity a omega at a crest."""
    H, T = 2.0, 8.0
    f = WaveField.regular(H, T, direction=0.0)
    t = np.linspace(0.0, T, 37)
    eta = f.elevation(0.0, 0.0, t)
    kin = f.kinematics(0.0, 0.0, eta, t)
    speed = np.hypot(kin.velocity[:, 0], kin.velocity[:, 2])
    assert np.allclose(speed, 0.5 * H * 2 * math.pi / T, rtol=1e-12)
    assert kin.velocity[0, 0] == pytest.approx(0.5 * H * 2 * math.pi / T, rel=1e-12)   # crest at t = 0
    # and decays as exp(k z') below: half a wavelength down, exp(-pi)
    L = G * T ** 2 / (2 * math.pi)
    deep = f.kinematics(0.0, 0.0, eta - L / 2, t)
    assert np.allclose(np.hypot(deep.velocity[:, 0], deep.velocity[:, 2]), speed * math.exp(-math.pi), rtol=1e-12)


def test_finite_depth_profiles_and_bottom():
    """Finite depth (Faltinsen 1990 Table 2.1): at z' = 0 a crest's horizontal velocity is
    a omega coth(kh) and the vertical at the bottom is zero; below the bottom and in air nothing."""
    H, T, h = 1.0, 10.0, 12.0
    f = WaveField.regular(H, T, depth=h)
    k, om = f.k[0], 2 * math.pi / T
    crest = f.kinematics(0.0, 0.0, 0.5 * H, 0.0)          # z = eta: z' = 0
    assert crest.velocity[0, 0] == pytest.approx(0.5 * H * om / math.tanh(k * h), rel=1e-12)
    assert crest.pressure[0] == pytest.approx(G * 0.5 * H, rel=1e-12)   # p_d / rho = g a at z' = 0
    t = 0.25 * T                                           # eta = 0: w is extreme
    bottom = f.kinematics(0.0, 0.0, -h, t)
    assert abs(bottom.velocity[0, 2]) < 1e-15
    assert bottom.velocity[0, 0] == pytest.approx(0.5 * H * om / math.sinh(k * h) * math.cos(-om * t), abs=1e-12)
    out = f.kinematics([0.0, 0.0], [0.0, 0.0], [-h - 0.1, 0.6], [0.0, 0.0])
    assert np.all(out.velocity == 0.0) and np.all(out.acceleration == 0.0) and np.all(out.pressure == 0.0)


def test_wheeler_at_the_surface_is_linear_theory_at_z0():
    """Wheeler (1970): z' = (z - eta) h / (h + eta), so the velocity at z = eta equals linear
    theory's at z = 0 (computed here by hand from Airy's formulas)."""
    H, T, h = 1.5, 9.0, 20.0
    f = WaveField.regular(H, T, depth=h, direction=0.4)
    k, om, a = f.k[0], 2 * math.pi / T, 0.75
    t = np.linspace(0.0, T, 13)
    x, y = 3.0, -2.0
    theta = k * (x * math.cos(0.4) + y * math.sin(0.4)) - om * t
    kin = f.kinematics(x, y, a * np.cos(theta), t)
    uh = a * om / math.tanh(k * h) * np.cos(theta)
    assert np.allclose(kin.velocity[:, 0], uh * math.cos(0.4), atol=1e-12)
    assert np.allclose(kin.velocity[:, 1], uh * math.sin(0.4), atol=1e-12)
    assert np.allclose(kin.velocity[:, 2], a * om * np.sin(theta), atol=1e-12)
    # just above the surface: in air
    assert np.all(f.kinematics(x, y, a * np.cos(theta) + 1e-6, t).velocity == 0.0)


def test_acceleration_is_the_time_derivative_of_the_velocity():
    """A tiny wave (the stretching's own time derivative is of order k a = 1e-7): a central
    difference of the velocity at a fixed point, inside the ramp (r' u included) and after it."""
    f = WaveField.regular(2e-6, 7.0, depth=15.0, direction=-0.7, ramp_time=20.0)
    for t in (5.0, 13.0, 31.0):
        dt = 1e-4
        v = [f.kinematics(2.0, 1.0, -3.0, tt).velocity[0] for tt in (t - dt, t + dt)]
        acc = f.kinematics(2.0, 1.0, -3.0, t).acceleration[0]
        assert np.allclose(acc, (v[1] - v[0]) / (2 * dt), rtol=1e-6, atol=0.0)


# ---- one sea for all bodies -----------------------------------------------------------------

def test_two_bodies_see_the_phase_difference_k_x():
    """A regular wave towards 30 deg (math) in deep water: the phase each body sees, from its
    elevation and vertical velocity at the surface (eta = a cos th, w = a omega sin th), differs
    by k . (x2 - x1) with k = omega^2 / g, to 1e-9 rad."""
    H, T, psi = 2.0, 10.0, math.radians(30.0)
    f = WaveField.regular(H, T, direction=psi, ramp_time=30.0)
    a, om = 0.5 * H, 2 * math.pi / T
    k = om ** 2 / G
    p1, p2 = np.array([10.0, -20.0]), np.array([57.0, 33.0])
    t = 47.3                                     # after the ramp
    phases = []
    for p in (p1, p2):
        eta = float(f.elevation(p[0], p[1], t))
        w = float(f.kinematics(p[0], p[1], eta, t).velocity[0, 2])
        phases.append(math.atan2(w / (a * om), eta / a))
    expect = k * ((p2 - p1) @ np.array([math.cos(psi), math.sin(psi)]))
    diff = (phases[1] - phases[0] - expect + math.pi) % (2 * math.pi) - math.pi
    assert abs(diff) < 1e-9


def test_ramp_starts_from_calm():
    f = WaveField.irregular(HS, TP, components=100, seed=3, ramp_time=27.0)
    assert np.all(f.elevation([0.0, 50.0], [0.0, -30.0], 0.0) == 0.0)
    kin = f.kinematics([0.0, 50.0], [0.0, -30.0], [-1.0, -5.0], 0.0)
    assert np.all(kin.velocity == 0.0) and np.all(kin.acceleration == 0.0)
    assert wave_elevation(f.packed, 0, 3.0, 4.0, 0.0) == 0.0
    # r(T/2) = 1/2, and 1 from T on: against the unramped sea
    full = WaveField.irregular(HS, TP, components=100, seed=3, ramp_time=0.0)
    assert f.elevation(3.0, 4.0, 13.5) == pytest.approx(0.5 * full.elevation(3.0, 4.0, 13.5), rel=1e-12)
    assert f.elevation(3.0, 4.0, 27.0) == full.elevation(3.0, 4.0, 27.0)


def test_one_time_ramp_is_the_arrays_ramp():
    """The scalar path a vessel takes every step equals the array form, inside and outside the ramp."""
    f = WaveField.irregular(HS, TP, components=10, seed=3, ramp_time=27.0)
    times = [-1.0, 0.0, 1e-9, 5.0, 13.5, 26.999, 27.0, 40.0]
    r_arr, dr_arr = f.ramp(np.array(times))
    for t, r, dr in zip(times, r_arr, dr_arr):
        r1, dr1 = f.ramp(t)
        assert r1 == pytest.approx(r, rel=1e-14, abs=1e-300) and dr1 == pytest.approx(dr, rel=1e-14, abs=1e-300), t
    assert f.ramp(13.5)[0] == pytest.approx(0.5, rel=1e-15)   # r(T/2) = 1/2
    assert f.ramp(13.5)[1] == pytest.approx(math.pi / (2.0 * 27.0), rel=1e-15)   # its slope there, pi / 2T


# ---- the compiled kernel ------------------------------------------------------------------------

@pytest.mark.parametrize("depth", [math.inf, 25.0])
def test_kernel_equals_numpy(depth):
    """wave_kinematics (numba) against WaveField.kinematics (numpy) at points in water, in air,
    below the bottom, inside the ramp; the block read at an offset inside a larger array (as the
    sampler will hold it): 1e-12 of each quantity's scale."""
    f = WaveField.irregular(HS, TP, direction=2.0, spreading_s=6.0, components=120, seed=7, depth=depth,
                            ramp_time=20.0)
    rng = np.random.default_rng(0)
    n = 200
    x, y = rng.uniform(-300, 300, n), rng.uniform(-300, 300, n)
    z = rng.uniform(-30.0, 3.0, n)
    t = rng.uniform(0.0, 200.0, n)
    ref = f.kinematics(x, y, z, t)
    ref_rows = np.column_stack([ref.eta, ref.velocity, ref.acceleration, ref.pressure])
    host = np.concatenate([np.full(17, np.nan), f.packed, np.full(5, np.nan)])
    got = np.array([wave_kinematics(host, 17, x[i], y[i], z[i], t[i]) for i in range(n)])
    scale = np.abs(ref_rows).max(axis=0)
    assert np.all(np.abs(got - ref_rows) <= 1e-12 * scale)
    etas = np.array([wave_elevation(host, 17, x[i], y[i], t[i]) for i in range(n)])
    assert np.all(np.abs(etas - ref.eta) <= 1e-12 * scale[0])
    wet = (z <= ref.eta) & (z >= -depth)
    assert 50 < wet.sum() < n                   # both cases exercised


# ---- the scenario -----------------------------------------------------------------------------

def _scenario(tmp_path, waves, depth=None):
    import yaml
    env = {"waves": waves}
    if depth is not None:
        env["depth"] = depth
    doc = {"name": "waves_check", "duration": 10.0, "environment": env,
           "vessels": [{"name": "tug", "ship_file": "harbour_tug.yaml", "initial": {"x": 0.0, "y": 0.0}}]}
    path = tmp_path / "waves.yaml"
    path.write_text(yaml.safe_dump(doc))
    return str(path)


GOOD = {"hs": 3.0, "tp": 9.0, "from_deg": 0.0}


@pytest.mark.parametrize("change, key", [
    ({"hs": -1.0}, "environment.waves.hs"),
    ({"hs": 25.0}, "environment.waves.hs"),
    ({"tp": 0.5}, "environment.waves.tp"),
    ({"tp": 40.0}, "environment.waves.tp"),
    ({"spectrum": "bretschneider"}, "environment.waves.spectrum"),
    ({"hs": 12.0, "tp": 6.0}, "environment.waves"),                  # Hs / L_p = 0.21 > 1/7
    ({"spectrum": "pierson_moskowitz", "gamma": 2.0}, "environment.waves"),
    ({"spreading_s": -2.0}, "environment.waves.spreading_s"),
    ({"components": 3}, "environment.waves.components"),
    ({"height": 2.0}, "environment.waves.height"),
])
def test_bad_waves_are_refused_naming_the_key(tmp_path, change, key):
    from scenario_format.scenario import ScenarioError, load_scenario
    with pytest.raises(ScenarioError, match=f"key '{key}'"):
        load_scenario(_scenario(tmp_path, {**GOOD, **change}), check_files=False)


def test_breaking_limit_uses_the_uniform_depth(tmp_path):
    """Hs 2 m, Tp 10 s: 1/78 of the deep wavelength (156 m), fine; in 2 m of water (L = 43.7 m,
    Hs / L = 0.046 against Miche's 1/7 tanh(kh) = 0.040) it breaks."""
    from scenario_format.scenario import ScenarioError, load_scenario
    waves = {"hs": 2.0, "tp": 10.0, "from_deg": 90.0}
    load_scenario(_scenario(tmp_path, waves), check_files=False)
    with pytest.raises(ScenarioError, match="key 'environment.waves'.*breaking"):
        load_scenario(_scenario(tmp_path, waves, depth=2.0), check_files=False)
    load_scenario(_scenario(tmp_path, waves, depth=2.5), check_files=False)   # 0.041 < 0.045


def test_scenario_waves_reach_the_nodes_environment(tmp_path):
    """The scenario's waves through the nodes' parameter: from_deg 90 (from the east) travels
    towards the west (math angle pi); hs 0 is the calm sea (no field, uniform environment)."""
    from scenario_format.scenario import environment_parameter, load_scenario
    path = _scenario(tmp_path, {"hs": 2.0, "tp": 8.0, "from_deg": 90.0, "spectrum": "regular", "ramp_time": 0.0})
    sc = load_scenario(path, check_files=False)
    env, rho = Environment.from_parameter(environment_parameter(sc, path))
    assert not sc.environment.is_uniform
    assert abs(abs(env.waves.direction[0]) - math.pi) < 1e-12
    assert env.waves.amplitude[0] == 1.0 and env.waves.omega[0] == pytest.approx(2 * math.pi / 8.0)
    # the wave runs west: a body 10 m west of another sees the crest later by 10 / c
    c = env.waves.omega[0] / env.waves.k[0]
    assert env.wave_elevation(10.0 / c, -10.0, 0.0) == pytest.approx(env.wave_elevation(0.0, 0.0, 0.0), abs=1e-12)
    calm = load_scenario(_scenario(tmp_path, {**GOOD, "hs": 0.0}), check_files=False)
    assert calm.environment.is_uniform
    env0, _ = Environment.from_parameter(environment_parameter(calm, path))
    assert env0.waves is None and env0.wave_elevation(5.0, 1.0, 2.0) == 0.0
    calm_kin = env0.wave_kinematics(2.0, [5.0, 6.0], [1.0, 1.0], [-1.0, -2.0])
    assert calm_kin.velocity.shape == (2, 3) and not np.any(calm_kin.velocity) and not np.any(calm_kin.pressure)
    kin = env.wave_kinematics(3.0, [5.0], [1.0], [-1.0])
    assert np.array_equal(kin.velocity, env.waves.kinematics(5.0, 1.0, -1.0, 3.0).velocity)
    assert Environment.from_parameter("{}")[0].waves is None


def _ship_scenario(tmp_path, ship_file, waves):
    import yaml
    doc = {"name": "waves_ship", "duration": 10.0, "environment": {"waves": waves},
           "vessels": [{"name": "boat", "ship_file": ship_file, "initial": {"x": 0.0, "y": 0.0}}]}
    path = tmp_path / "waves_ship.yaml"
    path.write_text(yaml.safe_dump(doc))
    return str(path)


def test_waves_a_hull_cannot_take_are_refused_before_the_run(tmp_path):
    """The planing hull is calm-water only (seed 004): refused with waves, fine on a calm sea;
    a displacement hull without its hydrodynamic data file, or with a damaged one, is refused
    naming the file (and the key); the shipped hulls take waves."""
    import shutil
    from scenario_format.scenario import ScenarioError, load_scenario
    from tug_dynamics.ship_file import ships_dir
    with pytest.raises(ScenarioError, match="(?s)key 'environment.waves': vessel 'boat'.*planing hull.*calm-water"):
        load_scenario(_ship_scenario(tmp_path, "planing_40ft.yaml", GOOD))
    load_scenario(_ship_scenario(tmp_path, "planing_40ft.yaml", {**GOOD, "hs": 0.0}))
    load_scenario(_ship_scenario(tmp_path, "harbour_tug.yaml", GOOD))
    own = tmp_path / "my_tug.yaml"
    shutil.copy(os.path.join(ships_dir(), "harbour_tug.yaml"), own)
    with pytest.raises(ScenarioError, match=r"(?s)vessel 'boat'.*hydro/my_tug.npz: hydrodynamic data file not found"):
        load_scenario(_ship_scenario(tmp_path, str(own), GOOD))
    (tmp_path / "hydro").mkdir()
    with np.load(os.path.join(ships_dir(), "hydro", "harbour_tug.npz")) as z:
        arrays = {k: z[k] for k in z.files}
    arrays["rao_phase"] = arrays["rao_phase"][:, :, :5]
    np.savez(tmp_path / "hydro" / "my_tug.npz", **arrays)
    with pytest.raises(ScenarioError, match=r"(?s)my_tug.npz.*rao_phase"):
        load_scenario(_ship_scenario(tmp_path, str(own), GOOD))
    assert load_scenario(_ship_scenario(tmp_path, "harbour_tug.yaml", GOOD)).warnings == []
