"""ROS-free linear model of the lockstep vessel-rope exchange (issue 30 item 4).

Bodies: a (the tug) and b (a second free body, or a fixed point), 1-DOF along the line.
Rope: a massless spring-damper between them, k = EA/L, c_r (the chain's end-to-end damping).
The lockstep network (sim_plumbing/stepping.py): the rope computes k-1 -> k from the vessels'
attachments stamped k-1, moving each end linearly x_{k-1} + v_{k-1} s over the step, and
publishes the force averaged over it (RopeChain.mean_end_force), stamped k; the vessel applies
that force, constant, over its step k -> k+1. The vessel integrates exactly (matrix exponential;
its RK4 with sub-steps <= 0.1 s is exact to 1e-7 for these frequencies).

Schemes for the force the vessel applies over its step k -> k+1 (s in [0, h] the time into it):
  lag   : F = Fbar_k = -k (xa_{k-1} + va_{k-1} h/2 - xb_{k-1} - vb_{k-1} h/2) - c_r (va_{k-1} - vb_{k-1})
          (what the code does now)
  pred  : the rope drives its ends at x_{k-1} + v_{k-1} (h + s): its mean force is the spring at
          the predicted middle of the step it acts over (x_{k-1} + 1.5 h v_{k-1}); fender.py's
          predict_half_step
  extrap: F = 2 Fbar_k - Fbar_{k-1} (linear force extrapolation)
  jac   : the rope publishes Fbar_k, its end Jacobians dF/dx = -kJ, dF/dv = -cJ and the reference
          end state it used (xhat = x_{k-1} + v_{k-1} h/2, vhat = v_{k-1}); the vessel applies
          F(s) = Fbar_k - kJ (xa(s) - xhat_a) - cJ (va(s) - vhat_a) + [other end term]
          inside its own integration. Other end (b free):
            jac      : other end lagged (cross Jacobian not used)
            jac_pred : the rope shifts the other end's reference to its predicted middle of the
                       vessel's step: + kJ (h vb_{k-1}) (+ cJ 0), i.e. 'pred' for the cross term
            jac_now  : the vessel takes the other end's state of step k (its attachments stamped k,
                       a direct subscription) and extrapolates it linearly inside its step:
                       + kJ (xb_k + vb_k s - xhat_b) + cJ (vb_k - vhat_b)
  exact : monolithic (the spring inside both integrations at once), the reference.
"""
from __future__ import annotations

import numpy as np
from scipy.linalg import expm

SCHEMES = ("lag", "pred", "extrap", "jac", "jac_pred", "jac_now", "exact")


def _disc(m, c, kown, cown, h):
    """x' = v, m v' = -c v - kown x - cown v + f0 + f1 s over [0, h]: returns the 2x4 map of
    (x, v, f0, f1) -> (x, v) at s = h."""
    A = np.zeros((4, 4))
    A[0, 1] = 1.0
    A[1, 0] = -kown / m
    A[1, 1] = -(c + cown) / m
    A[1, 2] = 1.0 / m
    A[2, 3] = 1.0
    return expm(A * h)[:2, :]


