"""A 40 m steel wire between two free ASD tugs (engines stopped), pre-stretched and let go: the
energy balance E = vessels' kinetic + rope kinetic + rope potential (gravity + elastic) for each
scheme and exchange rate, and the exchange's own books: the work the rope did on the vessels
(what they applied) plus the work the vessels did on the rope (what the rope was driven with)
is the energy the exchange created (0 for a lossless interface)."""
import sys
import numpy as np
from real_loop import run

schemes = sys.argv[1].split(",") if len(sys.argv) > 1 else ["lag", "predJ", "jac_pred", "jac_now"]
rates = [float(r) for r in sys.argv[2].split(",")] if len(sys.argv) > 2 else [5.0, 10.0, 20.0, 50.0]
dur = float(sys.argv[3]) if len(sys.argv) > 3 else 60.0
stretch = 0.3
for s in schemes:
    for r in rates:
        res = run(s, r, dur, case="free", stretch=stretch, smooth=True)
        E = res["E"]
        if len(E) == 0:
            print(f"{s:8s} {r:5g} Hz: parted at once"); continue
        tot = E[:, 0] + E[:, 1] + E[:, 3]
        e0 = tot[0]
        swing0 = E[:, 2][: int(5 * r)].max()
        t = res["t"]
        last = np.concatenate([[False], t >= t[-1] - 10])
        print(f"{s:8s} {r:5g} Hz: E(0) {e0/1e3:7.1f} kJ, E(end) / E(0) {tot[-1]/e0:7.3f}, max E / E(0) "
              f"{tot.max()/e0:7.3f}; elastic peak first 5 s {swing0/1e3:7.1f} kJ, last 10 s "
              f"{E[last, 2].max()/1e3:7.1f} kJ; exchange created {(E[-1, 4] + E[-1, 5])/1e3:8.2f} kJ"
              f"; momentum drift {(E[-1, 6] - E[0, 6]) / 1e3:6.2f} t m/s (peak one vessel "
              f"{np.sqrt(2 * 7.925e5 * E[:, 0].max() / 2) / 1e3:.1f})"
              f"{'  PARTED' if res['parted'] else ''}")
