"""Shallow water, whole (tug_dynamics README "Shallow water", sea_environment.shallow_water): the
factors against hand arithmetic of the README's equations (S1)-(S9) and UFC 4-159-03's worked
example, every term of each hull form taking its factor, the S-175's hard-over turn widening
steadily as the water shoals, and the stopped S-175's drift in a beam wind (README "Beam-on drag")."""
import math

import numpy as np
import pytest

from sea_environment import shallow_water as sw
from tug_dynamics import maneuvering as mv
from tug_dynamics.maneuver_trials import KN, run, turning_metrics
from tug_dynamics.ship_file import load_ship
from tug_dynamics.vessel import Command, ExternalWrench, VesselState

L, B, T, CB = 175.0, 25.4, 8.5, 0.559          # S-175, seed 003 Table 1
CD0 = 0.761                                    # s175_003.yaml hull.beam_on_drag
HALF = 44.5 / 89.0                             # half ahead: 9 kn (seed 003 Table 1)


def test_factors_by_hand_for_the_s175_at_h_over_t_1_5():
    """Each factor at h/T = 1.5 (h' = T/h = 2/3, F = 0.5) worked by hand from the README's
    equations, digits carried from a calculator (k = 2T/L = 0.097143; at h' = 2/3:
    a = pi/3, (pi/3) cot(pi/3) = 0.604600, so k_e(q) = k / (1/3 + 0.604600^q))."""
    f = sw.shallow_water_factors(L, B, T, CB, 1.5 * T, CD0)
    k = 0.0971429
    ke = {q: k / (1.0 / 3.0 + 0.604600 ** q) for q in (2.3, 0.7, 1.7)}
    # 0.604600^2.3 = 0.314323, ^0.7 = 0.703117, ^1.7 = 0.425104
    assert ke[2.3] == pytest.approx(k / 0.647656, rel=1e-5)
    assert ke[0.7] == pytest.approx(k / 1.036450, rel=1e-5)
    assert ke[1.7] == pytest.approx(k / 0.758438, rel=1e-5)
    cbl = 1.4 * 0.559 * 25.4 / 175.0                       # 0.113589
    assert f[sw.SW_YV] == pytest.approx((1.570796 * k / 0.647656 + cbl) / (1.570796 * k + cbl), rel=1e-5)
    assert f[sw.SW_YR] == pytest.approx(1.0 / 1.036450, rel=1e-5)                   # 0.964832
    assert f[sw.SW_NV] == pytest.approx(1.0 / 0.758438, rel=1e-5)                   # 1.318499
    ke07 = k / 1.036450
    assert f[sw.SW_NR] == pytest.approx((0.54 * ke07 - ke07 ** 2) / (0.54 * k - k * k), rel=1e-5)
    assert f[sw.SW_NONLINEAR] == pytest.approx(1.0 + 6.0 * 0.362887, rel=1e-5)   # (2/3)^2.5
    assert f[sw.SW_XVV] == pytest.approx(1.0 + 27.7 * 4 / 9 - 70.8 * 16 / 81, rel=1e-9)
    assert f[sw.SW_XVR] == pytest.approx(1.0 + 1.3 * 4 / 9, rel=1e-9)
    assert f[sw.SW_RESISTANCE] == pytest.approx(1.0 + 0.388 * 4 / 9, rel=1e-9)
    assert f[sw.SW_ONE_MINUS_T] == pytest.approx(1.0 / (1.0 - 0.2 * 2 / 3 + 0.7295 * 4 / 9), rel=1e-9)
    assert f[sw.SW_ONE_MINUS_W] == pytest.approx(math.cos(1.4 * 0.559 * 2 / 3), rel=1e-9)   # 0.866957
    assert f[sw.SW_GAMMA] == pytest.approx(1.0 + 0.0161 * 2 / 3 + 4.4222 * 4 / 9 - 4.9825 * 8 / 27, rel=1e-9)
    # added masses, F = 0.5: F^1.3 = 0.406126, F^0.82 = 0.566442; B/T = 2.988235, L/T = 20.588235
    assert f[sw.SW_MX] == pytest.approx((0.406126 + 3.77 + 1.14 * 2.988235 - 0.233 * 20.588235 - 3.43 * 0.559)
                                        / 0.406126, rel=1e-5)
    assert f[sw.SW_MY] == pytest.approx((0.566442 + 0.413 + 0.032 * 2.988235 + 0.129 * 8.929551) / 0.566442,
                                        rel=1e-5)
    assert f[sw.SW_JZ] == pytest.approx((0.566442 + 0.413 + 0.0192 * 2.988235 + 0.00554 * 8.929551) / 0.566442,
                                        rel=1e-5)
    assert f[sw.SW_CROSSFLOW] == pytest.approx((0.761 + (3.2 - 0.761) * 4 / 9) / 0.761, rel=1e-9)  # 2.424


