"""The rope's end connection when the end is re-pinned at the vessel's attachment every step
(set_end(x_k, v_k), as rope_node does: a jump of x_k - (x_{k-1} + h v_{k-1}) ~ h^2 a / 2 onto the
end connection, EA / (l/2) = 9.8e7 N/m here) against a continuous drive (smooth): largest excess
of the end connection's tension over the mid-span tension, bollard pull with the jac scheme."""
import numpy as np
import real_loop as R
from rope_model.chain import RopeChain

orig = RopeChain.step
rec = []


def step(self, dt):
    orig(self, dt)
    T = self.tensions
    rec.append(T[0] - T[len(T) // 2])


RopeChain.step = step
for rate in (5.0, 10.0, 20.0, 50.0):
    for smooth in (False, True):
        rec.clear()
        res = R.run("jac", rate, 30.0, smooth=smooth)
        print(f"{rate:4g} Hz {'smooth' if smooth else 'as now':7s}: end connection - mid-span tension, max "
              f"{max(rec) / 1e3:7.1f} kN, rms {np.sqrt(np.mean(np.square(rec))) / 1e3:6.1f} kN"
              f"{'  PARTED' if res['parted'] else ''}")
