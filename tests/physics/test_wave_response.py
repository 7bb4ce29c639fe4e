"""Hydrodynamic data of the displacement hulls (ships/hydro/*.npz, scripts/hydro_data.py) and the
wave-response model (tug_dynamics.wave_response) against independent truths.

Truths and tolerances:
- long-wave limits (Newman 1977, 6.14; Faltinsen 1990 ch. 3): a free floating body follows the
  surface when the wave is long: heave RAO -> 1 (phase 0), roll RAO in beam seas -> k (the wave
  slope, phase +90 deg: port side up where the surface rises to port). Shipped box_barge_000 at
  its lowest frequency (0.2 rad/s, lambda = 31 L): 0.5 %, 0.03 rad.
- heave natural frequency (undamped, w^2 (m + A33(w)) = rho g A_wp): the shipped data against a
  Capytaine heave radiation run made here on the same mesh at other frequencies (1 %: the
  shipped grid's linear interpolation), and against a hand estimate w_n = sqrt(rho g A_wp /
  (m + A33)) with A33 = 1/2 C_A rho pi B^2 L / 4 (the high-frequency free-surface limit: half
  the infinite-fluid added mass of a thin rectangular plate, C_A(L/B) from DNV-RP-C205 (2010)
  App. D, Table D-2, 3-D bodies: 0.830 at 3, 0.871 at 4) (5 %: the plate value is a
  high-frequency limit).
- Froude-Krylov heave force on a box in long-crested head seas (Faltinsen 1990 ch. 3; only
  the bottom carries vertical pressure): F3 = rho g a B L e^(-kT) sin(kL/2)/(kL/2), zero at
  lambda = L. Capytaine's own incident-pressure integration on a box mesh made here (0.3 % of
  rho g a B L e^(-kT); the zero to 1e-9 of it).
- mean drift in short beam waves on a wall-sided hull tends to the total-reflection limit
  1/2 rho g a^2 L (Faltinsen 1990 ch. 5, Maruo 1960): shipped barge_002_full (draft 2.57 m;
  kT = 1.64 at the highest frequency, where a fixed barrier transmits a few % of the energy):
  mean over the five highest frequencies within 8 %, the highest within 5 %.
- response model: a regular wave; heave = a |RAO| cos(k.x - w t + arg RAO) exactly (1e-9);
  a vessel 200 m further along the wave direction: phase + k 200 (k = w^2/g, deep water);
  velocity = the time derivative along a moving track (finite differences, 1e-6 relative);
  drift = a^2 D, x4 for twice the height, x r(t)^2 in the ramp (1e-12).
- bad data files: ValueError naming the file and the key.
"""
import importlib.util
import math
import os

import numpy as np
import pytest

from sea_environment.waves import WaveField
from tug_dynamics.wave_response import HydroData, WaveResponse, hydro_path

ROOT = os.path.join(os.path.dirname(__file__), "..", "..")
G = 9.80665


def _capytaine():
    """Capytaine is in requirements.lock: missing is a broken environment, a failure (not a skip)."""
    try:
        import capytaine
    except ImportError as exc:  # pragma: no cover - environment error
        pytest.fail(f"capytaine is not installed ({exc}); install requirements.lock (capytaine==3.0.0)")
    capytaine.set_logging("ERROR")
    return capytaine


def _script():
    spec = importlib.util.spec_from_file_location("hydro_data", os.path.join(ROOT, "scripts", "hydro_data.py"))
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _index(values, x):
    i = int(np.argmin(np.abs(np.asarray(values) - x)))
    assert abs(values[i] - x) < 1e-9
    return i


def _heave_natural_frequency(omega, a33, m, c33):
    f = omega ** 2 * (m + a33) - c33
    i = int(np.where(np.diff(np.sign(f)) != 0)[0][0])
    return omega[i] - f[i] * (omega[i + 1] - omega[i]) / (f[i + 1] - f[i])


# ---- shipped data -------------------------------------------------------------------------------