def test_factors_are_exactly_deep_beyond_h_over_t_4_and_fade_from_3():
    """Our deep-water bound (README): all 1 at h/T >= 4 and in deep water; the raw factors at
    h/T <= 3; half-way between at h/T = 3.5."""
    for ratio in (4.0, 4.5, 10.0, math.inf):
        assert list(sw.shallow_water_factors(L, B, T, CB, ratio * T, CD0)) == [1.0] * sw.N_SW
    f3 = sw.shallow_water_factors(L, B, T, CB, 3.0 * T, CD0)
    assert f3[sw.SW_NONLINEAR] == pytest.approx(1.0 + 6.0 * (1.0 / 3.0) ** 2.5, rel=1e-12)
    f35 = sw.shallow_water_factors(L, B, T, CB, 3.5 * T, CD0)
    raw = 1.0 + 6.0 * (1.0 / 3.5) ** 2.5
    assert f35[sw.SW_NONLINEAR] == pytest.approx(1.0 + 0.5 * (raw - 1.0), rel=1e-12)
    # below h/T = 1.1 the factors hold their value there
    assert list(sw.shallow_water_factors(L, B, T, CB, 1.0 * T, CD0)) == \
        list(sw.shallow_water_factors(L, B, T, CB, 1.1 * T, CD0))


def test_crossflow_growth_reproduces_the_ufc_worked_example():
    """UFC 4-159-03 Table 4-6 (FFG-7, current 1.5 m/s): side force 0.55, 0.66, 1.03, 1.30, 1.90 MN
    at T/d = 0.096, 0.288, 0.576, 0.72, 0.96. The force is proportional to C_yc, so its ratios
    test Eq 11's shape (C1 = 3.2, K = 2). C0 from the first and last rows by hand:
    (C0 + (3.2 - C0) 0.9216) / (C0 + (3.2 - C0) 0.009216) = 1.90 / 0.55 gives C0 = 0.852 (FFG-7:
    L C_m / (C_b B) about 14.8, 0.22 sqrt(14.8) = 0.85, Eq 12-13)."""
    c0 = (3.2 * 0.9216 - 3.2 * 0.009216 * 1.90 / 0.55) / (1.90 / 0.55 * (1.0 - 0.009216) - (1.0 - 0.9216))
    assert c0 == pytest.approx(0.852, abs=0.001)
    table = {0.096: 0.55, 0.288: 0.66, 0.576: 1.03, 0.72: 1.30, 0.96: 1.90}
    for t_over_d, force in table.items():
        ratio = sw.ufc_crossflow_factor(c0, t_over_d) / sw.ufc_crossflow_factor(c0, 0.096)
        assert ratio == pytest.approx(force / 0.55, rel=0.02), t_over_d      # the table's 2 digits
    # the S-175's deep-water C_D (ship file) is UFC Eq 12-13 with C_m 0.97
    assert sw.ufc_deep_crossflow_drag(L, B, CB, 0.97) == pytest.approx(0.22 * math.sqrt(175 * 0.97 / (0.559 * 25.4)))
    assert load_ship("s175_003.yaml").hp[mv.H_SW_CD0] == pytest.approx(sw.ufc_deep_crossflow_drag(L, B, CB, 0.97),
                                                                        abs=5e-4)


@pytest.mark.parametrize("ship_file", ["s175_003.yaml", "barge_002_full.yaml", "box_barge_000.yaml",
                                       "asd_tug.yaml", "harbour_tug.yaml"])
