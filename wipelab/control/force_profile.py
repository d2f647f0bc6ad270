"""Online learning of the force profile: the z waveform that keeps contact (Sec. II-B).

The commanded height Y(t) of eq. 10 (active compliance integrated onto the reference) is
learned as one more DOF of the periodic DMP, anchored to the same phase as the x-y movement:
each control period gives y, y', y'' (a centred polynomial fit of the recent commanded
heights, paired with the phase at the window's centre), the forcing target of the text after
eq. 12, and one step of the incremental LWR of eqs. 13-15.

The samples are learned in one compiled pass (numba) when the weights are next needed. The
pass is made of the learning package's compiled pieces, the same ones the online movement
learner runs (:func:`~wipelab.learning.derivatives.evaluate_polynomial`,
:func:`~wipelab.learning.dmp.forcing_target`, :func:`~wipelab.learning.kernels.activations`,
:func:`~wipelab.learning.lwr.lwr_update`): one implementation of each.

Convergence is judged once per period: the learned waveform (the DMP's limit cycle, on a
grid of phases) is compared with the one a period before; learning has converged when the
largest change is below ``tolerance`` for ``stable_periods`` periods in a row, after at least
``min_periods`` periods of learning.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from wipelab.learning import IncrementalLWR, kernel_centres, limit_cycle
from wipelab.learning.derivatives import evaluate_polynomial, polynomial_fit_matrix, window_for
from wipelab.learning.dmp import forcing_target
from wipelab.learning.kernels import activations
from wipelab.learning.lwr import lwr_update
from wipelab.numba_cache import forget_stale_kernels

#: Phases at which learned waveforms are compared (rad).
COMPARISON_PHASES = np.linspace(0.0, 2.0 * math.pi, 128, endpoint=False)
#: Degree of the centred polynomial fit that gives y, y', y''.
DERIVATIVE_DEGREE = 3
#: Most samples in that fit's window.
MAX_WINDOW = 1001


#: Accepted values of ``ProfileLearningParams.reference``.
REFERENCES = ("start", "learned")


@dataclass(frozen=True)
class ProfileLearningParams:
    """Parameters of force-profile learning and of its convergence criterion.

    ``reference`` is the Y_r of eq. 10 while learning. ``"start"`` is the paper's: the start
    height, so that compliance alone makes the whole height change and the learned Y lags
    the surface by what the force loop needs to follow it (k_F k_sponge ~ 20 /s: ~2 mm at
    the learning speed). ``"learned"`` (the default) makes Y_r the profile learned up to the
    end of the last period (iterative learning, as in the authors' later work on coupling
    DMPs with force feedback): compliance then only corrects what is left, which shrinks
    every period, so that the lag shrinks with it.
    """

    reference: str = "learned"     # Y_r of eq. 10 while learning: "start" or "learned" (below)
    forgetting: float = 0.99       # lambda of eq. 14 (the paper's value)
    derivative_window: float = 0.04  # fraction of a period spanned by the derivative fit
    tolerance: float = 0.002       # m: largest change of the waveform over one period
    stable_periods: int = 1        # consecutive periods below tolerance needed
    min_periods: int = 2           # periods of learning before convergence may be declared

    def __post_init__(self):
        if self.reference not in REFERENCES:
            raise ValueError(f"reference must be one of {', '.join(REFERENCES)}, "
                             f"got {self.reference!r}")


class ForceProfileLearner:
    """Learns one DOF (z) of a periodic DMP online from the commanded height.

    Per sample, as the paper's online learning: a centred cubic fit of the recent heights
    (``derivative_window`` of a period, at most :data:`MAX_WINDOW` samples) gives y, y', y''
    at the window's centre, paired with the phase and Omega recorded there; the forcing target
    (text after eq. 12) and the kernels at that phase (eq. 8) make one step of the incremental
    LWR (eqs. 13-15, an :class:`~wipelab.learning.lwr.IncrementalLWR` started at w = 0, P = 1).
    The samples are queued by :meth:`update` and learned in one compiled pass
    (:func:`learn_heights`) when the weights are next read: the result is the same as
    learning each at once.

    Parameters
    ----------
    n_kernels, width, alpha_s, beta_s : as the x-y model (eqs. 6-8).
    goal : float
        Anchor g (m) of the learned DOF (e.g. the height of first contact).
    amplitude : float
        r (m) of the learned DOF.
    dt : float
        Control period (s).
    params : ProfileLearningParams
    """

    def __init__(self, n_kernels: int, width: float, alpha_s: float, beta_s: float, goal: float,
                 amplitude: float, dt: float,
                 params: ProfileLearningParams = ProfileLearningParams()):
        self.n_kernels, self.width = int(n_kernels), float(width)
        self.alpha_s, self.beta_s = float(alpha_s), float(beta_s)
        self.goal, self.amplitude = float(goal), float(amplitude)
        self.dt = float(dt)
        self.params = params
        self._lwr = IncrementalLWR(self.n_kernels, 1, forgetting=params.forgetting)
        self._centres = kernel_centres(self.n_kernels)
        # samples not yet learned, after the MAX_WINDOW - 1 before them (the fit's history)
        self._heights: list[float] = []
        self._phases: list[float] = []
        self._omegas: list[float] = []
        self._learned = 0     # samples of the lists already learned
        self._count = 0       # samples received in all

    @property
    def weights_(self) -> np.ndarray:
        """Learned weights (N,)."""
        self._learn_queued()
        return self._lwr.weights_[0].copy()

    def update(self, height: float, phase: float, omega: float) -> None:
        """Feed the commanded height Y (m) at canonical phase (rad) and Omega (rad/s)."""
        self._heights.append(float(height))
        self._phases.append(float(phase))
        self._omegas.append(float(omega))
        self._count += 1

    def _learn_queued(self) -> None:
        new = len(self._heights) - self._learned
        if not new:
            return
        heights, phases, omegas = (np.array(v) for v in (self._heights, self._phases,
                                                         self._omegas))
        # the fit's window follows the Omega given with each sample
        unique, which = np.unique(omegas[self._learned:], return_inverse=True)
        windows = np.array([window_for(o, self.dt, self.params.derivative_window, MAX_WINDOW)
                            for o in unique])[which]
        first_count = self._count - len(heights)     # samples before the lists' first
        k = self._learned
        for window, run in itertools.groupby(windows.tolist()):
            stop = k + len(list(run))
            learn_heights(heights, phases, omegas, k, stop, first_count,
                          polynomial_fit_matrix(window, DERIVATIVE_DEGREE), self.dt,
                          self.goal, self.amplitude, self.alpha_s, self.beta_s, self._centres,
                          self.width, self._lwr.forgetting, self._lwr.weights_, self._lwr.P_)
            k = stop
        keep = max(0, len(heights) - (MAX_WINDOW - 1))
        del self._heights[:keep], self._phases[:keep], self._omegas[:keep]
        self._learned = len(self._heights)

    def waveform(self, phase) -> np.ndarray:
        """The learned height (m) at phases (n,) (the DMP's limit cycle), shape (n,)."""
        return limit_cycle(np.asarray(phase, dtype=float).reshape(-1), self.weights_[None, :],
                           np.array([self.goal]), np.array([self.amplitude]), self.width,
                           self.alpha_s, self.beta_s)[:, 0]


@njit(cache=True)
def learn_heights(heights, phases, omegas, start, stop, first_count, fit, dt, goal, amplitude,
                  alpha_s, beta_s, centres, width, forgetting, weights, P):
    """Learn samples ``start`` to ``stop`` (exclusive) of ``heights`` (m; with their
    ``phases`` rad and ``omegas`` rad/s) into ``weights`` and ``P`` (1, N) of eqs. 13-15.

    Sample k is the (``first_count`` + k + 1)-th received; once a window of L samples has
    been received (``fit``: the (degree + 1, L) matrix of
    :func:`~wipelab.learning.derivatives.polynomial_fit_matrix`), the polynomial through
    samples k - L + 1 .. k gives y, y', y'' at its centre, whose phase and Omega the forcing
    target and the kernels (``centres`` (N,), ``width``) take; r = ``amplitude``.
    """
    window = fit.shape[1]
    coefficients = np.empty((fit.shape[0], 1))
    psi = np.empty(centres.shape[0])
    goals, amplitudes = np.full(1, goal), np.full(1, amplitude)
    for k in range(start, stop):
        if first_count + k + 1 < window:
            continue
        first = k + 1 - window
        for q in range(fit.shape[0]):
            total = 0.0
            for j in range(window):
                total += fit[q, j] * heights[first + j]
            coefficients[q, 0] = total
        y, slope, curvature = evaluate_polynomial(coefficients, 0.0)
        centre = first + (window - 1) // 2
        target = forcing_target(y, slope / dt, curvature / dt ** 2, omegas[centre], goals,
                                alpha_s, beta_s)
        activations(phases[centre], centres, width, psi)
        lwr_update(psi, amplitudes, target, forgetting, weights, P)


class ConvergenceMonitor:
    """Per-period change of the learned waveform and the convergence decision."""

    def __init__(self, params: ProfileLearningParams = ProfileLearningParams()):
        self.params = params
        self.previous_: np.ndarray | None = None
        self.changes_: list[float] = []
        self.periods_ = 0

    def end_of_period(self, waveform: np.ndarray) -> float:
        """Record the waveform (heights at :data:`COMPARISON_PHASES`) at a period's end;
        returns its largest change (m) since the last one (inf for the first)."""
        change = (math.inf if self.previous_ is None
                  else float(np.max(np.abs(waveform - self.previous_))))
        self.previous_ = np.asarray(waveform, dtype=float).copy()
        self.changes_.append(change)
        self.periods_ += 1
        return change

    @property
    def converged(self) -> bool:
        p = self.params
        recent = self.changes_[-p.stable_periods:]
        return (self.periods_ >= p.min_periods and len(recent) == p.stable_periods
                and all(c < p.tolerance for c in recent))


forget_stale_kernels(__name__)
