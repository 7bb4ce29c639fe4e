"""Bank suction by the image method with Wang's kernel (tug_dynamics.bank_effect), without ROS.

Truths used:
- the image identity: the bank's force is Wang's integral for the ship's mirror image at twice
  the distance, written here and integrated by scipy.integrate.dblquad;
- the far field by hand: Y -> 3 rho U^2 V^2 / (16 pi d^4) for d >> L in deep water;
- the bank line's geometry by hand (distance to a line, which side is port).
"""
import math

import pytest
from scipy import integrate

from tug_dynamics.bank_effect import BankEffect, BankLine
from tug_dynamics.hull_interaction import SectionalAreaCurve

RHO = 1025.0
S175 = SectionalAreaCurve(175.0, 1.5 * 21648428.0 / RHO / 175.0, 25.4)


def image_sway(curve, distance, speed):
    def slope(x):
        return -8.0 * curve.midship_area * x / curve.length ** 2
    eta = 2.0 * distance
    half = curve.length / 2
    value = integrate.dblquad(lambda x2, x1: slope(x1) * slope(x2) / ((x2 - x1) ** 2 + eta ** 2) ** 1.5,
                              -half, half, -half, half, epsabs=0.0, epsrel=1e-10)[0]
    return RHO * speed ** 2 * eta / math.pi * value


@pytest.mark.parametrize("distance", [30.0, 60.0, 120.0])
def test_bank_force_is_the_mirror_image_force(distance):
    y, n = BankEffect(S175).loads(distance, 4.0)
    assert y == pytest.approx(image_sway(S175, distance, 4.0), rel=1e-4)
    assert y > 0.0                                   # toward the bank (port)
    assert abs(n) < 1e-9 * y * S175.length            # Wang's parabola is fore-aft symmetric


def test_bank_to_starboard_pulls_to_starboard_and_speed_squared():
    bank = BankEffect(S175)
    port = bank.loads(50.0, 3.0)[0]
    assert bank.loads(50.0, 3.0, bank_to_port=False)[0] == pytest.approx(-port, rel=1e-12)
    assert bank.loads(50.0, 6.0)[0] == pytest.approx(4.0 * port, rel=1e-12)
    assert bank.loads(50.0, 3.0, depth=12.0)[0] > port          # shallow water strengthens it


def test_far_field_by_hand():
    d = 4.0 * S175.length
    want = 3.0 * RHO * 4.0 ** 2 * S175.volume ** 2 / (16.0 * math.pi * d ** 4)
    assert BankEffect(S175).loads(d, 4.0)[0] == pytest.approx(want, rel=0.02)


def test_bank_line_geometry():
    line = BankLine((0.0, 100.0), (1000.0, 100.0))
    # left of start -> end (looking east) is north: the water lies north, the bank south of it
    assert line.distance(500.0, 160.0) == pytest.approx(60.0)
    assert line.side(0.0) == -1.0                   # heading east along it: the bank to starboard
    assert line.side(math.pi) == 1.0                # heading west: the bank to port


@pytest.mark.parametrize("start, end, word", [((0.0, 0.0), (0.0, 0.0), "same point"),
                                              ((0.0, float("nan")), (1.0, 0.0), "finite")])
def test_bad_bank_line(start, end, word):
    with pytest.raises(ValueError, match=word):
        BankLine(start, end)


@pytest.mark.parametrize("distance", [5.0, float("nan"), -30.0])
def test_distance_inside_the_hull_is_refused(distance):
    with pytest.raises(ValueError, match="distance"):
        BankEffect(S175).loads(distance, 3.0)


def test_bank_polyline_nearest_point_and_water_side_by_hand():
    from tug_dynamics.bank_effect import BankPolyline
    # an L-shaped channel edge: east along y = 0, then north along x = 100; water to the left (north-west)
    bank = BankPolyline([(0.0, 0.0), (100.0, 0.0), (100.0, 100.0)])
    assert bank.nearest(50.0, 30.0) == pytest.approx((30.0, 50.0, 0.0))
    assert bank.nearest(80.0, 60.0) == pytest.approx((20.0, 100.0, 60.0))
    assert bank.nearest(130.0, -40.0) == pytest.approx((50.0, 100.0, 0.0))     # the corner
    assert bank.water_side(50.0, 30.0) and bank.water_side(80.0, 60.0)
    assert not bank.water_side(50.0, -30.0) and not bank.water_side(120.0, 60.0)


