"""Small dense linear solves for the numba kernels, written once: LU factorisation with partial
pivoting (Gaussian elimination, row interchanges) and the substitutions with its factors.

Used by the rope chain's pivoting fallback (5x5 blocks), the finite-difference cable's block
tri-diagonal solve (10x10 blocks) and the planing hull's 6x6 mass matrix. Plain loops without
fastmath: every caller gets the same rounding. The order of the operations is that of the
cable's former solver (multipliers times the reciprocal of the pivot, back substitution
column by column from the last row up), so its results are bit-identical to it.

    piv = np.empty(n, np.int64)
    if lu_factor(M, piv):             # M (n x n) overwritten by its factors
        lu_solve(M, piv, b)           # b (n) overwritten by M^-1 b
        lu_solve_columns(M, piv, B, m)  # the first m columns of B (n x k) likewise
"""
import math

from numba import njit


@njit(cache=True)
def lu_factor(M, piv):
    """Factor the square matrix M in place as P M = L U: U on and above the diagonal, the
    multipliers of the unit lower L below it; piv[c] is the row swapped with row c at step c
    (int array, length n). Returns False (M partly factored) if a pivot is zero or not finite."""
    n = M.shape[0]
    for c in range(n):
        p = c
        big = abs(M[c, c])
        for i in range(c + 1, n):
            if abs(M[i, c]) > big:
                big = abs(M[i, c])
                p = i
        piv[c] = p
        if big == 0.0 or not math.isfinite(big):
            return False
        if p != c:
            for k in range(n):
                tmp = M[c, k]
                M[c, k] = M[p, k]
                M[p, k] = tmp
        inv = 1.0 / M[c, c]
        for i in range(c + 1, n):
            f = M[i, c] * inv
            M[i, c] = f
            if f != 0.0:
                for k in range(c + 1, n):
                    M[i, k] -= f * M[c, k]
    return True


@njit(cache=True)
def lu_solve(M, piv, b):
    """Overwrite the vector b with M^-1 b, M and piv from a successful lu_factor."""
    n = M.shape[0]
    for c in range(n):
        p = piv[c]
        if p != c:
            tmp = b[c]
            b[c] = b[p]
            b[p] = tmp
    for c in range(n):
        for i in range(c + 1, n):
            f = M[i, c]
            if f != 0.0:
                b[i] -= f * b[c]
    for c in range(n - 1, -1, -1):
        b[c] *= 1.0 / M[c, c]
        for i in range(c):
            f = M[i, c]
            if f != 0.0:
                b[i] -= f * b[c]


@njit(cache=True)
def lu_solve_columns(M, piv, B, m):
    """Overwrite the first m columns of B (n x k, k >= m) with M^-1 B[:, :m], M and piv from a
    successful lu_factor; each column is computed exactly as lu_solve would."""
    n = M.shape[0]
    for c in range(n):
        p = piv[c]
        if p != c:
            for k in range(m):
                tmp = B[c, k]
                B[c, k] = B[p, k]
                B[p, k] = tmp
    for c in range(n):
        for i in range(c + 1, n):
            f = M[i, c]
            if f != 0.0:
                for k in range(m):
                    B[i, k] -= f * B[c, k]
    for c in range(n - 1, -1, -1):
        inv = 1.0 / M[c, c]
        for k in range(m):
            B[c, k] *= inv
        for i in range(c):
            f = M[i, c]
            if f != 0.0:
                for k in range(m):
                    B[i, k] -= f * B[c, k]