def test_every_displacement_hull_has_valid_data():
    for ship in ("box_barge_000", "barge_002_model", "barge_002_full", "harbour_tug", "asd_tug", "s175_003"):
        h = HydroData.load(hydro_path(ship))
        assert h.ship == ship
        assert h.rao.shape == (len(h.omega), len(h.heading), 6) and h.drift.shape[2] == 3


def test_box_barge_long_wave_limits():
    h = HydroData.load(hydro_path("box_barge_000"))
    w0 = h.omega[0]
    k0 = w0 * w0 / G
    beam, head = _index(h.heading, math.pi / 2), _index(h.heading, math.pi)
    for ib in (beam, head):
        assert h.rao_amplitude[0, ib, 2] == pytest.approx(1.0, abs=0.005)
        assert abs(h.rao_phase[0, ib, 2]) < 0.03
    roll = h.rao[0, beam, 3]
    assert abs(roll) / k0 == pytest.approx(1.0, abs=0.005)
    assert np.angle(roll) == pytest.approx(math.pi / 2, abs=0.03)
    # starboard-side seas (mirrored half): roll of the opposite sign
    assert h.rao[0, _index(h.heading, 1.5 * math.pi), 3] == pytest.approx(-roll, rel=1e-12)


def test_box_barge_heave_natural_frequency():
    cpt = _capytaine()
    import xarray as xr
    h = HydroData.load(hydro_path("box_barge_000"))
    m, c33 = h.mass, h.hydrostatic_stiffness[2, 2]
    L, B, rho = h.length, h.beam, h.rho
    assert c33 == pytest.approx(rho * G * L * B, rel=1e-9)                    # A_wp = L B
    wn_shipped = _heave_natural_frequency(h.omega, h.added_mass[:, 2, 2], m, c33)

    hd = _script()
    p = hd.particulars(os.path.join(ROOT, "ros_ws", "src", "tug_dynamics", "ships", "box_barge_000.yaml"))
    body, nfaces, _ = hd.make_body(p, coarse=False)               # the shipped mesh
    assert nfaces == h.mesh_faces
    omega = np.linspace(1.2, 1.6, 5)
    test = xr.Dataset(coords=dict(omega=omega, radiating_dof=["Heave"], water_depth=[np.inf], rho=[rho], g=[G]))
    ds = cpt.BEMSolver().fill_dataset(test, body, progress_bar=False, _check_wavelength=False)
    a33 = ds["added_mass"].sel(influenced_dof="Heave", radiating_dof="Heave").squeeze().values
    wn_here = _heave_natural_frequency(omega, a33, m, c33)

    ca = 0.830 + (0.871 - 0.830) * (L / B - 3.0)                            # DNV plate, L/B = 3.33
    a33_hand = 0.5 * ca * rho * math.pi * B * B * L / 4.0
    wn_hand = math.sqrt(c33 / (m + a33_hand))
    print(f"heave w_n: shipped {wn_shipped:.4f}, Capytaine here {wn_here:.4f}, hand {wn_hand:.4f} rad/s")
    assert wn_here == pytest.approx(wn_shipped, rel=0.01)
    assert wn_hand == pytest.approx(wn_shipped, rel=0.05)


def test_froude_krylov_heave_on_a_box_in_head_seas():
    cpt = _capytaine()
    L, B, T, rho = 40.0, 10.0, 2.0, 1025.0
    mesh = cpt.mesh_parallelepiped(size=(L, B, T), center=(0.0, 0.0, -T / 2), resolution=(80, 10, 4),
                                   missing_sides={"top"})
    body = cpt.FloatingBody(mesh=mesh, dofs=cpt.rigid_body_dofs(only=["Heave"]))
    from capytaine.bem.airy_waves import froude_krylov_force
    for half_kl in (0.5, 1.5, math.pi, 4.0):
        k = 2.0 * half_kl / L
        pb = cpt.DiffractionProblem(body=body, wave_direction=math.pi, omega=math.sqrt(G * k), rho=rho, g=G,
                                    water_depth=np.inf)
        f3 = complex(froude_krylov_force(pb)["Heave"])
        scale = rho * G * B * L * math.exp(-k * T)
        exact = scale * math.sin(half_kl) / half_kl
        print(f"kL/2 = {half_kl:.3f}: FK heave {f3.real:.6g} {f3.imag:+.3g}j, closed form {exact:.6g} N/m")
        if half_kl == math.pi:                                                # lambda = L
            assert abs(f3) < 1e-9 * scale
        else:
            assert abs(f3 - exact) < 0.003 * scale


