"""Propeller wash (tug_dynamics.propeller_wash), without ROS.

Truths used:
- Blaauw & van de Kaa (1978), as in PIANC WG 180 (2015): V_max = 2.8 V0 D0 / x and
  V = V_max exp(-15.4 r^2 / x^2), evaluated here by hand; the half-velocity radius
  r_1/2 = x sqrt(ln 2 / 15.4) = 0.2122 x by hand;
- axial momentum theory by hand: V0 = sqrt(4 T / (rho pi D0^2)); for an open propeller
  (D0 = D / sqrt 2) with T = K_T rho n^2 D^4 that is sqrt(8 / pi) n D sqrt(K_T) (Fuehrer & Roemisch's 1.59);
- the jet's momentum flux int rho V^2 dA by scipy.integrate.quad, against T and 4 * 2.8^2 / 30.8;
- a jet straight at the hull side: the intercepted fraction is a product of two error functions
  (Gaussian over a rectangle, the surface mirror), by hand; at an angle: scipy.integrate.dblquad of
  the fraction's integrand written here from the velocity formula.
"""
import math
import time

import numpy as np
import pytest
from scipy import integrate

from tug_dynamics.propeller_wash import HullSide, PropellerJet, efflux_velocity, jet_velocity
from tug_dynamics.ship_file import load_ship
from tug_dynamics.vessel import VesselState

RHO = 1025.0
THRUST = 282e3                       # one ASD tug unit: 57.56 t bollard pull over two, N
DIAMETER = 2.4                       # m, in a nozzle (asd_tug.yaml)
DEPTH = 3.9                          # m, the units' axis below the waterline
S175_DRAFT = 8.5
S175_HALF = 87.5


def test_efflux_velocity_by_momentum_theory():
    assert efflux_velocity(THRUST, DIAMETER) == pytest.approx(math.sqrt(4 * THRUST / (RHO * math.pi * 2.4 ** 2)))
    kt, n, d = 0.35, 3.0, 3.0
    open_v0 = efflux_velocity(kt * RHO * n ** 2 * d ** 4, d, ducted=False)
    assert open_v0 == pytest.approx(1.5958 * n * d * math.sqrt(kt), rel=1e-4)
    assert open_v0 == pytest.approx(1.59 * n * d * math.sqrt(kt), rel=0.004)


@pytest.mark.parametrize("x_over_d0", [2.8, 5.0, 10.0, 20.0])
def test_centreline_and_spread_blaauw_van_de_kaa(x_over_d0):
    jet = PropellerJet(THRUST, DIAMETER, DEPTH)
    x = x_over_d0 * jet.d0
    v_max = 2.8 * jet.v0 / x_over_d0
    assert jet.velocity(x, 0.0) == pytest.approx(v_max, rel=1e-12)
    r_half = x * math.sqrt(math.log(2.0) / 15.4)
    assert r_half == pytest.approx(0.2122 * x, rel=1e-3)
    assert jet.velocity(x, r_half) == pytest.approx(0.5 * v_max, rel=1e-12)
    assert jet.velocity(x, 0.3 * x) == pytest.approx(v_max * math.exp(-15.4 * 0.09), rel=1e-12)


def test_zone_of_flow_establishment_holds_v0_and_upstream_is_still():
    jet = PropellerJet(THRUST, DIAMETER, DEPTH)
    for x in (0.1, 1.0, 2.7 * jet.d0):
        assert jet.velocity(x, 0.0) == pytest.approx(jet.v0, rel=1e-12)
    assert jet.velocity(-1.0, 0.0) == 0.0


@pytest.mark.parametrize("x_over_d0", [1.0, 5.0, 30.0])
def test_momentum_flux_equals_the_thrust(x_over_d0):
    """int rho V^2 2 pi r dr = T (4 * 2.8^2 / 30.8 = 1.0182: the published constants carry 1.8 % more)."""
    jet = PropellerJet(THRUST, DIAMETER, DEPTH)
    x = x_over_d0 * jet.d0
    flux = integrate.quad(lambda r: RHO * jet_velocity(x, r, jet.v0, jet.d0) ** 2 * 2 * math.pi * r,
                          0.0, np.inf, epsabs=0.0, epsrel=1e-10)[0]
    assert flux == pytest.approx(4 * 2.8 ** 2 / 30.8 * THRUST, rel=1e-6)
    assert flux == pytest.approx(THRUST, rel=0.02)


def fraction_by_dblquad(jet, side, offset, psi):
    """The fraction of the jet's momentum flux the side takes, (V^2 + mirror V^2) / flux integrated
    over the side's u and depth, V from the jet's formula."""
    flux = jet.v0 ** 2 * math.pi * (2.8 * jet.d0) ** 2 / 30.8      # V_max^2 pi x^2 / 30.8, all x

    def density(z, u):
        x = u * math.cos(psi) + offset * math.sin(psi)
        h2 = u * u + offset * offset - x * x
        v2 = sum(jet_velocity(x, math.sqrt(max(h2, 0.0) + (z - zp) ** 2), jet.v0, jet.d0) ** 2
                 for zp in (-jet.depth, jet.depth))
        return v2 / flux
    return integrate.dblquad(density, side.u_start, side.u_end, -side.draft, 0.0, epsabs=1e-10, epsrel=1e-8)[0]


