"""Does driving the rope end one step ahead (pred) disturb the chain? Rope alone, settled
40 m wire to a fixed point, end a driven along x(t) = x0 + A (1 - cos w t) at 50 Hz."""
import os
import dataclasses, numpy as np
from rope_model.chain import RopeChain
from rope_model.params import load_rope_params
p = dataclasses.replace(load_rope_params(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "ros_ws", "src") + "/" + "rope_model/ropes/steel_wire_40mm.yaml"), length=40.0)
pa = np.array([0.0, 0, 2.4]); pb = np.array([-40.0, 0, 2.4])
h = 0.02; A = 0.2; w = 1.44
for mode in ("now", "shift_exact", "pred_lin"):
    r = RopeChain.straight(p, pa, pb, n_elements=30, end_a="pinned", end_b="fixed")
    r.settle()
    out = []
    for k in range(100):
        t = k * h
        x = lambda t: pa + np.array([A * (1 - np.cos(w * t)), 0, 0])
        v = lambda t: np.array([A * w * np.sin(w * t), 0, 0])
        if mode == "now":
            r.set_end_kinematics("a", x(t), v(t))
        elif mode == "shift_exact":
            r.set_end_kinematics("a", x(t + h), v(t + h))
        else:
            r.set_end_kinematics("a", x(t) + h * v(t), v(t))
        r.step(h)
        out.append(r.tensions[[0, 1, 15, 30]] / 1e3)
    out = np.array(out)
    print(mode, "conn 0, 1, 15, 30 kN at steps 20,50,99:", np.round(out[[20, 50, 99]]).astype(int).tolist())
