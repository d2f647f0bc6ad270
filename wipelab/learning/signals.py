"""Synthetic periodic demonstrations with known truth, and the scores used on them.

A wiping-like movement in two DOFs: fundamental plus 2nd and 3rd harmonics on an offset,
optionally a frequency step, plus white noise as a fraction of each DOF's amplitude. Used by
the tests and ``benchmarks/bench_learn.py``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class HarmonicShape:
    """One DOF: offset + amplitude * sum_k a_k cos(k phi + theta_k), k = 1, 2, 3 (m, rad)."""

    offset: float
    amplitude: float
    harmonics: tuple[float, ...]      # a_k, k = 1, 2, ...
    phases: tuple[float, ...]         # theta_k (rad)

    def __call__(self, phase: np.ndarray) -> np.ndarray:
        k = np.arange(1, len(self.harmonics) + 1)
        terms = np.asarray(self.harmonics) * np.cos(np.multiply.outer(phase, k) + np.asarray(self.phases))
        return self.offset + self.amplitude * terms.sum(axis=-1)


#: x: a left-right stroke with a sharpened turn; y: a quarter period behind (an ellipse-like loop).
WIPING_SHAPES = (
    HarmonicShape(offset=0.55, amplitude=0.10, harmonics=(1.0, 0.3, 0.15), phases=(0.0, 0.5, 1.0)),
    HarmonicShape(offset=0.10, amplitude=0.06, harmonics=(1.0, 0.25, 0.1), phases=(-np.pi / 2, 1.2, -0.4)),
)


def true_phase(t: np.ndarray, frequency_hz: float, step_time_s: float | None = None,
               step_frequency_hz: float | None = None) -> np.ndarray:
    """phi(t) = 2 pi int f dt for a frequency that may step once, shape (n,)."""
    t = np.asarray(t, dtype=np.float64)
    phase = 2.0 * np.pi * frequency_hz * t
    if step_time_s is not None:
        after = t > step_time_s
        phase[after] = 2.0 * np.pi * (frequency_hz * step_time_s
                                      + step_frequency_hz * (t[after] - step_time_s))
    return phase


def wiping_signal(t: np.ndarray, frequency_hz: float, noise: float = 0.02, seed: int = 0,
                  step_time_s: float | None = None, step_frequency_hz: float | None = None,
                  shapes=WIPING_SHAPES) -> tuple[np.ndarray, np.ndarray]:
    """A noisy demonstration and its noise-free truth.

    Returns
    -------
    noisy, clean : ndarray, shape (n, len(shapes))
        Positions (m); noise std = ``noise`` x each DOF's amplitude.
    """
    phase = true_phase(t, frequency_hz, step_time_s, step_frequency_hz)
    clean = np.column_stack([shape(phase) for shape in shapes])
    rng = np.random.default_rng(seed)
    scale = np.array([shape.amplitude for shape in shapes])
    return clean + noise * scale * rng.standard_normal(clean.shape), clean


def periods_to_tolerance(t: np.ndarray, estimate_hz: np.ndarray, truth_hz: float,
                         start_s: float = 0.0, stop_s: float | None = None,
                         tolerance: float = 0.01) -> float:
    """Periods after ``start_s`` from which the estimate stays within ``tolerance`` of the truth.

    Counted up to ``stop_s`` (default: the end); inf if it is outside the band at the end.

    Parameters
    ----------
    t : ndarray, shape (n,)
    estimate_hz : ndarray, shape (n,)
    truth_hz : float
    """
    stop_s = t[-1] if stop_s is None else stop_s
    inside = (t >= start_s) & (t <= stop_s)
    times, error = t[inside] - start_s, np.abs(estimate_hz[inside] / truth_hz - 1.0)
    outside = np.flatnonzero(error > tolerance)
    if outside.size == 0:
        return 0.0
    if outside[-1] == error.size - 1:
        return float("inf")
    return float(times[outside[-1] + 1] * truth_hz)


def waveform_rms_percent(estimate: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """RMS error per DOF in percent of the truth's peak-to-peak; inputs shape (n, d)."""
    return 100.0 * np.sqrt(((estimate - truth) ** 2).mean(axis=0)) / np.ptp(truth, axis=0)
