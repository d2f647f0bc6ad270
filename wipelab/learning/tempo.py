"""The demonstrated tempo: the model's frequency, and deliberate changes of tempo (compiled).

A person's tempo wanders by several percent from stroke to stroke, and the canonical system
follows it: its frequency at the end of a demonstration is only the tempo of the last
strokes (the fundamental of the last period: up to 10.9 % off the nominal on the 27
human-like demonstrations of ``benchmarks/bench_learn.py``). The phase advance over many
periods gives the demonstrated frequency: the model's frequency is the canonical phase's mean
rate over the last ``window_periods`` periods of the current *tempo segment*.

A person also speeds up and slows down on purpose. Averaged over 40 periods without
segments, a change of tempo is learned only after tens of periods (table (b) of the
benchmark: not within 1 % in the 15 periods after a +-30 % step). So the
segment restarts at a change of tempo, found by a change-point test on the per-period
frequency: the period boundaries are the times the canonical phase passes a multiple of
2 pi; when each of the last ``change_periods`` periods is faster (or each slower) than the
segment's mean before them by more than a factor 1 + ``change_threshold``, the segment restarts
at the boundary where the change is found. Not retroactively at the first changed period:
there the canonical phase was still catching up with the new tempo, and its offset from the
person's phase biased the segment's mean for many periods (in development, some +-30 %
steps never came within 1 %; on held-out demonstrations every one of 60 does within 2.9
periods: ``benchmarks/bench_learn.py``, table (b)). Before ``min_periods`` periods of the
segment (and of data) exist, the fundamental of the last period stands in. The
stroke-to-stroke wander of a person (a few percent) stays far below the threshold; a change
of 30 % is found two periods after it.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from wipelab.numba_cache import forget_stale_kernels


class TempoSettings(NamedTuple):
    """Parameters of the tempo estimate (see the module docstring)."""

    window_periods: float     # the mean phase rate over at most this many periods
    min_periods: float        # fewer periods in the segment: the fundamental stands in
    change_threshold: float   # relative change of the per-period frequency (inf: never)
    change_periods: int       # ... in each of this many consecutive periods
    reference_periods: int    # periods of the segment needed before the test runs


class TempoState(NamedTuple):
    """Period boundaries of the canonical phase and the current segment.

    Attributes
    ----------
    times, phases : ndarray, shape (capacity,)
        Ring of boundaries (s, rad): the segment's first entry is where it starts (any
        phase), the others are where the phase passed a multiple of 2 pi.
    count : ndarray, shape (1,), int64
        Entries written since the restart (the latest is ``count - 1``).
    segment : ndarray, shape (1,), int64
        Entry where the current segment starts.
    next_phase : ndarray, shape (1,)
        The next multiple of 2 pi the phase will pass (rad).
    previous : ndarray, shape (2,)
        Time (s) and phase (rad) of the last sample.
    changes : ndarray, shape (1,), int64
        Changes of tempo found so far.
    """

    times: np.ndarray
    phases: np.ndarray
    count: np.ndarray
    segment: np.ndarray
    next_phase: np.ndarray
    previous: np.ndarray
    changes: np.ndarray


def new_tempo_state(settings: TempoSettings) -> TempoState:
    capacity = int(math.ceil(settings.window_periods)) + settings.change_periods \
        + settings.reference_periods + 4
    return TempoState(times=np.zeros(capacity), phases=np.zeros(capacity),
                      count=np.zeros(1, dtype=np.int64), segment=np.zeros(1, dtype=np.int64),
                      next_phase=np.zeros(1), previous=np.zeros(2),
                      changes=np.zeros(1, dtype=np.int64))


@njit(cache=True)
def tempo_restart(state: TempoState, time: float, phase: float) -> None:
    """Start a new segment at (time s, phase rad), forgetting the boundaries before."""
    state.times[0] = time
    state.phases[0] = phase
    state.count[0] = 1
    state.segment[0] = 0
    state.next_phase[0] = (math.floor(phase / (2.0 * math.pi)) + 1.0) * 2.0 * math.pi
    state.previous[0] = time
    state.previous[1] = phase


@njit(cache=True)
def _rate_hz(state: TempoState, first: int, last: int) -> float:
    """Mean phase rate between entries first and last (Hz)."""
    capacity = state.times.shape[0]
    a, b = first % capacity, last % capacity
    return (state.phases[b] - state.phases[a]) / (2.0 * math.pi * (state.times[b] - state.times[a]))


@njit(cache=True)
def _test_change(state: TempoState, settings: TempoSettings) -> bool:
    """Whether each of the last change_periods periods left the segment's mean before them
    by more than the threshold, all in the same direction."""
    last = state.count[0] - 1
    recent = settings.change_periods
    if last - recent - state.segment[0] < settings.reference_periods:
        return False
    reference = _rate_hz(state, state.segment[0], last - recent)
    limit = math.log1p(settings.change_threshold)
    faster, slower = 0, 0
    for k in range(last - recent + 1, last + 1):
        ratio = math.log(_rate_hz(state, k - 1, k) / reference)
        if ratio > limit:
            faster += 1
        elif ratio < -limit:
            slower += 1
    return faster == recent or slower == recent


@njit(cache=True)
def tempo_update(state: TempoState, settings: TempoSettings, time: float, phase: float,
                 fundamental_hz: float) -> float:
    """Absorb the canonical phase (rad) at ``time`` (s); return the model frequency (Hz).

    ``fundamental_hz``: the canonical system's fundamental averaged over the last period,
    which stands in while the segment is shorter than ``min_periods``.
    """
    capacity = state.times.shape[0]
    previous_time, previous_phase = state.previous[0], state.previous[1]
    while phase >= state.next_phase[0]:
        crossing = state.next_phase[0]
        fraction = (crossing - previous_phase) / (phase - previous_phase) \
            if phase > previous_phase else 1.0
        slot = state.count[0] % capacity
        state.times[slot] = previous_time + min(max(fraction, 0.0), 1.0) * (time - previous_time)
        state.phases[slot] = crossing
        state.count[0] += 1
        state.next_phase[0] = crossing + 2.0 * math.pi
        state.segment[0] = max(state.segment[0], state.count[0] - capacity + 1)
        if _test_change(state, settings):
            state.segment[0] = state.count[0] - 1
            state.changes[0] += 1
    state.previous[0] = time
    state.previous[1] = phase
    start = max(state.segment[0], state.count[0] - 1 - int(settings.window_periods))
    slot = start % capacity
    span = time - state.times[slot]
    if span * fundamental_hz < settings.min_periods:
        return fundamental_hz
    return (phase - state.phases[slot]) / (2.0 * math.pi * span)


forget_stale_kernels(__name__)
