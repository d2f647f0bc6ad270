"""The online learner's step, compiled: one sample in, the learner's state out.

:func:`learner_step` is the one implementation of the two-layer learner of
:mod:`wipelab.learning.online`: the per-sample interface (``OnlineLearner.step``, what a live
session calls at the camera rate) calls it for one sample, the batch interface
(``OnlineLearner.process``, :func:`learner_run`) calls it in a compiled loop. It composes the
compiled pieces of the package, each tested on its own: the period detector, the running
normaliser and the period statistics, the canonical systems (AFS or the AFO pool), the tempo
estimate, the weight regression (the position fit through the limit cycle, or eqs. 13-15
on f_targ) and the DMP integrator.

Numba's on-disk cache (``cache=True``) is refreshed when this file or any wipelab module it
uses changes (:mod:`wipelab.numba_cache`).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit, typeof, types

from wipelab.learning.afo import pool_fundamental, pool_lock, pool_logic_step, pool_substep
from wipelab.learning.afs import afs_lock, afs_substep
from wipelab.learning.derivatives import MIN_WINDOW, evaluate_polynomial, window_for
from wipelab.learning.dmp import dmp_step, forcing_target
from wipelab.learning.harmonic import locked_series
from wipelab.learning.kernels import activations
from wipelab.learning.lwr import lwr_update
from wipelab.learning.normalise import (PeriodWindow, RunningRange, period_statistics,
                                        running_normalise)
from wipelab.learning.oscillators import OscillatorGains, OscillatorState
from wipelab.learning.period_detector import (DetectorSettings, DetectorState, detector_restart,
                                              detector_update)
from wipelab.learning.position_fit import (PositionFit, position_fit_restart,
                                           position_fit_update, position_fit_weights)
from wipelab.learning.tempo import TempoSettings, TempoState, tempo_restart, tempo_update
from wipelab.numba_cache import forget_stale_kernels

AFS, AFO = 0, 1
POSITIONS, LWR = 0, 1
#: The canonical system's input is in units of each DOF's amplitude, but of no less than this
#: share of the reference DOF's (:func:`_normalise_locked`).
MIN_RELATIVE_SCALE = 0.5


class KernelSettings(NamedTuple):
    """Everything :func:`learner_step` reads and never writes (built by OnlineLearner)."""

    canonical: int                 # AFS or AFO
    gains: OscillatorGains
    reference: int                 # the DOF that defines phase 0
    mean_coupling: bool            # every moving DOF drives the phase
    n_sub: int                     # oscillator substeps per sample
    dt: float                      # sample interval (s)
    offset: float                  # added to the normalised input (pool: 1, AFS: 0)
    normaliser_rate: float         # dt / tau of the running range
    statistics_periods: float      # g, r and the fundamental over this many periods
    floor_omega: float             # Omega is at least this (rad/s)
    start_up: bool                 # the period detector hands over
    bridge_samples: int            # a gap this short carries the detector on the last sample
    detector: DetectorSettings
    confirm: float                 # the detector's (1 + confirm) periods are fitted at a hand-over
    n_terms: int                   # terms of the series fitted at a hand-over
    lock_search: float             # relative frequency search of that fit
    relock_tolerance: float        # hand over again beyond this disagreement (0: never)
    change_relock_tolerance: float  # ... or this after a change of tempo (0: never)
    change_relock_periods: float   # ... within this many periods of finding it
    tempo: TempoSettings
    regression: int                # POSITIONS or LWR
    memory_periods: float          # POSITIONS: memory of the fit (periods)
    forgetting: float              # LWR: lambda of eq. 14
    forgetting_samples_per_period: float  # LWR: lambda counts per 1/this period (0: per sample)
    update_spacing: float          # LWR: updates <= this x 2 pi / N apart (0: one per sample)
    window_periods: float          # LWR: derivative window, fraction of a period
    fit_matrices: np.ndarray       # LWR: (windows, degree + 1, max window) polynomial fits
    centres: np.ndarray            # kernel centres c_i (rad)
    width: float                   # h of eq. 8
    alpha_s: float                 # eq. 6
    beta_s: float                  # eq. 6
    max_phase_step: float          # DMP RK4 substep (rad)


class LearnerState(NamedTuple):
    """Everything :func:`learner_step` changes; what live draws is in the first fields.

    Scalars are arrays of one element, so that the compiled step can write them.
    """

    output: np.ndarray             # (d,) the DMP's position: the movement learned so far (m)
    velocity: np.ndarray           # (d,) the DMP's scaled velocity s (m/rad)
    phase: np.ndarray              # (1,) canonical phase phi (rad, unwrapped)
    omega: np.ndarray              # (1,) the fundamental Omega, averaged over a period (rad/s)
    frequency_hz: np.ndarray       # (1,) the model's frequency (Hz), see wipelab.learning.tempo
    weights: np.ndarray            # (d, N)
    goal: np.ndarray               # (d,) g (m)
    amplitude: np.ndarray          # (d,) r (m)
    hand_overs: np.ndarray         # (1,) int64, detected periods handed over so far
    count: np.ndarray              # (1,) int64, samples so far
    valid_run: np.ndarray          # (1,) int64, valid samples since the last gap
    gap_run: np.ndarray            # (1,) int64, samples of the gap so far (0: observing)
    anchor_run: np.ndarray         # (1,) int64, valid samples since the last gap longer than
                                   # the bridge (the anchor's window is whole after a period)
    locked: np.ndarray             # (1,) int64, 1 once a period was handed over
    relock_until: np.ndarray       # (1,) time until which a change of tempo may re-lock (s)
    moving: np.ndarray             # (d,) bool, DOFs with r > 0
    previous_u: np.ndarray         # (d,) the last normalised input
    oscillators: OscillatorState
    range: RunningRange
    statistics: PeriodWindow       # g and r
    fundamental: PeriodWindow      # Omega
    detector: DetectorState
    recent: np.ndarray             # (capacity, d) the last samples, for the hand-over's fit
    recent_count: np.ndarray       # (1,) int64
    tempo: TempoState
    fit: PositionFit               # POSITIONS
    lwr_P: np.ndarray              # LWR: (d, N) P of eq. 14
    values: np.ndarray             # LWR: (max window, d) recent samples
    value_phases: np.ndarray       # LWR: their phases
    value_omegas: np.ndarray       # LWR: their Omega
    scratch: np.ndarray            # (8, max(d, M + 1, 3)) work space


@njit(cache=True)
def canonical_fundamental(settings: KernelSettings, state: LearnerState) -> tuple[float, float]:
    """(phase rad, instantaneous Omega rad/s) of the canonical system."""
    if settings.canonical == AFS:
        return state.oscillators.phases[0], state.oscillators.omegas[0]
    return pool_fundamental(state.oscillators)


@njit(cache=True)
def _normalise_locked(state: LearnerState, y, offset: float, reference: int, u) -> None:
    """u = (y - g) / max(r, r_ref / 2) + offset (0 + offset for a DOF that does not move).

    Each DOF in units of its own amplitude, but of no less than half the reference DOF's: a
    DOF that barely moves (a line wiped along x leaves y only its slow drift) stays small
    and weighs little in the shared phase; in units of its own amplitude its drift would be as
    large as the movement and pull Omega away."""
    floor = MIN_RELATIVE_SCALE * state.amplitude[reference] if state.moving[reference] else 0.0
    for j in range(y.shape[0]):
        r = max(state.amplitude[j], floor)
        u[j] = ((y[j] - state.goal[j]) / r if state.moving[j] else 0.0) + offset


@njit(cache=True)
def _update_anchor(settings: KernelSettings, state: LearnerState, y, omega: float) -> None:
    """g = mean, r = sqrt(2 variance) over the last period (r = 1 for a DOF that does not move).

    A period of samples that spans a gap covers some phases twice and misses others: its mean
    is off the movement's centre by up to the amplitude. g and r then stay as they were until
    a whole period has been observed since the gap (a gap the bridge carries does not count:
    a tracker that drops a frame or a few here and there would freeze them for good)."""
    mean, variance = state.scratch[4], state.scratch[5]
    period_statistics(state.statistics, y, omega, settings.dt, settings.statistics_periods,
                      mean, variance)
    period_samples = settings.statistics_periods * 2.0 * math.pi / (max(omega, 1e-12)
                                                                     * settings.dt)
    if state.statistics.count[0] > state.anchor_run[0] and state.anchor_run[0] < period_samples:
        return
    for j in range(y.shape[0]):
        state.goal[j] = mean[j]
        spread = math.sqrt(2.0 * variance[j])
        state.moving[j] = spread > 0.0
        state.amplitude[j] = spread if spread > 0.0 else 1.0


@njit(cache=True)
def _hand_over(settings: KernelSettings, state: LearnerState, y, period: float, time: float,
               rearm: bool) -> None:
    """Start the canonical system from a detected period: frequency, phase and series of a
    least-squares fit of the last (1 + confirm) periods near 2 pi / period."""
    dt = settings.dt
    omega = 2.0 * math.pi / period
    _update_anchor(settings, state, y, omega)
    capacity = state.recent.shape[0]
    total = state.recent_count[0]
    count = min(total, int(round((1.0 + settings.confirm) * period / dt)))
    window = np.empty((count, y.shape[0]))
    for i in range(count):
        _normalise_locked(state, state.recent[(total - count + i) % capacity], settings.offset,
                          settings.reference, window[i])
    omega, phase, alpha, beta = locked_series(window, dt, omega, settings.n_terms,
                                              settings.reference, settings.lock_search)
    # An Euler substep compares the input at its end with the series at its start phase, so a
    # settled oscillator leads the input's phase by one substep.
    phase += omega * dt / settings.n_sub
    if settings.canonical == AFS:
        afs_lock(state.oscillators, omega, phase, alpha, beta)
    else:
        pool_lock(state.oscillators, omega, phase, alpha, beta, settings.reference)
    state.fundamental.count[0] = 0
    # A re-lock of the supervisor (rearm) may have fitted a window that straddles a change of
    # tempo: until the detector has seen the new tempo, a disagreement beyond
    # change_relock_tolerance re-locks once more.
    state.relock_until[0] = time + settings.change_relock_periods * 2.0 * math.pi / omega \
        if rearm else 0.0
    state.locked[0] = 1
    state.hand_overs[0] += 1
    state.previous_u[:] = window[count - 1]
    locked_phase = canonical_fundamental(settings, state)[0]
    tempo_restart(state.tempo, time, locked_phase)
    if settings.regression == POSITIONS:
        # The phase was redefined: refit the fitted window at its new phases.
        position_fit_restart(state.fit)
        z = state.scratch[6, :y.shape[0]]
        for i in range(count):
            for j in range(y.shape[0]):
                z[j] = window[i, j] - settings.offset
            position_fit_update(state.fit, locked_phase - omega * dt * (count - 1 - i), z,
                                omega * dt, settings.memory_periods)


@njit(cache=True)
def _observe(settings: KernelSettings, state: LearnerState, y) -> None:
    """The canonical system over one observed sample interval (input normalised)."""
    u, uj, error = state.scratch[0], state.scratch[1], state.scratch[2]
    cosines, sines, drives = state.scratch[3], state.scratch[4], state.scratch[5]
    _update_anchor(settings, state, y, canonical_fundamental(settings, state)[1])
    if state.locked[0] == 1:
        _normalise_locked(state, y, settings.offset, settings.reference, u)
    else:
        running_normalise(state.range, y, state.count[0] == 0, settings.normaliser_rate,
                          settings.offset, u)
    if state.valid_run[0] == 1:                       # the first sample, or the first after a gap
        state.previous_u[:] = u[:y.shape[0]]
    h = settings.dt / settings.n_sub
    for step in range(1, settings.n_sub + 1):
        for j in range(y.shape[0]):
            uj[j] = state.previous_u[j] + step / settings.n_sub * (u[j] - state.previous_u[j])
        if settings.canonical == AFS:
            afs_substep(state.oscillators, settings.gains, uj[:y.shape[0]], h, settings.dt,
                        settings.reference, settings.mean_coupling, error[:y.shape[0]], cosines,
                        sines)
        else:
            pool_substep(state.oscillators, settings.gains, uj[:y.shape[0]], h,
                         settings.reference, settings.mean_coupling, error[:y.shape[0]], cosines,
                         sines, drives)
    if settings.canonical == AFO:
        pool_logic_step(state.oscillators, settings.gains, settings.dt)
    state.previous_u[:] = u[:y.shape[0]]


@njit(cache=True)
def _learn_lwr(settings: KernelSettings, state: LearnerState, y, phase: float, omega: float,
               valid: bool) -> None:
    """Eqs. 13-15 on f_targ from a centred polynomial fit, at points between samples."""
    dt = settings.dt
    max_window = state.values.shape[0]
    n_kernels = settings.centres.shape[0]
    slot = state.count[0] % max_window
    state.values[slot] = y
    state.value_phases[slot] = phase
    state.value_omegas[slot] = omega
    if not valid:
        return
    window = window_for(omega, dt, settings.window_periods, max_window)
    if state.valid_run[0] < window:                   # a gap in the window
        return
    points = 1
    if settings.update_spacing > 0.0:
        spacing = settings.update_spacing * 2.0 * math.pi / n_kernels
        points = max(1, int(math.ceil(omega * dt / spacing - 1e-9)))
    first = state.count[0] + 1 - window
    centre = (first + (window - 1) // 2) % max_window
    omega_c = state.value_omegas[centre]
    forgetting = settings.forgetting
    if settings.forgetting_samples_per_period > 0.0:
        forgetting = settings.forgetting ** (omega_c * dt / points
                                             * settings.forgetting_samples_per_period
                                             / (2.0 * math.pi))
    matrix = settings.fit_matrices[(window - MIN_WINDOW) // 2]
    coefficients = np.zeros((matrix.shape[0], y.shape[0]))
    for k in range(window):
        sample = state.values[(first + k) % max_window]
        for q in range(matrix.shape[0]):
            for j in range(y.shape[0]):
                coefficients[q, j] += matrix[q, k] * sample[j]
    psi = np.empty(n_kernels)
    ones = np.ones(y.shape[0])
    for point in range(points):
        x = (point + 0.5) / points - 0.5
        phase_c = state.value_phases[centre] + x * omega_c * dt
        value, slope, curvature = evaluate_polynomial(coefficients, x)
        target = forcing_target(value, slope / dt, curvature / (dt * dt), omega_c, state.goal,
                                settings.alpha_s, settings.beta_s) / state.amplitude
        activations(phase_c, settings.centres, settings.width, psi)
        # f_targ ~ w r, regressed in units of r: the prior P0 = 1 then weighs the same for
        # any scale of the movement.
        lwr_update(psi, ones, target, forgetting, state.weights, state.lwr_P)


@njit(cache=True)
def _detect(settings: KernelSettings, state: LearnerState, y) -> float:
    """Remember y (d,) for a hand-over's fit and pass it to the period detector; its period
    (s) when it holds one, else 0."""
    slot = state.recent_count[0] % state.recent.shape[0]
    state.recent[slot] = y
    state.recent_count[0] += 1
    return detector_update(settings.detector, state.detector, y)


@njit(cache=True)
def learner_step(settings: KernelSettings, state: LearnerState, y, valid: bool) -> None:
    """Process one sample y (d,) in m (a placeholder when not ``valid``); update ``state``.

    1. the period detector: at the sample where it first holds a period, hand it over (the
       start-up); afterwards it supervises: hand over again when the period it holds and the
       fundamental differ by more than ``relock_tolerance``, or by more than
       ``change_relock_tolerance`` shortly after a change of tempo (a gap of at most
       ``bridge_samples`` carries the detector on the last sample, a longer one restarts it);
    2. g and r over the last period, the normalised input, and the canonical system over the
       sample interval (a gap: it runs on at its frequency, learning nothing);
    3. the fundamental Omega: the oscillator's frequency averaged over the last period; the
       tempo estimate and the model's frequency;
    4. the regression of the weights (no update from a gap);
    5. the DMP (eqs. 6-7) one sample on, with the weights learned so far.
    """
    dt = settings.dt
    count = state.count[0]
    time = count * dt
    if count == 0:
        state.output[:] = y
        state.velocity[:] = 0.0
    previous_phase, previous_omega = state.phase[0], state.omega[0]
    # 1. detector and hand-over
    period = 0.0
    if not valid:
        state.valid_run[0] = 0
        state.gap_run[0] += 1
        if state.gap_run[0] > settings.bridge_samples:
            state.anchor_run[0] = 0
        if settings.start_up and state.recent_count[0] > 0:
            if state.gap_run[0] <= settings.bridge_samples:
                # a short gap (a frame or a few the tracker dropped): the detector, which
                # compares samples a fixed time apart, goes on with the last sample held;
                # a period it finds now is handed over at the next observed sample
                held = state.recent[(state.recent_count[0] - 1) % state.recent.shape[0]]
                _detect(settings, state, held.copy())
            else:
                detector_restart(state.detector)
                state.recent_count[0] = 0
    else:
        state.valid_run[0] += 1
        state.anchor_run[0] += 1
        state.gap_run[0] = 0
        if settings.start_up:
            period = _detect(settings, state, y)
    after_change = time < state.relock_until[0]
    if period > 0.0 and state.locked[0] == 1:
        disagreement = abs(state.omega[0] * period / (2.0 * math.pi) - 1.0)
        tolerance = settings.change_relock_tolerance if after_change else settings.relock_tolerance
        if not (tolerance > 0.0 and disagreement > tolerance):
            period = 0.0
    # 2. the canonical system
    if period > 0.0:
        _hand_over(settings, state, y, period, time, state.locked[0] == 1 and not after_change)
    elif not valid:
        for i in range(state.oscillators.phases.shape[0]):
            state.oscillators.phases[i] += state.oscillators.omegas[i] * dt
    else:
        _observe(settings, state, y)
    phase, omega_now = canonical_fundamental(settings, state)
    # 3. the fundamental, the tempo
    omega_array, mean, variance = state.scratch[6, :1], state.scratch[7, :1], state.scratch[7, 1:2]
    omega_array[0] = omega_now
    period_statistics(state.fundamental, omega_array, omega_now, dt, settings.statistics_periods,
                      mean, variance)
    omega = max(mean[0], settings.floor_omega)
    state.phase[0] = phase
    state.omega[0] = omega
    if state.locked[0] == 1:
        changes = state.tempo.changes[0]
        state.frequency_hz[0] = tempo_update(state.tempo, settings.tempo, time, phase,
                                             omega / (2.0 * math.pi))
        if state.tempo.changes[0] > changes:
            state.relock_until[0] = time + settings.change_relock_periods * 2.0 * math.pi / omega
    else:
        state.frequency_hz[0] = omega / (2.0 * math.pi)
    # 4. the weights
    if settings.regression == POSITIONS:
        if valid and period == 0.0:
            z = state.scratch[6]
            for j in range(y.shape[0]):
                z[j] = (y[j] - state.goal[j]) / state.amplitude[j] if state.moving[j] else 0.0
            position_fit_update(state.fit, phase, z[:y.shape[0]], omega * dt,
                                settings.memory_periods)
        if valid:
            position_fit_weights(state.fit, state.weights)
    else:
        _learn_lwr(settings, state, y, phase, omega, valid)
    # 5. the DMP
    if count > 0:
        f0, f_mid, f1 = state.scratch[0], state.scratch[1], state.scratch[2]
        dmp_step(state.output, state.velocity, state.goal, state.amplitude, state.weights,
                 settings.width, settings.centres, settings.alpha_s, settings.beta_s,
                 previous_phase, previous_omega, dt, settings.max_phase_step,
                 f0[:y.shape[0]], f_mid[:y.shape[0]], f1[:y.shape[0]])
    state.count[0] = count + 1


def step_entry_point(settings: KernelSettings, state: LearnerState):
    """:func:`learner_step` compiled for these settings and state (and y float64 (d,)
    contiguous, valid bool), as a function that skips numba's dispatch.

    A call through the dispatcher types every argument first: for the ~70 arrays of the
    state that is most of the cost of one sample (measured in ``benchmarks/bench_learn.py``).
    The entry point only unboxes them; it must be given arguments of exactly these types
    (``OnlineLearner.step`` checks y).
    """
    return learner_step.compile((typeof(settings), typeof(state), types.float64[::1],
                                 types.boolean))


@njit(cache=True)
def learner_run(settings: KernelSettings, state: LearnerState, Y, valid, output, phase,
                fundamental_hz, frequency_hz, oscillators_hz, hand_overs, snapshots,
                every: int) -> int:
    """:func:`learner_step` over Y (n, d) and valid (n,); fill the per-sample outputs
    (n, ...) and a weight snapshot every ``every`` samples (counted from the first ever);
    return the number of snapshots written."""
    written = 0
    for k in range(Y.shape[0]):
        count = state.count[0]
        learner_step(settings, state, Y[k], valid[k])
        output[k] = state.output
        phase[k] = state.phase[0]
        fundamental_hz[k] = state.omega[0] / (2.0 * math.pi)
        frequency_hz[k] = state.frequency_hz[0]
        hand_overs[k] = state.hand_overs[0]
        for i in range(state.oscillators.omegas.shape[0]):
            oscillators_hz[k, i] = abs(state.oscillators.omegas[i]) / (2.0 * math.pi)
        if count % every == 0:
            snapshots[written] = state.weights
            written += 1
    return written


forget_stale_kernels(__name__)
