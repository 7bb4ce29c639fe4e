"""The rope Jacobian's axial part against the element chain itself: 40 m of the 40 mm wire in air,
both ends held, settled (RopeChain.settle) at chord c and c + 2 mm: chord stiffness dT/dc against
k_ch = 1 / (L/EA + (w L)^2 L / (12 T^3)) (elastic chain in series with the shallow elastic
catenary's sag compliance) and against EA/L."""
import os
import dataclasses, math, time
import numpy as np
from rope_model.chain import RopeChain
from rope_model.params import load_rope_params

p = dataclasses.replace(load_rope_params(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "ros_ws", "src") + "/" + "rope_model/ropes/steel_wire_40mm.yaml"), length=40.0)
w = p.mass_per_length * p.gravity


def settled_tension(chord):
    r = RopeChain.straight(p, [0.0, 0, 10.0], [chord, 0, 10.0], n_elements=30, end_a="pinned", end_b="pinned")
    r.settle()
    F = r.end_force("a")
    return float(F[0]), float(np.linalg.norm(F))   # horizontal component, magnitude


t0 = time.perf_counter()
for chord in (39.90, 39.98, 40.00, 40.02, 40.10, 40.30):
    d = 0.002
    (h0, T0), (h1, T1) = settled_tension(chord), settled_tension(chord + d)
    k_fd = (h1 - h0) / d
    T = 0.5 * (T0 + T1)
    k_f = 1.0 / (40.0 / p.ea + (w * 40.0) ** 2 * 40.0 / (12.0 * T ** 3))
    print(f"chord {chord:6.2f} m: tension {T / 1e3:8.1f} kN; chain dH/dc {k_fd:10.4g} N/m; formula {k_f:10.4g} "
          f"(ratio {k_f / k_fd:5.2f}); EA/L {p.ea / 40:.4g}")
print(f"({time.perf_counter() - t0:.1f} s)")
