"""Where each scheme stops keeping a rope between two free bodies from gaining energy: growth rate
of the rope mode per radian (g / omega) against omega h, omega^2 = k (1/m_a + 1/m_b)."""
import numpy as np
from linear_model import Exchange

k = 1.64e6
m = 7.925e5
oh = [0.02, 0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.7, 1.0, 1.5, 2.0]
for ratio in (1.0, 0.25, 0.0):       # m_a / m_b (0: b fixed)
    m_a = m
    m_b = m / ratio if ratio else np.inf
    w = np.sqrt(k * (1 / m_a + (ratio / m if ratio else 0.0)))
    for zeta in (0.0, 0.002):
        m_red = 1 / (1 / m_a + (1 / m_b if ratio else 0.0))
        c_r = 2 * zeta * np.sqrt(k * m_red)
        print(f"\nm_a/m_b = {ratio}, rope damping ratio {zeta} (c_r {c_r:.0f} N s/m): energy growth per "
              f"radian 2 g / omega (exact {-2*zeta:.4f})")
        print("scheme     " + "".join(f"{x:>9g}" for x in oh))
        for s in ("lag", "pred", "jac", "jac_pred", "jac_now"):
            row = []
            for x in oh:
                h = x / w
                row.append(2 * Exchange(s, h, m_a, 0.0, k, c_r, m_b=m_b).growth_rate() / w)
            print(f"{s:10s} " + "".join(f"{v:9.4f}" for v in row))
