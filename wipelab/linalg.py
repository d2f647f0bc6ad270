"""Small dense linear algebra in plain loops, for numba kernels (and numpy callers alike)."""

from __future__ import annotations

import math

import numpy as np
from numba.extending import register_jitable


@register_jitable
def solve_positive_definite(matrix: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """x with matrix x = rhs by Cholesky (matrix (m, m) symmetric positive definite, only its
    lower triangle read; rhs (m, k)).

    Loops: compiled by numba without its LAPACK bindings (np.linalg.solve alone added 11 s
    to the kernel's first compilation).
    """
    m = matrix.shape[0]
    lower = np.zeros((m, m))
    for i in range(m):
        for j in range(i + 1):
            total = matrix[i, j]
            for k in range(j):
                total -= lower[i, k] * lower[j, k]
            lower[i, j] = math.sqrt(total) if i == j else total / lower[j, j]
    x = np.empty(rhs.shape)
    for column in range(rhs.shape[1]):
        for i in range(m):                                  # lower y = rhs
            total = rhs[i, column]
            for k in range(i):
                total -= lower[i, k] * x[k, column]
            x[i, column] = total / lower[i, i]
        for i in range(m - 1, -1, -1):                      # lower^T x = y
            total = x[i, column]
            for k in range(i + 1, m):
                total -= lower[k, i] * x[k, column]
            x[i, column] = total / lower[i, i]
    return x