def test_set_depth_puts_a_factor_on_every_term_the_form_has(ship_file):
    """After set_depth every hull coefficient is its deep value times its factor (the form's table
    in maneuvering._SW_KINDS), the added masses (mass matrix) are scaled, and a return to deep
    water restores the ship exactly."""
    ship = load_ship(ship_file)
    deep_hp, deep_minv = ship.hp.copy(), ship.minv.copy()
    ratio = 1.5
    ship.set_depth(ratio * ship.draft)
    block = ship.volume / (ship.length * ship.beam * ship.draft)
    f = sw.shallow_water_factors(ship.length, ship.beam, ship.draft, block, ratio * ship.draft,
                                 deep_hp[mv.H_SW_CD0])
    kinds = mv._SW_KINDS[int(ship.hp[mv.H_FORM])]
    for i, kind in enumerate(kinds):
        want = deep_hp[mv.H_C0 + i] * (f[kind] if kind >= 0 else 1.0)
        assert ship.hp[mv.H_C0 + i] == pytest.approx(want, rel=1e-12), (ship_file, i)
    m = np.linalg.inv(deep_minv)
    m[0, 0] += deep_hp[mv.H_ADD0] * (f[sw.SW_MX] - 1.0)
    m[1, 1] += deep_hp[mv.H_ADD0 + 1] * (f[sw.SW_MY] - 1.0)
    m[2, 2] += deep_hp[mv.H_ADD0 + 2] * (f[sw.SW_JZ] - 1.0)
    assert np.allclose(np.linalg.inv(ship.minv), m, rtol=1e-9)
    assert ship.hp[mv.H_SWF + sw.SW_ONE_MINUS_W] == f[sw.SW_ONE_MINUS_W] < 1.0
    ship.set_depth(math.inf)
    assert np.array_equal(ship.hp[mv.H_C0:mv.H_C0 + 16], deep_hp[mv.H_C0:mv.H_C0 + 16])
    assert np.allclose(ship.minv, deep_minv, rtol=1e-12)


def _hard_over_turn(depth_ratio):
    ship = load_ship("s175_003.yaml")
    if depth_ratio is not None:
        ship.set_depth(depth_ratio * ship.draft)
    ship.set_state(VesselState(np.zeros(3), np.zeros(3), np.array([9.0 * KN, 0.0, 0.0]), np.zeros(3)))
    ship.settle_command(Command(HALF, 0.0))
    return turning_metrics(run(ship, 1200.0, 1.0, {0.0: Command(HALF, math.radians(35.0))}))


def test_s175_hard_over_turn_widens_steadily_as_the_water_shoals():
    """35 deg rudder from 9 kn (half ahead): the tactical diameter and advance are the deep-water
    ones for h/T >= 4 and grow at every step as h/T falls 4 -> 1.2 (full-scale trials and MMG
    models: the circle widens as the water shoals, markedly below h/T 2). Measured (L = 175 m):
    tactical diameter 4.09 L deep, 4.47 L at h/T 3, 4.86 L at 2, 5.18 L at 1.5, 5.33 L at 1.2."""
    deep = _hard_over_turn(None)
    for ratio in (4.0, 6.0):
        m = _hard_over_turn(ratio)
        assert m["tactical_diameter"] == pytest.approx(deep["tactical_diameter"], rel=1e-12)
        assert m["advance"] == pytest.approx(deep["advance"], rel=1e-12)
    ratios = (4.0, 3.5, 3.0, 2.5, 2.0, 1.5, 1.2)
    td = [_hard_over_turn(r)["tactical_diameter"] for r in ratios]
    assert all(b > a for a, b in zip(td, td[1:])), [round(x / L, 3) for x in td]
    assert td[-1] > 1.2 * deep["tactical_diameter"]


