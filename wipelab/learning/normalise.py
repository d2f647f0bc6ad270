"""Online running estimates of each DOF's offset and scale, and the recent samples.

Two estimators, for two jobs:

* :class:`RunningNormaliser` scales the input of the canonical system (the AFS "works best
  with a signal between -1 and 1") to the running range, so it needs no frequency: used
  until the start-up detector has found the period.
* :class:`PeriodStatistics` gives the output system its anchor g and amplitude r: the mean and
  sqrt(2) x RMS deviation over exactly the last fundamental period (fractional window). Over
  a whole period a periodic signal's mean has no ripple, so the weights learned at different
  phases all refer to the same g and r (a ripple in g would be learned into the waveform).
  Once the period is known the canonical system's input is (y - g) / r as well: the running
  range relaxes within each period (by e^(-2 T / tau), half the range at 0.3 Hz), and that
  modulation kicked a freshly locked oscillator off by up to 4 % (measured, see
  :mod:`wipelab.learning.online`).

:class:`RecentSamples` keeps the raw samples the hand-over fits its series to.
"""

from __future__ import annotations

import math

import numpy as np

#: Normalised inputs are clipped to +- this, so a start-up transient cannot kick the oscillators.
CLIP = 4.0
#: A DOF is passed on once its normalised value has been below -WARM and above +WARM.
WARM = 0.5


class RunningNormaliser:
    """u = (y - centre) / half_range + offset, per DOF, from the running extremes.

    The extremes follow new peaks at once and relax towards each other at the rate
    dt / tau (a fraction of the range per sample), so that a shrinking movement is followed.
    Half a period after the start the centre and scale are right, whatever the frequency;
    running mean and variance instead drift for several periods after the start, and every
    drift of the input's offset shakes the oscillators' phase. Until a DOF has swung across
    its range once (below -WARM and above +WARM), its output is 0: the oscillators run free
    instead of being kicked by a half-known range.

    Parameters
    ----------
    n_dofs : int
    dt : float
        Sample interval (s).
    time_constant_s : float
        tau (s).
    offset : float
        Constant added to every normalised DOF (1 for the AFO pool, whose eq. 4 has no
        constant term; 0 for the AFS).
    """

    def __init__(self, n_dofs: int, dt: float, time_constant_s: float, offset: float = 0.0):
        self.rate = dt / time_constant_s
        self.offset = offset
        self.count_ = 0
        self.high_ = np.zeros(n_dofs)
        self.low_ = np.zeros(n_dofs)
        self.seen_low_ = np.zeros(n_dofs, dtype=bool)
        self.seen_high_ = np.zeros(n_dofs, dtype=bool)

    def update(self, y: np.ndarray) -> np.ndarray:
        """Absorb a sample y (d,) and return it normalised, shape (d,)."""
        if self.count_ == 0:
            self.high_, self.low_ = y.copy(), y.copy()
        self.count_ += 1
        decay = (self.high_ - self.low_) * self.rate
        self.high_ = np.maximum(y, self.high_ - decay)
        self.low_ = np.minimum(y, self.low_ + decay)
        half = 0.5 * (self.high_ - self.low_)
        centred = y - 0.5 * (self.high_ + self.low_)
        u = np.divide(centred, half, out=np.zeros_like(half), where=half > 0.0)
        self.seen_low_ |= u < -WARM
        self.seen_high_ |= u > WARM
        return np.where(self.seen_low_ & self.seen_high_, np.clip(u, -CLIP, CLIP), 0.0) + self.offset


class PeriodStatistics:
    """Mean and amplitude sqrt(2) x RMS over the last fundamental period(s), per DOF.

    Keeps prefix sums of y and y^2 (relative to the first sample, for precision) in a ring
    buffer of ``capacity`` samples; the window is 2 pi / (Omega dt) samples, fractional.

    Parameters
    ----------
    n_dofs : int
    dt : float
        Sample interval (s).
    capacity : int
        Longest window in samples + 2.
    periods : float
        Window length in periods (a whole number, so that a periodic signal's mean is exact).
    """

    def __init__(self, n_dofs: int, dt: float, capacity: int, periods: float = 1.0):
        self.dt = dt
        self.capacity = capacity
        self.periods = periods
        self.count_ = 0
        self.reference_ = np.zeros(n_dofs)
        self.sums_ = np.zeros((capacity, n_dofs))
        self.squares_ = np.zeros((capacity, n_dofs))

    def restart(self) -> None:
        """Forget the past: the next window starts at the next sample."""
        self.count_ = 0

    def _prefix(self, back: int) -> tuple[np.ndarray, np.ndarray]:
        """Prefix sums up to and including sample count_ - 1 - back (zero before the first)."""
        index = self.count_ - 1 - back
        if index < 0:
            return np.zeros_like(self.reference_), np.zeros_like(self.reference_)
        return self.sums_[index % self.capacity], self.squares_[index % self.capacity]

    def update(self, y: np.ndarray, omega: float) -> tuple[np.ndarray, np.ndarray]:
        """Absorb y (d,) and return (mean g, amplitude r), each shape (d,), over the last period."""
        if self.count_ == 0:
            self.reference_ = np.array(y, dtype=np.float64)
        z = y - self.reference_
        last_sum, last_square = self._prefix(0)
        slot = self.count_ % self.capacity
        self.sums_[slot] = last_sum + z
        self.squares_[slot] = last_square + z * z
        self.count_ += 1
        window = min(self.periods * 2.0 * math.pi / (max(omega, 1e-12) * self.dt), self.count_,
                     self.capacity - 2)
        whole = int(window)
        fraction = window - whole
        s0, q0 = self._prefix(whole)
        s1, q1 = self._prefix(whole + 1)
        head_sum, head_square = self._prefix(0)
        total = (head_sum - s0) + fraction * (s0 - s1)
        total_square = (head_square - q0) + fraction * (q0 - q1)
        mean = total / window
        variance = np.maximum(total_square / window - mean ** 2, 0.0)
        return self.reference_ + mean, np.sqrt(2.0 * variance)


class RecentSamples:
    """Ring buffer of the last ``capacity`` samples (d,), oldest first on read."""

    def __init__(self, n_dofs: int, capacity: int):
        self.values_ = np.zeros((capacity, n_dofs))
        self.count_ = 0

    def push(self, y: np.ndarray) -> None:
        self.values_[self.count_ % self.values_.shape[0]] = y
        self.count_ += 1

    def restart(self) -> None:
        """Forget every sample."""
        self.count_ = 0

    def last(self, n: int) -> np.ndarray:
        """The last n samples (n <= capacity and <= count_), shape (n, d), oldest first."""
        return self.values_[(self.count_ - n + np.arange(n)) % self.values_.shape[0]]
