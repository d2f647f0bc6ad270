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

When the start-up detector has found the period, the learner sets the pool to the state it
would converge to (:func:`locked_pool`): 0 Hz with the offset, the fundamental, and the
stronger of the 2nd and 3rd harmonics. The gain schedule that steadies the locked AFS
slows the pool down after a frequency step (see :mod:`wipelab.learning.oscillators`), so it
is off by default here (c_L = 1, kappa = 0).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from wipelab.learning.oscillators import (DOF_COUPLINGS, gain_scale, interpolated_inputs,
                                          nearest_turn, phase_drive, residual_step)


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


class AdaptiveOscillatorPool:
    """The AFO pool canonical system for d DOFs (reference implementation, numpy).

    Attributes
    ----------
    phases_ : ndarray, shape (M,)
        phi_i (rad), unwrapped.
    omegas_ : ndarray, shape (M,)
        omega_i (rad/s); may be negative (the oscillator then runs backwards).
    alpha_, beta_ : ndarray, shape (M, d)
        Cosine and sine amplitude per oscillator and DOF (beta of the reference DOF held at 0).
    resets_ : int
        Number of resets so far.
    """

    def __init__(self, n_dofs: int, params: AFOParameters = AFOParameters(), reference: int = 0,
                 dof_coupling: str = "mean"):
        if dof_coupling not in DOF_COUPLINGS:
            raise ValueError(f"dof_coupling must be one of {DOF_COUPLINGS}, got {dof_coupling!r}")
        if len(params.initial_frequencies_hz) != 3:
            raise ValueError("the logic step picks the middle of three oscillators: M must be 3")
        self.params = params
        self.reference = reference
        self.mean_coupling = dof_coupling == "mean"
        self.initial_omegas = 2.0 * math.pi * np.asarray(params.initial_frequencies_hz, dtype=np.float64)
        self.phases_ = np.zeros(3)
        self.omegas_ = self.initial_omegas.copy()
        self.alpha_ = np.zeros((3, n_dofs))
        self.beta_ = np.zeros((3, n_dofs))
        self.resets_ = 0
        self._zero_time = 0.0
        self.locked_ = False
        self.residual_ = 0.0

    def _substep(self, u: np.ndarray, h: float) -> None:
        p = self.params
        m = gain_scale(self.fundamental[1], p.scale_with_frequency)
        cos_i, sin_i = np.cos(self.phases_), np.sin(self.phases_)
        error = u - (cos_i @ self.alpha_ + sin_i @ self.beta_)                 # eqs. 3-4
        drive = phase_drive(error, self.phases_, self.alpha_, self.beta_, self.reference,
                            self.mean_coupling)
        if self.locked_:
            self.residual_ = residual_step(self.residual_, error, self.fundamental[1], h,
                                           p.residual_periods)
            drive = drive * (p.locked_coupling + p.residual_gain * self.residual_)
        self.phases_ = self.phases_ + h * (self.omegas_ - p.coupling * m * drive)          # eq. 1
        limit = 2.0 * math.pi * p.max_frequency_hz
        self.omegas_ = np.clip(self.omegas_ - h * p.frequency_coupling * m * m * drive,
                               -limit, limit)                                              # eq. 2
        self.alpha_ += (h * p.learning_rate * m) * np.outer(cos_i, error)                  # eq. 5
        self.beta_ += (h * p.learning_rate * m) * np.outer(sin_i, error)
        self.beta_[:, self.reference] = 0.0

    def _logic_step(self, dt: float) -> None:
        """Reset the pool when more than one oscillator has sat at 0 Hz for reset_dwell_s."""
        near_zero = np.abs(self.omegas_) < 2.0 * math.pi * self.params.zero_frequency_hz
        self._zero_time = self._zero_time + dt if near_zero.sum() > 1 else 0.0
        if self._zero_time >= self.params.reset_dwell_s:
            self.omegas_ = self.initial_omegas.copy()
            self.alpha_[:] = 0.0
            self.beta_[:] = 0.0
            self._zero_time = 0.0
            self.resets_ += 1
            self.locked_ = False

    def lock(self, omega: float, phase: float, alpha: np.ndarray, beta: np.ndarray, dt: float) -> None:
        """Start from a known fundamental and series (see :func:`locked_pool`); dt is unused
        (the pool has no Nyquist cut-off). Each phase moves by less than half a turn."""
        del dt
        omegas, phases, pool_alpha, pool_beta = locked_pool(omega, phase, alpha, beta, self.reference)
        self.phases_ = self.phases_ + np.array([nearest_turn(v) for v in phases - self.phases_])
        self.omegas_ = omegas
        self.alpha_, self.beta_ = pool_alpha.T.copy(), pool_beta.T.copy()
        self._zero_time = 0.0
        self.locked_ = True
        self.residual_ = 0.0

    def advance(self, previous: np.ndarray, current: np.ndarray, dt: float, n_sub: int) -> None:
        """Integrate over one sample interval dt (input (d,) linear from previous to current),
        then apply the logic step."""
        h = dt / n_sub
        for u in interpolated_inputs(previous, current, n_sub):
            self._substep(u, h)
        self._logic_step(dt)

    def free_run(self, dt: float) -> None:
        """Advance dt without input (a gap): every phase at its own omega, nothing learned."""
        self.phases_ = self.phases_ + dt * self.omegas_

    @property
    def frequencies_hz(self) -> np.ndarray:
        """|omega_i| / 2 pi of the M oscillators (Hz), shape (M,) (the paper's Fig. 4)."""
        return np.abs(self.omegas_) / (2.0 * math.pi)

    @property
    def fundamental(self) -> tuple[float, float]:
        """(phase in rad, Omega in rad/s) of the middle-frequency oscillator (the logic step).

        An oscillator with negative omega runs backwards; its phase is negated so that the
        returned phase always advances at +Omega.
        """
        middle = int(np.argsort(np.abs(self.omegas_), kind="stable")[1])
        sign = 1.0 if self.omegas_[middle] >= 0.0 else -1.0
        return sign * self.phases_[middle], abs(self.omegas_[middle])


def locked_pool(omega: float, phase: float, alpha: np.ndarray, beta: np.ndarray,
                reference: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The pool state that a known fundamental and series converge to.

    Oscillator 1 sits at 0 Hz and carries the offset, oscillator 2 the fundamental (phase
    ``phase``), oscillator 3 the stronger of the 2nd and 3rd harmonics, with its own phase so
    that the reference DOF's beta is 0. Loops only: the online kernel compiles this function.

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
