"""The S-175 of S. D. Yoon, "A Study on the Control of Ship Maneuvering by the Simulation of
Anchor Dredging", against independent references for the same ship and orders.

Reference: the Son & Nomoto (1981) 175 m container ship as coded in Fossen's MSS toolbox
(`VESSELS/container.m`), run with its rudder limit raised to 35 deg: hard to port from 9.06 kn
at 44.5 rpm gives advance 3.37 L, tactical diameter 4.28 L, steady yaw rate 0.398 deg/s and
4.14 kn (the figures of the project's manoeuvring-fidelity review; measured with the IMO
definitions of sim_math.turning). The seed's own model differs (quadratic hull terms, Fujii's
rudder), so the goal is agreement within 10 %, not identity.
"""
import math

import numpy as np
import pytest
from scipy.optimize import brentq

from sim_math.turning import turning_measures
from tug_dynamics.maneuver_trials import KN, run
from tug_dynamics.ship_file import load_ship
from tug_dynamics.vessel import Command, VesselState

L, D_DRAFT = 175.0, 8.5
RATED = 89.0
HALF, SLOW = 44.5 / RATED, 29.69 / RATED  # Table 1 engine orders

# Son & Nomoto / container.m, forces over 0.5 rho L^2 U^2: converted to the seed's 0.5 rho L d U^2
SON_NOMOTO_XUU = -0.0004226 * L / D_DRAFT
SON_NOMOTO_T = 0.175


def eq4_steady_speed(rpm, x_uu=-0.00957, t=0.20, w=0.26, rho=1025.0, d_prop=6.533,
                     kt=(0.5277, -0.4264, -0.115)):
    """Surge balance of the seed's Eq 1 and Eq 4 written out here: (1 - t) rho n^2 D^4 K_T(J)
    = -X'uu 0.5 rho L d u^2 with J = u (1 - w) / (n D); Table 2 values by default. m/s."""
    n = rpm / 60.0

    def surplus(u):
        j = u * (1.0 - w) / (n * d_prop)
        return (1 - t) * rho * n * n * d_prop ** 4 * (kt[0] + kt[1] * j + kt[2] * j * j) \
            + x_uu * 0.5 * rho * L * D_DRAFT * u * u
    return brentq(surplus, 0.1, 20.0)


@pytest.mark.parametrize("order", [HALF, SLOW])
def test_straight_speed_is_the_surge_balance_of_table2(order):
    """The model's steady speed is what its Table 2 resistance, thrust deduction, wake and K_T
    give by hand (the paper's 9 / 6 kn are not reached: see the next test)."""
    s = load_ship("s175_003.yaml")
    s.set_state(VesselState(np.zeros(3), np.zeros(3), np.array([8.0 * KN, 0, 0.0]), np.zeros(3)),
                shaft_rps=order * RATED / 60.0)
    tr = run(s, 1500.0, 1.0, {0.0: Command(order, 0.0)})
    assert tr.u[-1] == pytest.approx(eq4_steady_speed(order * RATED), rel=2e-3)


@pytest.mark.parametrize("rpm,knots", [(44.5, 9.0), (29.69, 6.0)])
def test_paper_speeds_follow_from_son_nomotos_resistance_and_thrust_deduction(rpm, knots):
    """Why the model sails 8.75 / 5.84 kn where Table 1 says 9 / 6 kn: Table 2's X'uu (-0.00957)
    and t (0.20) are 10 % and 14 % above Son & Nomoto's (-0.0087, 0.175); with those two the
    same balance gives the paper's speeds, so Table 1's speeds come from the Son & Nomoto ship,
    not from Table 2. The seed's coefficients are kept (no trim of the engine order)."""
    seed = eq4_steady_speed(rpm) / KN
    son_nomoto = eq4_steady_speed(rpm, x_uu=SON_NOMOTO_XUU, t=SON_NOMOTO_T) / KN
    assert son_nomoto == pytest.approx(knots, rel=0.005)
    assert seed == pytest.approx(knots * 0.973, rel=0.005)  # 2.7 % slow at both orders: a resistance gap


@pytest.fixture(scope="module")
def hard_port_turn():
    s = load_ship("s175_003.yaml")
    s.set_state(VesselState(np.zeros(3), np.zeros(3), np.array([9.0 * KN, 0, 0.0]), np.zeros(3)),
                shaft_rps=HALF * RATED / 60.0)
    tr = run(s, 1500.0, 0.2, {0.0: Command(HALF, math.radians(35.0))})
    return turning_measures(tr.t, tr.x, tr.y, tr.psi, tr.u, tr.v, tr.r, 0.0)


@pytest.mark.parametrize("measure,reference,scale", [
    ("advance", 3.37, L), ("tactical_diameter", 4.28, L), ("steady_yaw_rate", 0.398, math.radians(1.0))])
def test_35deg_turn_within_10_percent_of_the_son_nomoto_ship(hard_port_turn, measure, reference, scale):
    assert hard_port_turn[measure] / scale == pytest.approx(reference, rel=0.10)
