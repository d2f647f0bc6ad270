"""Imitation learning while the person demonstrates (paper, Sec. III-A3), one sample per frame.

:class:`Imitation` takes the tracked sponge position of each frame and

1. measures the demonstration area online (Fig. 3, :class:`~wipelab.vision.
   demonstration_area.AreaMeter`): from the first tracked frame until the learner locks
   onto the movement (about two periods), the rectangle of the tracked positions; the
   normalised offsets are taken from it from then on;
2. learns the movement with the online learner (:class:`~wipelab.learning.OnlineLearner`,
   one :meth:`~wipelab.learning.OnlineLearner.step` per frame; frames where the sponge was
   not tracked, or that were dropped, are gaps that teach nothing). The learner starts after
   ``reference_seconds`` of tracking with the samples seen so far; its reference DOF (whose
   fundamental defines phase 0) is the one that moved over the larger range in them;
3. decides when imitation learning ends (:attr:`stop_reason`), after the learner has locked:

   * ``learn-periods``: ``learn_periods`` periods of the canonical phase since the lock;
   * ``converged``: the learned waveform has stopped changing: at the end of each period
     since the lock, the learned period (each DOF's limit cycle (y - g) / r on 64 phases)
     differs from the one a period before by less than ``waveform_tolerance`` RMS of its
     peak-to-peak, and the model's frequency by less than ``frequency_tolerance``, in
     ``settled_periods`` consecutive periods, at least ``min_periods`` after the lock;
   * ``sponge gone``: not tracked for ``gone_seconds``;
   * ``sponge still``: over the last ``still_seconds`` the tracked positions spanned less
     than ``still_fraction`` of the demonstration area's larger side;
   * a request (the user's word, the end of the source): see :meth:`request_stop`.

Pure numpy and the learner: tests drive it with synthetic signals, no video or simulator.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field

import numpy as np

from wipelab.learning import OnlineLearner, OnlineParameters, PeriodicModel, limit_cycle
from wipelab.vision.demonstration_area import AreaMeter, DemonstrationArea

#: Phases at which the convergence criterion compares learned periods.
WAVEFORM_PHASES = np.linspace(0.0, 2.0 * math.pi, 64, endpoint=False)


@dataclass(frozen=True)
class ImitationParams:
    """How imitation learning runs and when it ends (CLI flags in brackets)."""

    dofs: tuple[str, ...] = ("x", "y")     # tracked coordinates learned (m, track frame)
    learner: OnlineParameters = field(default_factory=OnlineParameters)
    reference_seconds: float = 1.0        # tracking before the learner starts (s)
    learn_periods: float | None = None    # [--learn-periods] stop after this many periods
    stop_on_convergence: bool = True      # [--stop-on-convergence/--no-...]
    waveform_tolerance: float = 0.02      # change of the learned period (of its p-p, RMS)
    frequency_tolerance: float = 0.01     # change of the model frequency per period (relative)
    settled_periods: int = 2              # ... in this many consecutive periods
    min_periods: float = 4.0              # periods after the lock before it may stop so
    gone_seconds: float = 3.0             # not tracked this long: the demonstration ended
    still_seconds: float = 2.0            # moved less than still_fraction in this long: ended
    still_fraction: float = 0.1           # of the demonstration area's larger side

    def __post_init__(self):
        if self.learn_periods is not None and not self.learn_periods > 0:
            raise ValueError(f"learn_periods must be positive, got {self.learn_periods}")
        if not (self.reference_seconds > 0 and self.gone_seconds > 0
                and self.still_seconds > 0):
            raise ValueError("reference_seconds, gone_seconds and still_seconds must be > 0")


class Imitation:
    """Online imitation learning of the tracked movement, one frame at a time.

    Parameters
    ----------
    fps : float
        Frame rate (Hz): sample k is at k / fps seconds.
    params : ImitationParams

    Attributes
    ----------
    learner : OnlineLearner or None
        None until ``reference_seconds`` of tracking.
    meter : AreaMeter
    lock_time : float
        Time (s) of the sample at which the learner first locked (NaN before).
    stop_reason : str or None
        Why imitation learning ended (None while it goes on).
    stop_time : float
    converged_time : float
        Time (s) at which the convergence criterion first held (also when it does not stop).
    requested : str or None
        A stop asked for (:meth:`request_stop`) before the learner locked, applied at the lock.
    """

    def __init__(self, fps: float, params: ImitationParams = ImitationParams()):
        self.fps, self.dt = float(fps), 1.0 / float(fps)
        self.params = params
        self.learner: OnlineLearner | None = None
        self.meter = AreaMeter()
        self.count = 0
        self.lock_time = self.stop_time = math.nan
        self.stop_reason: str | None = None
        self.converged_time = math.nan
        self.requested: str | None = None
        self.first_tracked = math.nan
        self.last_tracked = math.nan
        self._waiting: list[tuple[np.ndarray, bool]] = []   # samples before the learner starts
        self._lock_phase = math.nan
        self._period_end = math.nan
        self._last_period: tuple[np.ndarray, float] | None = None
        self._settled = 0
        self._recent: deque[tuple[float, np.ndarray]] = deque()

    @property
    def locked(self) -> bool:
        """Whether the learner has locked onto the movement (the robot may imitate)."""
        return not math.isnan(self.lock_time)

    @property
    def area(self) -> DemonstrationArea | None:
        return self.meter.area

    @property
    def periods(self) -> float:
        """Periods of the canonical phase since the lock (0 before)."""
        if not self.locked:
            return 0.0
        return (self.learner.phase - self._lock_phase) / (2.0 * math.pi)

    def step(self, xy, valid: bool) -> None:
        """Sample ``count`` (time count / fps): the tracked position ``xy`` (d,) (m; ignored
        when not ``valid``)."""
        t = self.count * self.dt
        self.count += 1
        y = np.asarray(xy, dtype=np.float64) if valid else np.full(len(self.params.dofs), np.nan)
        if valid:
            if math.isnan(self.first_tracked):
                self.first_tracked = t
            self.last_tracked = t
            self.meter.add(t, y)
            self._recent.append((t, y))
        while self._recent and self._recent[0][0] < t - self.params.still_seconds:
            self._recent.popleft()
        if self.learner is None:
            if not math.isnan(self.first_tracked):
                self._waiting.append((y, bool(valid)))
            if t - self.first_tracked >= self.params.reference_seconds - 1e-9:
                self._start_learner()
            return
        self.learner.step(np.nan_to_num(y), valid)
        if self.stop_reason is None:
            self._after_sample(t)

    def request_stop(self, reason: str) -> None:
        """End imitation learning now (at the lock if the learner has not locked yet)."""
        if self.stop_reason is not None:
            return
        if self.locked:
            self._stop(reason, (self.count - 1) * self.dt)
        else:
            self.requested = self.requested or reason

    def model(self, source: dict) -> PeriodicModel:
        """The movement learned so far (world frame, t = 0 at the first frame)."""
        return self.learner.model(self.params.dofs, source, (self.count - 1) * self.dt)

    # -- internals ------------------------------------------------------------------------
    def _start_learner(self) -> None:
        samples = np.array([y for y, _ in self._waiting])
        valid = np.array([v for _, v in self._waiting])
        span = np.nanmax(samples[valid], axis=0) - np.nanmin(samples[valid], axis=0)
        self.learner = OnlineLearner(len(self.params.dofs), self.dt, self.params.learner,
                                     reference_dof=int(np.argmax(span)))
        self.learner.process(np.nan_to_num(samples), valid)
        self._waiting = []
        if self.learner.locked:
            self._on_lock(self.count * self.dt - self.dt)

    def _after_sample(self, t: float) -> None:
        if not self.locked:
            if self.learner.locked:
                self._on_lock(t)
            return
        p = self.params
        if p.learn_periods is not None and self.periods >= p.learn_periods:
            self._stop("learn-periods", t)
        elif t - self.last_tracked >= p.gone_seconds:
            self._stop("sponge gone", t)
        elif self._still(t):
            self._stop("sponge still", t)
        elif self.learner.phase >= self._period_end:
            self._period_end += 2.0 * math.pi
            if self._converged() and math.isnan(self.converged_time):
                self.converged_time = t
                if p.stop_on_convergence:
                    self._stop("converged", t)

    def _on_lock(self, t: float) -> None:
        self.lock_time = t
        self.meter.freeze()
        self._lock_phase = self.learner.phase
        self._period_end = self._lock_phase + 2.0 * math.pi
        if self.requested is not None:
            self._stop(self.requested, t)

    def _stop(self, reason: str, t: float) -> None:
        self.stop_reason, self.stop_time = reason, t

    def _still(self, t: float) -> bool:
        """Whether the sponge moved less than ``still_fraction`` of the area lately."""
        p = self.params
        if self.area is None or t - self.lock_time < p.still_seconds or \
                len(self._recent) < 0.5 * p.still_seconds * self.fps:
            return False
        points = np.array([y for _, y in self._recent])
        extent = float(np.max(points.max(axis=0) - points.min(axis=0)))
        side = float(np.max(self.area.upper_right - self.area.lower_left))
        return extent < p.still_fraction * side

    def _converged(self) -> bool:
        """End of a period: has the learned waveform (and frequency) stopped changing?"""
        p, learner = self.params, self.learner
        shape = limit_cycle(WAVEFORM_PHASES, learner.weights, np.zeros(len(p.dofs)),
                            np.ones(len(p.dofs)), learner.params.kernel_width,
                            learner.params.alpha_s, learner.params.beta_s)
        frequency = learner.frequency_hz
        previous, self._last_period = self._last_period, (shape, frequency)
        if previous is None:
            return False
        span = np.maximum(np.ptp(shape, axis=0), 1e-9)
        change = float(np.max(np.sqrt(np.mean((shape - previous[0]) ** 2, axis=0)) / span))
        steady = abs(frequency - previous[1]) <= p.frequency_tolerance * previous[1]
        self._settled = self._settled + 1 if change <= p.waveform_tolerance and steady else 0
        return self._settled >= p.settled_periods and self.periods >= p.min_periods
