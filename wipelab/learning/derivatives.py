"""Causal estimates of position, velocity and acceleration for the online learner.

A robot learning from a stream cannot differentiate noisy samples without either lag or
noise. Here each estimate is a local polynomial (Savitzky-Golay) fit over the last L samples,
evaluated at the window's centre: no phase lag relative to the centre sample, at the price of
learning (L - 1) / 2 samples late. The learner pairs the estimate with the phase and
frequency recorded at that centre sample, so the weights are learned at the right phase.
L follows the current period (a fixed fraction of it, odd, at least 5 samples).

The same polynomial also gives position, velocity and acceleration *between* samples
(:meth:`CentredDerivatives.between`). At 30 Hz a 3 Hz movement has ten samples per period
for 25 kernels: the samples fall on ten phases, and a kernel between two of them learns only
from its tails. Updating the regression at points within half a sample of the centre,
spaced by at most half the kernel spacing, covers every kernel (see
:func:`wipelab.learning.online.update_points`; the online kernel calls
:func:`evaluate_polynomial`).
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


@lru_cache(maxsize=64)
def savgol_centre_coefficients(window: int, degree: int) -> np.ndarray:
    """Weights giving value, 1st and 2nd derivative (per sample^k) at the centre of a window.

    Parameters
    ----------
    window : int
        L, odd, >= 3.
    degree : int
        Polynomial degree p (clipped to L - 1), >= 2.

    Returns
    -------
    ndarray, shape (3, L)
        Row k applied to the L samples (oldest first) gives d^k y / dj^k at the centre, with j
        in samples; divide by dt^k for time units.
    """
    coefficients = polynomial_fit_matrix(window, degree)[:3] * np.array([1.0, 1.0, 2.0])[:, None]
    coefficients.setflags(write=False)
    return coefficients


def window_for(omega: float, dt: float, window_periods: float, max_window: int) -> int:
    """Odd window length covering ``window_periods`` of the period 2 pi / Omega, in [5, max_window]."""
    samples = window_periods * 2.0 * math.pi / (max(omega, 1e-12) * dt)
    window = 2 * int(round((samples - 1.0) / 2.0)) + 1
    return min(max(window, MIN_WINDOW), max_window)


class CentredDerivatives:
    """Ring buffer of recent samples with their phase and frequency; centred polynomial fits.

    Parameters
    ----------
    n_dofs : int
    dt : float
        Sample interval (s).
    window_periods : float
        Fraction of the current period spanned by the window.
    degree : int
        Polynomial degree.
    max_window : int
        Largest window (odd), also the buffer length.
    """

    def __init__(self, n_dofs: int, dt: float, window_periods: float, degree: int, max_window: int):
        self.dt = dt
        self.window_periods = window_periods
        self.degree = degree
        self.max_window = max_window
        self.count_ = 0
        self.valid_run_ = 0
        self.values_ = np.zeros((max_window, n_dofs))
        self.phases_ = np.zeros(max_window)
        self.omegas_ = np.zeros(max_window)

    def push(self, y: np.ndarray, phase: float, omega: float, valid: bool = True) -> None:
        """Store sample y (d,) with the canonical phase (rad) and Omega (rad/s) at its time.

        An invalid sample (a gap in the input, y bridged) keeps every window that holds it
        from giving estimates."""
        slot = self.count_ % self.max_window
        self.values_[slot], self.phases_[slot], self.omegas_[slot] = y, phase, omega
        self.count_ += 1
        self.valid_run_ = self.valid_run_ + 1 if valid else 0

    def centre(self, omega: float):
        """Estimates at the centre of the current window, or None while too few valid samples.

        Returns
        -------
        (y, yd, ydd, phase, omega) : ndarray (d,) x 3 in m, m/s, m/s^2; float rad; float rad/s
        """
        window = window_for(omega, self.dt, self.window_periods, self.max_window)
        if self.valid_run_ < window:
            return None
        slots = (self.count_ - window + np.arange(window)) % self.max_window
        estimates = savgol_centre_coefficients(window, self.degree) @ self.values_[slots]
        centre = slots[(window - 1) // 2]
        return (estimates[0], estimates[1] / self.dt, estimates[2] / self.dt ** 2,
                self.phases_[centre], self.omegas_[centre])

    def between(self, omega: float, points: int):
        """Estimates at ``points`` positions x_s = (s + 1/2) / points - 1/2 samples around the
        centre of the current window (x = 0 for one point), or None while too few valid samples.

        The phase at x is the centre sample's phase plus x Omega_c dt.

        Returns
        -------
        (y, yd, ydd, phase, omega) : ndarray (points, d) x 3 in m, m/s, m/s^2; ndarray
        (points,) in rad; float, Omega at the centre sample in rad/s
        """
        window = window_for(omega, self.dt, self.window_periods, self.max_window)
        if self.valid_run_ < window:
            return None
        slots = (self.count_ - window + np.arange(window)) % self.max_window
        coefficients = polynomial_fit_matrix(window, self.degree) @ self.values_[slots]
        centre = slots[(window - 1) // 2]
        omega_c = self.omegas_[centre]
        offsets = (np.arange(points) + 0.5) / points - 0.5
        estimates = np.array([evaluate_polynomial(coefficients, x) for x in offsets])  # (S, 3, d)
        return (estimates[:, 0], estimates[:, 1] / self.dt, estimates[:, 2] / self.dt ** 2,
                self.phases_[centre] + offsets * omega_c * self.dt, omega_c)


forget_stale_kernels(__name__)