class Exchange:
    """State z = [xa, va, xb, vb] at steps k and k-1 and k-2 (12 numbers): enough history for
    every scheme. m_b = inf: b is a fixed point."""

    def __init__(self, scheme, h, m_a, c_a, k, c_r, m_b=np.inf, c_b=0.0, kJ=None, cJ=None):
        assert scheme in SCHEMES
        self.scheme, self.h, self.k, self.c_r = scheme, h, k, c_r
        self.m = (m_a, m_b)
        self.c = (c_a, c_b)
        self.fixed_b = not np.isfinite(m_b)
        self.kJ = k if kJ is None else kJ      # the rope's estimate of its stiffness
        self.cJ = c_r if cJ is None else cJ
        jac = scheme.startswith("jac")
        self.D = [None if (i == 1 and self.fixed_b) else
                  _disc(self.m[i], self.c[i], self.kJ if jac else 0.0, self.cJ if jac else 0.0, h)
                  for i in range(2)]
        if scheme == "exact":
            self._exact_map()

    def _exact_map(self):
        m_a, m_b = self.m
        A = np.zeros((4, 4))
        A[0, 1] = A[2, 3] = 1.0
        A[1, 0], A[1, 2] = -self.k / m_a, self.k / m_a
        A[1, 1], A[1, 3] = -(self.c[0] + self.c_r) / m_a, self.c_r / m_a
        if not self.fixed_b:
            A[3, 0], A[3, 2] = self.k / m_b, -self.k / m_b
            A[3, 1], A[3, 3] = self.c_r / m_b, -(self.c[1] + self.c_r) / m_b
        self.Phi = expm(A * self.h)

    def fbar(self, z):
        """Mean rope force on a over the rope's step from state z (ends moving linearly)."""
        xa, va, xb, vb = z
        h = self.h
        return -self.k * ((xa + 0.5 * h * va) - (xb + 0.5 * h * vb)) - self.c_r * (va - vb)

    def step(self, hist):
        """hist = [z_k, z_{k-1}, z_{k-2}] -> z_{k+1}."""
        z, z1, z2 = hist
        h, s = self.h, self.scheme
        if s == "exact":
            return self.Phi @ z
        out = np.zeros(4)
        if s == "lag":
            fa = (self.fbar(z1), 0.0)
            fb = fa
        elif s == "pred":
            zp = z1 + np.array([h * z1[1], 0.0, h * z1[3], 0.0])   # ends driven one step ahead
            fa = (self.fbar(zp), 0.0)
            fb = fa
        elif s == "extrap":
            fa = (2 * self.fbar(z1) - self.fbar(z2), 0.0)
            fb = fa
        else:
            F = self.fbar(z1)
            xhat_a, vhat_a = z1[0] + 0.5 * h * z1[1], z1[1]
            xhat_b, vhat_b = z1[2] + 0.5 * h * z1[3], z1[3]
            lead = h if s == "jac_pred" else 0.0
            # force on a: F - kJ (xa - xhat_a) + kJ (xb_ref - xhat_b) - cJ (va - vhat_a) + ...
            # the own-end terms go into a's integration (kown, cown); constant part here
            fa0 = F + self.kJ * xhat_a + self.cJ * vhat_a + self.kJ * lead * z1[3]
            fa = (fa0, 0.0)
            if s == "jac_now" and not self.fixed_b:
                fa = (F + self.kJ * (xhat_a + z[2] - xhat_b) + self.cJ * (vhat_a + z[3] - vhat_b), self.kJ * z[3])
            # force on b is -F(a) with the roles swapped: -F + kJ (xb - xhat_b) ... own-end terms
            # of b: dF_b/dxb = -kJ as well
            fb0 = -F + self.kJ * xhat_b + self.cJ * vhat_b + self.kJ * lead * z1[1]
            fb = (fb0, 0.0)
            if s == "jac_now" and not self.fixed_b:
                fb = (-F + self.kJ * (xhat_b + z[0] - xhat_a) + self.cJ * (vhat_b + z[1] - vhat_a), self.kJ * z[1])
            # note: with b's own term in b's integration, force on b = fb0 - kJ xb - cJ vb
        Da = self.D[0]
        out[:2] = Da @ np.array([z[0], z[1], fa[0], fa[1]])
        if not self.fixed_b:
            if s in ("lag", "pred", "extrap"):
                fb = (-fb[0], -fb[1])
            out[2:] = self.D[1] @ np.array([z[2], z[3], fb[0], fb[1]])
        return out

    def matrix(self):
        """The one-step map of the 12-vector [z_k, z_{k-1}, z_{k-2}] (linear, homogeneous)."""
        M = np.zeros((12, 12))
        for j in range(12):
            e = np.zeros(12)
            e[j] = 1.0
            hist = [e[0:4], e[4:8], e[8:12]]
            M[0:4, j] = self.step(hist)
            M[4:8, j] = e[0:4]
            M[8:12, j] = e[4:8]
        if self.fixed_b:          # b's rows/cols are identically zero: drop them
            keep = [i for i in range(12) if i % 4 < 2]
            M = M[np.ix_(keep, keep)]
        return M

    def growth_rate(self):
        """ln(spectral radius) / h: > 0 the exchange grows, < 0 it decays (1/s). Modes of the
        free-free pair's rigid translation (eigenvalue 1) are removed."""
        lam = np.linalg.eigvals(self.matrix())
        if not self.fixed_b and self.c[0] == 0.0 and self.c[1] == 0.0:
            # the pair's common translation (momentum): a double eigenvalue at 1 (a Jordan pair,
            # which rounding splits by ~sqrt(eps)); the two closest to 1 are dropped
            order = np.argsort(np.abs(lam - 1.0))
            lam = lam[order[2:]]
        lam = lam[np.abs(lam) > 1e-12]
        return float(np.log(np.max(np.abs(lam))) / self.h)


def simulate(ex: Exchange, z0, n):
    """Time history z_k, k = 0..n, starting from z0 with the history at rest at z0."""
    hist = [np.array(z0, float)] * 3
    out = [hist[0]]
    for _ in range(n):
        z = ex.step(hist)
        hist = [z, hist[0], hist[1]]
        out.append(z)
    return np.array(out)
