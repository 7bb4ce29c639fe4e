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


def fraction_by_dblquad(jet, side, offset, psi, weight=lambda u: 1.0):
    """The fraction of the jet's momentum flux the side takes, (V^2 + mirror V^2) / flux integrated
    over the side's u and depth, V from the jet's formula (times weight(u): the first moment)."""
    flux = jet.v0 ** 2 * math.pi * (2.8 * jet.d0) ** 2 / 30.8      # V_max^2 pi x^2 / 30.8, all x

    def density(z, u):
        x = u * math.cos(psi) + offset * math.sin(psi)
        h2 = u * u + offset * offset - x * x
        v2 = sum(jet_velocity(x, math.sqrt(max(h2, 0.0) + (z - zp) ** 2), jet.v0, jet.d0) ** 2
                 for zp in (-jet.depth, jet.depth))
        return weight(u) * v2 / flux
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


# ---- the wash on a hull in a run (wash_on_hull; InteractionSet's washes) --------------------------
S175_BEAM = 25.4


@pytest.mark.parametrize("px, jet_deg, offset", [(10.0, -90.0, 30.0), (-40.0, -60.0, 25.0), (30.0, -150.0, 20.0),
                                                 (0.0, 170.0, 12.0)])
def test_wash_on_a_box_hull_against_quadrature(px, jet_deg, offset):
    """A jet from a propeller `offset` m off the S-175's port side at x = px, heading jet_deg (the
    hull's axes): the sway force is the side's normal momentum (toward starboard when the jet heads
    at the hull, suction to port when it leaves it) and the moment puts it at the intercepted
    flux's centroid, both by dblquad of the jet's formula over the side (u from the foot along the
    jet's along-hull part)."""
    from tug_dynamics.propeller_wash import GAUSS_W, GAUSS_X, wash_on_hull
    jet = PropellerJet(THRUST, DIAMETER, DEPTH)
    jx, jy = math.cos(math.radians(jet_deg)), math.sin(math.radians(jet_deg))
    psi = math.asin(-jy)                        # to the port side (normal -y), positive toward it
    along = 1.0 if jx >= 0.0 else -1.0
    side = HullSide(min(along * (-S175_HALF - px), along * (S175_HALF - px)),
                    max(along * (-S175_HALF - px), along * (S175_HALF - px)), S175_DRAFT)
    fraction = fraction_by_dblquad(jet, side, offset, psi)
    first = fraction_by_dblquad(jet, side, offset, psi, weight=lambda u: u)
    fy, n = wash_on_hull(THRUST, jet.d0, DEPTH, 1.0, px, 0.5 * S175_BEAM + offset, jx, jy, 2 * S175_HALF,
                         S175_BEAM, S175_DRAFT, GAUSS_X, GAUSS_W)
    want = -math.copysign(THRUST * math.sin(psi) ** 2 * fraction, psi)
    assert fy == pytest.approx(want, rel=1e-4, abs=2e-5 * THRUST)
    assert n / fy == pytest.approx(px + along * first / fraction, abs=0.05)
    # the starboard side, mirrored: the same force to the other side, the same lever
    fs, ns = wash_on_hull(THRUST, jet.d0, DEPTH, 1.0, px, -0.5 * S175_BEAM - offset, jx, -jy, 2 * S175_HALF,
                          S175_BEAM, S175_DRAFT, GAUSS_X, GAUSS_W)
    assert (fs, ns) == pytest.approx((-fy, -n), rel=1e-12)


def test_a_jet_wholly_stopped_by_the_side_gives_the_thrust():
    """Momentum: a jet straight at a long, deep side 1 m away (all of it within the hull's draft)
    pushes the hull with the jet's whole momentum: T (the wash takes the fraction of the jet's flux)."""
    from tug_dynamics.propeller_wash import GAUSS_W, GAUSS_X, wash_on_hull
    d0 = 2.4
    fy, n = wash_on_hull(THRUST, d0, 10.0, 1.0, 0.0, 13.7, 0.0, -1.0, 175.0, 25.4, 30.0, GAUSS_X, GAUSS_W)
    assert -fy == pytest.approx(THRUST, rel=1e-4)
    assert abs(n) < 1e-9 * THRUST


