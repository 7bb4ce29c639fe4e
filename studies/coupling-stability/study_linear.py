"""Growth rates (1/s) of the surge swing for every scheme: ASD tug on 40 m of 40 mm steel wire to
a fixed point, and a rope between two free bodies."""
import numpy as np
from linear_model import Exchange, SCHEMES

EA, L, mu, N = 6.56e7, 40.0, 6.4, 30
k = EA / L
c_r = np.sqrt(EA * mu) / N        # chain of N Kelvin-Voigt connections c = 2 zeta sqrt(EA mu), zeta 0.5
M_ASD, C_ASD = 7.925e5, 4.042e4   # vessel_params.py: surge mass incl. added, d(net force)/du at bollard
M_HT, C_HT = 3.10e5, 2.442e4

if __name__ == "__main__":
    print(f"k = EA/L = {k:.4g} N/m, rope end-to-end damping c_r = {c_r:.3g} N s/m, "
          f"omega(ASD, fixed) = {np.sqrt(k / M_ASD):.3f} rad/s")
    rates = (1, 2, 5, 10, 20, 40, 50, 100)
    print("\nASD tug, full ahead, 40 m wire to a fixed point: growth rate of the surge swing, 1/s (>0 grows)")
    print("scheme  " + "".join(f"{r:>9g}Hz" for r in rates))
    for s in SCHEMES:
        g = [Exchange(s, 1.0 / r, M_ASD, C_ASD, k, c_r).growth_rate() for r in rates]
        print(f"{s:8s}" + "".join(f"{x:11.4f}" for x in g))
    print(f"  analytic small-h estimate for 'lag': (k h - c - c_r) / (2 m): "
          + ", ".join(f"{r} Hz {(k / r - C_ASD - c_r) / (2 * M_ASD):.4f}" for r in rates))
    print("\nTwo free ASD tugs (no water damping) on 40 m wire: growth rate, 1/s")
    print("scheme  " + "".join(f"{r:>9g}Hz" for r in rates))
    for s in SCHEMES:
        g = [Exchange(s, 1.0 / r, M_ASD, 0.0, k, c_r, m_b=M_ASD).growth_rate() for r in rates]
        print(f"{s:8s}" + "".join(f"{x:11.4f}" for x in g))
    print("\nHarbour tug + ASD tug free (no water damping) on 40 m wire: growth rate, 1/s")
    print("scheme  " + "".join(f"{r:>9g}Hz" for r in rates))
    for s in SCHEMES:
        g = [Exchange(s, 1.0 / r, M_HT, 0.0, k, c_r, m_b=M_ASD).growth_rate() for r in rates]
        print(f"{s:8s}" + "".join(f"{x:11.4f}" for x in g))
