"""Within-step spike on the end connection from the re-pinning jump: the rope stepped one
10 ms sub-step per call (same physics as step(h) with max_substep 0.01), recording the end
connection's tension after every sub-step. Bollard pull, jac scheme, 30 s."""
import numpy as np
import real_loop as R
from rope_model.chain import RopeChain

orig = RopeChain.step
rec = []


def step(self, dt):
    n = int(round(dt / 0.01))
    imp = np.zeros((2, 3))
    for _ in range(n):
        orig(self, dt / n)
        T = self.tensions
        rec.append(T[0] - T[len(T) // 2])
        imp += np.array([self.mean_end_force("a"), self.mean_end_force("b")])
    self._mean_end_force[:] = imp / n            # the mean over the whole step, as step(h) writes


RopeChain.step = step
for rate in (5.0, 10.0, 20.0, 50.0):
    for smooth in (False, True):
        rec.clear()
        res = R.run("jac", rate, 30.0, smooth=smooth)
        print(f"{rate:4g} Hz {'smooth' if smooth else 'as now':7s}: end connection - mid-span, max over sub-steps "
              f"{max(rec) / 1e3:7.1f} kN{'  PARTED' if res['parted'] else ''}")
