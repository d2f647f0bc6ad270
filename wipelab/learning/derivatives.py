"""Causal estimates of position, velocity and acceleration for eqs. 13-15 on f_targ.

A robot learning from a stream cannot differentiate noisy samples without either lag or
noise. Here each estimate is a local polynomial (Savitzky-Golay) fit over the last L samples
(:func:`polynomial_fit_matrix`), evaluated at the window's centre
(:func:`evaluate_polynomial` at x = 0): no phase lag relative to the centre sample, at the
price of learning (L - 1) / 2 samples late. The learners pair the estimate with the phase
and frequency recorded at that centre sample, so the weights are learned at the right phase
(the online learner's ``regression="lwr"`` and the force-profile learner of
:mod:`wipelab.control.force_profile`). L follows the current period (a fixed fraction of
it, odd, at least 5 samples: :func:`window_for`).

The same polynomial also gives position, velocity and acceleration *between* samples. At
30 Hz a 3 Hz movement has ten samples per period for 25 kernels: the samples fall on ten
phases, and a kernel between two of them learns only from its tails. The online learner
updates the regression at points within half a sample of the centre, spaced by at most
half the kernel spacing, which covers every kernel.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
from numba import njit

from wipelab.numba_cache import forget_stale_kernels

MIN_WINDOW = 5


@lru_cache(maxsize=64)
def polynomial_fit_matrix(window: int, degree: int) -> np.ndarray:
    """Least-squares polynomial coefficients from a window: row q gives c_q of sum_q c_q j^q.

    Parameters
    ----------
    window : int
        L, odd, >= 3; j = -(L - 1) / 2 .. (L - 1) / 2 samples from the centre.
    degree : int
        Polynomial degree p (clipped to L - 1).

    Returns
    -------
    ndarray, shape (p + 1, L)
    """
    if window < 3 or window % 2 == 0:
        raise ValueError(f"window must be odd and >= 3, got {window}")
    degree = min(degree, window - 1)
    j = np.arange(window) - (window - 1) / 2
    matrix = np.linalg.pinv(j[:, None] ** np.arange(degree + 1))
    matrix.setflags(write=False)
    return matrix


@njit(cache=True)
def evaluate_polynomial(coefficients: np.ndarray, x: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Value, 1st and 2nd derivative (per sample^k) at x samples from the centre.

    Parameters
    ----------
    coefficients : ndarray, shape (p + 1, d)
        From ``polynomial_fit_matrix(L, p) @ values``.
    x : float
        Position in samples relative to the window's centre.

    Returns
    -------
    y, y', y'' : ndarray, shape (d,) each
    """
    value = np.zeros(coefficients.shape[1])
    first = np.zeros(coefficients.shape[1])
    second = np.zeros(coefficients.shape[1])
    power, below1, below2 = 1.0, 0.0, 0.0                       # x^q, x^(q-1), x^(q-2)
    for q in range(coefficients.shape[0]):
        value += coefficients[q] * power
        first += q * coefficients[q] * below1
        second += q * (q - 1) * coefficients[q] * below2
        below2, below1, power = below1, power, power * x
    return value, first, second


@njit(cache=True)
def window_for(omega: float, dt: float, window_periods: float, max_window: int) -> int:
    """Odd window length covering ``window_periods`` of the period 2 pi / Omega, in [5, max_window]."""
    samples = window_periods * 2.0 * math.pi / (max(omega, 1e-12) * dt)
    window = 2 * int(round((samples - 1.0) / 2.0)) + 1
    return min(max(window, MIN_WINDOW), max_window)


forget_stale_kernels(__name__)
