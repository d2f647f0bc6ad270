"""Batch (ridge) regression of the DMP weights over a whole recording.

Rather than regressing the forcing term on differentiated positions (which amplifies noise
twice and needs lag-free derivatives), the weights are fitted to the positions themselves
through the DMP's limit cycle, which is linear in them:
y(phi) = g + r sum_i w_i B_i(phi) (see :mod:`wipelab.learning.limit_cycle`). The fit then
minimises exactly the reproduction error of the rollout.
"""

from __future__ import annotations

import numpy as np

from wipelab.learning.limit_cycle import limit_cycle_basis

#: Smoothness penalty relative to the mean diagonal of the normal matrix. It decides the
#: weights the data cannot (e.g. 3 Hz seen at 30 Hz: ten distinct phases for 25 kernels) and
#: damps noise; measured over 0.3-3 Hz at 30 and 500 Hz, 1e-2 never raised the error.
SMOOTHING = 1e-2


def fit_weights(phase: np.ndarray, Y: np.ndarray, goal: np.ndarray, amplitude: np.ndarray,
                n_kernels: int, width: float, alpha_s: float = 12.0, beta_s: float = 3.0,
                smoothing: float = SMOOTHING) -> np.ndarray:
    """Weights whose limit cycle best reproduces Y at the given phases (regularised least squares).

    Minimises sum_t |y_t - g - r B(phi_t) w|^2 + lambda |D w|^2 per DOF, where D takes circular
    second differences of the weights over the kernels (a smooth waveform is preferred where
    the data leave the weights free) and lambda = smoothing x mean diagonal of B^T B.

    Parameters
    ----------
    phase : ndarray, shape (n,)
        Canonical phase of each sample (rad).
    Y : ndarray, shape (n, d)
        Positions (m).
    goal, amplitude : ndarray, shape (d,)
        Anchor g and amplitude r per DOF (m; r > 0).
    n_kernels, width, alpha_s, beta_s :
        As in eqs. 6-8.
    smoothing : float
        Relative smoothness penalty.

    Returns
    -------
    weights : ndarray, shape (d, N)
    """
    basis = limit_cycle_basis(phase, n_kernels, width, alpha_s, beta_s)        # (n, N)
    gram = basis.T @ basis
    gram += smoothness_penalty(n_kernels, smoothing * np.trace(gram) / n_kernels)
    targets = (np.asarray(Y, dtype=np.float64) - goal) / amplitude              # (n, d)
    return np.linalg.solve(gram, basis.T @ targets).T


def smoothness_penalty(n_kernels: int, weight: float) -> np.ndarray:
    """weight x D^T D, D the circular second differences over the N kernels; shape (N, N)."""
    second_difference = np.roll(np.eye(n_kernels), -1, axis=1) - 2.0 * np.eye(n_kernels) \
        + np.roll(np.eye(n_kernels), 1, axis=1)
    return weight * (second_difference.T @ second_difference)
