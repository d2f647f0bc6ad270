"""Iterative learning of the height profile at a tempo: the same force when the robot wipes fast.

The profile learned online at a slowed-down tempo (eqs. 10-15) is the height that keeps F_0 at
that tempo. Faster, the arm and the sensing lag and the profile no longer fits. Iterative
learning control (as the coupling terms of Gams, Nemec, Ijspeert, Ude, "Coupling movement
primitives", IEEE T-RO 2014) learns the feed-forward height over repetitions of the periodic
movement at the new tempo, starting from the profile learned so far:

    z_{k+1}(phi) = z_k(phi) + gamma Q[e_k](phi + Omega tau) / k_c

with e_k the force error |F| - F_0 of period k as a function of the phase, Q a zero-phase
Gaussian low-pass (``smoothing`` seconds wide: the Q-filter that keeps the iteration stable
where the plant's lag is not known exactly), tau the sensing delay (the error at phase phi
answers the command a little earlier), k_c the contact stiffness d|F|/dz and gamma < 1 the
learning gain. The stiffness is not known (sponge, grasp, surface slope): it is measured
between periods as the secant -<de, dz> / <dz, dz> of the last update dz and the change de of
the error it caused, over the phases in contact in both periods (out of contact the force
does not answer), starting from a stiff guess (``stiffness``: small first steps).

Pure numpy: the profile is a waveform on ``grid`` phases; the caller turns it into DMP
weights to execute it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class IterativeLearningParams:
    """Parameters of the iterative learning of a height profile at one tempo."""

    gain: float = 0.7               # gamma: fraction of the estimated correction per period
    stiffness: float = 4000.0       # N/m: k_c assumed until it is measured (a stiff guess)
    stiffness_range: tuple[float, float] = (300.0, 10000.0)  # N/m: measured k_c is clipped
    smoothing: float = 0.015        # s: sigma of the Gaussian Q-filter of the error
    lead: float = 0.011             # s: tau, the sensing delay (filter, period mean)
    periods: int = 5                # most learning periods per tempo
    tolerance: float = 0.5          # N: a tempo is learned when the RMS force error is below
    grid: int = 256                 # phases of the profile waveform
    contact: float = 1.0            # N: force above which a phase counts as in contact

    def __post_init__(self):
        low, high = self.stiffness_range
        if not (0 < self.gain <= 1 and 0 < low <= self.stiffness <= high):
            raise ValueError("gain must be in (0, 1] and stiffness inside stiffness_range")
        if self.periods < 1 or self.grid < 16 or self.smoothing < 0 or self.lead < 0:
            raise ValueError("periods >= 1, grid >= 16, smoothing >= 0 and lead >= 0 needed")


def profile_phases(grid: int) -> np.ndarray:
    """The phases (grid,) (rad) of a profile waveform."""
    return np.linspace(0.0, 2.0 * math.pi, grid, endpoint=False)


def phase_average(phase: np.ndarray, values: np.ndarray, grid: int) -> np.ndarray:
    """Mean of ``values`` (n,) per phase bin of a ``grid``-phase waveform (nearest bin);
    empty bins are interpolated periodically. ``phase`` (n,) in rad, any range."""
    index = np.rint(np.mod(phase, 2.0 * math.pi) * (grid / (2.0 * math.pi))).astype(int) % grid
    total = np.bincount(index, weights=values, minlength=grid)
    count = np.bincount(index, minlength=grid)
    filled = count > 0
    phases = profile_phases(grid)
    return np.interp(phases, phases[filled], total[filled] / count[filled], period=2.0 * math.pi)


def periodic_gaussian(waveform: np.ndarray, sigma: float) -> np.ndarray:
    """Zero-phase Gaussian smoothing of a periodic waveform (grid,), ``sigma`` in samples."""
    grid = waveform.size
    frequency = np.fft.rfftfreq(grid, 1.0 / grid)        # cycles per period
    response = np.exp(-0.5 * (2.0 * math.pi * frequency * sigma / grid) ** 2)
    return np.fft.irfft(np.fft.rfft(waveform) * response, grid)


class IterativeProfile:
    """Iterative learning of a height profile at one tempo.

    Per control period :meth:`record` the commanded phase and the force error; at the end of
    each period :meth:`end_of_period` updates the profile and says whether to go on.

    Parameters
    ----------
    profile : array, shape (grid,)
        Start profile (m, world z) at :func:`profile_phases`.
    omega : float
        The tempo Omega (rad/s).
    target_force : float
        F_0 (N): with the error it gives the force, to tell contact.
    params : IterativeLearningParams
    stiffness : float, optional
        k_c (N/m) to start from (e.g. measured at the previous tempo).

    Attributes
    ----------
    profile_ : ndarray (grid,)
        The profile to execute next period.
    best_ : ndarray (grid,)
        The profile of the period with the smallest RMS error so far.
    errors_ : list of float
        RMS force error (N) of each learning period.
    stiffness_ : float
        Current k_c (N/m).
    """

    def __init__(self, profile, omega: float, target_force: float,
                 params: IterativeLearningParams, stiffness: float | None = None):
        self.params, self.omega, self.target_force = params, float(omega), float(target_force)
        self.profile_ = np.asarray(profile, dtype=float).copy()
        if self.profile_.shape != (params.grid,):
            raise ValueError(f"profile must have {params.grid} phases")
        self.best_ = self.profile_.copy()
        self.errors_: list[float] = []
        self.stiffness_ = float(params.stiffness if stiffness is None else stiffness)
        self._phases: list[float] = []
        self._errors: list[float] = []
        self._last_update: tuple | None = None   # (dz, filtered error, in contact) of the last

    def record(self, phase: float, force_error: float) -> None:
        """One control period: the commanded phase (rad) and the force error |F| - F_0 (N)
        sensed in it."""
        self._phases.append(phase)
        self._errors.append(force_error)

    def end_of_period(self) -> bool:
        """Update the profile from the period's errors; True while learning should go on
        (the error is above ``tolerance``, still falling, and periods are left)."""
        p = self.params
        errors = np.array(self._errors)
        rms = float(np.sqrt(np.mean(errors ** 2)))
        if not self.errors_ or rms < min(self.errors_):
            self.best_ = self.profile_.copy()
        self.errors_.append(rms)
        # the error at phase phi answers the command at phi - Omega tau
        error = phase_average(np.array(self._phases) - self.omega * p.lead, errors, p.grid)
        error = periodic_gaussian(error, p.smoothing * self.omega / (2.0 * math.pi) * p.grid)
        touching = error + self.target_force > p.contact
        self._phases, self._errors = [], []
        if self._last_update is not None:
            step, before, touched = self._last_update
            both = touching & touched
            # a step the force noise cannot hide, over a good part of the period
            if both.mean() > 0.25 and np.sqrt(np.mean(step[both] ** 2)) > 2e-4:
                measured = -float(np.dot((error - before)[both], step[both])
                                  / np.dot(step[both], step[both]))
                self.stiffness_ = float(np.clip(measured, *p.stiffness_range))
        step = p.gain * error / self.stiffness_
        self.profile_ = self.profile_ + step
        self._last_update = (step, error, touching)
        stalled = len(self.errors_) >= 3 and min(self.errors_[-2:]) > 0.9 * min(self.errors_[:-2])
        return rms > p.tolerance and len(self.errors_) < p.periods and not stalled
