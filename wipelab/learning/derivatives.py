"""Causal estimates of position, velocity and acceleration for the online learner.

A robot learning from a stream cannot differentiate noisy samples without either lag or
noise. Here each estimate is a local polynomial (Savitzky-Golay) fit over the last L samples,
evaluated at the window's centre: no phase lag relative to the centre sample, at the price of
learning (L - 1) / 2 samples late. The learner pairs the estimate with the phase and
frequency recorded at that centre sample, so the weights are learned at the right phase.
L follows the current period (a fixed fraction of it, odd, at least 5 samples).
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

MIN_WINDOW = 5


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
    if window < 3 or window % 2 == 0:
        raise ValueError(f"window must be odd and >= 3, got {window}")
    degree = min(degree, window - 1)
    j = np.arange(window) - (window - 1) / 2
    vandermonde = j[:, None] ** np.arange(degree + 1)
    coefficients = np.linalg.pinv(vandermonde)[:3] * np.array([1.0, 1.0, 2.0])[:, None]
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
        self.values_ = np.zeros((max_window, n_dofs))
        self.phases_ = np.zeros(max_window)
        self.omegas_ = np.zeros(max_window)

    def push(self, y: np.ndarray, phase: float, omega: float) -> None:
        """Store sample y (d,) with the canonical phase (rad) and Omega (rad/s) at its time."""
        slot = self.count_ % self.max_window
        self.values_[slot], self.phases_[slot], self.omegas_[slot] = y, phase, omega
        self.count_ += 1

    def centre(self, omega: float):
        """Estimates at the centre of the current window, or None while too few samples.

        Returns
        -------
        (y, yd, ydd, phase, omega) : ndarray (d,) x 3 in m, m/s, m/s^2; float rad; float rad/s
        """
        window = window_for(omega, self.dt, self.window_periods, self.max_window)
        if self.count_ < window:
            return None
        slots = (self.count_ - window + np.arange(window)) % self.max_window
        estimates = savgol_centre_coefficients(window, self.degree) @ self.values_[slots]
        centre = slots[(window - 1) // 2]
        return (estimates[0], estimates[1] / self.dt, estimates[2] / self.dt ** 2,
                self.phases_[centre], self.omegas_[centre])
