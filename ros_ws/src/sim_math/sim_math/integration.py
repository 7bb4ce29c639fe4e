"""The classical fourth-order Runge-Kutta step (Kutta 1901), written once for the numba
kernels that integrate the vessel models.

numba cannot cache a kernel that receives its derivative function as an argument (measured:
"Cannot cache compiled function ... dynamic globals"), so the kernels keep their own calls of
the derivative and use these inline helpers for the stage states and the weighted update."""
import numpy as np
from numba import njit


@njit(cache=True, inline="always")
def rk4_stage(x: np.ndarray, h: float, k: np.ndarray, out: np.ndarray) -> np.ndarray:
    """out = x + h k: the state at which the next stage's derivative is taken (h is half the
    step for stages 2 and 3, the full step for stage 4)."""
    for i in range(x.shape[0]):
        out[i] = x[i] + h * k[i]
    return out


@njit(cache=True, inline="always")
def rk4_update(x: np.ndarray, h: float, k1: np.ndarray, k2: np.ndarray, k3: np.ndarray,
               k4: np.ndarray) -> None:
    """x += h/6 (k1 + 2 k2 + 2 k3 + k4), in place."""
    for i in range(x.shape[0]):
        x[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
