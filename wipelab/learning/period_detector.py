"""A fast start-up estimate of the period, handed to the canonical system as its Omega(0).

An adaptive oscillator started far from the fundamental needs several periods to descend
to it and to lock (about 3.5 periods even when started at the right frequency, because its
phase and its series start from nothing). This detector finds the period within the first
two periods, by the difference function of YIN (de Cheveigne and Kawahara, 2002) on the raw
positions:

    D(tau) = mean_k |y_k - y_{k - tau}|^2      (all DOFs pooled, in metres)
    D'(tau) = D(tau) tau / sum_{j <= tau} D(j)  (cumulative-mean normalised)

A periodic signal makes D'(T) ~ (noise / amplitude)^2; the first lag whose D' falls below a
threshold and is a local minimum of D is the period, refined by a parabola through three
lags. Lags are known once ``confirm`` x tau sample pairs have been compared (the signal then
spans (1 + confirm) tau), so a period T is found after about (1 + confirm) T. Pooling the
DOFs in metres gives a DOF that barely moves little say, and makes the common period of
DOFs at different harmonics (a figure eight) the first dip. Input that is not periodic gives
no dip: the detector never fires and the canonical system runs from its own initial
frequency.

The search runs on block averages at about ``rate_hz`` (a few samples per period are
enough for the parabola), so the incremental update costs O(max lag) per averaged sample.
Measured on the benchmark signals (0.3-3 Hz, 30 and 500 Hz, 2 % noise, 8 seeds): found
after 1.9-2.2 periods with ``confirm`` = 1, within 0.18 % of the truth (0.54 % after 1.5
periods with ``confirm`` = 0.5).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class PeriodDetectorParameters:
    """Settings of the start-up period detector."""

    threshold: float = 0.1   # a dip of D' below this is a period (YIN's absolute threshold)
    confirm: float = 1.0     # a lag tau is known once confirm x tau pairs were compared
    rate_hz: float = 50.0    # rate of the block-averaged stream searched (Hz)

    def __post_init__(self):
        if not 0.0 < self.threshold < 1.0:
            raise ValueError(f"threshold must be in (0, 1), got {self.threshold}")
        if not self.confirm > 0.0:
            raise ValueError(f"confirm must be > 0, got {self.confirm}")
        if not self.rate_hz > 0.0:
            raise ValueError(f"rate_hz must be > 0, got {self.rate_hz}")


@dataclass(frozen=True)
class DetectorLayout:
    """Sizes derived from the parameters and the sample interval.

    Attributes
    ----------
    decimation : int
        Samples per block average.
    min_lag, max_lag : int
        Lags searched, in blocks (max_lag from the lowest frequency, min_lag from the highest).
    """

    decimation: int
    min_lag: int
    max_lag: int

    @classmethod
    def for_rate(cls, dt: float, params: PeriodDetectorParameters, min_frequency_hz: float,
                 max_frequency_hz: float) -> DetectorLayout:
        decimation = max(1, int(round(1.0 / (dt * params.rate_hz))))
        block = dt * decimation
        return cls(decimation=decimation,
                   min_lag=max(2, int(math.floor(1.0 / (max_frequency_hz * block)))),
                   max_lag=int(math.ceil(1.0 / (min_frequency_hz * block))) + 1)


def add_block(blocks: np.ndarray, sums: np.ndarray, n_blocks: int, block: np.ndarray) -> None:
    """Add the pairs of a new block average to the difference sums and store it (in place).

    Plain loops, so that the numba kernel compiles this very function.

    Parameters
    ----------
    blocks : ndarray, shape (max_lag + 1, d)
        Ring buffer of the block averages so far.
    sums : ndarray, shape (max_lag + 1,)
        sums[tau] = sum over compared pairs of |y_k - y_{k - tau}|^2 (m^2; index 0 unused).
    n_blocks : int
        Block averages before this one.
    block : ndarray, shape (d,)
        The new block average (m).
    """
    capacity = blocks.shape[0]
    for tau in range(1, min(n_blocks, capacity - 1) + 1):
        previous = blocks[(n_blocks - tau) % capacity]
        total = 0.0
        for j in range(block.shape[0]):
            total += (block[j] - previous[j]) ** 2
        sums[tau] += total
    blocks[n_blocks % capacity] = block


def first_period_lag(sums: np.ndarray, n_blocks: int, min_lag: int, max_lag: int, confirm: float,
                     threshold: float) -> float:
    """The period in blocks (fractional) from the difference sums; 0 while none is found.

    Parameters
    ----------
    sums : ndarray, shape (max_lag + 1,)
        See :func:`add_block`.
    n_blocks : int
        Block averages seen so far (pairs at lag tau: n_blocks - tau).
    min_lag, max_lag : int
        Lags searched (blocks).
    confirm, threshold : float
        As in :class:`PeriodDetectorParameters`.
    """
    known = min(max_lag, int(n_blocks / (1.0 + confirm)))
    total = 0.0
    tau = 1
    found = False
    while tau <= known:
        difference = sums[tau] / (n_blocks - tau)
        total += difference
        if tau >= min_lag and total > 0.0 and difference * tau < threshold * total:
            found = True
            break
        tau += 1
    if not found:
        return 0.0
    while tau < known and sums[tau + 1] / (n_blocks - tau - 1) < sums[tau] / (n_blocks - tau):
        tau += 1
    if tau >= known:
        return 0.0                                    # the dip's far side is not known yet
    before = sums[tau - 1] / (n_blocks - tau + 1)
    at = sums[tau] / (n_blocks - tau)
    after = sums[tau + 1] / (n_blocks - tau - 1)
    curvature = before - 2.0 * at + after
    return tau + (0.5 * (before - after) / curvature if curvature > 0.0 else 0.0)


class PeriodDetector:
    """Online start-up period detector for d DOFs sampled every dt (reference implementation).

    Parameters
    ----------
    n_dofs : int
    dt : float
        Sample interval (s).
    params : PeriodDetectorParameters
    min_frequency_hz, max_frequency_hz : float
        Range of fundamentals searched (Hz).

    Attributes
    ----------
    period_s_ : float or None
        The detected period (s), once found.
    """

    def __init__(self, n_dofs: int, dt: float, params: PeriodDetectorParameters,
                 min_frequency_hz: float, max_frequency_hz: float):
        self.params = params
        self.layout = DetectorLayout.for_rate(dt, params, min_frequency_hz, max_frequency_hz)
        self.block_s = dt * self.layout.decimation
        self.blocks_ = np.zeros((self.layout.max_lag + 1, n_dofs))   # ring buffer
        self.sums_ = np.zeros(self.layout.max_lag + 1)
        self.n_blocks_ = 0
        self._accumulated = np.zeros(n_dofs)
        self._in_block = 0
        self.period_s_: float | None = None

    def update(self, y: np.ndarray) -> bool:
        """Absorb a sample y (d,) in m; True at the one sample where the period is found."""
        if self.period_s_ is not None:
            return False
        self._accumulated += y
        self._in_block += 1
        if self._in_block < self.layout.decimation:
            return False
        block = self._accumulated / self._in_block
        self._accumulated[:] = 0.0
        self._in_block = 0
        add_block(self.blocks_, self.sums_, self.n_blocks_, block)
        self.n_blocks_ += 1
        layout, params = self.layout, self.params
        lag = first_period_lag(self.sums_, self.n_blocks_, layout.min_lag, layout.max_lag,
                               params.confirm, params.threshold)
        if lag == 0.0:
            return False
        self.period_s_ = lag * self.block_s
        return True
