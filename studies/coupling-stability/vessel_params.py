"""Surge mass and linear damping of the ASD / harbour tug at full ahead at bollard (u ~ 0),
measured on the real model (tug_dynamics) by finite differences of the surge acceleration."""
import os
import sys
import numpy as np
from tug_dynamics.ship_file import load_ship
from tug_dynamics.vessel import Command, VesselState, ThrusterOrder, ExternalWrench

SHIPS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "ros_ws", "src") + "/" + "tug_dynamics/ships/"


def surge_props(ship, engine=1.0, du=0.05):
    v = load_ship(SHIPS + ship)
    v.settle_command(Command(engine, 0.0))
    base = v.state
    acc = {}
    for u in (-du, du):
        s = VesselState(base.position.copy(), base.rpy.copy(), np.array([u, 0, 0.0]), np.zeros(3))
        import copy
        w = copy.deepcopy(v)
        w.set_state(s)
        w.step(1e-3, [])
        acc[u] = (w.state.linear_velocity_body[0] - u) / 1e-3
    # mass: response to a known extra force
    w = copy.deepcopy(v)
    w.set_state(VesselState(base.position.copy(), base.rpy.copy(), np.zeros(3), np.zeros(3)))
    w2 = copy.deepcopy(w)
    w.step(1e-3, [])
    w2.step(1e-3, [ExternalWrench(np.array([1e5, 0, 0.0]), np.zeros(3))])
    m = 1e5 / ((w2.state.linear_velocity_body[0] - w.state.linear_velocity_body[0]) / 1e-3)
    c = -m * (acc[du] - acc[-du]) / (2 * du)
    thrust = m * 0.5 * (acc[du] + acc[-du])
    return m, c, thrust, v.attachments


if __name__ == "__main__":
    for ship in ("asd_tug.yaml", "harbour_tug.yaml"):
        m, c, t, att = surge_props(ship)
        print(f"{ship}: surge mass incl. added {m:.4g} kg, d(net surge force)/du {c:.4g} N s/m, "
              f"net force at u=0 {t/1e3:.1f} kN ({t/9806.65:.1f} t); attachments {sorted(att)}")
