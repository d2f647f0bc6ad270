"""Harmonic analysis of a whole recording: fundamental frequency, phase, and periodicity.

Used offline (the frequency refined over the whole recording by least squares), by the
learn stage to refuse input that is not periodic, and by the online learner to start its
canonical system from the last two periods once their period is known
(:func:`locked_series`). All DOFs share one fundamental; they are pooled in physical units
(the online learner's normalised units for :func:`locked_series`), so a DOF that barely
moves weighs little.

Model: y_j(t) = c_0j + sum_{k=1}^{K} a_kj cos(k w t) + b_kj sin(k w t), w = 2 pi f.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit
from numba.extending import register_jitable

from wipelab.linalg import solve_positive_definite
from wipelab.numba_cache import forget_stale_kernels

#: Most harmonics a fit uses (fewer when they would pass Nyquist).
MAX_HARMONICS = 8


@dataclass(frozen=True)
class HarmonicFit:
    """A least-squares harmonic fit at one frequency.

    Attributes
    ----------
    frequency_hz : float
    coefficients : ndarray, shape (2K + 1, d)
        Rows: c_0, a_1, b_1, a_2, b_2, ...
    explained : float
        Fraction of the variance (about each DOF's mean, pooled) the fit explains, in [0, 1].
    """

    frequency_hz: float
    coefficients: np.ndarray
    explained: float

    @property
    def offset(self) -> np.ndarray:
        """c_0 per DOF, shape (d,)."""
        return self.coefficients[0]

    @property
    def fundamental(self) -> np.ndarray:
        """Amplitude of the fundamental per DOF, shape (d,)."""
        return np.hypot(self.coefficients[1], self.coefficients[2])

    @property
    def amplitude(self) -> np.ndarray:
        """sqrt(2) x RMS of the periodic part per DOF (= A for a sinusoid), shape (d,)."""
        return np.sqrt((self.coefficients[1:] ** 2).sum(axis=0))


def harmonic_count(frequency_hz: float, dt: float) -> int:
    """Harmonics below Nyquist, at most MAX_HARMONICS, at least 1."""
    return int(max(1, min(MAX_HARMONICS, math.ceil(0.5 / (dt * frequency_hz)) - 1)))


def _design(t: np.ndarray, frequency_hz: float, n_harmonics: int) -> np.ndarray:
    angles = 2.0 * math.pi * frequency_hz * np.outer(t, np.arange(1, n_harmonics + 1))
    columns = np.empty((t.size, 2 * n_harmonics + 1))
    columns[:, 0] = 1.0
    columns[:, 1::2] = np.cos(angles)
    columns[:, 2::2] = np.sin(angles)
    return columns


def harmonic_fit(t: np.ndarray, Y: np.ndarray, frequency_hz: float,
                 n_harmonics: int | None = None) -> HarmonicFit:
    """Least-squares fit of the harmonic model at a given frequency.

    Parameters
    ----------
    t : ndarray, shape (n,)
        Times (s).
    Y : ndarray, shape (n, d)
    frequency_hz : float
    n_harmonics : int, optional
        K (default: :func:`harmonic_count` for the median sample interval).
    """
    if n_harmonics is None:
        n_harmonics = harmonic_count(frequency_hz, float(np.median(np.diff(t))))
    design = _design(t, frequency_hz, n_harmonics)
    gram = design.T @ design
    coefficients = np.linalg.lstsq(gram, design.T @ Y, rcond=None)[0]
    residual = Y - design @ coefficients
    total = float(((Y - Y.mean(axis=0)) ** 2).sum())
    explained = 1.0 - float((residual ** 2).sum()) / total if total > 0.0 else 0.0
    return HarmonicFit(float(frequency_hz), coefficients, min(max(explained, 0.0), 1.0))


def estimate_fundamental_hz(t: np.ndarray, Y: np.ndarray, min_hz: float, max_hz: float,
                            valid: np.ndarray | None = None) -> float:
    """Coarse fundamental from the pooled spectrum by harmonic summation.

    Score(f) = P(f) + P(2f) / 2 + P(3f) / 3 over a zero-padded, Hann-windowed periodogram:
    weighting the harmonics keeps the score of f above those of f/2 and 2f. With gaps
    (``valid`` false somewhere), the Lomb-Scargle periodogram of the observed samples on the
    same grid instead: bridged by straight lines, a 1.5 s gap in 8 s of wiping put the
    periodogram's peak at a half or a quarter of the frequency.
    """
    dt = float(np.median(np.diff(t)))
    if valid is not None and not np.all(valid):
        return _lomb_scargle_fundamental_hz(t[valid], Y[valid], min_hz, max_hz, dt)
    centred = (Y - Y.mean(axis=0)) * np.hanning(t.size)[:, None]
    n_fft = int(2 ** math.ceil(math.log2(8 * t.size)))
    power = (np.abs(np.fft.rfft(centred, n=n_fft, axis=0)) ** 2).sum(axis=1)
    frequencies = np.fft.rfftfreq(n_fft, dt)
    candidates = frequencies[(frequencies >= min_hz) & (frequencies <= max_hz)]
    if candidates.size == 0:
        raise ValueError(f"no frequency between {min_hz} and {max_hz} Hz is resolvable")
    nyquist = frequencies[-1]
    score = np.zeros(candidates.size)
    for k in (1, 2, 3):
        inside = k * candidates <= nyquist
        score[inside] += np.interp(k * candidates[inside], frequencies, power) / k
    return float(candidates[int(np.argmax(score))])


def _lomb_scargle_fundamental_hz(t: np.ndarray, Y: np.ndarray, min_hz: float, max_hz: float,
                                 dt: float) -> float:
    """:func:`estimate_fundamental_hz` for unevenly sampled data (the Lomb-Scargle periodogram)."""
    from scipy.signal import lombscargle  # imported here: scipy.signal costs 0.5 s at start-up

    step = 1.0 / (8.0 * float(t[-1] - t[0]))
    candidates = np.arange(min_hz, max_hz + 0.5 * step, step)
    if candidates.size == 0:
        raise ValueError(f"no frequency between {min_hz} and {max_hz} Hz is resolvable")
    centred = Y - Y.mean(axis=0)
    score = np.zeros(candidates.size)
    for k in (1, 2, 3):
        inside = k * candidates < 0.5 / dt
        angular = 2.0 * np.pi * k * candidates[inside]
        score[inside] += sum(lombscargle(t, column, angular) for column in centred.T) / k
    return float(candidates[int(np.argmax(score))])


def refine_frequency_hz(t: np.ndarray, Y: np.ndarray, initial_hz: float, half_width_hz: float,
                        n_harmonics: int | None = None) -> float:
    """The frequency in initial_hz +- half_width_hz that minimises the harmonic fit's residual."""
    from scipy.optimize import minimize_scalar  # imported here: 0.5 s at start-up

    result = minimize_scalar(lambda f: 1.0 - harmonic_fit(t, Y, f, n_harmonics).explained,
                             bounds=(max(initial_hz - half_width_hz, 1e-6), initial_hz + half_width_hz),
                             method="bounded", options={"xatol": 1e-7 * initial_hz})
    return float(result.x)


def _stride(n_samples: int, max_samples: int) -> int:
    """Keep every stride-th sample so that at most max_samples remain (searches only)."""
    return max(1, -(-n_samples // max_samples))


#: Fewest periods of a sub-multiple f/2, f/3 a recording must hold for it to be tried.
SUBMULTIPLE_MIN_PERIODS = 3.0
#: A sub-multiple f/d wins when it explains at least this share of the variance that f leaves
#: unexplained: all of it for a figure eight, little for a person's wandering tempo and drift.
SUBMULTIPLE_SHARE = 0.5


def fundamental_frequency_hz(t: np.ndarray, Y: np.ndarray, min_hz: float, max_hz: float,
                             max_search_samples: int = 4000,
                             valid: np.ndarray | None = None) -> HarmonicFit:
    """Fundamental of the whole recording, refined by least squares; returns the fit there.

    The search runs on at most ``max_search_samples`` evenly strided samples (the frequency's
    precision comes from the duration, not the rate); the returned fit uses every sample.
    After refining the spectral estimate f, the sub-multiples f/2 and f/3 are tried: if one
    explains most of what f leaves unexplained (:data:`SUBMULTIPLE_SHARE`), the DOFs share a
    longer period (e.g. a figure eight, where one DOF moves at twice the frequency of the
    other). A tempo that wanders by several per cent leaves a fifth of the variance around f
    unexplained, of which the extra harmonics of f/3 fit a little (14 s of circles at 0.67 Hz
    came out at 0.22 Hz when any 2 % more won). Only
    sub-multiples the recording holds at least :data:`SUBMULTIPLE_MIN_PERIODS` periods of are
    tried: over a period and a half, the extra harmonics of f/3 fit a person's drift and
    wander well enough to pass (8 s of line strokes at 0.6 Hz came out at 0.199 Hz).

    With ``valid`` (bool, shape (n,): the samples observed), the spectral estimate uses the
    whole uniform recording, gaps bridged, and every least-squares fit the observed samples
    only: fitted as data, a 1.5 s straight-line bridge made f/2 or f/3 explain more.
    """
    stride = _stride(t.size, max_search_samples)
    ts, Ys = t[::stride], Y[::stride]
    n_harmonics = harmonic_count(max_hz, float(np.median(np.diff(ts))))
    resolution = 1.0 / float(t[-1] - t[0])
    observed = np.ones(t.size, dtype=bool) if valid is None else np.asarray(valid, dtype=bool)
    coarse = estimate_fundamental_hz(ts, Ys, min_hz, max_hz, observed[::stride])
    ts, Ys = ts[observed[::stride]], Ys[observed[::stride]]
    t, Y = t[observed], Y[observed]
    best_hz = refine_frequency_hz(ts, Ys, coarse, resolution, n_harmonics)
    best = harmonic_fit(ts, Ys, best_hz, n_harmonics).explained
    for divisor in (2, 3):
        if best_hz / divisor < min_hz or \
                best_hz / divisor * float(t[-1] - t[0]) < SUBMULTIPLE_MIN_PERIODS:
            continue
        candidate_hz = refine_frequency_hz(ts, Ys, best_hz / divisor, resolution / divisor,
                                           n_harmonics)
        candidate = harmonic_fit(ts, Ys, candidate_hz, n_harmonics).explained
        if candidate - best > SUBMULTIPLE_SHARE * (1.0 - best):
            best_hz, best = candidate_hz, candidate
    return harmonic_fit(t, Y, best_hz)


@dataclass(frozen=True)
class PeriodicityEstimate:
    """Is the recording periodic?

    Attributes
    ----------
    score : float
        Upper quartile over windows of several periods of the variance fraction that a
        harmonic fit (each window at its own best frequency) explains: ~1 for a periodic
        movement, also when its frequency changes now and then (only the windows across a
        change score low) or slowly; below 0.7 for noise, random drifts, a DOF held still.
    frequency_hz : float
        Fundamental of the whole recording.
    periods : float
        Number of fundamental periods in the recording.
    """

    score: float
    frequency_hz: float
    periods: float


def periodicity(t: np.ndarray, Y: np.ndarray, min_hz: float, max_hz: float,
                window_periods: float = 2.0, window_samples: int = 90,
                n_harmonics: int = 3, valid: np.ndarray | None = None) -> PeriodicityEstimate:
    """Estimate whether a recording is periodic, window by window (tolerates frequency changes).

    Parameters
    ----------
    t : ndarray, shape (n,)
        Uniform times (s).
    Y : ndarray, shape (n, d)
    min_hz, max_hz : float
        Range of fundamentals to consider (Hz); the lower bound is raised to 1.5 / duration
        (a period must be seen more than once; callers judge ``periods``).
    window_periods, window_samples : float, int
        A window spans at least this many fundamental periods and samples; windows overlap by half.
    n_harmonics : int
        Harmonics per window fit (few, so that noise explains little by chance).
    valid : ndarray of bool, shape (n,), optional
        Samples that were observed: the windows fit those only (a gap's bridge would score as
        a movement that is not periodic); a window less than half observed is skipped.
    """
    duration = float(t[-1] - t[0])
    min_hz = min(max(min_hz, 1.5 / duration), max_hz)
    whole = fundamental_frequency_hz(t, Y, min_hz, max_hz, valid=valid)
    f = whole.frequency_hz
    stride = _stride(t.size, int(window_samples * duration * f / window_periods))
    valid = np.ones(t.size, dtype=bool) if valid is None else np.asarray(valid, dtype=bool)
    t, Y, valid = t[::stride], Y[::stride], valid[::stride]
    dt = float(np.median(np.diff(t)))
    window = min(float(t[-1] - t[0]), max(window_periods / f, window_samples * dt))
    n_harmonics = min(n_harmonics, harmonic_count(f * 1.6, dt))
    grid = f * np.linspace(0.6, 1.6, 41)
    scores = []
    for start in np.arange(t[0], t[-1] - window + 1e-9, window / 2.0):
        inside = (t >= start) & (t <= start + window)
        if 2 * np.count_nonzero(inside & valid) < np.count_nonzero(inside):
            continue
        inside &= valid
        tw, Yw = t[inside] - start, Y[inside]
        explained = [harmonic_fit(tw, Yw, g, n_harmonics).explained for g in grid]
        best = grid[int(np.argmax(explained))]
        refined = refine_frequency_hz(tw, Yw, best, f * 0.025, n_harmonics)
        scores.append(harmonic_fit(tw, Yw, refined, n_harmonics).explained)
    return PeriodicityEstimate(score=float(np.percentile(scores, 75)) if scores else 0.0,
                               frequency_hz=f,
                               periods=duration * f)


#: :func:`locked_series` fits the harmonics below this fraction of the Nyquist frequency of
#: the samples (well determined by two periods); the canonical system learns the others.
LOCK_NYQUIST_FRACTION = 0.75
#: Ridge on the normal equations of :func:`locked_series`, relative to the row count (a guard).
LOCK_RIDGE = 1e-9
#: Golden-section steps of the frequency search in :func:`locked_series`: the bracket
#: shrinks to 0.618^12 ~ 3e-3 of its width (6e-5 of the frequency for +- 1 %).
LOCK_SEARCH_STEPS = 12
#: The search fits at most this many samples (evenly strided, ending at the last one): the
#: frequency's precision comes from the span, not the rate.
LOCK_SEARCH_SAMPLES = 256


@register_jitable
def _recent_fit(U: np.ndarray, dt: float, omega: float, terms: int):
    """Least-squares harmonic fit of samples U (n, d), the last at t = 0 (see locked_series).

    Returns (coefficients (2 terms + 1, d): c_0, a_1, b_1, ..., residual sum of squares).
    """
    n, d = U.shape
    columns = 2 * terms + 1
    design = np.empty((n, columns))
    for k in range(n):
        angle = omega * dt * (k - n + 1)
        cos_1, sin_1 = math.cos(angle), math.sin(angle)
        cos_c, sin_c = 1.0, 0.0
        design[k, 0] = 1.0
        for c in range(1, terms + 1):                   # cos(c x), sin(c x) by angle addition
            cos_c, sin_c = cos_c * cos_1 - sin_c * sin_1, sin_c * cos_1 + cos_c * sin_1
            design[k, 2 * c - 1] = cos_c
            design[k, 2 * c] = sin_c
    gram = design.T @ design + LOCK_RIDGE * n * np.eye(columns)
    projection = design.T @ U
    coefficients = solve_positive_definite(gram, projection)
    return coefficients, (U * U).sum() - (coefficients * projection).sum()




@njit(cache=True)
def locked_series(U: np.ndarray, dt: float, omega: float, n_terms: int, reference: int,
                  search: float = 0.0) -> tuple[float, float, np.ndarray, np.ndarray]:
    """Frequency, phase and Fourier series of recent input, in a canonical system's phase.

    Least squares of u_j(t) = sum_{c=0}^{K} a_cj cos(c w t) + b_cj sin(c w t) over the samples
    (t <= 0, the last sample at t = 0), at the w in omega (1 +- search) that leaves the
    smallest residual (golden section, on at most LOCK_SEARCH_SAMPLES evenly strided
    samples), rewritten in the phase phi = w t - theta that makes the reference DOF's
    fundamental a cosine (beta_1 = 0 for it, the convention of the AFS and the AFO pool).
    Compiled: the online learner's hand-over calls it.

    Parameters
    ----------
    U : ndarray, shape (n, d)
        Normalised input, one sample every dt, at least one period; oldest first.
    dt : float
        Sample interval (s).
    omega : float
        Frequency (rad/s), the centre of the search.
    n_terms : int
        K, highest harmonic. Only terms with c omega dt <= LOCK_NYQUIST_FRACTION pi are
        fitted; the others are 0.
    reference : int
        The DOF whose fundamental defines phase 0.
    search : float
        Relative half-width of the frequency search (0: take omega as it is).

    Returns
    -------
    omega : float
        The fitted frequency (rad/s).
    phase : float
        phi at the last sample (rad, in (-pi, pi]).
    alpha, beta : ndarray, shape (d, K + 1)
        Cosine and sine coefficients of c phi per DOF (beta[:, 0] = 0).
    """
    n, d = U.shape
    terms = min(n_terms, int(LOCK_NYQUIST_FRACTION * math.pi / (omega * dt)))
    if search > 0.0:
        stride = max(1, -(-n // LOCK_SEARCH_SAMPLES))
        strided = np.ascontiguousarray(U[(n - 1) % stride::stride])
        search_terms = min(terms, int(LOCK_NYQUIST_FRACTION * math.pi / (omega * dt * stride)))
        golden = 0.5 * (math.sqrt(5.0) - 1.0)
        low, high = omega * (1.0 - search), omega * (1.0 + search)
        left, right = high - golden * (high - low), low + golden * (high - low)
        left_residual = _recent_fit(strided, dt * stride, left, search_terms)[1]
        right_residual = _recent_fit(strided, dt * stride, right, search_terms)[1]
        for _ in range(LOCK_SEARCH_STEPS):
            if left_residual <= right_residual:
                high, right, right_residual = right, left, left_residual
                left = high - golden * (high - low)
                left_residual = _recent_fit(strided, dt * stride, left, search_terms)[1]
            else:
                low, left, left_residual = left, right, right_residual
                right = low + golden * (high - low)
                right_residual = _recent_fit(strided, dt * stride, right, search_terms)[1]
        omega = 0.5 * (low + high)
    coefficients = _recent_fit(np.ascontiguousarray(U), dt, omega, terms)[0]     # (2K + 1, d)
    theta = math.atan2(coefficients[2, reference], coefficients[1, reference])
    alpha = np.zeros((d, n_terms + 1))
    beta = np.zeros((d, n_terms + 1))
    for j in range(d):
        alpha[j, 0] = coefficients[0, j]
        for c in range(1, terms + 1):
            a, b = coefficients[2 * c - 1, j], coefficients[2 * c, j]
            alpha[j, c] = a * math.cos(c * theta) + b * math.sin(c * theta)
            beta[j, c] = b * math.cos(c * theta) - a * math.sin(c * theta)
    beta[reference, 1] = 0.0
    return omega, -theta, alpha, beta


forget_stale_kernels(__name__)
