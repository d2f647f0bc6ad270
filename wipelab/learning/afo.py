"""Canonical system (a): the paper's pool of M adaptive-frequency phase oscillators, eqs. 1-5.

    phi_i' = omega_i - K e sin(phi_i)        (1)
    omega_i' = -K e sin(phi_i)               (2)
    e = y_in - y_hat                         (3)
    y_hat = sum_i alpha_i cos(phi_i)         (4)
    alpha_i' = eta cos(phi_i) e              (5)

followed by the logic step of Section III-B: the fundamental Omega is the middle of the M = 3
frequencies (one oscillator sits on the offset at 0 Hz, one on a higher harmonic), and the
pool is reset when more than one oscillator has converged to 0 Hz.

Eq. 4 has no constant term, so the offset must be carried by an oscillator at 0 Hz for the
middle-frequency rule to hold. The learner therefore feeds the pool a normalised input with a
unit offset (see :mod:`wipelab.learning.normalise`). Several DOFs share the oscillators
(see :mod:`wipelab.learning.oscillators`); non-reference DOFs add a sine coefficient beta_i to
eq. 4 with the analogue of eq. 5.

Integrated with explicit Euler substeps (:func:`pool_substep`, compiled; the online learner
calls it). When the start-up detector has found the period, the learner sets the pool to
the state it would converge to (:func:`locked_pool`, :func:`pool_lock`): 0 Hz with the offset, the fundamental, and the
stronger of the 2nd and 3rd harmonics. The gain schedule that steadies the locked AFS
slows the pool down after a frequency step (see :mod:`wipelab.learning.oscillators`), so it
is off by default here (c_L = 1, kappa = 0).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from wipelab.learning.oscillators import (OscillatorGains, OscillatorState, gain_scale,
                                          locked_boost, nearest_turn, new_oscillator_state,
                                          phase_drive)
from wipelab.numba_cache import forget_stale_kernels


@dataclass(frozen=True)
class AFOParameters:
    """Parameters of the oscillator pool and its logic step (gains at 1 Hz when scaled).

    The defaults were chosen on the benchmark signals (0.3-3 Hz, 30 and 500 Hz sampling):
    the middle oscillator must start above the fundamental, as it is captured from at most
    about twice the frequency; :meth:`paper` gives constant gains K = K_Omega = 20.
    """

    initial_frequencies_hz: tuple[float, ...] = (0.2, 3.0, 9.0)  # omega_i(0) / 2 pi (Hz), M of them
    coupling: float = 6.0             # K (1/s)
    frequency_coupling: float = 6.0   # K_Omega, the gain of eq. 2 (1/s^2)
    learning_rate: float = 1.0        # eta (1/s)
    scale_with_frequency: bool = True  # gains x (Omega / 2 pi) of the selected fundamental
    zero_frequency_hz: float = 0.1    # |omega| below this counts as "converged to 0 Hz" (Hz)
    reset_dwell_s: float = 1.0        # two oscillators near 0 Hz this long trigger a reset (s)
    max_frequency_hz: float = 10.0    # |omega_i| is kept below this (Hz)
    locked_coupling: float = 1.0      # c_L: once locked, K, K_Omega x (c_L + kappa E), E = mean e^2
    residual_gain: float = 0.0        # kappa
    residual_periods: float = 1.0     # E is low-passed over this many periods of the fundamental

    @classmethod
    def paper(cls) -> AFOParameters:
        """Eqs. 1-5 as printed: one gain K = 20 for phase and frequency, not scaled."""
        return cls(initial_frequencies_hz=(0.2, 1.0, 3.0), coupling=20.0, frequency_coupling=20.0,
                   learning_rate=1.0, scale_with_frequency=False)

    def gains(self) -> OscillatorGains:
        """The gains in the compiled substep's units (rad/s)."""
        return OscillatorGains(
            coupling=self.coupling, frequency_coupling=self.frequency_coupling,
            learning_rate=self.learning_rate, scale_with_frequency=self.scale_with_frequency,
            min_omega=-2.0 * math.pi * self.max_frequency_hz,
            max_omega=2.0 * math.pi * self.max_frequency_hz,
            locked_coupling=self.locked_coupling, residual_gain=self.residual_gain,
            residual_periods=self.residual_periods,
            zero_omega=2.0 * math.pi * self.zero_frequency_hz, reset_dwell_s=self.reset_dwell_s)

    def new_state(self, n_dofs: int) -> OscillatorState:
        """The pool at rest: omega_i(0), phases 0, no amplitudes (3 per DOF)."""
        if len(self.initial_frequencies_hz) != 3:
            raise ValueError("the logic step picks the middle of three oscillators: M must be 3")
        return new_oscillator_state(n_dofs, 2.0 * math.pi * np.asarray(self.initial_frequencies_hz), 3)


@njit(cache=True)
def pool_fundamental(state: OscillatorState) -> tuple[float, float]:
    """(phase in rad, Omega in rad/s) of the middle-frequency oscillator (the logic step).

    An oscillator with negative omega runs backwards; its phase is negated so that the
    returned phase always advances at +Omega.
    """
    omegas = state.omegas
    order = [0, 1, 2]                     # stable sort of |omega_i|, the middle one
    for i in range(3):
        for j in range(2 - i):
            if abs(omegas[order[j]]) > abs(omegas[order[j + 1]]):
                order[j], order[j + 1] = order[j + 1], order[j]
    middle = order[1]
    sign = 1.0 if omegas[middle] >= 0.0 else -1.0
    return sign * state.phases[middle], abs(omegas[middle])