@pytest.mark.parametrize("points, words", [
    ([(0.0, 0.0), (100.0, 0.0), (100.0, 50.0), (50.0, -50.0)], "segment 0"),      # an 'alpha' loop
    ([(0.0, 0.0), (100.0, 0.0), (100.0, 50.0), (0.0, 50.0), (0.0, 0.0)], "segment 0"),   # closed on itself
    ([(0.0, 0.0), (100.0, 0.0), (40.0, 0.0)], "doubles back"),
    ([(0.0, 0.0), (0.0, 0.0), (10.0, 0.0)], "same point"),
    ([(0.0, 0.0)], "at least two points"),
    ([(0.0, 0.0), (float("nan"), 1.0)], "point 1"),
])
def test_bank_polyline_refuses_a_line_crossing_itself(points, words):
    from tug_dynamics.bank_effect import BankPolyline
    with pytest.raises(ValueError, match=words):
        BankPolyline(points)


def test_loads_along_a_polyline_are_the_straight_bank_loads_at_the_nearest_point():
    from tug_dynamics.bank_effect import BankPolyline
    bank = BankPolyline([(-500.0, -40.0), (2000.0, -40.0)])
    effect = BankEffect(S175)
    # heading east (yaw 0): the bank 40 m to starboard; heading west: to port
    east = effect.loads_along(bank, 100.0, 0.0, 0.0, 3.0, 12.75)
    assert east == pytest.approx(effect.loads(40.0, 3.0, 12.75, bank_to_port=False), rel=1e-12)
    assert east[0] < 0.0                                  # drawn to starboard, toward the bank
    west = effect.loads_along(bank, 100.0, 0.0, math.pi, 3.0, 12.75)
    assert west[0] == pytest.approx(-east[0], rel=1e-12)
    with pytest.raises(ValueError, match="land side"):
        effect.loads_along(bank, 100.0, -60.0, 0.0, 3.0, 12.75)


def test_the_image_method_against_the_published_vertical_wall_test():
    """A published reference point: test H of the open data of Lataire, Vantorre & Eloot (2009),
    "Systematic model tests on ship-bank interaction effects" (MASHCON, Antwerp; subset 2, the
    8000 TEU container carrier model along bank I, a vertical surface-piercing wall 2.830 m from
    the tank's centreline): lateral position 1.965 m (0.865 m from the wall), h 0.163 m, T 0.149 m
    (10 % under-keel clearance), 0.4578 m/s, propeller not working; measured sway force -2.545 N,
    yaw moment -6.959 N m (ship axes x forward, y starboard, z down). The model: B 0.530 m and
    C_B 0.65 from the paper's Table 2, L_pp 4.01 m as the pi-BEM repository's scripts use for
    this hull, fresh water. The image method is the wall's mirror and its bottom images: it
    gives 1.60 N (63 % of the measured force) and no yaw moment; the measurement's -6.96 N m, a
    couple of 2.7 m arm on 2.5 N, is the bow-away moment this model lacks (docs/confined-water.md)."""
    length, beam, draft, block = 4.01, 0.530, 0.149, 0.65
    volume = block * length * beam * draft
    effect = BankEffect(SectionalAreaCurve(length, 1.5 * volume / length, beam), water_density=1000.0)
    y, n = effect.loads(2.830 - 1.965, 0.4578, 0.163)
    measured_y, measured_n = 2.545, 6.959
    assert y / measured_y == pytest.approx(0.63, abs=0.01)
    assert n == pytest.approx(0.0, abs=1e-9) and measured_n / measured_y > 0.5 * length   # a couple, not a force
    # the tank's far wall, 5.465 m off, adds 1.5 % of it: the single-wall image is the test's set-up
    assert effect.loads(3.5 + 1.965, 0.4578, 0.163)[0] < 0.02 * y