@pytest.mark.parametrize("offset", [10.0, 30.0, 60.0])
def test_pulling_with_the_wash_on_the_hull_by_hand(offset):
    """Jet straight at the side: F = T (1/4) [erf(sqrt a (draft + zp)) - erf(sqrt a (zp - draft))]
    [erf(sqrt a u1) - erf(sqrt a u0)], a = 30.8 / x^2; delivered T - F, less than the bollard pull."""
    jet = PropellerJet(THRUST, DIAMETER, DEPTH)
    side = HullSide(-S175_HALF, S175_HALF, S175_DRAFT)
    ra = math.sqrt(30.8) / max(offset, 2.8 * jet.d0)
    fraction = 0.25 * (math.erf(ra * (S175_DRAFT + DEPTH)) - math.erf(ra * (DEPTH - S175_DRAFT))) \
        * (math.erf(ra * S175_HALF) - math.erf(-ra * S175_HALF))
    normal, along = jet.pull_delivered(side, offset, 0.5 * math.pi)
    assert normal == pytest.approx(THRUST * (1.0 - fraction), rel=1e-6, abs=2e-5 * THRUST)
    assert along == pytest.approx(normal, rel=1e-12)
    assert 0.0 <= normal < THRUST


@pytest.mark.parametrize("psi_deg, offset", [(60.0, 25.0), (30.0, 20.0)])
def test_oblique_jet_on_the_hull_against_quadrature(psi_deg, offset):
    jet = PropellerJet(THRUST, DIAMETER, DEPTH)
    side = HullSide(-60.0, 115.0, S175_DRAFT)
    psi = math.radians(psi_deg)
    want = THRUST * math.sin(psi) ** 2 * fraction_by_dblquad(jet, side, offset, psi)
    assert jet.wash_force(side, offset, psi) == pytest.approx(want, rel=1e-4, abs=2e-5 * THRUST)


@pytest.mark.parametrize("angle_deg", [8.0, 10.0, 15.0])
def test_pushing_at_a_shallow_angle_delivers_less_than_at_90_degrees(angle_deg):
    """ASD tug's bow on the S-175's side at midship, propeller 26.5 m behind it: the wash leaving
    along the hull takes T sin^2(a) x (fraction) as suction: less push per unit thrust than at 90 deg."""
    jet = PropellerJet(THRUST, DIAMETER, DEPTH)
    lever, angle = 26.5, math.radians(angle_deg)
    contact = -lever * math.cos(angle)                     # the bow, from the propeller's foot
    side = HullSide(contact - S175_HALF, contact + S175_HALF, S175_DRAFT)
    suction = THRUST * math.sin(angle) ** 2 * fraction_by_dblquad(jet, side, lever * math.sin(angle), -angle)
    push = jet.push_delivered(side, lever, angle)
    assert push == pytest.approx(THRUST * math.sin(angle) - suction, abs=2e-5 * THRUST)
    assert suction > 1e-4 * THRUST * math.sin(angle)
    assert push / (THRUST * math.sin(angle)) < jet.push_delivered(side, lever, 0.5 * math.pi) / THRUST == 1.0


@pytest.mark.parametrize("kwargs, word", [
    (dict(thrust=-1.0), "thrust"), (dict(thrust=float("nan")), "thrust"), (dict(diameter=0.0), "diameter"),
    (dict(diameter=float("inf")), "diameter"), (dict(propeller_depth=-2.0), "propeller_depth"),
    (dict(water_density=0.0), "water_density")])
def test_bad_input_names_the_value(kwargs, word):
    args = dict(thrust=THRUST, diameter=DIAMETER, propeller_depth=DEPTH) | kwargs
    with pytest.raises(ValueError, match=word):
        PropellerJet(**args)


@pytest.mark.parametrize("call, word", [
    (lambda j, s: j.wash_force(s, 0.0, 1.0), "offset"), (lambda j, s: j.wash_force(s, 10.0, float("nan")), "psi"),
    (lambda j, s: j.wash_force(s, 10.0, 2.0), "psi"),
    (lambda j, s: j.push_delivered(s, 20.0, 0.0), "angle"), (lambda j, s: HullSide(5.0, 5.0, 8.0), "u_end"),
    (lambda j, s: HullSide(0.0, 5.0, -8.0), "draft")])
def test_bad_geometry_names_the_value(call, word):
    with pytest.raises(ValueError, match=word):
        call(PropellerJet(THRUST, DIAMETER, DEPTH), HullSide(-S175_HALF, S175_HALF, S175_DRAFT))


def best_time(fn, repeats=5, calls=300):
    best = math.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(calls):
            fn()
        best = min(best, (time.perf_counter() - t0) / calls)
    return best


def test_cost_against_one_s175_step():
    """Ratios only (printed): one wash evaluation against one bare S-175 Vessel.step."""
    ship = load_ship("s175_003.yaml")
    ship.set_state(VesselState(np.zeros(3), np.zeros(3), np.array([3.0, 0.0, 0.0]), np.zeros(3)))
    jet = PropellerJet(THRUST, DIAMETER, DEPTH)
    side = HullSide(-S175_HALF, S175_HALF, S175_DRAFT)
    jet.wash_force(side, 30.0, 1.0)                        # compile / load the numba cache
    step = best_time(lambda: ship.step(0.05))
    normal = best_time(lambda: jet.wash_force(side, 30.0, 0.5 * math.pi))
    oblique = best_time(lambda: jet.wash_force(side, 20.0, math.radians(30.0)))
    print(f"\nwash / S-175 step: normal {normal / step:.3f}, oblique {oblique / step:.3f}")
    assert normal < 2.0 * step and oblique < 2.0 * step
