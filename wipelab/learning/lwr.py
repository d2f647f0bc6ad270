"""Incremental locally weighted regression of the DMP weights, eqs. 13-15 (compiled)."""

from __future__ import annotations

import numpy as np
from numba import njit

from wipelab.numba_cache import forget_stale_kernels


@njit(cache=True)
def lwr_update(psi, r, f_target, forgetting: float, weights, P) -> None:
    """One step of eqs. 13-15 for every kernel i and DOF j, in place.

    Kernel i of DOF j fits f_targ ~ w_ij r_j, with samples weighted by psi_i and older samples
    discounted by the forgetting factor lambda per update.

    Parameters
    ----------
    psi : ndarray, shape (N,)
        Kernel activations at the sample's phase (eq. 8).
    r : ndarray, shape (d,)
        Amplitude r(t) per DOF.
    f_target : ndarray, shape (d,)
        f_targ(t) per DOF (see :func:`~wipelab.learning.dmp.forcing_target`).
    forgetting : float
        lambda in (0, 1] for this step.
    weights, P : ndarray, shape (d, N)
        w and P (the inverse covariance of each scalar estimate), updated.
    """
    for j in range(weights.shape[0]):
        for i in range(weights.shape[1]):
            error = f_target[j] - weights[j, i] * r[j]                                  # eq. 15
            # Eq. 14, rearranged: (P - P^2 r^2 / (lambda/psi + P r^2)) / lambda
            # = P / (lambda + psi P r^2), the same value without dividing by psi (which
            # underflows far from the kernel's centre).
            P[j, i] = P[j, i] / (forgetting + psi[i] * P[j, i] * r[j] * r[j])          # eq. 14
            weights[j, i] += psi[i] * P[j, i] * r[j] * error                            # eq. 13


class IncrementalLWR:
    """Eqs. 13-15 for N kernels and d DOFs, started at w = 0, P = p0 (:func:`lwr_update`).

    Parameters
    ----------
    n_kernels, n_dofs : int
        N and d.
    forgetting : float
        lambda in (0, 1], per update (the paper: 0.99).
    p0 : float
        Initial P_i (the paper: 1).

    Attributes
    ----------
    weights_, P_ : ndarray, shape (d, N)
    """

    def __init__(self, n_kernels: int, n_dofs: int, forgetting: float = 0.99, p0: float = 1.0):
        if not 0.0 < forgetting <= 1.0:
            raise ValueError(f"forgetting must be in (0, 1], got {forgetting}")
        if p0 <= 0.0:
            raise ValueError(f"p0 must be positive, got {p0}")
        self.forgetting = float(forgetting)
        self.weights_ = np.zeros((n_dofs, n_kernels))
        self.P_ = np.full((n_dofs, n_kernels), float(p0))

    def update(self, psi, r, f_target, forgetting: float | None = None) -> None:
        """One recursion step: psi (N,), r (d,), f_target (d,); lambda for this step only."""
        lwr_update(np.asarray(psi, dtype=np.float64), np.asarray(r, dtype=np.float64),
                   np.asarray(f_target, dtype=np.float64),
                   self.forgetting if forgetting is None else float(forgetting),
                   self.weights_, self.P_)


forget_stale_kernels(__name__)
