"""The periodic kernels of the output system (eq. 8) and the forcing term they weight (eq. 6)."""

from __future__ import annotations

import numpy as np


def default_width(n_kernels: int) -> float:
    """Kernel width h = 2.5 N, the value of the JSI periodic-DMP code: neighbours overlap at ~0.5."""
    return 2.5 * n_kernels


def kernel_centres(n_kernels: int) -> np.ndarray:
    """Centres c_i = 2 pi i / N, i = 0..N-1 (rad), equally spaced over one period; shape (N,)."""
    return 2.0 * np.pi * np.arange(n_kernels) / n_kernels


def kernel_activations(phase, n_kernels: int, width: float) -> np.ndarray:
    """Eq. 8: psi_i = exp(h (cos(phi - c_i) - 1)), which peaks (= 1) at phi = c_i.

    Parameters
    ----------
    phase : float or array, shape (...)
        Canonical phase phi in rad (any real value; the kernels are 2 pi periodic).
    n_kernels : int
        N.
    width : float
        h, dimensionless; larger is narrower (about a Gaussian of std 1/sqrt(h) rad).

    Returns
    -------
    psi : ndarray, shape (..., N)
    """
    phase = np.asarray(phase, dtype=np.float64)
    return np.exp(width * (np.cos(phase[..., None] - kernel_centres(n_kernels)) - 1.0))


def normalised_forcing(psi: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """The forcing shape sum_i psi_i w_i / sum_i psi_i of eq. 6, before the amplitude r.

    Parameters
    ----------
    psi : ndarray, shape (..., N)
        Kernel activations.
    weights : ndarray, shape (d, N)
        One row of weights per DOF.

    Returns
    -------
    ndarray, shape (..., d)
    """
    return (psi @ weights.T) / psi.sum(axis=-1, keepdims=True)