@pytest.mark.parametrize("depth_ratio", [None, 1.5])
def test_stopped_s175_drifts_where_beam_wind_meets_crossflow_drag(depth_ratio):
    """A stopped S-175 (engine stopped, rudder amidships) in a 30 kn wind from abeam (port) drifts
    to starboard at the speed v where the wind's side force on the apparent wind W - v meets the
    hull's cross-flow drag: C_Y 1/2 rho_a A_L (W - v)^2 = 1/2 rho C_D L T v^2, so
    v = W sqrt(a) / (sqrt(a) + sqrt(b)), a = C_Y 1/2 rho_a A_L, b = 1/2 rho C_D L T. C_D = 0.761
    deep (UFC 4-159-03 Eq 12-13) and 0.761 + (3.2 - 0.761) (1/1.5)^2 = 1.845 at h/T = 1.5 (Eq 11).
    The wind force is applied at midship (no yaw) from Blendermann's C_Y at 90 deg (sea_environment
    wind_loads, its own tests). Measured: within 0.1 %; tolerance 0.5 %."""
    from sea_environment.wind_loads import RHO_AIR, blendermann_coefficients, wind_wrench_body
    ship = load_ship("s175_003.yaml")
    cd = 0.761
    if depth_ratio is not None:
        ship.set_depth(depth_ratio * T)
        cd = 0.761 + (3.2 - 0.761) / depth_ratio ** 2
    wind = 30.0 * KN
    w = ship.windage

    def beam_wind(vessel, _t):
        v = vessel.state.linear_velocity_body[1]                 # < 0: drifting to starboard
        _x, y, _xp, _zp, _n = wind_wrench_body(wind + v, math.pi / 2, w)   # apparent wind from port
        psi = vessel.state.rpy[2]
        return [ExternalWrench(np.array([-math.sin(psi) * y, math.cos(psi) * y, 0.0]), np.zeros(3), np.zeros(3))]

    ship.set_state(VesselState(np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(3)))
    tr = run(ship, 1500.0, 1.0, {0.0: Command(0.0, 0.0)}, wrenches=beam_wind)
    cy = blendermann_coefficients(math.pi / 2, w)[1]
    a = cy * 0.5 * RHO_AIR * w.lateral_area
    b = 0.5 * 1025.0 * cd * L * T
    v_hand = wind * math.sqrt(a) / (math.sqrt(a) + math.sqrt(b))
    assert abs(tr.v[-1] - tr.v[-100]) < 1e-4 * abs(tr.v[-1])            # steady
    assert -tr.v[-1] == pytest.approx(v_hand, rel=0.005)
    assert abs(tr.u[-1]) < 1e-3 and abs(tr.r[-1]) < 1e-6


def test_an_attached_environment_sets_the_same_factors_as_set_depth():
    """The depth sampled every step (environment_loads, the vessel node's path) and set_depth give
    the ship the same coefficients and mass matrix."""
    from sea_environment.environment import Environment
    from tug_dynamics.environment_loads import VesselInEnvironment
    direct = load_ship("s175_003.yaml")
    direct.set_depth(1.5 * T)
    sampled = load_ship("s175_003.yaml")
    VesselInEnvironment(sampled, Environment.from_mapping({"depth": 1.5 * T}))
    assert np.array_equal(sampled.hp[mv.H_C0:mv.H_C0 + 16], direct.hp[mv.H_C0:mv.H_C0 + 16])
    assert np.array_equal(sampled.hp[mv.H_SWF:mv.H_SWF + sw.N_SW], direct.hp[mv.H_SWF:mv.H_SWF + sw.N_SW])
    assert np.allclose(sampled.minv, direct.minv, rtol=1e-14)


def test_ship_form_regressions_apply_to_ship_forms_only():
    """(S4)'s X'vv, X'vr and (S8) (ship-form regressions) are 1 outside L/T >= 10, B/T <= 4 (the
    box barge: S8 would give m_x x 95); the rest applies to every hull. The S-175 gets them."""
    box = sw.shallow_water_factors(50.0, 15.0, 0.5, 0.9, 1.2 * 0.5, 1.0)     # box_barge_000, B/T 30
    tug = sw.shallow_water_factors(24.0, 8.0, 3.0, 0.5, 1.2 * 3.0, 1.0)      # harbour_tug, L/T 8
    for f in (box, tug):
        assert [f[i] for i in (sw.SW_XVV, sw.SW_XVR, sw.SW_MX, sw.SW_MY, sw.SW_JZ)] == [1.0] * 5
        assert f[sw.SW_NONLINEAR] == pytest.approx(1.0 + 6.0 / 1.2 ** 2.5, rel=1e-12)
        assert f[sw.SW_CROSSFLOW] == pytest.approx(1.0 + 2.2 / 1.44, rel=1e-12)
    s175 = sw.shallow_water_factors(L, B, T, CB, 1.2 * T, CD0)
    assert s175[sw.SW_MY] > 1.0 and s175[sw.SW_XVR] == pytest.approx(1.0 + 1.3 / 1.44, rel=1e-12)
