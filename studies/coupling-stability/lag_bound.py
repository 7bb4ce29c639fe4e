"""The exchange rate below which the present (lagged) exchange grows: exact discrete bound
(spectral radius 1, linear_model 'lag') against h_max = (c + c_r) / k."""
import numpy as np
from scipy.optimize import brentq
from linear_model import Exchange
from study_linear import k, c_r, M_ASD, C_ASD, M_HT, C_HT

for name, m, c in (("ASD tug, full ahead", M_ASD, C_ASD), ("harbour tug, full ahead", M_HT, C_HT)):
    for L in (28.0, 40.0, 80.0):
        kk = 6.56e7 / L
        cr = c_r * 40.0 / L * (L / 40.0)      # c_r = sqrt(EA mu)/N does not depend on L (N fixed)
        f = lambda h: Exchange("lag", h, m, c, kk, cr).growth_rate()
        h_exact = brentq(f, 1e-4, 0.2)
        print(f"{name:24s} on {L:4.0f} m wire (k {kk:.3g} N/m): lag grows below {1 / h_exact:6.1f} Hz "
              f"(exact discrete); (c + c_r)/k gives {kk / (c + cr):6.1f} Hz; omega {np.sqrt(kk / m):.2f} rad/s")
