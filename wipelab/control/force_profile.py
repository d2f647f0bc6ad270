"""Online learning of the force profile: the z waveform that keeps contact (Sec. II-B).

The commanded height Y(t) of eq. 10 (active compliance integrated onto the reference) is
learned as one more DOF of the periodic DMP, anchored to the same phase as the x-y movement:
each control period gives y, y', y'' (a centred polynomial fit of the recent commanded
heights, paired with the phase at the window's centre), the forcing target of the text after
eq. 12, and one step of the incremental LWR of eqs. 13-15.

Convergence is judged once per period: the learned waveform (the DMP's limit cycle, on a
grid of phases) is compared with the one a period before; learning has converged when the
largest change is below ``tolerance`` for ``stable_periods`` periods in a row, after at least
``min_periods`` periods of learning.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from wipelab.learning import IncrementalLWR, forcing_target, kernel_activations, limit_cycle
from wipelab.learning.derivatives import CentredDerivatives

#: Phases at which learned waveforms are compared (rad).
COMPARISON_PHASES = np.linspace(0.0, 2.0 * math.pi, 128, endpoint=False)


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
        self.params = params
        self.lwr = IncrementalLWR(self.n_kernels, 1, forgetting=params.forgetting)
        self.derivatives = CentredDerivatives(1, dt, params.derivative_window, degree=3,
                                              max_window=1001)
        self.updates_ = 0

    @property
    def weights_(self) -> np.ndarray:
        """Learned weights (N,)."""
        return self.lwr.weights_[0].copy()

    def update(self, height: float, phase: float, omega: float) -> None:
        """Feed the commanded height Y (m) at canonical phase (rad) and Omega (rad/s)."""
        self.derivatives.push(np.array([height]), phase, omega)
        estimate = self.derivatives.centre(omega)
        if estimate is None:
            return
        y, yd, ydd, centre_phase, centre_omega = estimate
        target = forcing_target(y, yd, ydd, centre_omega, self.goal, self.alpha_s, self.beta_s)
        psi = kernel_activations(centre_phase, self.n_kernels, self.width)
        self.lwr.update(psi, np.array([self.amplitude]), target)
        self.updates_ += 1

    def waveform(self, phase) -> np.ndarray:
        """The learned height (m) at phases (n,) (the DMP's limit cycle), shape (n,)."""
        return limit_cycle(np.asarray(phase, dtype=float).reshape(-1), self.lwr.weights_,
                           np.array([self.goal]), np.array([self.amplitude]), self.width,
                           self.alpha_s, self.beta_s)[:, 0]


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
