"""Incremental locally weighted regression of the DMP weights, eqs. 13-15."""

from __future__ import annotations

import numpy as np


class IncrementalLWR:
    """One scalar recursive least-squares estimator per kernel and DOF (eqs. 13-15).

    Kernel i of DOF j fits f_targ ~ w_ij r_j, with samples weighted by psi_i and older samples
    discounted by the forgetting factor lambda per update. Started at w = 0, P = p0.

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
    weights_ : ndarray, shape (d, N)
        Current w.
    P_ : ndarray, shape (d, N)
        Current P (the inverse covariance of each scalar estimate).
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
        """One recursion step.

        Parameters
        ----------
        psi : array, shape (N,)
            Kernel activations at the sample's phase (eq. 8).
        r : array, shape (d,)
            Amplitude r(t) per DOF.
        f_target : array, shape (d,)
            f_targ(t) per DOF (see :func:`forcing_target`).
        forgetting : float, optional
            lambda for this step only (default: the constructor's).
        """
        forgetting = self.forgetting if forgetting is None else forgetting
        psi = np.asarray(psi, dtype=np.float64)[None, :]
        r = np.asarray(r, dtype=np.float64)[:, None]
        error = np.asarray(f_target, dtype=np.float64)[:, None] - self.weights_ * r      # eq. 15
        # Eq. 14, rearranged: (P - P^2 r^2 / (lambda/psi + P r^2)) / lambda = P / (lambda + psi P r^2),
        # the same value without dividing by psi (which underflows far from the kernel's centre).
        self.P_ = self.P_ / (forgetting + psi * self.P_ * r ** 2)
        self.weights_ += psi * self.P_ * r * error                                         # eq. 13