def _asd_beside_the_ship(tug_yaw_from_ship):
    """The ASD tug's stern 20 m off the S-175's port side at x = 30 m (the ship at (100, 50), heading
    30 deg), the tug heading tug_yaw_from_ship relative to the ship."""
    from tug_dynamics.interaction_set import PlanarState
    ship = PlanarState(100.0, 50.0, math.radians(30.0), 0.0, 0.0)
    c, s = math.cos(ship.yaw), math.sin(ship.yaw)
    yaw = ship.yaw + tug_yaw_from_ship
    # the tug's midship so that its stern units' mid-point (x = -11.5) sits at (30, 12.7 + 20) in the ship's axes
    bx, by = 30.0 + 11.5 * math.cos(tug_yaw_from_ship), 32.7 + 11.5 * math.sin(tug_yaw_from_ship)
    tug = PlanarState(ship.x + c * bx - s * by, ship.y + s * bx + c * by, yaw, 0.0, 0.0)
    return ship, tug


def test_interaction_set_wash_of_an_asd_tug_on_the_s175_by_hand():
    """The ASD tug at right angles to the S-175's port side, stern to it, both units ahead (jets
    straight astern at the side): each unit's jet (ducted, D0 = D) acts as PropellerJet.wash_force
    at its own offset and foot; reversed thrust at azimuth 180 deg is the same jet; a tug heading
    away from the hull washes nothing; and the ship file's particulars are what is used."""
    from tug_dynamics.hull_interaction import SectionalAreaCurve
    from tug_dynamics.interaction_set import InteractionSet, WashEntry, propulsors_of
    from tug_dynamics.ship_file import ship_config
    from sim_math.data_files import resolve
    tug_cfg = ship_config(resolve("tug_dynamics", "ships", "asd_tug.yaml"))[1]
    ship_cfg = ship_config(resolve("tug_dynamics", "ships", "s175_003.yaml"))[1]
    kind, props = propulsors_of(tug_cfg)
    assert kind == "thrusters" and [p.d0 for p in props] == [2.4, 2.4] and [p.depth for p in props] == [3.9, 3.9]
    hulls = {"ship": SectionalAreaCurve.from_ship_config(ship_cfg),
             "tug": SectionalAreaCurve.from_ship_config(tug_cfg)}
    sets = InteractionSet(hulls, washes=[WashEntry("w", "tug", "ship")], propulsors={"tug": props},
                          drafts={"ship": 8.5})
    assert sets.vessels == ["ship"] and sets.tracked == ["ship", "tug"]
    ship, tug = _asd_beside_the_ship(math.radians(90.0))          # bow away from the ship: stern to it
    loads, _ = sets.loads({"ship": ship, "tug": tug}, 0.0, {"tug": [(THRUST, 0.0), (THRUST, 0.0)]})
    want_y = want_n = 0.0
    for foot in (30.0 + 3.0, 30.0 - 3.0):          # port unit (body y +3) lies toward the ship's stern
        jet = PropellerJet(THRUST, 2.4, 3.9, ducted=True)
        f = jet.wash_force(HullSide(-S175_HALF - foot, S175_HALF - foot, 8.5), 20.0, 0.5 * math.pi)
        want_y -= f
        want_n -= f * foot
    x, y, n = loads["ship"]
    assert x == 0.0 and y == pytest.approx(want_y, rel=1e-6) and n == pytest.approx(want_n, rel=1e-4)
    assert -y < 2 * THRUST
    reversed_, _ = sets.loads({"ship": ship, "tug": tug}, 0.0, {"tug": [(-THRUST, math.pi)] * 2})
    assert reversed_["ship"] == pytest.approx(loads["ship"], rel=1e-9)
    ship, tug = _asd_beside_the_ship(math.radians(-90.0))          # bow to the ship: jets away from it
    none, _ = sets.loads({"ship": ship, "tug": tug}, 0.0, {"tug": [(THRUST, 0.0), (THRUST, 0.0)]})
    assert none["ship"] == (0.0, 0.0, 0.0)
    with pytest.raises(ValueError, match="3 thrusts for 2 propulsors"):
        sets.loads({"ship": ship, "tug": tug}, 0.0, {"tug": [(THRUST, 0.0)] * 3})
    with pytest.raises(ValueError, match="washes its own hull"):
        InteractionSet(hulls, washes=[WashEntry("w", "tug", "tug")], propulsors={"tug": props}, drafts={"tug": 4.0})
    with pytest.raises(ValueError, match="'ship' has no draft"):
        InteractionSet(hulls, washes=[WashEntry("w", "tug", "ship")], propulsors={"tug": props})
    with pytest.raises(ValueError, match="both propellers and azimuth thrusters"):
        propulsors_of(tug_cfg | {"propellers": ship_cfg["propellers"]})


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
