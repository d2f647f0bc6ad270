"""Online fit of the DMP weights to positions through the limit cycle (recursive, compiled).

The offline fit (:mod:`wipelab.learning.batch_fit`) regresses the positions themselves on the
DMP's limit cycle, y(phi) = g + r sum_i w_i B_i(phi), which is linear in the weights: no
derivatives of noisy samples, and it minimises exactly the error of the movement the DMP
will make. This is the same fit online: exponentially weighted least squares with the same
smoothness penalty, kept in information form per DOF-shared regressor,

    R <- lambda R + dphi (B B^T + Lambda),      X <- lambda X + dphi B z^T,      R W = X,

with z = (y - g) / r per DOF, each sample weighted by the phase dphi it advances (so the fit
is the same at any sample rate), lambda = exp(-dphi / (2 pi memory)) (a memory in periods)
and Lambda the penalty of :func:`~wipelab.learning.batch_fit.smoothness_penalty`, added at the
same rate as the data so that its weight relative to them is the offline one at every time.
The weights come from a Cholesky solve of R (N x N) after each update: a few microseconds
for N = 25.

Compared with the paper's eqs. 13-15 on f_targ (:mod:`wipelab.learning.lwr`, selectable as
``OnlineParameters(regression="lwr")``) it needs no derivative window, so it learns each
sample at once at its own phase instead of half a window late, and it does not amplify the
noise by differentiating twice (measured in ``benchmarks/bench_learn.py``).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from wipelab.learning.batch_fit import smoothness_penalty
from wipelab.learning.limit_cycle import basis_row, basis_table, limit_cycle_basis
from wipelab.linalg import solve_positive_definite
from wipelab.numba_cache import forget_stale_kernels

#: Ridge added to the penalty, relative to the mean diagonal of B B^T (keeps R invertible
#: before a whole period has been seen).
RIDGE = 1e-6


class PositionFit(NamedTuple):
    """State of the recursive position fit.

    Attributes
    ----------
    information : ndarray, shape (N, N)
        R.
    moments : ndarray, shape (N, d)
        X.
    penalty : ndarray, shape (N, N)
        Lambda, per radian of phase.
    table : ndarray, shape (TABLE_SIZE + 1, N)
        The limit-cycle basis B_i (:func:`~wipelab.learning.limit_cycle.basis_table`).
    basis : ndarray, shape (N,)
        Scratch: B at the current phase.
    """

    information: np.ndarray
    moments: np.ndarray
    penalty: np.ndarray
    table: np.ndarray
    basis: np.ndarray


def new_position_fit(n_dofs: int, n_kernels: int, width: float, alpha_s: float, beta_s: float,
                     smoothing: float) -> PositionFit:
    """An empty fit (no data: R = Lambda dphi for one radian, X = 0)."""
    grid = np.linspace(0.0, 2.0 * math.pi, 512, endpoint=False)
    basis = limit_cycle_basis(grid, n_kernels, width, alpha_s, beta_s)
    scale = float(np.trace(basis.T @ basis)) / (grid.size * n_kernels)
    penalty = smoothness_penalty(n_kernels, smoothing * scale) + RIDGE * scale * np.eye(n_kernels)
    return PositionFit(information=penalty.copy(), moments=np.zeros((n_kernels, n_dofs)),
                       penalty=penalty,
                       table=np.ascontiguousarray(basis_table(n_kernels, width, alpha_s, beta_s)),
                       basis=np.zeros(n_kernels))


@njit(cache=True)
def position_fit_restart(fit: PositionFit) -> None:
    """Forget every sample (after the phase was redefined)."""
    fit.information[:] = fit.penalty
    fit.moments[:] = 0.0


@njit(cache=True)
def position_fit_update(fit: PositionFit, phase: float, z, phase_step: float,
                        memory_periods: float) -> None:
    """Absorb one sample: z (d,) = (y - g) / r at ``phase`` (rad), weighted by the phase it
    advances (rad); older samples decay as exp(-phase_step / (2 pi memory_periods))."""
    forgetting = math.exp(-phase_step / (2.0 * math.pi * memory_periods))
    b = fit.basis
    basis_row(fit.table, phase, b)
    n = b.shape[0]
    for i in range(n):
        for k in range(n):
            fit.information[i, k] = forgetting * fit.information[i, k] \
                + phase_step * (b[i] * b[k] + fit.penalty[i, k])
        for j in range(z.shape[0]):
            fit.moments[i, j] = forgetting * fit.moments[i, j] + phase_step * b[i] * z[j]


@njit(cache=True)
def position_fit_weights(fit: PositionFit, weights) -> None:
    """The weights (d, N) that best reproduce the samples so far: R W = X."""
    solution = solve_positive_definite(fit.information, fit.moments)
    for j in range(weights.shape[0]):
        for i in range(weights.shape[1]):
            weights[j, i] = solution[i, j]


forget_stale_kernels(__name__)
