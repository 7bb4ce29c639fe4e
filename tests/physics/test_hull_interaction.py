"""Wang's (1975) passing-ship interaction (tug_dynamics.hull_interaction), without ROS.

Truths used:
- the double integrals, written here independently and integrated by scipy.integrate.dblquad
  (deep water; finite depth with the bottom images summed here to |n| = 300);
- a worked example of Wang's formulas: the MathCAD sheet "Calculation of forces and moments from
  Wang" (N. Barczak, 2016) as quoted in the public repository vamseeachanta/digitalmodel (passing
  ship benchmark tests, case REF1): moored ship L 950 ft, midship area 3192 ft^2; passing ship
  L 475 ft, 6413 ft^2; rho 1.9905 slug/ft^3, U 11.2 ft/s, separation 190 ft, depth 95 ft:
  sway 7.644e4 lbf at stagger 0 (surge and yaw zero);
- the far field by hand: at separation eta >> L in deep water, Taylor-expanding the kernel gives
  Y = 3 rho U^2 V1 V2 / (pi eta^4) (the integrals of S' and of x S' are 0 and -V);
- symmetry: Y and the forces scale with U^2, Y is even and X and N odd in the stagger, Y is odd
  in the separation (attraction toward the passing ship abeam).
"""
import math
import os

import numpy as np
import pytest
import yaml
from scipy import integrate

from tug_dynamics.hull_interaction import HullPair, SectionalAreaCurve, pair_from_ship_configs

pytestmark = pytest.mark.filterwarnings("ignore::scipy.integrate.IntegrationWarning")  # dblquad at 1e-9
SHIPS = os.path.join(os.path.dirname(__file__), "..", "..", "ros_ws", "src", "tug_dynamics", "ships")
RHO = 1025.0
S175 = SectionalAreaCurve(175.0, 1.5 * 21648428.0 / RHO / 175.0, 25.4)
TUG = SectionalAreaCurve(30.0, 1.5 * 400.0 / 30.0, 10.0)


def slope(curve, x):
    return -8.0 * curve.midship_area * x / curve.length ** 2


def quadrature_loads(a, b, stagger, eta, speed, depth=None, images=300):
    """(X, Y, N) on ship a from ship b by dblquad, straight from Wang's integrals."""
    def kernel(d):
        r2 = d * d + eta * eta
        if depth is None:
            return r2 ** -1.5
        n = np.arange(1, images + 1)
        return r2 ** -1.5 + 2.0 * np.sum((r2 + (2.0 * n * depth) ** 2) ** -1.5)

    def area(x):
        return a.midship_area * (1.0 - (2.0 * x / a.length) ** 2)

    def dbl(f):
        return integrate.dblquad(f, -a.length / 2, a.length / 2, -b.length / 2, b.length / 2,
                                 epsabs=0.0, epsrel=1e-9)[0]
    k = RHO * speed ** 2 / math.pi
    x = dbl(lambda x2, x1: slope(a, x1) * slope(b, x2) * (stagger - x1 + x2) * kernel(stagger - x1 + x2))
    y = dbl(lambda x2, x1: slope(a, x1) * slope(b, x2) * kernel(stagger - x1 + x2))
    n = dbl(lambda x2, x1: (area(x1) + x1 * slope(a, x1)) * slope(b, x2) * kernel(stagger - x1 + x2))
    return k * x, k * eta * y, k * eta * n


@pytest.mark.parametrize("a, b, eta", [(S175, S175, 26.0), (S175, S175, 60.0), (S175, TUG, 18.0),
                                       (TUG, S175, 18.0)])
@pytest.mark.parametrize("stagger", [0.0, 50.0, -120.0])
def test_deep_water_integrals_match_quadrature(a, b, eta, stagger):
    got = HullPair(a, b).loads(stagger, eta, 5.0)
    want = quadrature_loads(a, b, stagger, eta, 5.0)
    scale = abs(quadrature_loads(a, b, 0.0, eta, 5.0)[1])
    assert np.allclose(got[:2], want[:2], rtol=0.0, atol=1e-3 * scale)
    assert got[2] == pytest.approx(want[2], rel=0.0, abs=1e-3 * scale * a.length)


@pytest.mark.parametrize("depth", [10.2, 20.0])
@pytest.mark.parametrize("a, b, eta, stagger", [(S175, S175, 40.0, 0.0), (S175, S175, 40.0, 60.0),
                                                (S175, TUG, 18.0, 70.0)])