def test_drift_in_short_beam_waves_tends_to_total_reflection():
    h = HydroData.load(hydro_path("barge_002_full"))
    beam = _index(h.heading, math.pi / 2)
    ratio = h.drift[:, beam, 1] / (0.5 * h.rho * G * h.length)
    print("Y drift / (rho g L / 2), five highest frequencies:", np.round(ratio[-5:], 3))
    assert np.mean(ratio[-5:]) == pytest.approx(1.0, abs=0.08)
    assert ratio[-1] == pytest.approx(1.0, abs=0.05)
    assert np.all(np.abs(ratio[:3]) < 1e-3)                                 # long waves pass
    assert np.all(np.abs(h.drift[:, beam, 0]) < 1e-3 * np.max(np.abs(h.drift[:, beam, 1])))
    # head seas: pushed aft by 1/2 rho g a^2 B
    head = _index(h.heading, math.pi)
    assert h.drift[-1, head, 0] / (0.5 * h.rho * G * h.beam) == pytest.approx(-1.0, abs=0.05)


# ---- the response model -------------------------------------------------------------------------

def _regular(h, iw, beta_towards, height=2.0, ramp_time=0.0):
    return WaveField.regular(height, 2.0 * math.pi / h.omega[iw], direction=beta_towards, ramp_time=ramp_time)


def _phase(series, t, omega):
    """phi of A cos(w t - phi) fitted over whole periods."""
    c = 2.0 * np.mean(series * np.cos(omega * t))
    s = 2.0 * np.mean(series * np.sin(omega * t))
    return math.hypot(c, s), math.atan2(s, c)


def test_regular_wave_heave_amplitude_phase_and_spatial_shift():
    h = HydroData.load(hydro_path("box_barge_000"))
    iw = 12
    w = h.omega[iw]
    k = w * w / G
    psi_w, psi = 0.4, 0.4 - math.pi / 2                                      # beam seas from starboard
    ib = _index(h.heading, math.pi / 2)
    a = 1.0
    resp = WaveResponse(h, _regular(h, iw, psi_w, 2.0 * a))
    t = np.linspace(0.0, 2.0 * math.pi / w, 400, endpoint=False)
    amp, ph = h.rao_amplitude[iw, ib, 2], h.rao_phase[iw, ib, 2]
    heave_a = np.array([resp.motion(0.0, 0.0, psi, 0.0, ti)[0][2] for ti in t])
    assert np.max(np.abs(heave_a - a * amp * np.cos(-w * t + ph))) < 1e-9
    amp_a, ph_a = _phase(heave_a, t, w)
    assert amp_a == pytest.approx(a * amp, rel=1e-9) and ph_a == pytest.approx(ph, abs=1e-9)
    d = 200.0
    xb, yb = d * math.cos(psi_w), d * math.sin(psi_w)
    heave_b = np.array([resp.motion(xb, yb, psi, 0.0, ti)[0][2] for ti in t])
    amp_b, ph_b = _phase(heave_b, t, w)
    shift = math.remainder(ph_b - ph_a - k * d, 2.0 * math.pi)
    print(f"heave RAO {amp:.4f} phase {ph:.4f}; 200 m on: phase shift {ph_b - ph_a:.4f} vs k x = {k * d:.4f} (mod 2 pi)")
    assert amp_b == pytest.approx(amp_a, rel=1e-9) and abs(shift) < 1e-9