@njit(cache=True)
def pool_substep(state: OscillatorState, gains: OscillatorGains, u, h: float, reference: int,
                 mean_coupling: bool, error, cosines, sines, drives) -> None:
    """One explicit Euler substep of h seconds of eqs. 1-5 with input u (d,), in place.

    error (d,), cosines, sines and drives (3,) are scratch arrays.
    """
    alpha, beta, phases, omegas = state.alpha, state.beta, state.phases, state.omegas
    fundamental = pool_fundamental(state)[1]
    m = gain_scale(fundamental, gains.scale_with_frequency)
    for i in range(3):
        cosines[i] = math.cos(phases[i])
        sines[i] = math.sin(phases[i])
    for j in range(u.shape[0]):
        prediction = 0.0
        for i in range(3):
            prediction += alpha[j, i] * cosines[i] + beta[j, i] * sines[i]      # eq. 4
        error[j] = u[j] - prediction                                          # eq. 3
    for i in range(3):
        drives[i] = phase_drive(error, sines[i], cosines[i], alpha, beta, i, reference,
                                mean_coupling)
    boost = locked_boost(state, gains, error, fundamental, h)
    for i in range(3):
        drive = drives[i] * boost
        phases[i] += h * (omegas[i] - gains.coupling * m * drive)                    # eq. 1
        omega = omegas[i] - h * gains.frequency_coupling * m * m * drive              # eq. 2
        omegas[i] = min(max(omega, gains.min_omega), gains.max_omega)
    rate = h * gains.learning_rate * m
    for j in range(u.shape[0]):
        for i in range(3):
            alpha[j, i] += rate * error[j] * cosines[i]                              # eq. 5
            beta[j, i] += rate * error[j] * sines[i]
    for i in range(3):
        beta[reference, i] = 0.0


@njit(cache=True)
def pool_logic_step(state: OscillatorState, gains: OscillatorGains, dt: float) -> None:
    """Reset the pool when more than one oscillator has sat at 0 Hz for reset_dwell_s."""
    near_zero = 0
    for i in range(3):
        if abs(state.omegas[i]) < gains.zero_omega:
            near_zero += 1
    state.zero_time[0] = state.zero_time[0] + dt if near_zero > 1 else 0.0
    if state.zero_time[0] >= gains.reset_dwell_s:
        state.omegas[:] = state.initial_omegas
        state.alpha[:] = 0.0
        state.beta[:] = 0.0
        state.zero_time[0] = 0.0
        state.resets[0] += 1.0
        state.locked[0] = 0.0


@njit(cache=True)
def pool_lock(state: OscillatorState, omega: float, phase: float, alpha, beta,
              reference: int) -> None:
    """Start from a known fundamental and series (:func:`locked_pool`); each phase moves by
    less than half a turn."""
    omegas, phases, pool_alpha, pool_beta = locked_pool(omega, phase, alpha, beta, reference)
    for i in range(3):
        state.phases[i] += nearest_turn(phases[i] - state.phases[i])
        state.omegas[i] = omegas[i]
    state.alpha[:] = pool_alpha
    state.beta[:] = pool_beta
    state.zero_time[0] = 0.0
    state.locked[0] = 1.0
    state.residual[0] = 0.0


@njit(cache=True)
def locked_pool(omega: float, phase: float, alpha: np.ndarray, beta: np.ndarray,
                reference: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The pool state that a known fundamental and series converge to.

    Oscillator 1 sits at 0 Hz and carries the offset, oscillator 2 the fundamental (phase
    ``phase``), oscillator 3 the stronger of the 2nd and 3rd harmonics, with its own phase so
    that the reference DOF's beta is 0.

    Parameters
    ----------
    omega : float
        Fundamental Omega (rad/s).
    phase : float
        Fundamental phase now (rad).
    alpha, beta : ndarray, shape (d, K + 1), K >= 1
        Series coefficients in the fundamental phase (normalised input with its offset).
    reference : int
        Index of the reference DOF.

    Returns
    -------
    omegas, phases : ndarray, shape (3,)
        omega_i (rad/s) and phi_i now (rad).
    alpha, beta : ndarray, shape (d, 3)
        Amplitudes per DOF and oscillator.
    """
    d, n_coef = alpha.shape
    k, best = 2, -1.0
    for c in range(2, min(3, n_coef - 1) + 1):
        power = 0.0
        for j in range(d):
            power += alpha[j, c] ** 2 + beta[j, c] ** 2
        if power > best:
            k, best = c, power
    pool_alpha = np.zeros((d, 3))
    pool_beta = np.zeros((d, 3))
    theta = 0.0
    if k < n_coef:
        theta = math.atan2(beta[reference, k], alpha[reference, k])
        for j in range(d):
            pool_alpha[j, 2] = alpha[j, k] * math.cos(theta) + beta[j, k] * math.sin(theta)
            pool_beta[j, 2] = beta[j, k] * math.cos(theta) - alpha[j, k] * math.sin(theta)
    for j in range(d):
        pool_alpha[j, 0] = alpha[j, 0]
        pool_alpha[j, 1] = alpha[j, 1]
        pool_beta[j, 1] = beta[j, 1]
    pool_beta[reference, 2] = 0.0
    omegas = np.array([0.0, omega, k * omega])
    phases = np.array([0.0, phase, k * phase - theta])
    return omegas, phases, pool_alpha, pool_beta


forget_stale_kernels(__name__)
