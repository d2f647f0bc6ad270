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
(:func:`afs_lock`). A gain schedule after the lock (couple weakly while
the series fits, strongly while its residual is large) is available and off by default: see
:mod:`wipelab.learning.oscillators`.

``AFSParameters.petric()`` gives the published constant gains. Several DOFs share phi and
Omega. Integrated with explicit Euler substeps (:func:`afs_substep`, compiled; the online
learner calls it); series terms at or above the Nyquist frequency of the samples are
switched off.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from numba import njit

from wipelab.learning.oscillators import (OscillatorGains, OscillatorState, gain_scale,
                                          locked_boost, nearest_turn, new_oscillator_state,
                                          phase_drive)
from wipelab.numba_cache import forget_stale_kernels


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

    def gains(self) -> OscillatorGains:
        """The gains in the compiled substep's units (rad/s)."""
        return OscillatorGains(
            coupling=self.coupling, frequency_coupling=self.frequency_coupling,
            learning_rate=self.learning_rate, scale_with_frequency=self.scale_with_frequency,
            min_omega=2.0 * math.pi * self.min_frequency_hz,
            max_omega=2.0 * math.pi * self.max_frequency_hz,
            locked_coupling=self.locked_coupling, residual_gain=self.residual_gain,
            residual_periods=self.residual_periods, zero_omega=0.0, reset_dwell_s=math.inf)

    def new_state(self, n_dofs: int) -> OscillatorState:
        """The AFS at rest: Omega(0), phi = 0, no series (M + 1 coefficients per DOF)."""
        return new_oscillator_state(n_dofs, [2.0 * math.pi * self.initial_frequency_hz],
                                    self.n_terms + 1)


@njit(cache=True)
def afs_substep(state: OscillatorState, gains: OscillatorGains, u, h: float, dt: float,
                reference: int, mean_coupling: bool, error, cosines, sines) -> None:
    """One explicit Euler substep of h seconds of the AFS with input u (d,), in place.

    dt is the sample interval: terms c with c Omega dt >= pi (at or above Nyquist) are off.
    error (d,), cosines and sines (M + 1,) are scratch arrays.
    """
    alpha, beta = state.alpha, state.beta
    phase, omega = state.phases[0], state.omegas[0]
    m = gain_scale(omega, gains.scale_with_frequency)
    n_terms = 0
    while n_terms < alpha.shape[1] and n_terms * omega * dt < math.pi:
        n_terms += 1
    # cos(c phi), sin(c phi) by the angle-addition recurrence: two trig calls, not 2 M.
    cos_phi, sin_phi = math.cos(phase), math.sin(phase)
    cosines[0], sines[0] = 1.0, 0.0
    for c in range(1, n_terms):
        cosines[c] = cosines[c - 1] * cos_phi - sines[c - 1] * sin_phi
        sines[c] = sines[c - 1] * cos_phi + cosines[c - 1] * sin_phi
    for j in range(u.shape[0]):
        prediction = 0.0
        for c in range(n_terms):
            prediction += alpha[j, c] * cosines[c] + beta[j, c] * sines[c]
        error[j] = u[j] - prediction                                    # the series' eq. 3
    drive = phase_drive(error, sin_phi, cos_phi, alpha, beta, 1, reference, mean_coupling)
    drive *= locked_boost(state, gains, error, omega, h)
    state.phases[0] = phase + h * (omega - gains.coupling * m * drive)            # eq. 1
    omega -= h * gains.frequency_coupling * m * m * drive                          # eq. 2
    state.omegas[0] = min(max(omega, gains.min_omega), gains.max_omega)
    rate = h * gains.learning_rate * m
    for j in range(u.shape[0]):
        for c in range(n_terms):
            alpha[j, c] += rate * error[j] * cosines[c]
            beta[j, c] += rate * error[j] * sines[c]
    beta[reference, 1] = 0.0


@njit(cache=True)
def afs_lock(state: OscillatorState, omega: float, phase: float, alpha, beta) -> None:
    """Start from a known frequency and series (:func:`~wipelab.learning.harmonic.locked_series`):
    Omega (rad/s), phi now (rad; the nearest equivalent angle to the current phase is
    taken), coefficients (d, M + 1) in phi."""
    state.omegas[0] = omega
    state.phases[0] += nearest_turn(phase - state.phases[0])
    state.alpha[:] = alpha
    state.beta[:] = beta
    state.locked[0] = 1.0
    state.residual[0] = 0.0


forget_stale_kernels(__name__)
