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
DOFs, low-passed over about a period; 2-5e-4 with 2 % noise when the series fits): a weaker
coupling when converged, a stronger one when the movement changes. On the clean signals of
``benchmarks/bench_learn.py`` the AFS with c_L = 0.5, kappa = 100 re-converges after a
frequency step in 2.06-2.24 instead of 2.91-3.31 periods. On human-like demonstrations (a
wandering tempo, drifting amplitude and centre, two gaps; same benchmark) the residual stays
large, the coupling grows tenfold and the AFS drifts to subharmonics: 4 of 27 model
frequencies more than 1 % off (worst 18 %) with the supervisor of
:mod:`wipelab.learning.online`, 11 (worst 88 %) without; with kappa = 30 all 27 within
0.79 %, without the schedule within 0.72 %. Robustness on people's movements decides: off.
The pool, with lower gains (K_Omega = 6), is also best without it: after a step 2.6-2.9
periods, 5.2-5.9 with c_L = 0.5, 3.2-3.3 with kappa = 50. Before the lock the schedule never
applies: with the large residual of an unlocked oscillator it made the fallback (no period
detected) slower and less stable (kappa = 100: up to 11 periods, or no lock).

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

import numpy as np

#: Normalised amplitude below which a non-reference DOF's phase drive is faded out.
R_FADE = 0.1

DOF_COUPLINGS = ("mean", "reference")

#: Frequency at which scaled gains are specified: 1 Hz, in rad/s.
REFERENCE_OMEGA = 2.0 * math.pi


def gain_scale(omega: float, scale_with_frequency: bool) -> float:
    """m = |Omega| / (2 pi rad/s) when gains scale with the frequency, else 1."""
    return abs(omega) / REFERENCE_OMEGA if scale_with_frequency else 1.0


def phase_drive(error: np.ndarray, phase, alpha1: np.ndarray, beta1: np.ndarray, reference: int,
                mean_coupling: bool) -> np.ndarray:
    """The coupling term of eqs. 1-2 for several DOFs: K times this is subtracted from phi' and omega'.

    Parameters
    ----------
    error : ndarray, shape (d,)
        e_j = y_j - y_hat_j of eq. 3 per DOF (normalised units).
    phase : float or ndarray, shape (m,)
        Oscillator phase(s) phi (rad).
    alpha1, beta1 : ndarray, shape (d,) or (m, d)
        Each DOF's cosine and sine coefficients at the oscillator(s).
    reference : int
        Index of the reference DOF.
    mean_coupling : bool
        Whether the other DOFs contribute (``"mean"``) or only the reference (``"reference"``).

    Returns
    -------
    float or ndarray, shape (m,)
    """
    phase = np.asarray(phase, dtype=np.float64)
    sin_phi, cos_phi = np.sin(phase)[..., None], np.cos(phase)[..., None]
    drive = error[reference] * np.sin(phase)
    if mean_coupling:
        amplitude = np.hypot(alpha1, beta1)
        others = np.ones(error.shape[0], dtype=bool)
        others[reference] = False
        terms = error * (alpha1 * sin_phi - beta1 * cos_phi) / (amplitude + R_FADE)
        drive = (drive + (terms * others).sum(axis=-1)) \
            / (1.0 + (amplitude / (amplitude + R_FADE) * others).sum(axis=-1))
    return drive


def residual_step(residual: float, error: np.ndarray, omega: float, h: float, periods: float) -> float:
    """E, the mean squared error e_j^2 over the DOFs low-passed over ``periods`` periods of
    Omega, one substep of h seconds later (normalised units)."""
    rate = min(h * abs(omega) / (2.0 * math.pi * periods), 1.0)
    return residual + rate * (float(np.mean(error ** 2)) - residual)


def nearest_turn(angle: float) -> float:
    """angle wrapped to [-pi, pi) (rad): the smallest change of phase to reach a target angle."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def substep_count(dt: float, substep_hz: float) -> int:
    """Euler substeps per sample so that the oscillators integrate at >= substep_hz."""
    return max(1, int(np.ceil(dt * substep_hz - 1e-9)))


def interpolated_inputs(previous: np.ndarray, current: np.ndarray, n_sub: int) -> np.ndarray:
    """Inputs at the end of each substep, linear between two samples; shape (n_sub, d)."""
    fractions = np.arange(1, n_sub + 1)[:, None] / n_sub
    return previous + fractions * (current - previous)
