"""The two-layer online learner (Fig. 1): canonical system -> phase and Omega -> periodic DMP.

Per sample, as a robot watching the demonstration would:

1. feed the period detector (:mod:`~wipelab.learning.period_detector`); at the sample where
   it first holds a period, hand it over: the canonical system starts locked, with the
   frequency, phase and series of a least-squares fit of the last two periods near 2 pi / T
   (:func:`~wipelab.learning.harmonic.locked_series`, the systems' ``lock``). Afterwards the
   detector supervises: when the period it holds and the fundamental differ by more than
   ``relock_tolerance`` (30 %: a subharmonic, a lost lock), or by more than
   ``change_relock_tolerance`` (2 %) within ``change_relock_periods`` of a change of tempo,
   hand over again;
2. update the anchor g and amplitude r (mean and sqrt(2) RMS of each DOF over the last
   period of the current Omega; after a gap longer than ``bridge_s`` they are held until a
   whole period has been observed again: a period of samples spanning the gap covers some
   phases twice, and its mean is off the centre), normalise the input -- (y - g) /
   max(r, r_ref / 2) once locked, so that a DOF that barely moves stays small (in units of
   its own r, the slow drift of y under a line wiped along x pulled Omega away), the running
   range before -- and advance the canonical system over the sample interval (AFS, or the
   AFO pool with its logic step) -> phase phi;
3. the fundamental Omega: the oscillator's frequency averaged over the last period (free
   of the ripple the coupling term puts on it), restarted at the hand-over; the model's
   frequency: the mean phase rate of the current tempo segment
   (:mod:`~wipelab.learning.tempo`);
4. learn the weights: by default fitted to the positions through the DMP's limit cycle
   (:mod:`~wipelab.learning.position_fit`, recursive least squares with a memory of
   ``memory_periods``); with ``regression="lwr"`` the paper's incremental LWR of
   eqs. 13-15 on f_targ (text after eq. 12), from a centred polynomial fit of the last
   samples (:mod:`~wipelab.learning.derivatives`), at points between samples;
5. integrate the DMP (eqs. 6-7) with the current weights: the imitated movement (Fig. 5).

:class:`OnlineLearner` is the one implementation: ``step`` (one sample, as a live session
calls it) and ``process`` (many, in a compiled loop) run the same compiled step
(:func:`~wipelab.learning.online_kernel.learner_step`).

Gaps. A sample marked invalid (the tracker lost the sponge) teaches nothing: the canonical
system runs on at its frequency without coupling or learning, the detector restarts, and no
regression update uses it; g and r are held (step 2); the DMP keeps moving. Fed the
tracker's straight-line bridge as data instead, the fundamental swung 49.5 % off after a
1.5-period gap (0.9 % gap-aware; 10.4 % before g and r were held; the setup of
``test_a_gap_teaches_nothing_and_the_oscillator_runs_through_it`` in
``tests/learning/test_online.py``), and over the benchmark's 27 human-like demonstrations
6 model frequencies ended more than 1 % off (worst 2.64 %), none gap-aware (worst 0.47 %).

Numbers below are printed by ``benchmarks/bench_learn.py``: on its signals (two DOFs with
2nd and 3rd harmonics and 2 % noise; 0.3, 0.5, 1, 2, 3 Hz at 30 and 500 Hz; worst of two
noise seeds) unless stated otherwise; issue 11's tables (a)-(c) are on held-out
demonstrations of :mod:`wipelab.learning.demonstrator`.

Default canonical system: the AFS. With the start-up detector both systems stay within 1 %
of the fundamental from the hand-over on, after 1.95-2.30 periods (AFS) and 2.11-2.30
(pool): the start does not decide, nor does a step of the frequency (re-converged within
2.05-2.11 periods, pool 2.03-2.11). The AFS is better elsewhere: its model's rollout after 10
periods is within 0.06-0.22 % of peak-to-peak at 500 Hz (pool 0.71-0.76 %; at 30 Hz
0.35-1.07 %, pool 0.69-1.16 %); if no period is detected (the oscillators alone) it still
locks in 3.9-8.7 periods (pool 3.5-11.7); and it needs neither the offset trick (the pool's
eq. 4 has no constant term) nor the logic step. With the published constant gains
(K = K_Omega = 20) and no detector, neither settles at most of these frequencies (see
:mod:`wipelab.learning.oscillators`). On the 27 human-like demonstrations (60 s, two 1.5 s
gaps) the model frequency is within 0.47 % of the nominal (median 0.18 %; the pool 0.35 %).

Departures from the paper:

* the start-up detector and the hand-over (step 1): the oscillators alone take 3.9-8.7
  periods (median 5.2) to stay within 1 %, because phase and series start from nothing.
  The hand-over refines the detector's frequency by the fit (within ``lock_search``) and
  advances the phase by one oscillator substep: an Euler substep compares the input at its
  end with the series at its start phase, so a settled oscillator leads by one substep;
* after the hand-over the input is normalised by the period statistics instead of the
  running range, whose relaxation (tau = 10 s) modulates the input's scale within each
  period (:mod:`wipelab.learning.normalise`);
* the detector keeps running as a supervisor and re-locks (step 1): a safety net for a lost
  lock or a subharmonic. On the 27 human-like demonstrations the default learner needs it
  little (worst 0.47 % with it or without), nor does the gain schedule of
  :mod:`wipelab.learning.oscillators` (kappa = 100, off by default: 0.38 % with it or
  without); before the two normalisation fixes of step 2 the schedule kept 21 of 27
  within 1 % with it (worst 11.9 %), 17 without (worst 88 %);
* the model's frequency is per tempo segment, not the last Omega: the fundamental of the
  last period was within 1 % on 2 of the 27 (worst 10.9 %); a +-30 % step of tempo is
  followed within 2.9 periods (table (b), 60 held-out steps; the 40-period mean without
  segments: not within the 15 periods after the step);
* the weights are fitted to positions (step 4): after 10 periods the rollout is within
  0.35-1.07 % of peak-to-peak at 30 Hz and 0.06-0.22 % at 500 Hz, against 0.93-2.06 % and
  0.92-1.01 % for eqs. 13-15 on f_targ (on the held-out demonstrations, table (c): worst
  1.14 % against 2.68 %);
* with ``regression="lwr"``: the recursion of eqs. 13-15 regresses f_targ / r on 1 instead
  of f_targ on r (the same fit, but the prior P0 = 1 then weighs the same whatever the unit
  of r); lambda counts per 1/100 of a period rather than per sample; and the regression is
  updated between samples, at most half a kernel spacing apart in phase, from the same
  local polynomial: at 3 Hz sampled at 30 Hz (ten phases per period for 25 kernels) the
  rollout error after 10 periods drops from 3.80 % to 2.06 % of peak-to-peak, at 2 Hz from
  2.40 % to 2.05 %; at 500 Hz one update per sample already suffices.

Cost: ``step`` about 24 us of CPU per sample at 30 Hz (3 DOFs; 13 us at 500 Hz), ``process``
21 us (10 us); the benchmark's speed table, measured at a load average of 9 on 2 cores.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from wipelab.learning.afo import AFOParameters
from wipelab.learning.afs import AFSParameters
from wipelab.learning.derivatives import MIN_WINDOW, polynomial_fit_matrix
from wipelab.learning.dmp import max_phase_step
from wipelab.learning.kernels import default_width, kernel_centres
from wipelab.learning.model import PeriodicModel
from wipelab.learning.normalise import new_period_window, new_running_range
from wipelab.learning.online_kernel import (AFO, AFS, LWR, POSITIONS, KernelSettings,
                                           LearnerState, learner_run, step_entry_point)
from wipelab.learning.oscillators import DOF_COUPLINGS, substep_count
from wipelab.learning.period_detector import PeriodDetectorParameters, new_detector
from wipelab.learning.position_fit import new_position_fit
from wipelab.learning.tempo import TempoSettings, new_tempo_state

CANONICAL_SYSTEMS = ("afs", "afo")
REGRESSIONS = ("positions", "lwr")


@dataclass(frozen=True)
class OnlineParameters:
    """Settings of the online learner (learned state lives in the learner)."""

    canonical: str = "afs"                  # "afs" (adaptive Fourier series) or "afo" (pool, eqs. 1-5)
    kernels: int = 25                       # N
    width: float | None = None              # h of eq. 8; None -> 2.5 N
    alpha_s: float = 12.0                   # eq. 6
    beta_s: float = 3.0                     # eq. 6
    regression: str = "positions"           # "positions" (limit-cycle fit) or "lwr" (eqs. 13-15)
    memory_periods: float = 3.0             # positions: the fit's memory (periods)
    smoothing: float = 1e-2                 # positions: smoothness penalty, as the offline fit's
    forgetting: float = 0.99                # lwr: lambda of eq. 14
    forgetting_samples_per_period: float | None = 100.0  # lwr: lambda counts per 1/this of a period
    p0: float = 1.0                         # lwr: P_i(0) of eq. 14
    update_spacing: float | None = 0.5      # lwr: updates <= this x 2 pi / N apart (phase); None: 1/sample
    derivative_window_periods: float = 0.125  # lwr: polynomial window as a fraction of the period
    derivative_degree: int = 4              # lwr: polynomial degree of the derivative fit
    max_derivative_window: int = 101        # lwr: samples, odd
    dof_coupling: str = "mean"              # "mean": every moving DOF drives the phase; "reference": one
    substep_hz: float = 500.0               # oscillators integrate at >= this rate (Hz)
    normaliser_time_constant_s: float = 10.0  # tau of the running range used until the lock (s)
    min_frequency_hz: float = 0.1           # longest period the anchor window and detector cover (Hz)
    statistics_periods: int = 1             # periods over which Omega, g and r are averaged
    start_up: bool = True                   # detect the period and hand it to the canonical system
    bridge_s: float = 0.15                  # a gap up to this long (s) carries the detector on the
                                            # last observed sample; a longer one restarts it
    detector: PeriodDetectorParameters = field(default_factory=PeriodDetectorParameters)
    lock_search: float = 0.01               # the hand-over refines Omega within +- this (relative)
    relock_tolerance: float | None = 0.3    # hand over again when the detector's held period and the
                                            # fundamental differ by more (relative); None: once only
    frequency_periods: float = 40.0         # the model's frequency: mean phase rate over this many periods
    min_frequency_periods: float = 2.0      # ... of the current tempo; fewer: the fundamental
    change_threshold: float | None = 0.15   # a change of tempo: the per-period frequency off by more
    change_periods: int = 2                 # ... in this many consecutive periods (None above: never)
    change_relock_tolerance: float | None = 0.02  # after a change, hand over at this disagreement
    change_relock_periods: float = 3.0      # ... within this many periods of finding the change
    weights_every_s: float = 0.05           # interval of the weight snapshots in the history (s)
    afs: AFSParameters = field(default_factory=AFSParameters)
    afo: AFOParameters = field(default_factory=AFOParameters)

    def __post_init__(self):
        if self.canonical not in CANONICAL_SYSTEMS:
            raise ValueError(f"canonical must be one of {CANONICAL_SYSTEMS}, got {self.canonical!r}")
        if self.regression not in REGRESSIONS:
            raise ValueError(f"regression must be one of {REGRESSIONS}, got {self.regression!r}")
        if self.dof_coupling not in DOF_COUPLINGS:
            raise ValueError(f"dof_coupling must be one of {DOF_COUPLINGS}, got {self.dof_coupling!r}")
        if self.kernels < 2:
            raise ValueError(f"kernels must be >= 2, got {self.kernels}")
        if self.max_derivative_window < 5 or self.max_derivative_window % 2 == 0:
            raise ValueError("max_derivative_window must be odd and >= 5")
        if self.update_spacing is not None and not self.update_spacing > 0.0:
            raise ValueError(f"update_spacing must be > 0 or None, got {self.update_spacing}")
        if self.relock_tolerance is not None and not self.relock_tolerance > 0.0:
            raise ValueError(f"relock_tolerance must be > 0 or None, got {self.relock_tolerance}")
        if not self.frequency_periods > 0.0 or not self.memory_periods > 0.0:
            raise ValueError("frequency_periods and memory_periods must be > 0")
        if not self.bridge_s >= 0.0:
            raise ValueError(f"bridge_s must be >= 0, got {self.bridge_s}")
        if self.change_periods < 1:
            raise ValueError(f"change_periods must be >= 1, got {self.change_periods}")

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
    frequency_hz : ndarray, shape (n,)
        The model's frequency as it would be saved at that sample (Hz).
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
    frequency_hz: np.ndarray
    oscillators_hz: np.ndarray
    weights_t: np.ndarray
    weights: np.ndarray
    valid: np.ndarray
    hand_overs: np.ndarray


def _wrap(angle: float) -> float:
    return float(np.mod(angle, 2.0 * math.pi))


def kernel_settings(n_dofs: int, dt: float, params: OnlineParameters,
                    reference_dof: int) -> KernelSettings:
    """The compiled step's settings for d DOFs sampled every dt (s)."""
    p = params
    canonical = p.afs if p.canonical == "afs" else p.afo
    detector, _ = new_detector(n_dofs, dt, p.detector, p.min_frequency_hz,
                               canonical.max_frequency_hz)
    w = p.max_derivative_window
    fit_matrices = np.zeros(((w - MIN_WINDOW) // 2 + 1, p.derivative_degree + 1, w))
    for index, length in enumerate(range(MIN_WINDOW, w + 1, 2)):
        matrix = polynomial_fit_matrix(length, p.derivative_degree)
        fit_matrices[index, :matrix.shape[0], :length] = matrix
    width = p.kernel_width
    return KernelSettings(
        canonical=AFS if p.canonical == "afs" else AFO, gains=canonical.gains(),
        reference=int(reference_dof), mean_coupling=p.dof_coupling == "mean",
        n_sub=substep_count(dt, p.substep_hz), dt=float(dt),
        offset=0.0 if p.canonical == "afs" else 1.0,
        normaliser_rate=dt / p.normaliser_time_constant_s,
        statistics_periods=float(p.statistics_periods),
        floor_omega=2.0 * math.pi * p.min_frequency_hz, start_up=p.start_up,
        bridge_samples=int(round(p.bridge_s / dt)), detector=detector,
        confirm=p.detector.confirm, n_terms=p.afs.n_terms if p.canonical == "afs" else 3,
        lock_search=p.lock_search, relock_tolerance=p.relock_tolerance or 0.0,
        change_relock_tolerance=p.change_relock_tolerance or 0.0,
        change_relock_periods=p.change_relock_periods,
        tempo=TempoSettings(window_periods=p.frequency_periods,
                            min_periods=p.min_frequency_periods,
                            change_threshold=math.inf if p.change_threshold is None
                            else p.change_threshold,
                            change_periods=p.change_periods, reference_periods=2),
        regression=POSITIONS if p.regression == "positions" else LWR,
        memory_periods=p.memory_periods, forgetting=p.forgetting,
        forgetting_samples_per_period=p.forgetting_samples_per_period or 0.0,
        update_spacing=p.update_spacing or 0.0, window_periods=p.derivative_window_periods,
        fit_matrices=fit_matrices, centres=kernel_centres(p.kernels), width=width,
        alpha_s=p.alpha_s, beta_s=p.beta_s, max_phase_step=max_phase_step(width))


def new_learner_state(n_dofs: int, dt: float, params: OnlineParameters,
                      settings: KernelSettings) -> LearnerState:
    """A learner that has seen nothing."""
    p = params
    canonical = p.afs if p.canonical == "afs" else p.afo
    oscillators = canonical.new_state(n_dofs)
    _, detector = new_detector(n_dofs, dt, p.detector, p.min_frequency_hz,
                               canonical.max_frequency_hz)
    capacity = anchor_capacity(dt, params)
    w = p.max_derivative_window
    one = lambda dtype=np.float64: np.zeros(1, dtype=dtype)   # noqa: E731
    return LearnerState(
        output=np.zeros(n_dofs), velocity=np.zeros(n_dofs), phase=one(), omega=one(),
        frequency_hz=one(), weights=np.zeros((n_dofs, p.kernels)), goal=np.zeros(n_dofs),
        amplitude=np.ones(n_dofs), hand_overs=one(np.int64), count=one(np.int64),
        valid_run=one(np.int64), gap_run=one(np.int64), anchor_run=one(np.int64),
        locked=one(np.int64), relock_until=one(),
        moving=np.zeros(n_dofs, dtype=np.bool_), previous_u=np.zeros(n_dofs),
        oscillators=oscillators, range=new_running_range(n_dofs),
        statistics=new_period_window(n_dofs, capacity),
        fundamental=new_period_window(1, capacity), detector=detector,
        recent=np.zeros((recent_capacity(dt, p) if p.start_up else 1, n_dofs)),
        recent_count=one(np.int64), tempo=new_tempo_state(settings.tempo),
        fit=new_position_fit(n_dofs, p.kernels, p.kernel_width, p.alpha_s, p.beta_s, p.smoothing),
        lwr_P=np.full((n_dofs, p.kernels), float(p.p0)), values=np.zeros((w, n_dofs)),
        value_phases=np.zeros(w), value_omegas=np.zeros(w),
        scratch=np.zeros((8, max(n_dofs, oscillators.alpha.shape[1], 3))))


class OnlineLearner:
    """The online two-layer learner for d DOFs sampled every dt: one sample at a time
    (:meth:`step`, what a live session calls at the camera rate) or many (:meth:`process`),
    through the same compiled step (:func:`~wipelab.learning.online_kernel.learner_step`).

    Parameters
    ----------
    n_dofs : int
    dt : float
        Sample interval (s); samples are assumed uniform.
    params : OnlineParameters
    reference_dof : int
        The DOF whose fundamental defines phase 0 (a cosine peak).

    The state after the last sample is read through the properties (copies are cheap to
    avoid: ``output``, ``weights``, ``goal`` and ``amplitude`` are the learner's own arrays,
    changed in place by the next sample).
    """

    def __init__(self, n_dofs: int, dt: float, params: OnlineParameters = OnlineParameters(),
                 reference_dof: int = 0):
        if not 0 <= reference_dof < n_dofs:
            raise ValueError(f"reference_dof must be in [0, {n_dofs}), got {reference_dof}")
        self.params = params
        self.dt = float(dt)
        self.n_dofs = n_dofs
        self.settings = kernel_settings(n_dofs, dt, params, reference_dof)
        self.state = new_learner_state(n_dofs, dt, params, self.settings)
        self._step = None      # the compiled step's entry point, resolved at the first step

    def step(self, y, valid: bool = True) -> np.ndarray:
        """Learn from one sample y (d,) in m (a placeholder when not ``valid``: the input was
        not observed; it teaches nothing, the canonical system runs on at its frequency);
        return the learned movement at the same time (d,), m (the learner's own array)."""
        y = np.ascontiguousarray(y, dtype=np.float64)
        if y.shape != (self.n_dofs,):
            raise ValueError(f"y must have shape ({self.n_dofs},), got {y.shape}")
        if self._step is None:
            self._step = step_entry_point(self.settings, self.state)
        self._step(self.settings, self.state, y, bool(valid))
        return self.state.output

    def process(self, Y, valid=None, every: int = 1) -> dict:
        """Learn from Y (n, d) (rows not ``valid`` are gaps); return the per-sample state.

        Returns
        -------
        dict of ndarray
            ``output`` (n, d), ``phase`` (n,), ``fundamental_hz`` (n,), ``frequency_hz``
            (n,), ``oscillators_hz`` (n, M), ``hand_overs`` (n,) and ``weights`` (k, d, N),
            a snapshot at every sample whose index since the first ever is a multiple of
            ``every``.
        """
        Y = np.ascontiguousarray(Y, dtype=np.float64)
        n = Y.shape[0]
        valid = np.ones(n, dtype=np.bool_) if valid is None else \
            np.ascontiguousarray(valid, dtype=np.bool_)
        count = self.count
        snapshots = np.empty(((count + n - 1) // every - (count - 1) // every if count
                              else (n - 1) // every + 1, self.n_dofs, self.params.kernels))
        result = {"output": np.empty((n, self.n_dofs)), "phase": np.empty(n),
                  "fundamental_hz": np.empty(n), "frequency_hz": np.empty(n),
                  "oscillators_hz": np.empty((n, self.state.oscillators.omegas.size)),
                  "hand_overs": np.empty(n, dtype=np.int64)}
        written = learner_run(self.settings, self.state, Y, valid, result["output"],
                              result["phase"], result["fundamental_hz"], result["frequency_hz"],
                              result["oscillators_hz"], result["hand_overs"], snapshots,
                              int(every))
        result["weights"] = snapshots[:written]
        return result

    @property
    def count(self) -> int:
        """Samples processed."""
        return int(self.state.count[0])

    @property
    def output(self) -> np.ndarray:
        """The DMP's position, the movement learned so far (d,), m."""
        return self.state.output

    @property
    def phase(self) -> float:
        """Canonical phase phi (rad, unwrapped)."""
        return float(self.state.phase[0])

    @property
    def omega(self) -> float:
        """The fundamental Omega (rad/s): the oscillator's frequency averaged over the last
        period, what the DMP integrates with."""
        return float(self.state.omega[0])

    @property
    def fundamental_hz(self) -> float:
        return self.omega / (2.0 * math.pi)

    @property
    def frequency_hz(self) -> float:
        """The model's frequency now (Hz), see :mod:`wipelab.learning.tempo`."""
        return float(self.state.frequency_hz[0])

    @property
    def oscillators_hz(self) -> np.ndarray:
        """Every oscillator's |omega_i| / 2 pi (Hz), shape (M,)."""
        return np.abs(self.state.oscillators.omegas) / (2.0 * math.pi)

    @property
    def weights(self) -> np.ndarray:
        """Current weights (d, N)."""
        return self.state.weights

    @property
    def goal(self) -> np.ndarray:
        """g over the last period (d,), m."""
        return self.state.goal

    @property
    def amplitude(self) -> np.ndarray:
        """r over the last period (d,), m."""
        return self.state.amplitude

    @property
    def locked(self) -> bool:
        """Whether a detected period has been handed to the canonical system."""
        return bool(self.state.locked[0])

    @property
    def hand_overs(self) -> int:
        """How often it has been (the start-up, then re-locks)."""
        return int(self.state.hand_overs[0])

    @property
    def tempo_changes(self) -> int:
        """Changes of tempo found so far."""
        return int(self.state.tempo.changes[0])

    def model(self, dofs, source: dict, t_last: float) -> PeriodicModel:
        """The model learned so far; ``t_last`` (s) is the time of the last sample on the
        clock of the model's phase_offset."""
        return build_model(dofs, self.params, self.frequency_hz, self.phase, t_last,
                           self.weights, self.goal, self.amplitude, source)


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


def learn_online(t: np.ndarray, Y: np.ndarray, params: OnlineParameters = OnlineParameters(),
                 dofs=None, reference_dof: int = 0, source: dict | None = None,
                 progress: Callable[[int], None] | None = None, chunk: int = 2048,
                 valid: np.ndarray | None = None) -> tuple[PeriodicModel, LearnHistory]:
    """Learn a periodic model online, sample by sample (:class:`OnlineLearner`).

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
    chunk : int
        Samples per call of the compiled loop (granularity of ``progress``).
    valid : ndarray of bool, shape (n,), optional
        Which samples were observed (default: all); see :meth:`OnlineLearner.step`.

    Returns
    -------
    model : PeriodicModel
        The final weights, the model frequency (:mod:`wipelab.learning.tempo`), g and r over
        the last period, and the phase extrapolated back to t = 0.
    history : LearnHistory
    """
    t = np.asarray(t, dtype=np.float64)
    Y = np.asarray(Y, dtype=np.float64)
    n, d = Y.shape
    valid = np.ones(n, dtype=bool) if valid is None else np.asarray(valid, dtype=bool)
    dt = float((t[-1] - t[0]) / (n - 1))
    dofs = tuple(dofs) if dofs is not None else tuple(f"q{j}" for j in range(d))
    learner = OnlineLearner(d, dt, params, reference_dof)
    every = max(1, int(round(params.weights_every_s / dt)))
    parts = []
    for start in range(0, n, chunk):
        stop = min(n, start + chunk)
        parts.append(learner.process(Y[start:stop], valid[start:stop], every))
        if progress is not None:
            progress(stop - start)
    joined = {key: np.concatenate([part[key] for part in parts]) for key in parts[0]}
    model = learner.model(dofs, source or {}, t[-1])
    history = LearnHistory(t=t, input=Y, output=joined["output"], phase=joined["phase"],
                           fundamental_hz=joined["fundamental_hz"],
                           frequency_hz=joined["frequency_hz"],
                           oscillators_hz=joined["oscillators_hz"], weights_t=t[::every],
                           weights=joined["weights"].reshape(-1, d, params.kernels),
                           valid=valid, hand_overs=joined["hand_overs"])
    return model, history
