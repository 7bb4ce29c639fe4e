"""Verification against a reference tool: shipmmg (an implementation of the MMG standard method
of Yasukawa & Yoshimura 2015). The S-175's propeller of S. D. Yoon's anchor-dredging paper
(Eq 4 with the wake law w_P0 exp(-4 (beta - x_P r')^2)), thrust deduction, hull resistance X'uu
and surge added mass are the MMG surge model, so the straight acceleration must agree with
shipmmg fed the same numbers. (The lateral derivatives passed to shipmmg are placeholders: on a
straight course with v = r = delta = 0 they do not act.)"""

import numpy as np
import pytest
import yaml

shipmmg = pytest.importorskip("shipmmg")
from shipmmg import mmg_3dof  # noqa: E402

from tug_dynamics.maneuver_trials import run  # noqa: E402
from tug_dynamics.ship_file import list_ship_files, load_ship  # noqa: E402
from tug_dynamics.vessel import Command, VesselState  # noqa: E402


def test_s175_straight_acceleration_matches_shipmmg():
    cfg = yaml.safe_load(open([f for f in list_ship_files() if f.endswith("s175_003.yaml")][0]))
    h, p = cfg["hull"], cfg["propellers"][0]
    L, d, m = h["length"], h["draft"], h["mass"]
    nps = 44.5 / 60.0
    u0, t_end = 2.0, 600.0
    times = np.linspace(0.0, t_end, 601)
    # shipmmg's MMG model: lateral terms are irrelevant on a straight course (v = r = 0, delta = 0)
    sol = mmg_3dof.simulate(
        L_pp=L, B=h["beam"], d=d, x_G=0.0, D_p=p["diameter"], m=m, I_zG=m * h["yaw_radius_of_gyration"] ** 2,
        A_R=33.0, η=0.84, m_x=h["added_mass"]["mx_over_m"] * m, m_y=h["added_mass"]["my_over_m"] * m,
        J_z=h["added_mass"]["Jz_over_mL2"] * m * L * L, f_α=2.74, ε=1.0, t_R=0.2, x_R=-0.5 * L, a_H=0.237,
        x_H=-0.48 * L, γ_R_minus=0.4, γ_R_plus=0.4, l_R=-0.9, κ=0.6, t_P=p["thrust_deduction"],
        w_P0=p["wake_fraction"], x_P=-0.526, k_0=p["kt"][0], k_1=p["kt"][1], k_2=p["kt"][2],
        R_0_dash=-h["derivatives"]["Xuu"], X_vv_dash=0, X_vr_dash=0, X_rr_dash=0, X_vvvv_dash=0,
        Y_v_dash=-0.3, Y_r_dash=0.05, Y_vvv_dash=0, Y_vvr_dash=0, Y_vrr_dash=0, Y_rrr_dash=0,
        N_v_dash=-0.1, N_r_dash=-0.05, N_vvv_dash=0, N_vvr_dash=0, N_vrr_dash=0, N_rrr_dash=0,
        time_list=list(times), δ_list=[0.0] * len(times), nps_list=[nps] * len(times), u0=u0,
        ρ=cfg["water_density"], method="DOP853", t_eval=times, rtol=1e-10, atol=1e-10)
    u_ref = sol.y[0]
    ship = load_ship("s175_003.yaml")
    ship.set_state(VesselState(np.zeros(3), np.zeros(3), np.array([u0, 0, 0.0]), np.zeros(3)), shaft_rps=nps)
    tr = run(ship, t_end, 1.0, {0.0: Command(nps * 60.0 / 89.0, 0.0)})
    print("max |u - u_shipmmg| =", np.max(np.abs(tr.u - u_ref)), "u_end", u_ref[-1])
    assert np.max(np.abs(tr.u - u_ref)) < 1e-3 * u_ref[-1]
    assert tr.x[-1] == pytest.approx(sol.y[3][-1], rel=1e-4)
