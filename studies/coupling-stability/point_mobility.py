"""Mobility (acceleration per unit force, m/s^2/N) of an attachment point in the horizontal plane,
measured on the real models by finite differences: 1 / its largest eigenvalue is the smallest
effective mass a rope at that point can meet (the line pulling across the hull turns the vessel
too), against the surge mass the simple bound uses."""
import os
import copy
import numpy as np
from tug_dynamics.ship_file import load_ship
from tug_dynamics.vessel import ExternalWrench, VesselState

SHIPS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "ros_ws", "src") + "/" + "tug_dynamics/ships/"


def mobility(ship, att, dt=1e-3):
    v = load_ship(SHIPS + ship)
    v.set_state(VesselState.at_rest())
    r = np.asarray(v.attachments[att], float)
    base = copy.deepcopy(v)
    base.step(dt, [])
    p0, v0 = base.attachment_kinematics(att)
    G = np.zeros((2, 2))
    for j in range(2):
        f = np.zeros(3)
        f[j] = 1e4
        w = copy.deepcopy(v)
        w.step(dt, [ExternalWrench(f, r)])
        G[:, j] = (w.attachment_kinematics(att)[1][:2] - v0[:2]) / dt / 1e4
    return G


for ship, atts in (("asd_tug.yaml", ("winch_aft", "bow_staple")), ("harbour_tug.yaml", ("towing_hook", "bow_bollard")),
                   ("s175_003.yaml", ("bow_bollard_port", "stern_bollard_port")), ("barge_002_full.yaml", ("bow_bollard",))):
    for a in atts:
        G = mobility(ship, a)
        Gs = 0.5 * (G + G.T)
        lam = np.linalg.eigvalsh(Gs)
        print(f"{ship:20s} {a:18s}: surge mass {1 / G[0, 0]:.3g} kg; smallest effective mass 1/lambda_max {1 / lam.max():.3g} kg "
              f"(ratio {G[0, 0] / lam.max():.2f})")