def test_velocity_is_the_derivative_along_a_moving_track():
    h = HydroData.load(hydro_path("asd_tug"))
    wf = WaveField.irregular(2.0, 7.0, direction=1.0, components=120, spreading_s=8.0, seed=3, ramp_time=20.0)
    resp = WaveResponse(h, wf)
    x0, y0, psi, u = 30.0, -40.0, 2.5, 4.0

    def pos(t):
        return x0 + u * math.cos(psi) * t, y0 + u * math.sin(psi) * t

    for t0 in (7.0, 55.0):                                                     # in and after the ramp
        dt = 1e-4
        fd = (resp.motion(*pos(t0 + dt), psi, u, t0 + dt)[0] - resp.motion(*pos(t0 - dt), psi, u, t0 - dt)[0]) / (2 * dt)
        vel = resp.motion(*pos(t0), psi, u, t0)[1]
        assert np.allclose(vel, fd, rtol=1e-6, atol=1e-6 * np.max(np.abs(vel)))


def test_encounter_frequency_in_head_seas():
    h = HydroData.load(hydro_path("s175_003"))
    iw = 10
    w = h.omega[iw]
    k = w * w / G
    u = 8.0
    resp = WaveResponse(h, _regular(h, iw, 0.0, 2.0))
    psi = math.pi                                                              # heading west into the waves
    we = w - k * u * math.cos(math.pi)                                         # beta = 180 deg: w + k U
    t = np.linspace(0.0, 4.0 * 2.0 * math.pi / we, 800, endpoint=False)
    heave = np.array([resp.motion(-u * ti, 0.0, psi, u, ti)[0][2] for ti in t])
    amp, _ = _phase(heave, t, we)
    assert amp == pytest.approx(1.0 * h.rao_amplitude[iw, _index(h.heading, math.pi), 2], rel=1e-9)


def test_drift_scales_with_amplitude_squared_and_ramp():
    h = HydroData.load(hydro_path("harbour_tug"))
    iw, psi_w, psi = 20, 0.3, 0.3 - 2.0 * math.pi / 3                          # beta = 120 deg (bow-quartering)
    ib = _index(h.heading, 2.0 * math.pi / 3)
    f1 = WaveResponse(h, _regular(h, iw, psi_w, 1.0)).drift_force(psi, 0.0)
    assert np.allclose(f1, 0.25 * h.drift[iw, ib], rtol=1e-12, atol=0)
    f2 = WaveResponse(h, _regular(h, iw, psi_w, 2.0)).drift_force(psi, 0.0)
    assert np.allclose(f2, 4.0 * f1, rtol=1e-12)
    ramped = WaveResponse(h, _regular(h, iw, psi_w, 2.0, ramp_time=40.0))
    assert np.allclose(ramped.drift_force(psi, 20.0), 0.25 * f2, rtol=1e-12)   # r = 1/2
    assert np.allclose(ramped.drift_force(psi, 0.0), 0.0)
    assert np.allclose(ramped.evaluate(0.0, 0.0, psi, 0.0, 50.0).drift, f2, rtol=1e-12)


# ---- bad files ----------------------------------------------------------------------------------

def _copy(tmp_path, change):
    with np.load(hydro_path("box_barge_000")) as z:
        data = {k: z[k] for k in z.files}
    change(data)
    path = tmp_path / "bad.npz"
    np.savez(path, **data)
    return str(path)


@pytest.mark.parametrize("key, change", [
    ("drift", lambda d: d.pop("drift")),
    ("rao_phase", lambda d: d.__setitem__("rao_phase", d["rao_phase"][:, :-1])),
    ("rao_amplitude", lambda d: d["rao_amplitude"].__setitem__((3, 2, 1), np.nan)),
    ("added_mass", lambda d: d["added_mass"].__setitem__((0, 0, 0), np.inf)),
    ("omega", lambda d: d.__setitem__("omega", d["omega"][::-1].copy())),
    ("format_version", lambda d: d.__setitem__("format_version", np.int64(99))),
])
def test_bad_files_name_file_and_key(tmp_path, key, change):
    path = _copy(tmp_path, change)
    with pytest.raises(ValueError) as err:
        HydroData.load(path)
    assert str(path) in str(err.value) and f"'{key}'" in str(err.value)


def test_missing_file_is_named(tmp_path):
    with pytest.raises(ValueError, match="nowhere.npz"):
        HydroData.load(str(tmp_path / "nowhere.npz"))
