"""Jacobian coupling when the rope's stiffness estimate kJ is off (sag, tension-dependence):
ASD tug, full ahead, 40 m wire to a fixed point; growth rate 1/s (exact -0.0259)."""
import numpy as np
from linear_model import Exchange
from study_linear import k, c_r, M_ASD, C_ASD

rates = (1, 2, 5, 10, 20, 50)
print("kJ/k   " + "".join(f"{r:>9g}Hz" for r in rates) + "   small-h estimate at 20 Hz ((1-a) k h - c - c_r)/(2m)")
for a in (0.0, 0.25, 0.5, 0.75, 0.9, 1.0, 1.5, 3.0, 10.0):
    g = [Exchange("jac", 1.0 / r, M_ASD, C_ASD, k, c_r, kJ=a * k).growth_rate() for r in rates]
    est = ((1 - a) * k / 20 - C_ASD - c_r) / (2 * M_ASD)
    print(f"{a:5.2f} " + "".join(f"{x:11.4f}" for x in g) + f"   {est:.4f}")
