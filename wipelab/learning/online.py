"""The two-layer online learner (Fig. 1): canonical system -> phase and Omega -> periodic DMP.

Per sample, as a robot watching the demonstration would:

1. feed the period detector (:mod:`~wipelab.learning.period_detector`); at the sample where
   it first holds a period, hand it over: the canonical system starts locked, with the
   frequency, phase and series of a least-squares fit of the last two periods near 2 pi / T
   (:func:`~wipelab.learning.harmonic.locked_series`, the systems' ``lock``). Afterwards the
   detector supervises: when the period it holds and the fundamental differ by more than
   ``relock_tolerance`` (30 %: a subharmonic, a lost lock), hand over again;
2. update the anchor g and amplitude r (mean and sqrt(2) RMS of each DOF over the last
   period of the current Omega), normalise the input -- (y - g) / r once locked, the
   running range before -- and advance the canonical system over the sample interval (AFS,
   or the AFO pool with its logic step) -> phase phi;
3. the fundamental Omega: the oscillator's frequency averaged over the last period (free
   of the ripple the coupling term puts on it), restarted at the hand-over;
4. estimate position, velocity and acceleration by a centred polynomial fit over the last
   samples and learn the weights with the incremental LWR of eqs. 13-15 from f_targ (text
   after eq. 12), at points between samples (:func:`update_points`);
5. integrate the DMP (eqs. 6-7) with the current weights: the imitated movement (Fig. 5).

Gaps. A sample marked invalid (the tracker lost the sponge) teaches nothing: the canonical
system runs on at its frequency without coupling or learning, the detector restarts, and no
regression update uses a derivative window that holds the gap; the DMP keeps moving. Fed
the tracker's straight-line bridge as data instead, the fundamental swung 49 % off after a
1.5-period gap (10 % gap-aware) and the waveform error grew from 1.4 to 1.7 % of
peak-to-peak (test_online.py); over the
benchmark's 27 human-like demonstrations, 5 model frequencies ended more than 1 % off
(worst 1.4 %), none gap-aware.

The model's frequency is the canonical phase's mean rate over the last 40 periods since the
last hand-over (:func:`model_frequency_hz`): a person's tempo wanders by several percent from
stroke to stroke, the fundamental follows it, and its value at the end of a demonstration is
only the tempo of the last strokes (up to 8 % off on the benchmark's human-like
demonstrations). Over 27 of those (60 s with two 1.5 s gaps) the model frequency is within
0.72 % of the nominal (median 0.22 %; the fundamental of the last period: 9 of 27 within 1 %,
worst 9.7 %); the price is that after a deliberate change of tempo the
model frequency mixes the two until 40 periods have passed (the history's fundamental follows
within about three).

:class:`OnlineLearner` is the reference implementation, composed of the numpy classes of this
package; :func:`learn_online` runs the same algorithm through a numba kernel
(:mod:`wipelab.learning._online_kernel`) unless asked for the reference.

All numbers below are from ``benchmarks/bench_learn.py`` (two DOFs with 2nd and 3rd
harmonics and 2 % noise; 0.3, 0.5, 1, 2, 3 Hz at 30 and 500 Hz; worst of two noise seeds)
unless stated otherwise.

Default canonical system: the AFS. With the start-up detector both systems stay within 1 %
of the fundamental from the hand-over on, after 1.95-2.30 periods (AFS) and 2.11-2.30
(pool): the start does not decide. After a frequency step both re-converge in about three
periods (AFS 2.91-3.31, pool 2.56-2.87). The AFS is better elsewhere: its rollout after 10 periods is within
0.92-1.01 % of peak-to-peak at 500 Hz (pool 1.2-1.3 %); if no period is detected (the
oscillators alone) it still locks in 3.9-8.7 periods (pool 3.5-11.7); and it needs neither
the offset trick (the pool's eq. 4 has no constant term) nor the logic step. With the
published constant gains (K = K_Omega = 20) and no detector, neither settles at most of these
frequencies (see :mod:`wipelab.learning.oscillators`).

Departures from the paper, each measured there:

* the start-up detector and the hand-over (step 1): the oscillators alone take 3.9-8.7
  periods (median 5.2) to stay within 1 %, and about 3.5 even when started at the right
  frequency, because phase and series start from nothing. The hand-over refines the
  detector's frequency by the fit (+- 1 %) and advances the phase by one oscillator substep
  (an Euler substep compares the input at its end with the series at its start, so a
  settled oscillator leads by one substep); without that lead a freshly locked AFS at 3 Hz
  sampled at 30 Hz swung up to 1 % off, with it the fundamental stays within 0.5 % of the
  truth after the hand-over (AFS; pool 0.6 %; 30 noise seeds x 5 cases);
* after the hand-over the input is normalised by the period statistics instead of the
  running range: the range's relaxation (tau = 10 s) modulates the input's scale within
  each period and kicked a freshly locked oscillator off by up to 4 %;
* the detector keeps running as a supervisor and re-locks (step 1): a safety net for a lost
  lock or a subharmonic. On the 27 human-like demonstrations of the benchmark it re-locked
  once (worst model frequency 0.72 %, 0.47 % without the supervisor); with the gain schedule
  of :mod:`wipelab.learning.oscillators` (kappa = 100, off by default) it kept 23 of 27
  within 1 %, against 16 without it (worst 88 %);
* the recursion of eqs. 13-15 regresses f_targ / r on 1 instead of f_targ on r: the same fit,
  but the prior P0 = 1 then weighs the same whatever the unit of r (with r in metres it
  outweighed ten periods of data at 30 Hz and halved the learned waveform);
* lambda counts per 1/100 of a period rather than per sample (:func:`forgetting_factor`);
* the regression is updated between samples, at most half a kernel spacing apart in phase,
  from the same local polynomial (:func:`update_points`): at 3 Hz sampled at 30 Hz (ten
  phases per period for 25 kernels) the rollout error after 10 periods drops from 3.7 % to
  2.0 % of peak-to-peak, at 2 Hz from 2.4 % to 2.0 %; at 500 Hz one update per sample
  already suffices.

With them the rollout after 10 periods is within 1.0 % of the noise-free waveform's
peak-to-peak at 0.3-3 Hz and 500 Hz, and within 2.1 % at 30 Hz.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from wipelab.learning.afo import AdaptiveOscillatorPool, AFOParameters
from wipelab.learning.afs import AdaptiveFourierSeries, AFSParameters
from wipelab.learning.derivatives import CentredDerivatives
from wipelab.learning.dmp import PeriodicDMP, forcing_target
from wipelab.learning.harmonic import locked_series
from wipelab.learning.kernels import default_width, kernel_activations
from wipelab.learning.lwr import IncrementalLWR
from wipelab.learning.model import PeriodicModel
from wipelab.learning.normalise import PeriodStatistics, RecentSamples, RunningNormaliser
from wipelab.learning.oscillators import substep_count
from wipelab.learning.period_detector import PeriodDetector, PeriodDetectorParameters

CANONICAL_SYSTEMS = ("afs", "afo")


@dataclass(frozen=True)
class OnlineParameters:
    """Settings of the online learner (learned state lives in the learner)."""

    canonical: str = "afs"                  # "afs" (adaptive Fourier series) or "afo" (pool, eqs. 1-5)
    kernels: int = 25                       # N
    width: float | None = None              # h of eq. 8; None -> 2.5 N
    alpha_s: float = 12.0                   # eq. 6
    beta_s: float = 3.0                     # eq. 6
    forgetting: float = 0.99                # lambda of eq. 14
    forgetting_samples_per_period: float | None = 100.0  # lambda counts per 1/this of a period
    p0: float = 1.0                         # P_i(0) of eq. 14
    update_spacing: float | None = 0.5      # LWR updates <= this x 2 pi / N apart (phase); None: 1/sample
    dof_coupling: str = "mean"              # "mean": every moving DOF drives the phase; "reference": one
    substep_hz: float = 500.0               # oscillators integrate at >= this rate (Hz)
    normaliser_time_constant_s: float = 10.0  # tau of the running range used until the lock (s)
    derivative_window_periods: float = 0.125  # polynomial window as a fraction of the period
    derivative_degree: int = 4              # polynomial degree of the derivative fit
    max_derivative_window: int = 101        # samples, odd
    min_frequency_hz: float = 0.1           # longest period the anchor window and detector cover (Hz)
    statistics_periods: int = 1             # periods over which Omega, g and r are averaged
    start_up: bool = True                   # detect the period and hand it to the canonical system
    detector: PeriodDetectorParameters = field(default_factory=PeriodDetectorParameters)
    lock_search: float = 0.01               # the hand-over refines Omega within +- this (relative)
    relock_tolerance: float | None = 0.3    # hand over again when the detector's held period and the
                                            # fundamental differ by more (relative); None: once only
    frequency_periods: float = 40.0         # the model's frequency: mean phase rate over this many periods
    weights_every_s: float = 0.05           # interval of the weight snapshots in the history (s)
    afs: AFSParameters = field(default_factory=AFSParameters)
    afo: AFOParameters = field(default_factory=AFOParameters)

    def __post_init__(self):
        if self.canonical not in CANONICAL_SYSTEMS:
            raise ValueError(f"canonical must be one of {CANONICAL_SYSTEMS}, got {self.canonical!r}")
        if self.kernels < 2:
            raise ValueError(f"kernels must be >= 2, got {self.kernels}")
        if self.max_derivative_window < 5 or self.max_derivative_window % 2 == 0:
            raise ValueError("max_derivative_window must be odd and >= 5")
        if self.update_spacing is not None and not self.update_spacing > 0.0:
            raise ValueError(f"update_spacing must be > 0 or None, got {self.update_spacing}")
        if self.relock_tolerance is not None and not self.relock_tolerance > 0.0:
            raise ValueError(f"relock_tolerance must be > 0 or None, got {self.relock_tolerance}")
        if not self.frequency_periods > 0.0:
            raise ValueError(f"frequency_periods must be > 0, got {self.frequency_periods}")

    @property
    def kernel_width(self) -> float:
        """h actually used."""
        return default_width(self.kernels) if self.width is None else float(self.width)


@dataclass(frozen=True)
class LearnHistory:
    """What a learning run went through, for logs and figures.

    Attributes
    ----------
    t : ndarray, shape (n,)
        Sample times (s).
    input : ndarray, shape (n, d)
        The demonstration (m).
    output : ndarray, shape (n, d)
        The learned movement at the same times (online: the DMP integrated while learning,
        Fig. 5; offline: the model's rollout).
    phase : ndarray, shape (n,)
        Canonical phase (rad, unwrapped).
    fundamental_hz : ndarray, shape (n,)
        Selected fundamental Omega / 2 pi (Hz).
    oscillators_hz : ndarray, shape (n, M)
        Every oscillator's frequency (Hz): M = 3 for the AFO pool (Fig. 4), 1 for the AFS.
    weights_t : ndarray, shape (k,)
        Times of the weight snapshots (s).
    weights : ndarray, shape (k, d, N)
        The weights as they converge.
    valid : ndarray of bool, shape (n,)
        Samples that were observed (False: a gap the learner ran through without input).
    hand_overs : ndarray of int, shape (n,)
        Hand-overs of a detected period to the canonical system so far (online; the first is
        the start-up, later ones re-locks).
    """

    t: np.ndarray
    input: np.ndarray
    output: np.ndarray
    phase: np.ndarray
    fundamental_hz: np.ndarray
    oscillators_hz: np.ndarray
    weights_t: np.ndarray
    weights: np.ndarray
    valid: np.ndarray
    hand_overs: np.ndarray


def _wrap(angle: float) -> float:
    return float(np.mod(angle, 2.0 * math.pi))


class OnlineLearner:
    """Reference implementation of the online two-layer learner for d DOFs sampled every dt.

    Parameters
    ----------
    n_dofs : int
    dt : float
        Sample interval (s); samples are assumed uniform.
    params : OnlineParameters
    reference_dof : int
        The DOF whose fundamental defines phase 0 (a cosine peak).

    Attributes
    ----------
    locked_ : bool
        Whether the detected period has been handed to the canonical system.
    hand_overs_ : int
        How often it has been (the start-up, then re-locks).
    omega_ : float
        The fundamental Omega (rad/s): the oscillator's frequency averaged over the last period.
    goal_, amplitude_ : ndarray, shape (d,)
        g and r over the last period (m).
    """

    def __init__(self, n_dofs: int, dt: float, params: OnlineParameters = OnlineParameters(),
                 reference_dof: int = 0):
        self.params = params
        self.dt = dt
        self.n_sub = substep_count(dt, params.substep_hz)
        width = params.kernel_width
        if params.canonical == "afs":
            self.canonical = AdaptiveFourierSeries(n_dofs, params.afs, reference_dof, params.dof_coupling)
            offset = 0.0
        else:
            self.canonical = AdaptiveOscillatorPool(n_dofs, params.afo, reference_dof, params.dof_coupling)
            offset = 1.0
        self.offset = offset
        self.reference_dof = reference_dof
        self.normaliser = RunningNormaliser(n_dofs, dt, params.normaliser_time_constant_s, offset)
        self.detector = PeriodDetector(n_dofs, dt, params.detector, params.min_frequency_hz,
                                       self.canonical.params.max_frequency_hz) \
            if params.start_up else None
        self.recent = RecentSamples(n_dofs, recent_capacity(dt, params)) if params.start_up else None
        self.locked_ = False
        capacity = anchor_capacity(dt, params)
        self.statistics = PeriodStatistics(n_dofs, dt, capacity, params.statistics_periods)
        # The fundamental is the oscillator's Omega averaged over the last period: free of
        # the ripple the coupling term puts on the instantaneous value.
        self.frequency_statistics = PeriodStatistics(1, dt, capacity, params.statistics_periods)
        self.derivatives = CentredDerivatives(n_dofs, dt, params.derivative_window_periods,
                                              params.derivative_degree, params.max_derivative_window)
        self.lwr = IncrementalLWR(params.kernels, n_dofs, params.forgetting, params.p0)
        self.dmp = PeriodicDMP(self.lwr.weights_, np.zeros(n_dofs), np.ones(n_dofs), width,
                               params.alpha_s, params.beta_s)
        self.goal_ = np.zeros(n_dofs)
        self.amplitude_ = np.ones(n_dofs)
        self._moving = np.zeros(n_dofs, dtype=bool)
        self.count_ = 0
        self.hand_overs_ = 0
        self._valid_run = 0
        self._previous_input = np.zeros(n_dofs)
        self._previous_phase = 0.0
        self._previous_omega = 0.0
        self.omega_ = 0.0

    def _normalised(self, y: np.ndarray) -> np.ndarray:
        """u = (y - g) / r + offset over the last period once locked (0 for a still DOF)."""
        return np.where(self._moving, (y - self.goal_) / self.amplitude_, 0.0) + self.offset

    def _update_statistics(self, y: np.ndarray, omega: float) -> None:
        self.goal_, amplitude = self.statistics.update(y, omega)
        self._moving = amplitude > 0.0
        self.amplitude_ = np.where(self._moving, amplitude, 1.0)

    def _lock(self, y: np.ndarray) -> np.ndarray:
        """Hand the detected period to the canonical system with the series of the recent input."""
        p = self.params
        omega = 2.0 * math.pi / self.detector.period_s_
        self._update_statistics(y, omega)
        count = min(self.recent.count_, int(round((1.0 + p.detector.confirm)
                                                   * self.detector.period_s_ / self.dt)))
        window = self._normalised(self.recent.last(count))
        n_terms = p.afs.n_terms if p.canonical == "afs" else 3
        omega, phase, alpha, beta = locked_series(window, self.dt, omega, n_terms,
                                                  self.reference_dof, p.lock_search)
        # An Euler substep compares the input at its end with the series at its start phase, so
        # a settled oscillator leads the input's phase by one substep.
        self.canonical.lock(omega, phase + omega * self.dt / self.n_sub, alpha, beta, self.dt)
        self.frequency_statistics.restart()
        self.locked_ = True
        self.hand_overs_ += 1
        return window[-1]

    def _needs_hand_over(self) -> bool:
        """Whether the period the detector holds should be handed to the canonical system: at
        the start-up, and when the fundamental has strayed from it (a subharmonic, a lost lock)."""
        if not self.locked_:
            return True
        tolerance = self.params.relock_tolerance
        return tolerance is not None and \
            abs(self.omega_ * self.detector.period_s_ / (2.0 * math.pi) - 1.0) > tolerance

    def _observe(self, y: np.ndarray) -> None:
        """Steps 1-2 for an observed sample: detector and hand-over, or the canonical system."""
        if self.detector is not None:
            self.recent.push(y)
            detected = self.detector.update(y)
            if detected and self._needs_hand_over():
                self._previous_input = self._lock(y)
                return
        self._update_statistics(y, self.canonical.fundamental[1])
        u = self._normalised(y) if self.locked_ else self.normaliser.update(y)
        if self._valid_run == 1:                      # the first sample, or the first after a gap
            self._previous_input = u
        self.canonical.advance(self._previous_input, u, self.dt, self.n_sub)
        self._previous_input = u

    def _skip(self) -> None:
        """Steps 1-2 for a gap: the canonical system runs on at its frequency, learning nothing;
        the detector restarts (its lags need contiguous samples)."""
        if self.detector is not None and self._valid_run > 0:
            self.detector.restart()
            self.recent.restart()
        self.canonical.free_run(self.dt)

    def step(self, y: np.ndarray, valid: bool = True) -> np.ndarray:
        """Process one sample y (d,) in m; return the DMP output (d,) at the same time.

        An invalid sample (``valid`` False: the input was not observed, y is only a
        placeholder) teaches nothing: the canonical system runs on at its frequency, and no
        regression update uses a window that holds it.
        """
        p = self.params
        y = np.asarray(y, dtype=np.float64)
        if self.count_ == 0:
            self.dmp.reset(y, np.zeros_like(y))
        if valid:
            self._valid_run += 1
            self._observe(y)
        else:
            self._skip()
            self._valid_run = 0
        phase, omega_now = self.canonical.fundamental
        mean_omega, _ = self.frequency_statistics.update(np.array([omega_now]), omega_now)
        omega = self.omega_ = max(float(mean_omega[0]), 2.0 * math.pi * p.min_frequency_hz)
        self.derivatives.push(y, phase, omega, valid)
        points = update_points(p, omega * self.dt)
        estimates = self.derivatives.between(omega, points)
        if estimates is not None:
            y_x, yd_x, ydd_x, phases_x, omega_c = estimates
            forgetting = forgetting_factor(p, omega_c * self.dt / points)
            for yc, ydc, yddc, phase_c in zip(y_x, yd_x, ydd_x, phases_x):
                f_target = forcing_target(yc, ydc, yddc, omega_c, self.goal_, p.alpha_s, p.beta_s)
                psi = kernel_activations(phase_c, p.kernels, p.kernel_width)
                # f_targ ~ w r, regressed in units of r: the prior P0 = 1 then weighs the same
                # for any scale of the movement (with r in metres it would outweigh seconds of data).
                self.lwr.update(psi, np.ones_like(self.amplitude_), f_target / self.amplitude_,
                                forgetting)
        self.dmp.goal, self.dmp.amplitude = self.goal_, self.amplitude_
        if self.count_ > 0:
            self.dmp.step(self._previous_phase, self._previous_omega, self.dt)
        self._previous_phase, self._previous_omega = phase, omega
        self.count_ += 1
        return self.dmp.y_.copy()

    @property
    def weights_(self) -> np.ndarray:
        """Current weights, shape (d, N)."""
        return self.lwr.weights_


def forgetting_factor(params: OnlineParameters, phase_step: float) -> float:
    """lambda for one sample that advances the phase by ``phase_step`` (rad).

    Eq. 14 forgets per sample, so its memory in periods shrinks with the sample rate: at
    500 Hz and 0.3 Hz, lambda = 0.99 remembers 0.06 periods, shorter than a kernel's pass,
    and each weight is biased towards the latest samples (a phase lag). Counted per
    1/``forgetting_samples_per_period`` of a period instead, the paper's lambda keeps the
    memory it has at 100 samples per period at every rate and frequency.
    """
    if params.forgetting_samples_per_period is None:
        return params.forgetting
    return params.forgetting ** (phase_step * params.forgetting_samples_per_period / (2.0 * math.pi))


def update_points(params: OnlineParameters, phase_step: float) -> int:
    """Regression updates per sample that advances the phase by ``phase_step`` (rad).

    One per sample as printed, or enough that consecutive update phases are at most
    ``update_spacing`` kernel spacings (2 pi / N) apart: the learner knows the phase between
    samples, and the local polynomial of :class:`CentredDerivatives` gives position,
    velocity and acceleration there. Every update discounts the past by the forgetting factor
    of its own phase step, so the memory in periods does not change.
    """
    if params.update_spacing is None:
        return 1
    spacing = params.update_spacing * 2.0 * math.pi / params.kernels
    return max(1, int(math.ceil(phase_step / spacing - 1e-9)))


def anchor_capacity(dt: float, params: OnlineParameters) -> int:
    """Ring-buffer length of the period statistics: the longest window in samples, plus 2."""
    return int(math.ceil(params.statistics_periods / (params.min_frequency_hz * dt))) + 2


def recent_capacity(dt: float, params: OnlineParameters) -> int:
    """Samples kept for the series fit at the hand-over: the span the detector compares at
    the lowest frequency, plus a block."""
    return int(math.ceil((1.0 + params.detector.confirm) / (params.min_frequency_hz * dt))) \
        + int(round(1.0 / (dt * params.detector.rate_hz))) + 2


def build_model(dofs, params: OnlineParameters, frequency_hz: float, phase: float, t_last: float,
                weights, goal, amplitude, source: dict) -> PeriodicModel:
    """A PeriodicModel from a learner's final state; phase_offset extrapolates phi back to t = 0."""
    omega = 2.0 * math.pi * frequency_hz
    return PeriodicModel(
        frequency_hz=float(frequency_hz), dofs=tuple(dofs), kernels=params.kernels,
        width=params.kernel_width, alpha_s=params.alpha_s, beta_s=params.beta_s,
        goal=np.array(goal), amplitude=np.array(amplitude), weights=np.array(weights),
        phase_offset=_wrap(phase - omega * t_last), source=source)


def model_frequency_hz(t: np.ndarray, phase: np.ndarray, fundamental_hz: np.ndarray,
                       hand_overs: np.ndarray, periods: float) -> float:
    """The frequency a learned model keeps (Hz): the canonical phase's mean rate over the last
    ``periods`` periods since the last hand-over.

    A person's tempo wanders by several percent from stroke to stroke, and the canonical
    system follows it: the fundamental at the end of a demonstration is the tempo of its last
    strokes (up to 8 % from the mean on the synthetic demos of ``benchmarks/bench_track.py``),
    while the phase advance over many periods gives the demonstrated frequency. With fewer
    than two periods since the hand-over (or none), the fundamental averaged over the last
    period.
    """
    n = t.size
    dt = float((t[-1] - t[0]) / (n - 1))
    start = int(np.searchsorted(hand_overs, hand_overs[-1])) if hand_overs[-1] > 0 else n - 1
    start = max(start, n - 1 - int(round(periods / (fundamental_hz[-1] * dt))))
    if hand_overs[-1] > 0 and (t[-1] - t[start]) * fundamental_hz[-1] >= 2.0:
        return float((phase[-1] - phase[start]) / (2.0 * math.pi * (t[-1] - t[start])))
    last_period = max(1, int(round(1.0 / (fundamental_hz[-1] * dt))))
    return float(fundamental_hz[-last_period:].mean())


def learn_online(t: np.ndarray, Y: np.ndarray, params: OnlineParameters = OnlineParameters(),
                 dofs=None, reference_dof: int = 0, source: dict | None = None,
                 progress: Callable[[int], None] | None = None, reference: bool = False,
                 chunk: int = 2048, valid: np.ndarray | None = None
                 ) -> tuple[PeriodicModel, LearnHistory]:
    """Learn a periodic model online, sample by sample.

    Parameters
    ----------
    t : ndarray, shape (n,)
        Uniformly spaced sample times (s).
    Y : ndarray, shape (n, d)
        The demonstration (m); rows that are not ``valid`` are placeholders (e.g. bridged).
    params : OnlineParameters
    dofs : sequence of str, optional
        DOF names (default "q0", "q1", ...).
    reference_dof : int
        The DOF that defines phase 0.
    source : dict, optional
        Provenance stored in the model.
    progress : callable, optional
        Called with the number of samples processed after each chunk.
    reference : bool
        Run the numpy reference implementation instead of the numba kernel (slow; for tests).
    chunk : int
        Samples per call of the kernel (granularity of ``progress``).
    valid : ndarray of bool, shape (n,), optional
        Which samples were observed (default: all); see :meth:`OnlineLearner.step`.

    Returns
    -------
    model : PeriodicModel
        The final weights, the frequency of :func:`model_frequency_hz`, g and r over the last
        period, and the phase extrapolated back to t = 0.
    history : LearnHistory
    """
    if not reference:
        from wipelab.learning._online_kernel import FastOnlineLearner

    t = np.asarray(t, dtype=np.float64)
    Y = np.asarray(Y, dtype=np.float64)
    n, d = Y.shape
    valid = np.ones(n, dtype=bool) if valid is None else np.asarray(valid, dtype=bool)
    dt = float((t[-1] - t[0]) / (n - 1))
    dofs = tuple(dofs) if dofs is not None else tuple(f"q{j}" for j in range(d))
    learner = OnlineLearner(d, dt, params, reference_dof) if reference else \
        FastOnlineLearner(d, dt, params, reference_dof)
    every = max(1, int(round(params.weights_every_s / dt)))
    output = np.empty((n, d))
    phase = np.empty(n)
    fundamental = np.empty(n)
    hand_overs = np.empty(n, dtype=np.int64)
    n_osc = 3 if params.canonical == "afo" else 1
    oscillators = np.empty((n, n_osc))
    snapshots = []
    for start in range(0, n, chunk):
        stop = min(n, start + chunk)
        if reference:
            for k in range(start, stop):
                output[k] = learner.step(Y[k], bool(valid[k]))
                phase[k] = learner.canonical.fundamental[0]
                fundamental[k] = learner.omega_ / (2.0 * math.pi)
                oscillators[k] = learner.canonical.frequencies_hz
                hand_overs[k] = learner.hand_overs_
                if k % every == 0:
                    snapshots.append(learner.weights_.copy())
        else:
            snapshots.extend(learner.process(Y[start:stop], valid[start:stop], output[start:stop],
                                             phase[start:stop], fundamental[start:stop],
                                             oscillators[start:stop], hand_overs[start:stop],
                                             every))
        if progress is not None:
            progress(stop - start)
    frequency_hz = model_frequency_hz(t, phase, fundamental, hand_overs, params.frequency_periods)
    model = build_model(dofs, params, frequency_hz, phase[-1], t[-1], learner.weights_,
                        learner.goal_, learner.amplitude_, source or {})
    history = LearnHistory(t=t, input=Y, output=output, phase=phase, fundamental_hz=fundamental,
                           oscillators_hz=oscillators, weights_t=t[::every],
                           weights=np.array(snapshots).reshape(-1, d, params.kernels),
                           valid=valid, hand_overs=hand_overs)
    return model, history
