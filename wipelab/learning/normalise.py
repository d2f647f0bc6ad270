"""Online running estimates of each DOF's offset and scale, and the recent samples.

Two estimators, for two jobs:

* :func:`running_normalise` scales the input of the canonical system (the AFS "works best
  with a signal between -1 and 1") to the running range, so it needs no frequency: used
  until the start-up detector has found the period.
* :func:`period_statistics` gives the output system its anchor g and amplitude r: the mean and
  sqrt(2) x RMS deviation over exactly the last fundamental period (fractional window). Over
  a whole period a periodic signal's mean has no ripple, so the weights learned at different
  phases all refer to the same g and r (a ripple in g would be learned into the waveform).
  Once the period is known the canonical system's input is (y - g) / r as well: the running
  range relaxes within each period (by e^(-2 T / tau), half the range at 0.3 Hz), and that
  modulation kicked a freshly locked oscillator off by up to 4 % (measured, see
  :mod:`wipelab.learning.online`).

Both are compiled functions on state arrays (the online learner's kernel calls them).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from wipelab.numba_cache import forget_stale_kernels

#: Normalised inputs are clipped to +- this, so a start-up transient cannot kick the oscillators.
CLIP = 4.0
#: A DOF is passed on once its normalised value has been below -WARM and above +WARM.
WARM = 0.5


class RunningRange(NamedTuple):
    """State of :func:`running_normalise` per DOF: the running extremes (m) and whether the
    normalised value has been below -WARM (column 0) and above +WARM (column 1)."""

    high: np.ndarray      # (d,)
    low: np.ndarray       # (d,)
    seen: np.ndarray      # (d, 2) bool


def new_running_range(n_dofs: int) -> RunningRange:
    return RunningRange(high=np.zeros(n_dofs), low=np.zeros(n_dofs),
                        seen=np.zeros((n_dofs, 2), dtype=np.bool_))


@njit(cache=True)
def running_normalise(state: RunningRange, y, first: bool, rate: float, offset: float, u) -> None:
    """u = (y - centre) / half_range + offset per DOF, from the running extremes, into u (d,).

    The extremes follow new peaks at once and relax towards each other at ``rate`` = dt / tau
    (a fraction of the range per sample), so that a shrinking movement is followed. Half a
    period after the start the centre and scale are right, whatever the frequency; running
    mean and variance instead drift for several periods after the start, and every drift of
    the input's offset shakes the oscillators' phase. Until a DOF has swung across its range
    once (below -WARM and above +WARM), its output is 0 (+ offset): the oscillators run free
    instead of being kicked by a half-known range. ``first``: y is the first sample. The
    offset is 1 for the AFO pool, whose eq. 4 has no constant term, 0 for the AFS.
    """
    for j in range(y.shape[0]):
        if first:
            state.high[j] = y[j]
            state.low[j] = y[j]
        decay = (state.high[j] - state.low[j]) * rate
        state.high[j] = max(y[j], state.high[j] - decay)
        state.low[j] = min(y[j], state.low[j] + decay)
        half = 0.5 * (state.high[j] - state.low[j])
        value = (y[j] - 0.5 * (state.high[j] + state.low[j])) / half if half > 0.0 else 0.0
        if value < -WARM:
            state.seen[j, 0] = True
        if value > WARM:
            state.seen[j, 1] = True
        if not (state.seen[j, 0] and state.seen[j, 1]):
            value = 0.0
        u[j] = min(max(value, -CLIP), CLIP) + offset


class PeriodWindow(NamedTuple):
    """State of :func:`period_statistics`: prefix sums of x and x^2 (relative to the first
    sample, for precision) in a ring buffer of ``capacity`` samples, and the sample count."""

    reference: np.ndarray     # (k,)
    sums: np.ndarray          # (capacity, k)
    squares: np.ndarray       # (capacity, k)
    count: np.ndarray         # (1,) int64


def new_period_window(n_values: int, capacity: int) -> PeriodWindow:
    """capacity: the longest window in samples + 2."""
    return PeriodWindow(reference=np.zeros(n_values), sums=np.zeros((capacity, n_values)),
                        squares=np.zeros((capacity, n_values)), count=np.zeros(1, dtype=np.int64))


@njit(cache=True)
def period_statistics(window: PeriodWindow, x, omega: float, dt: float, periods: float, mean,
                      variance) -> None:
    """Absorb x (k,); write the mean and variance over the last ``periods`` periods of
    2 pi / Omega (a fractional number of samples; fewer while fewer have been seen) into
    mean and variance (k,).

    Over a whole period a periodic signal's mean has no ripple: the anchor g is the mean and
    the amplitude r = sqrt(2 variance) (= A for a sinusoid). ``window.count[0] = 0`` forgets
    the past (the next window starts at the next sample).
    """
    capacity = window.sums.shape[0]
    count = window.count[0]
    if count == 0:
        window.reference[:] = x
    slot = count % capacity
    previous = (count - 1) % capacity
    for j in range(x.shape[0]):
        z = x[j] - window.reference[j]
        window.sums[slot, j] = (window.sums[previous, j] if count > 0 else 0.0) + z
        window.squares[slot, j] = (window.squares[previous, j] if count > 0 else 0.0) + z * z
    count += 1
    window.count[0] = count
    length = min(periods * 2.0 * math.pi / (max(omega, 1e-12) * dt), float(count),
                 float(capacity - 2))
    whole = int(length)
    fraction = length - whole
    head = (count - 1) % capacity
    first = count - 1 - whole
    for j in range(x.shape[0]):
        s0 = window.sums[first % capacity, j] if first >= 0 else 0.0
        q0 = window.squares[first % capacity, j] if first >= 0 else 0.0
        s1 = window.sums[(first - 1) % capacity, j] if first >= 1 else 0.0
        q1 = window.squares[(first - 1) % capacity, j] if first >= 1 else 0.0
        total = (window.sums[head, j] - s0) + fraction * (s0 - s1)
        total_square = (window.squares[head, j] - q0) + fraction * (q0 - q1)
        average = total / length
        mean[j] = window.reference[j] + average
        variance[j] = max(total_square / length - average * average, 0.0)


forget_stale_kernels(__name__)
