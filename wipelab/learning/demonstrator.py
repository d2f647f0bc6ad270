"""Held-out test demonstrations: a person's periodic wiping built stroke by stroke.

An independent generator for judging the online learner on movements it was not tuned on.
It shares no code and no model with :mod:`wipelab.learning.signals` (fixed harmonic shapes
on a uniform or once-stepped phase) or with synth's :class:`wipelab.vision.WipingMotion`
(phase wander as a sum of slow sinusoids): here time is cut into strokes whose durations
and sizes are drawn one after the other, as a person's are.

* Tempo: stroke k lasts T_k = T_base(t) exp(e_k), e an AR(1) sequence (correlation 0.5,
  std ``tempo_wander``); the phase is 2 pi k at the stroke boundaries and monotone cubic
  (PCHIP) in between, so the instantaneous frequency is smooth. ``tempo_steps`` change
  T_base deliberately from the first stroke that starts after each step time.
* Shape: per DOF, c + A(t) (cos(phi + theta_1) + a_2 cos(2 phi + theta_2) + a_3 cos(3 phi +
  theta_3)), the a_k and theta_k drawn per DOF (random phases), A(t) the DOF's size times a
  per-stroke AR(1) factor (std ``amplitude_wander``) interpolated between stroke centres.
* The centre drifts (a random walk smoothed over seconds), white noise of ``noise`` times
  each DOF's size is added, and ``gaps`` are not observed: flagged invalid and bridged by
  straight lines, as the learn stage's resampling fills them.

Seeds 0-99 may be looked at while developing; seeds from :data:`HELD_OUT_SEEDS` on are for
reporting only.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.interpolate import PchipInterpolator

#: First seed of the held-out range (never used while tuning).
HELD_OUT_SEEDS = 1000


@dataclass(frozen=True)
class DemonstratorParams:
    """What the simulated person does.

    Attributes
    ----------
    frequency_hz : float
        Tempo at the start (strokes per second).
    duration_s, rate_hz : float
        Length (s) and sample rate (Hz) of the recording.
    n_dofs : int
        Number of DOFs (metres, 1 to 3).
    tempo_wander : float
        Relative std of a stroke's duration about the tempo.
    amplitude_wander : float
        Relative std of a stroke's size.
    harmonics : float
        Largest relative amplitude of the 2nd and 3rd harmonics (drawn in [0.05, this]).
    noise : float
        White noise std, relative to each DOF's size.
    drift_m : float
        Std of the centre's slow drift (m).
    tempo_steps : tuple of (time s, factor)
        Deliberate tempo changes: from the first stroke after ``time`` the tempo is multiplied
        by ``factor``.
    gaps : tuple of (start s, length s)
        Stretches that are not observed.
    """

    frequency_hz: float = 1.0
    duration_s: float = 30.0
    rate_hz: float = 30.0
    n_dofs: int = 2
    tempo_wander: float = 0.03
    amplitude_wander: float = 0.05
    harmonics: float = 0.3
    noise: float = 0.02
    drift_m: float = 0.004
    tempo_steps: tuple[tuple[float, float], ...] = ()
    gaps: tuple[tuple[float, float], ...] = ()


@dataclass(frozen=True)
class Demonstration:
    """A generated recording and its truth.

    Attributes
    ----------
    t : ndarray, shape (n,)
        Sample times (s), uniform.
    Y : ndarray, shape (n, d)
        What a tracker delivers (m): noisy, bridged across gaps.
    valid : ndarray of bool, shape (n,)
        False in a gap.
    clean : ndarray, shape (n, d)
        The movement without noise (m).
    phase : ndarray, shape (n,)
        True stroke phase (rad, 2 pi per stroke).
    frequency_hz : ndarray, shape (n,)
        Instantaneous tempo d phase / dt / 2 pi (Hz).
    base_hz : ndarray, shape (n,)
        The tempo the person aims at (Hz): the start tempo times the steps taken so far.
    """

    t: np.ndarray
    Y: np.ndarray
    valid: np.ndarray
    clean: np.ndarray
    phase: np.ndarray
    frequency_hz: np.ndarray
    base_hz: np.ndarray


def _ar1(rng: np.random.Generator, n: int, std: float, correlation: float = 0.5) -> np.ndarray:
    """An AR(1) sequence of length n with stationary std ``std``."""
    values = np.empty(n)
    innovation = std * math.sqrt(1.0 - correlation ** 2)
    values[0] = rng.normal(0.0, std)
    for k in range(1, n):
        values[k] = correlation * values[k - 1] + rng.normal(0.0, innovation)
    return values


def demonstrate(params: DemonstratorParams, seed: int) -> Demonstration:
    """Generate one demonstration (deterministic in ``seed``)."""
    p = params
    rng = np.random.default_rng([seed, 0xD3A0])
    t = np.arange(int(round(p.duration_s * p.rate_hz))) / p.rate_hz
    # strokes: boundaries in time, one after the other
    steps = sorted(p.tempo_steps)
    boundaries = [0.0]
    wander = _ar1(rng, int(p.duration_s * p.frequency_hz * 4) + 8, p.tempo_wander)
    k = 0
    while boundaries[-1] <= t[-1] + 2.0 / p.frequency_hz:
        base_hz = p.frequency_hz * math.prod(f for s, f in steps if s <= boundaries[-1])
        boundaries.append(boundaries[-1] + math.exp(wander[k % wander.size]) / base_hz)
        k += 1
    boundaries = np.array(boundaries) - rng.uniform(0.0, 1.0) / p.frequency_hz
    turns = 2.0 * math.pi * np.arange(boundaries.size)
    phase_of = PchipInterpolator(boundaries, turns)
    phase = phase_of(t)
    frequency_hz = phase_of.derivative()(t) / (2.0 * math.pi)
    base_hz = p.frequency_hz * np.array([math.prod(f for s, f in steps if s <= time) for time in t])
    # sizes per stroke, interpolated between stroke centres
    centres = 0.5 * (boundaries[1:] + boundaries[:-1])
    size = rng.uniform(0.05, 0.15) * np.concatenate([[1.0], rng.uniform(0.3, 1.0, p.n_dofs - 1)])
    clean = np.empty((t.size, p.n_dofs))
    for j in range(p.n_dofs):
        factor = PchipInterpolator(centres, np.exp(_ar1(rng, centres.size, p.amplitude_wander)))(t)
        weights = np.concatenate([[1.0], rng.uniform(0.05, p.harmonics, 2)])
        angles = rng.uniform(0.0, 2.0 * math.pi, 3)
        shape = sum(weights[h] * np.cos((h + 1) * phase + angles[h]) for h in range(3))
        walk = np.cumsum(rng.normal(0.0, 1.0, t.size))
        kernel = np.hanning(max(3, int(3.0 * p.rate_hz)))
        drift = np.convolve(walk - walk.mean(), kernel / kernel.sum(), mode="same")
        drift *= p.drift_m / max(drift.std(), 1e-12)
        clean[:, j] = rng.uniform(-0.3, 0.7) + drift + size[j] * factor * shape
    Y = clean + p.noise * size * rng.standard_normal(clean.shape)
    valid = np.ones(t.size, dtype=bool)
    for start, length in p.gaps:
        valid &= ~((t >= start) & (t < start + length))
    for j in range(p.n_dofs):
        Y[~valid, j] = np.interp(t[~valid], t[valid], Y[valid, j])
    return Demonstration(t=t, Y=Y, valid=valid, clean=clean, phase=phase,
                         frequency_hz=frequency_hz, base_hz=base_hz)
