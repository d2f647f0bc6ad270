"""The periodic kernels of the output system (eq. 8)."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from wipelab.numba_cache import forget_stale_kernels


def default_width(n_kernels: int) -> float:
    """Kernel width h = 2.5 N, the value of the JSI periodic-DMP code: neighbours overlap at ~0.5."""
    return 2.5 * n_kernels


def kernel_centres(n_kernels: int) -> np.ndarray:
    """Centres c_i = 2 pi i / N, i = 0..N-1 (rad), equally spaced over one period; shape (N,)."""
    return 2.0 * np.pi * np.arange(n_kernels) / n_kernels


@njit(cache=True)
def activation(phase: float, centre: float, width: float) -> float:
    """Eq. 8 for one kernel: psi = exp(h (cos(phi - c) - 1)), which peaks (= 1) at phi = c
    (phase and centre in rad, width h dimensionless)."""
    return math.exp(width * (math.cos(phase - centre) - 1.0))


@njit(cache=True)
def activations(phase: float, centres, width: float, out) -> None:
    """Eq. 8 for every kernel at one phase (rad): psi_i into out (N,), centres c_i (N,)."""
    for i in range(centres.shape[0]):
        out[i] = activation(phase, centres[i], width)


def kernel_activations(phase, n_kernels: int, width: float) -> np.ndarray:
    """Eq. 8 at many phases (the array form of :func:`activation`):
    psi_i = exp(h (cos(phi - c_i) - 1)), which peaks (= 1) at phi = c_i.

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


forget_stale_kernels(__name__)
