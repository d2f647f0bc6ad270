"""What the two canonical systems share: gain scaling, substepping and the multi-DOF phase drive.

Gains scaled with the frequency. Eqs. 1-2 with constant gains behave very differently over
the 0.3-3 Hz of human wiping: a coupling K that locks quickly at 3 Hz exceeds Omega at
0.3 Hz, where the coupling term then dominates phi' and warps the phase within each period.
With ``scale_with_frequency`` the gains are given at 1 Hz and scaled as K (Omega / 2 pi),
K_Omega (Omega / 2 pi)^2 and nu (Omega / 2 pi): written in phase time the loop is then the same
at every frequency, and so is its convergence measured in periods. Eq. 2 also gets its own
gain K_Omega: with K_Omega = K (eqs. 1-2 as printed) the linearised loop
s^2 + k s + k = 0 (k = K A / 2) keeps a pole near -1 rad/s however large K is.

Gain schedule after the lock (off by default: c_L = 1, kappa = 0). Once a canonical system
has been locked onto a detected period (its ``lock`` method), its coupling gains K and
K_Omega can be multiplied by c_L + kappa E, where E is the fit residual (mean e^2 over the
DOFs, low-passed over about a period): a weaker coupling when converged, a stronger one when
the movement changes. Measured in ``benchmarks/bench_learn.py``: on its clean signals the
AFS with c_L = 0.5, kappa = 100 re-converges after a frequency step in 2.06-2.17 periods,
the default in 2.05-2.11 (the change-of-tempo re-lock of :mod:`wipelab.learning.online`
does the work). On the 27 human-like demonstrations (a wandering tempo, drifting amplitude
and centre, two gaps) the schedule drifted to subharmonics while the online learner
normalised its input wrongly (g and r learnt from a period spanning a gap; a DOF that barely
moves in units of its own amplitude): 6 of 27 model frequencies more than 1 % off (worst
11.9 %) with the supervisor, 10 (worst 88 %) without. With both fixed, all 27 are within
0.38 % with kappa = 100, with or without the supervisor, 0.45 % with kappa = 30, 0.47 %
without the schedule. It stays off: the re-lock already re-converges after a step, and the
schedule has not been through the held-out tables (a)-(c). A weaker coupling
alone (c_L = 0.7) smooths Omega after a lock (noise and drift make it wobble) but slows the
re-convergence after a clean frequency step to 3.00-3.12 periods (the same table): off as
well. Before the lock the schedule never applies.

Several DOFs share one phase. The *reference* DOF defines it: its component at an
oscillator's frequency is a pure cosine of that oscillator's phase (the beta coefficient is
held at 0, as in Petric et al.), so its error drives the phase through e sin(phi) exactly as
in eqs. 1-2. Every other DOF learns a cosine and a sine coefficient (alpha, beta), i.e. its
own phase lag theta = atan2(beta, alpha); with ``dof_coupling = "mean"`` it also drives the
shared phase with e sin(phi - theta) -- the same correction seen in its own phase frame --
weighted by R / (R + R_FADE), R = |(alpha, beta)|, so that a DOF that barely moves does not
count. The drive is the weighted mean of the DOFs' terms (the reference weighs 1): the loop
gain, and so the convergence, does not depend on how many DOFs move.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from wipelab.numba_cache import forget_stale_kernels

#: Normalised amplitude below which a non-reference DOF's phase drive is faded out.
R_FADE = 0.1

DOF_COUPLINGS = ("mean", "reference")

#: Frequency at which scaled gains are specified: 1 Hz, in rad/s.
REFERENCE_OMEGA = 2.0 * math.pi


class OscillatorGains(NamedTuple):
    """The gains of a canonical system in the units the compiled substeps take (rad/s)."""

    coupling: float               # K (1/s), at 1 Hz when scaled
    frequency_coupling: float     # K_Omega (1/s^2), at 1 Hz when scaled
    learning_rate: float          # nu or eta (1/s), at 1 Hz when scaled
    scale_with_frequency: bool    # gains x (Omega / 2 pi), K_Omega x (Omega / 2 pi)^2
    min_omega: float              # AFS: Omega is kept >= this (rad/s)
    max_omega: float              # |Omega| is kept <= this (rad/s)
    locked_coupling: float        # c_L of the gain schedule after a lock
    residual_gain: float          # kappa of the gain schedule
    residual_periods: float       # E is low-passed over this many periods
    zero_omega: float             # AFO pool: |omega| below this counts as 0 Hz (rad/s)
    reset_dwell_s: float          # AFO pool: two oscillators at 0 Hz this long reset it (s)


class OscillatorState(NamedTuple):
    """The state of a canonical system (M oscillators: 1 for the AFS, 3 for the pool).

    Attributes
    ----------
    phases, omegas : ndarray, shape (M,)
        phi_i (rad, unwrapped) and omega_i (rad/s; a pool oscillator may run backwards).
    alpha, beta : ndarray, shape (d, C)
        Cosine and sine coefficients per DOF (AFS: C = M_terms + 1 harmonics of phi; pool:
        C = 3, one per oscillator), normalised input units.
    initial_omegas : ndarray, shape (M,)
        omega_i(0), where a reset of the pool returns them (rad/s).
    residual, locked, zero_time, resets : ndarray, shape (1,)
        E of the gain schedule; 1 once a detected period was handed over (0 after a reset);
        time two pool oscillators have sat at 0 Hz (s); resets of the pool so far.
    """

    phases: np.ndarray
    omegas: np.ndarray
    alpha: np.ndarray
    beta: np.ndarray
    initial_omegas: np.ndarray
    residual: np.ndarray
    locked: np.ndarray
    zero_time: np.ndarray
    resets: np.ndarray


def new_oscillator_state(n_dofs: int, initial_omegas, n_coefficients: int) -> OscillatorState:
    """A canonical system at rest: phases 0, omega_i(0), no series."""
    initial = np.array(initial_omegas, dtype=np.float64)
    return OscillatorState(phases=np.zeros(initial.size), omegas=initial.copy(),
                           alpha=np.zeros((n_dofs, n_coefficients)),
                           beta=np.zeros((n_dofs, n_coefficients)), initial_omegas=initial,
                           residual=np.zeros(1), locked=np.zeros(1), zero_time=np.zeros(1),
                           resets=np.zeros(1))


@njit(cache=True)
def locked_boost(state: OscillatorState, gains: OscillatorGains, error, omega: float,
                 h: float) -> float:
    """The factor on K and K_Omega for one substep: c_L + kappa E once locked (E updated
    with this substep's error), 1 before."""
    if state.locked[0] == 0.0:
        return 1.0
    state.residual[0] = residual_step(state.residual[0], error, omega, h, gains.residual_periods)
    return gains.locked_coupling + gains.residual_gain * state.residual[0]


@njit(cache=True)
def gain_scale(omega: float, scale_with_frequency: bool) -> float:
    """m = |Omega| / (2 pi rad/s) when gains scale with the frequency, else 1."""
    return abs(omega) / REFERENCE_OMEGA if scale_with_frequency else 1.0


@njit(cache=True)
def phase_drive(error, sin_phi: float, cos_phi: float, alpha, beta, column: int, reference: int,
                mean_coupling: bool) -> float:
    """The coupling term of eqs. 1-2 for several DOFs: K times this is subtracted from phi'
    and K_Omega times it from Omega'.

    Parameters
    ----------
    error : ndarray, shape (d,)
        e_j = u_j - y_hat_j of eq. 3 per DOF (normalised units).
    sin_phi, cos_phi : float
        sin and cos of the oscillator's phase phi.
    alpha, beta : ndarray, shape (d, C)
        Cosine and sine coefficients; column ``column`` is the oscillator's.
    column : int
        The oscillator's column (AFS: 1, the fundamental; AFO pool: its index).
    reference : int
        Index of the reference DOF.
    mean_coupling : bool
        Whether the other DOFs contribute (``"mean"``) or only the reference (``"reference"``).
    """
    total = error[reference] * sin_phi
    weight = 1.0
    if mean_coupling:
        for j in range(error.shape[0]):
            if j != reference:
                a, b = alpha[j, column], beta[j, column]
                amplitude = math.hypot(a, b)
                total += error[j] * (a * sin_phi - b * cos_phi) / (amplitude + R_FADE)
                weight += amplitude / (amplitude + R_FADE)
    return total / weight


@njit(cache=True)
def residual_step(residual: float, error, omega: float, h: float, periods: float) -> float:
    """E, the mean squared error e_j^2 over the DOFs low-passed over ``periods`` periods of
    Omega, one substep of h seconds later (normalised units)."""
    squares = 0.0
    for j in range(error.shape[0]):
        squares += error[j] * error[j]
    rate = min(h * abs(omega) / (2.0 * math.pi * periods), 1.0)
    return residual + rate * (squares / error.shape[0] - residual)


@njit(cache=True)
def nearest_turn(angle: float) -> float:
    """angle wrapped to [-pi, pi) (rad): the smallest change of phase to reach a target angle."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def substep_count(dt: float, substep_hz: float) -> int:
    """Euler substeps per sample so that the oscillators integrate at >= substep_hz."""
    return max(1, int(math.ceil(dt * substep_hz - 1e-9)))


forget_stale_kernels(__name__)
