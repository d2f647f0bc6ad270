"""Canonical system (b): the adaptive Fourier series of Petric, Gams and Zlajpah (2011).

One adaptive-frequency phase oscillator learns a truncated Fourier series of the input,
y_hat = sum_{c=0}^{M} alpha_c cos(c phi) + beta_c sin(c phi), and is driven by its error
(the form of eqs. 1-3, with eq. 4 replaced by the series):

    phi' = Omega - K e sin(phi),   Omega' = -K_Omega e sin(phi),
    alpha_c' = nu e cos(c phi),    beta_c' = nu e sin(c phi),   beta_1 = 0 (defines phi).

Because the series holds the offset and every harmonic, the oscillator settles on the
fundamental without the pool's logic step -- provided it approaches from above: a series at
f/2 fits a signal of period 1/f just as well (with even terms only), so an oscillator started
below the fundamental can lock onto a subharmonic. The default initial frequency is therefore
the top of the expected range (3 Hz for wiping), and the gains scale with the frequency (see
:mod:`wipelab.learning.oscillators`).

In the learner the approach from above is only the fallback: the start-up period detector
normally hands the series its frequency, phase and coefficients after about two periods
(:meth:`AdaptiveFourierSeries.lock`). A gain schedule after the lock (couple weakly while
the series fits, strongly while its residual is large) is available and off by default: see
:mod:`wipelab.learning.oscillators`.

``AFSParameters.petric()`` gives the published constant gains. Several DOFs share phi and
Omega. Integrated with explicit Euler substeps; series terms at or above the Nyquist
frequency of the samples are switched off.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from wipelab.learning.oscillators import (DOF_COUPLINGS, gain_scale, interpolated_inputs,
                                          nearest_turn, phase_drive, residual_step)


@dataclass(frozen=True)
class AFSParameters:
    """Parameters of the adaptive Fourier series (gains at 1 Hz when scaled).

    K, K_Omega and nu were chosen by grid search on the benchmark signals (0.3-3 Hz, 30 and
    500 Hz sampling, two DOFs): larger gains warp the phase with the harmonics and the noise,
    smaller ones lock slowly.
    """

    n_terms: int = 10                  # M, harmonics of the series (plus the offset)
    coupling: float = 5.0              # K (1/s)
    frequency_coupling: float = 10.0   # K_Omega (1/s^2)
    learning_rate: float = 2.0         # nu (1/s)
    scale_with_frequency: bool = True  # gains x (Omega / 2 pi), K_Omega x (Omega / 2 pi)^2
    initial_frequency_hz: float = 3.0  # Omega(0) / 2 pi (Hz): the top of the expected range
    min_frequency_hz: float = 0.05     # Omega is kept in [min, max] (Hz)
    max_frequency_hz: float = 10.0
    locked_coupling: float = 1.0       # c_L: once locked, K, K_Omega x (c_L + kappa E), E = mean e^2
    residual_gain: float = 0.0         # kappa (the gain schedule is off by default)
    residual_periods: float = 1.0      # E is low-passed over this many periods

    @classmethod
    def petric(cls) -> AFSParameters:
        """The published defaults: M = 10, nu = 2, K = K_Omega = 20, Omega(0) = 2 pi, unscaled,
        the same gains before and after a lock."""
        return cls(n_terms=10, coupling=20.0, frequency_coupling=20.0, learning_rate=2.0,
                   scale_with_frequency=False, initial_frequency_hz=1.0, locked_coupling=1.0,
                   residual_gain=0.0)


class AdaptiveFourierSeries:
    """The AFS canonical system for d DOFs (reference implementation, numpy).

    Attributes
    ----------
    phase_ : float
        phi (rad), unwrapped.
    omega_ : float
        Omega (rad/s).
    alpha_, beta_ : ndarray, shape (d, M + 1)
        Cosine and sine coefficients per DOF, index c = 0..M (normalised input units).
    """

    def __init__(self, n_dofs: int, params: AFSParameters = AFSParameters(), reference: int = 0,
                 dof_coupling: str = "mean"):
        if dof_coupling not in DOF_COUPLINGS:
            raise ValueError(f"dof_coupling must be one of {DOF_COUPLINGS}, got {dof_coupling!r}")
        self.params = params
        self.reference = reference
        self.mean_coupling = dof_coupling == "mean"
        self.harmonics = np.arange(params.n_terms + 1)
        self.phase_ = 0.0
        self.omega_ = 2.0 * math.pi * params.initial_frequency_hz
        self.alpha_ = np.zeros((n_dofs, params.n_terms + 1))
        self.beta_ = np.zeros((n_dofs, params.n_terms + 1))
        self.dt = math.inf
        self.locked_ = False
        self.residual_ = 0.0

    def _substep(self, u: np.ndarray, h: float) -> None:
        p = self.params
        m = gain_scale(self.omega_, p.scale_with_frequency)
        angles = self.harmonics * self.phase_
        # Terms at or above the Nyquist frequency of the samples cannot be observed: off.
        observable = self.harmonics * self.omega_ * self.dt < math.pi
        cos_c = np.where(observable, np.cos(angles), 0.0)
        sin_c = np.where(observable, np.sin(angles), 0.0)
        error = u - (self.alpha_ @ cos_c + self.beta_ @ sin_c)
        drive = phase_drive(error, self.phase_, self.alpha_[:, 1], self.beta_[:, 1],
                            self.reference, self.mean_coupling)
        if self.locked_:
            self.residual_ = residual_step(self.residual_, error, self.omega_, h, p.residual_periods)
            drive = drive * (p.locked_coupling + p.residual_gain * self.residual_)
        self.phase_ += h * (self.omega_ - p.coupling * m * drive)
        omega = self.omega_ - h * p.frequency_coupling * m * m * drive
        self.omega_ = min(max(omega, 2.0 * math.pi * p.min_frequency_hz),
                          2.0 * math.pi * p.max_frequency_hz)
        self.alpha_ += (h * p.learning_rate * m) * error[:, None] * cos_c
        self.beta_ += (h * p.learning_rate * m) * error[:, None] * sin_c
        self.beta_[self.reference, 1] = 0.0

    def lock(self, omega: float, phase: float, alpha: np.ndarray, beta: np.ndarray, dt: float) -> None:
        """Start from a known frequency and series (see :func:`~wipelab.learning.harmonic.locked_series`).

        Parameters
        ----------
        omega : float
            Omega (rad/s).
        phase : float
            phi now (rad); the nearest equivalent angle to the current phase is taken.
        alpha, beta : ndarray, shape (d, M + 1)
            Series coefficients in phi.
        dt : float
            Sample interval (s).
        """
        self.dt = dt
        self.omega_ = float(omega)
        self.phase_ += nearest_turn(phase - self.phase_)
        self.alpha_ = np.array(alpha, dtype=np.float64)
        self.beta_ = np.array(beta, dtype=np.float64)
        self.locked_ = True
        self.residual_ = 0.0

    def advance(self, previous: np.ndarray, current: np.ndarray, dt: float, n_sub: int) -> None:
        """Integrate over one sample interval dt with the input (d,) linear from previous to current."""
        self.dt = dt
        h = dt / n_sub
        for u in interpolated_inputs(previous, current, n_sub):
            self._substep(u, h)

    def free_run(self, dt: float) -> None:
        """Advance dt without input (a gap): phi at Omega, nothing learned."""
        self.phase_ += dt * self.omega_

    @property
    def frequencies_hz(self) -> np.ndarray:
        """The oscillator frequency as an array of one (Hz), for logging like the AFO pool."""
        return np.array([self.omega_ / (2.0 * math.pi)])

    @property
    def fundamental(self) -> tuple[float, float]:
        """(phase phi in rad, instantaneous Omega in rad/s)."""
        return self.phase_, self.omega_