def test_finite_depth_images_match_quadrature(a, b, eta, stagger, depth):
    """Three images each side exactly and the rest as their integral: within 0.3 % of the peak."""
    got = HullPair(a, b).loads(stagger, eta, 5.0, depth)
    want = quadrature_loads(a, b, stagger, eta, 5.0, depth)
    scale = abs(quadrature_loads(a, b, 0.0, eta, 5.0, depth)[1])
    assert np.allclose(got[:2], want[:2], rtol=0.0, atol=3e-3 * scale)


def test_worked_example_barczak_mathcad():
    ft, lbf, slug_ft3 = 0.3048, 4.4482216152605, 14.59390294 / 0.3048 ** 3
    moored = SectionalAreaCurve(950 * ft, 3192 * ft ** 2, 105 * ft)
    passing = SectionalAreaCurve(475 * ft, 6413 * ft ** 2, 100 * ft)
    pair = HullPair(moored, passing, water_density=1.9905 * slug_ft3)
    x, y, n = pair.loads(0.0, 190 * ft, 11.2 * ft, 95 * ft)
    assert y / lbf == pytest.approx(7.644e4, rel=2e-3)
    assert abs(x) / lbf < 1e-6 * 7.644e4 and abs(n) / lbf / ft < 1e-6 * 7.644e4 * 950


def test_sway_scales_with_speed_squared_and_symmetries():
    pair = HullPair(S175, S175)
    base = np.array(pair.loads(70.0, 50.0, 3.0))
    assert np.allclose(pair.loads(70.0, 50.0, 6.0), 4.0 * base, rtol=1e-12)
    assert np.allclose(pair.loads(70.0, 50.0, -3.0), base, rtol=1e-12)
    mirrored = np.array(pair.loads(-70.0, 50.0, 3.0))
    assert mirrored[1] == pytest.approx(base[1], rel=1e-9)            # sway even in stagger
    assert mirrored[0] == pytest.approx(-base[0], rel=1e-9)           # surge odd
    assert mirrored[2] == pytest.approx(-base[2], rel=1e-9)           # yaw odd
    starboard = np.array(pair.loads(70.0, -50.0, 3.0))
    assert np.allclose(starboard, base * [1.0, -1.0, -1.0], rtol=1e-12)
    assert pair.loads(0.0, 50.0, 3.0)[1] > 0.0                        # abeam: pulled toward her


def test_far_field_decays_as_inverse_fourth_power():
    pair = HullPair(S175, TUG)
    for eta in (5 * 175.0, 10 * 175.0):
        far = 3.0 * RHO * 4.0 ** 2 * S175.volume * TUG.volume / (math.pi * eta ** 4)
        assert pair.loads(0.0, eta, 4.0)[1] == pytest.approx(far, rel=0.02 * (875.0 / eta) ** 2)


def test_hull_from_ship_files_holds_the_displacement():
    with open(os.path.join(SHIPS, "s175_003.yaml")) as f:
        s175 = yaml.safe_load(f)
    with open(os.path.join(SHIPS, "harbour_tug.yaml")) as f:
        tug = yaml.safe_load(f)
    pair = pair_from_ship_configs(tug, s175)
    assert pair.ship2.volume == pytest.approx(21648428.0 / 1025.0, rel=1e-12)
    assert pair.ship1.length == tug["hull"]["length"]
    assert math.isfinite(pair.loads(40.0, 25.0, 3.0)[1])


@pytest.mark.parametrize("args, word", [((0.0, 20.0, 3.0), "separation 20.0"),
                                        ((0.0, -10.0, 3.0), "separation -10.0"),
                                        ((float("nan"), 40.0, 3.0), "stagger"),
                                        ((0.0, 40.0, float("inf")), "speed"),
                                        ((0.0, 40.0, 3.0, 0.0), "depth"),
                                        ((0.0, 40.0, 3.0, float("nan")), "depth")])
def test_bad_input_names_the_value(args, word):
    with pytest.raises(ValueError, match=word):
        HullPair(S175, S175).loads(*args)


def test_hulls_in_line_are_allowed_but_not_overlapping():
    pair = HullPair(S175, TUG)
    x, y, n = pair.loads(110.0, 0.0, 3.0)                              # tug 7.5 m ahead of the bow
    assert x == pytest.approx(quadrature_loads(S175, TUG, 110.0, 1e-2, 3.0)[0], rel=0.01)  # 24 nodes, 7.5 m gap
    assert y == 0.0 and n == 0.0
    with pytest.raises(ValueError, match="inside each other"):
        pair.loads(100.0, 0.0, 3.0)
    with pytest.raises(ValueError, match="length"):
        SectionalAreaCurve(-1.0, 10.0, 2.0)
    with pytest.raises(ValueError, match="planing"):
        SectionalAreaCurve.from_ship_config({"model": "planing_6dof", "name": "p"})
