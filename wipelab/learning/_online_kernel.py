"""The online learner's per-sample loop compiled with numba (the fast path of learn_online).

It runs exactly the algorithm of :class:`wipelab.learning.online.OnlineLearner`, which
composes the numpy reference classes (normaliser, period detector, canonical system, period
statistics, centred derivatives, IncrementalLWR, PeriodicDMP); tests hold the two to the same
outputs. The start-up pieces that run once or rarely (the detector's difference sums and its
dip search, the series fit at the hand-over, the pool's locked state) are plain-loop
functions of their own modules, compiled here as they are. Fused into one loop over samples,
a step costs a few microseconds instead of ~200 us.

Numba's on-disk cache (``cache=True``) is refreshed when this file or any wipelab module it
uses changes (:mod:`wipelab.numba_cache`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from wipelab.learning._dmp_kernel import dmp_step
from wipelab.learning.afo import locked_pool
from wipelab.learning.derivatives import MIN_WINDOW, polynomial_fit_matrix
from wipelab.learning.dmp import max_phase_step
from wipelab.learning.harmonic import locked_series
from wipelab.learning.kernels import kernel_centres
from wipelab.learning.normalise import CLIP, WARM
from wipelab.learning.online import OnlineParameters, anchor_capacity, recent_capacity
from wipelab.learning.oscillators import R_FADE, REFERENCE_OMEGA, nearest_turn, substep_count
from wipelab.learning.period_detector import (DetectorLayout, add_block, compared_pairs,
                                              first_period_lag, stable_lag)
from wipelab.numba_cache import forget_stale_kernels

AFS, AFO = 0, 1

# Indices into the float parameter vector.
F_K, F_KW, F_NU, F_SCALE, F_MIN_OMEGA, F_MAX_OMEGA, F_ZERO_OMEGA, F_DWELL, F_NORM_RATE, \
    F_NORM_OFFSET, F_ALPHA, F_BETA, F_LAMBDA, F_WIDTH, F_WINDOW_PERIODS, F_FLOOR_OMEGA, \
    F_MAX_PHASE_STEP, F_STAT_PERIODS, F_FORGET_SAMPLES, F_CONFIRM, F_THRESHOLD, \
    F_UPDATE_SPACING, F_KAPPA, F_RESIDUAL_PERIODS, F_STABLE_PERIODS, F_TOLERANCE, \
    F_LOCKED_COUPLING, F_LOCK_SEARCH, F_RELOCK = range(29)
# Indices into the integer parameter vector.
I_KIND, I_REFERENCE, I_MEAN, I_NSUB, I_MAX_WINDOW, I_EVERY, I_START_UP, I_DECIMATION, \
    I_MIN_LAG, I_N_TERMS = range(10)
# Indices into the scalar state vector.
S_COUNT, S_PREV_PHASE, S_PREV_OMEGA, S_OMEGA, S_ZERO_TIME, S_RESETS, S_STATS_COUNT, \
    S_DERIV_COUNT, S_FREQ_COUNT, S_LOCKED, S_BLOCKS, S_IN_BLOCK, S_RECENT_COUNT, \
    S_CANONICAL_LOCKED, S_RESIDUAL, S_CANDIDATE, S_SINCE, S_VALID_RUN, S_HAND_OVERS = range(19)

_add_block = njit(cache=True)(add_block)
_first_period_lag = njit(cache=True)(first_period_lag)
_stable_lag = njit(cache=True)(stable_lag)
_locked_series = njit(cache=True)(locked_series)
_locked_pool = njit(cache=True)(locked_pool)
_nearest_turn = njit(cache=True)(nearest_turn)


@njit(cache=True)
def _fundamental(kind, phases, omegas):
    """(phase, Omega) of the canonical system: the AFS oscillator, or the pool's middle one."""
    if kind == AFS:
        return phases[0], omegas[0]
    a0, a1, a2 = abs(omegas[0]), abs(omegas[1]), abs(omegas[2])
    # stable argsort of three values, middle element
    order = [0, 1, 2]
    values = [a0, a1, a2]
    for i in range(3):
        for j in range(2 - i):
            if values[order[j]] > values[order[j + 1]]:
                order[j], order[j + 1] = order[j + 1], order[j]
    middle = order[1]
    sign = 1.0 if omegas[middle] >= 0.0 else -1.0
    return sign * phases[middle], abs(omegas[middle])


@njit(cache=True)
def _canonical_substep(kind, fp, ip, scalars, u, h, dt, phases, omegas, alpha, beta, error,
                       drive, cosines, sines):
    """One Euler substep of the AFS (alpha, beta: (d, M + 1)) or AFO pool (alpha, beta: (d, 3)).

    cosines, sines: scratch arrays of length M + 1 (or 3). scalars holds the lock flag and
    the residual E of the gain schedule.
    """
    n_dofs = u.shape[0]
    n_coef = alpha.shape[1]
    reference = ip[I_REFERENCE]
    m = 1.0
    if fp[F_SCALE] > 0.0:
        m = _fundamental(kind, phases, omegas)[1] / REFERENCE_OMEGA
    n_osc = phases.shape[0]
    n_terms = n_coef
    if kind == AFS:
        # Terms at or above the Nyquist frequency of the samples cannot be observed: off.
        n_terms = 0
        while n_terms < n_coef and n_terms * omegas[0] * dt < math.pi:
            n_terms += 1
    cos_phi, sin_phi = 0.0, 0.0
    if kind == AFS:
        # cos(c phi), sin(c phi) by the angle-addition recurrence: two trig calls, not 2 M.
        cos_phi, sin_phi = math.cos(phases[0]), math.sin(phases[0])
        cosines[0], sines[0] = 1.0, 0.0
        for c in range(1, n_terms):
            cosines[c] = cosines[c - 1] * cos_phi - sines[c - 1] * sin_phi
            sines[c] = sines[c - 1] * cos_phi + cosines[c - 1] * sin_phi
    else:
        for c in range(n_terms):
            cosines[c] = math.cos(phases[c])
            sines[c] = math.sin(phases[c])
    for d in range(n_dofs):
        prediction = 0.0
        for c in range(n_terms):
            prediction += alpha[d, c] * cosines[c] + beta[d, c] * sines[c]
        error[d] = u[d] - prediction
    for i in range(n_osc):
        column = 1 if kind == AFS else i
        if kind == AFO:                                   # the AFS's are still those of phi
            cos_phi, sin_phi = cosines[i], sines[i]
        total = error[reference] * sin_phi
        weight = 1.0
        if ip[I_MEAN] == 1:
            for d in range(n_dofs):
                if d != reference:
                    a, b = alpha[d, column], beta[d, column]
                    amplitude = math.hypot(a, b)
                    total += error[d] * (a * sin_phi - b * cos_phi) / (amplitude + R_FADE)
                    weight += amplitude / (amplitude + R_FADE)
        drive[i] = total / weight
    if scalars[S_CANONICAL_LOCKED] > 0.0:
        squares = 0.0
        for d in range(n_dofs):
            squares += error[d] * error[d]
        fundamental = _fundamental(kind, phases, omegas)[1]
        rate = min(h * fundamental / (2.0 * math.pi * fp[F_RESIDUAL_PERIODS]), 1.0)
        scalars[S_RESIDUAL] += rate * (squares / n_dofs - scalars[S_RESIDUAL])
        boost = fp[F_LOCKED_COUPLING] + fp[F_KAPPA] * scalars[S_RESIDUAL]
        for i in range(n_osc):
            drive[i] *= boost
    rate = h * fp[F_NU] * m
    for d in range(n_dofs):
        for c in range(n_terms):
            alpha[d, c] += rate * error[d] * cosines[c]
            beta[d, c] += rate * error[d] * sines[c]
    if kind == AFS:
        beta[reference, 1] = 0.0
    else:
        for c in range(n_coef):
            beta[reference, c] = 0.0
    for i in range(n_osc):
        phases[i] += h * (omegas[i] - fp[F_K] * m * drive[i])
        omega = omegas[i] - h * fp[F_KW] * m * m * drive[i]
        if kind == AFS:
            omegas[i] = min(max(omega, fp[F_MIN_OMEGA]), fp[F_MAX_OMEGA])
        else:
            omegas[i] = min(max(omega, -fp[F_MAX_OMEGA]), fp[F_MAX_OMEGA])


@njit(cache=True)
def _statistics(x, omega, dt, periods, count, reference, sums, squares, mean, variance):
    """PeriodStatistics.update in place: absorb x (k,), write the mean and variance over the
    last periods (fractional window) into mean and variance (k,); return the new count."""
    capacity = sums.shape[0]
    if count == 0:
        reference[:] = x
    slot = count % capacity
    previous = (count - 1) % capacity
    for j in range(x.shape[0]):
        z = x[j] - reference[j]
        sums[slot, j] = (sums[previous, j] if count > 0 else 0.0) + z
        squares[slot, j] = (squares[previous, j] if count > 0 else 0.0) + z * z
    count += 1
    window = min(periods * 2.0 * math.pi / (max(omega, 1e-12) * dt), float(count),
                 float(capacity - 2))
    whole = int(window)
    fraction = window - whole
    head = (count - 1) % capacity
    first = count - 1 - whole
    for j in range(x.shape[0]):
        s0 = sums[first % capacity, j] if first >= 0 else 0.0
        q0 = squares[first % capacity, j] if first >= 0 else 0.0
        s1 = sums[(first - 1) % capacity, j] if first >= 1 else 0.0
        q1 = squares[(first - 1) % capacity, j] if first >= 1 else 0.0
        total = (sums[head, j] - s0) + fraction * (s0 - s1)
        total_square = (squares[head, j] - q0) + fraction * (q0 - q1)
        average = total / window
        mean[j] = reference[j] + average
        variance[j] = max(total_square / window - average * average, 0.0)
    return count


@njit(cache=True)
def _normalise_locked(y, goal, amplitude, moving, offset, u):
    """u = (y - g) / r + offset (0 + offset for a DOF that does not move)."""
    for j in range(y.shape[0]):
        u[j] = ((y[j] - goal[j]) / amplitude[j] if moving[j] else 0.0) + offset


@njit(cache=True)
def _set_anchor(mean, variance, goal, amplitude, moving):
    """g = mean, r = sqrt(2 variance) (1 for a DOF that does not move)."""
    for j in range(mean.shape[0]):
        goal[j] = mean[j]
        spread = math.sqrt(2.0 * variance[j])
        moving[j] = spread > 0.0
        amplitude[j] = spread if spread > 0.0 else 1.0


@njit(cache=True)
def _run(Y, valid, offset, dt, fp, ip, scalars, previous_u, norm_high, norm_low, norm_seen, phases, omegas,
         initial_omegas, alpha, beta, stats_reference, sums, squares, frequency_reference,
         frequency_sums, frequency_squares, blocks, block_sums, block_pairs, block_accumulated,
         recent, values, value_phases, value_omegas, fit_matrices, weights, P, dmp_y, dmp_s, goal,
         amplitude, moving, centres, out_y, out_phase, out_fundamental, out_oscillators,
         out_hand_overs, snapshots):
    """Process Y (n, d) sample by sample (rows not ``valid`` are gaps); returns the number of
    weight snapshots written."""
    n, n_dofs = Y.shape
    kind = ip[I_KIND]
    n_sub = ip[I_NSUB]
    h = dt / n_sub
    max_window = ip[I_MAX_WINDOW]
    n_kernels = centres.shape[0]
    width = fp[F_WIDTH]
    degree_terms = fit_matrices.shape[1]
    u = np.empty(n_dofs)
    uj = np.empty(n_dofs)
    error = np.empty(n_dofs)
    drive = np.empty(phases.shape[0])
    cosines = np.empty(alpha.shape[1])
    sines = np.empty(alpha.shape[1])
    mean = np.empty(n_dofs)
    variance = np.empty(n_dofs)
    omega_now_array = np.empty(1)
    omega_mean = np.empty(1)
    omega_variance = np.empty(1)
    block = np.empty(n_dofs)
    coefficients = np.empty((degree_terms, n_dofs))
    psi = np.empty(n_kernels)
    f0 = np.empty(n_dofs)
    f_mid = np.empty(n_dofs)
    f1 = np.empty(n_dofs)
    written = 0
    for k in range(n):
        y = Y[k]
        count = int(scalars[S_COUNT])
        locked = scalars[S_LOCKED] > 0.0
        if count == 0:
            dmp_y[:] = y
            dmp_s[:] = 0.0
        # 1. the period detector: the start-up, then the supervisor (hand over again when the
        #    fundamental strays from the period it holds); a gap restarts it
        found = 0.0
        if not valid[k]:
            if scalars[S_VALID_RUN] > 0.0 and ip[I_START_UP] == 1:
                blocks[:] = 0.0
                block_sums[:] = 0.0
                block_accumulated[:] = 0.0
                for index in (S_BLOCKS, S_IN_BLOCK, S_CANDIDATE, S_SINCE, S_RECENT_COUNT):
                    scalars[index] = 0.0
            scalars[S_VALID_RUN] = 0.0
        elif ip[I_START_UP] == 1:
            scalars[S_VALID_RUN] += 1.0
            recent_count = int(scalars[S_RECENT_COUNT])
            recent[recent_count % recent.shape[0]] = y
            scalars[S_RECENT_COUNT] = recent_count + 1
            for j in range(n_dofs):
                block_accumulated[j] += y[j]
            in_block = int(scalars[S_IN_BLOCK]) + 1
            if in_block < ip[I_DECIMATION]:
                scalars[S_IN_BLOCK] = in_block
            else:
                for j in range(n_dofs):
                    block[j] = block_accumulated[j] / in_block
                    block_accumulated[j] = 0.0
                scalars[S_IN_BLOCK] = 0.0
                n_blocks = int(scalars[S_BLOCKS])
                _add_block(blocks, block_sums, block_pairs, n_blocks, block)
                scalars[S_BLOCKS] = n_blocks + 1
                lag = _first_period_lag(block_sums, block_pairs, n_blocks + 1, ip[I_MIN_LAG],
                                        fp[F_THRESHOLD])
                candidate, since, stable = _stable_lag(lag, scalars[S_CANDIDATE],
                                                       int(scalars[S_SINCE]), n_blocks + 1,
                                                       fp[F_STABLE_PERIODS], fp[F_TOLERANCE])
                scalars[S_CANDIDATE] = candidate
                scalars[S_SINCE] = since
                if stable:
                    period = lag * dt * ip[I_DECIMATION]
                    if not locked or (fp[F_RELOCK] > 0.0 and abs(scalars[S_OMEGA] * period
                                                                 / (2.0 * math.pi) - 1.0)
                                      > fp[F_RELOCK]):
                        found = period
        else:
            scalars[S_VALID_RUN] += 1.0
        if found > 0.0:
            # 2a. hand-over: the canonical system starts from the detected period
            omega0 = 2.0 * math.pi / found
            scalars[S_STATS_COUNT] = _statistics(y, omega0, dt, fp[F_STAT_PERIODS],
                                                 int(scalars[S_STATS_COUNT]), stats_reference,
                                                 sums, squares, mean, variance)
            _set_anchor(mean, variance, goal, amplitude, moving)
            recent_count = int(scalars[S_RECENT_COUNT])
            fit_count = min(recent_count, int(round((1.0 + fp[F_CONFIRM]) * found / dt)))
            window_u = np.empty((fit_count, n_dofs))
            for i in range(fit_count):
                _normalise_locked(recent[(recent_count - fit_count + i) % recent.shape[0]], goal,
                                  amplitude, moving, offset, window_u[i])
            omega0, phase0, series_alpha, series_beta = _locked_series(
                window_u, dt, omega0, ip[I_N_TERMS], ip[I_REFERENCE], fp[F_LOCK_SEARCH])
            phase0 += omega0 * h                       # a settled oscillator leads by one substep
            if kind == AFS:
                omegas[0] = omega0
                phases[0] += _nearest_turn(phase0 - phases[0])
                alpha[:] = series_alpha
                beta[:] = series_beta
            else:
                pool_omegas, pool_phases, pool_alpha, pool_beta = _locked_pool(
                    omega0, phase0, series_alpha, series_beta, ip[I_REFERENCE])
                for i in range(3):
                    phases[i] += _nearest_turn(pool_phases[i] - phases[i])
                    omegas[i] = pool_omegas[i]
                alpha[:] = pool_alpha
                beta[:] = pool_beta
                scalars[S_ZERO_TIME] = 0.0
            scalars[S_FREQ_COUNT] = 0.0
            scalars[S_LOCKED] = 1.0
            scalars[S_CANONICAL_LOCKED] = 1.0
            scalars[S_RESIDUAL] = 0.0
            scalars[S_HAND_OVERS] += 1.0
            u[:] = window_u[fit_count - 1]
            previous_u[:] = u
        elif not valid[k]:
            # 2c. a gap: the canonical system runs on at its frequency, learning nothing
            for i in range(phases.shape[0]):
                phases[i] += omegas[i] * dt
        else:
            # 2b. anchor and amplitude, normalised input, canonical system over the interval
            scalars[S_STATS_COUNT] = _statistics(y, _fundamental(kind, phases, omegas)[1], dt,
                                                 fp[F_STAT_PERIODS], int(scalars[S_STATS_COUNT]),
                                                 stats_reference, sums, squares, mean, variance)
            _set_anchor(mean, variance, goal, amplitude, moving)
            if locked:
                _normalise_locked(y, goal, amplitude, moving, offset, u)
            else:
                for d in range(n_dofs):
                    if count == 0:
                        norm_high[d] = y[d]
                        norm_low[d] = y[d]
                    decay = (norm_high[d] - norm_low[d]) * fp[F_NORM_RATE]
                    norm_high[d] = max(y[d], norm_high[d] - decay)
                    norm_low[d] = min(y[d], norm_low[d] + decay)
                    half = 0.5 * (norm_high[d] - norm_low[d])
                    value = (y[d] - 0.5 * (norm_high[d] + norm_low[d])) / half if half > 0.0 else 0.0
                    if value < -WARM:
                        norm_seen[d, 0] = True
                    if value > WARM:
                        norm_seen[d, 1] = True
                    if not (norm_seen[d, 0] and norm_seen[d, 1]):
                        value = 0.0
                    u[d] = min(max(value, -CLIP), CLIP) + offset
            if scalars[S_VALID_RUN] == 1.0:           # the first sample, or the first after a gap
                previous_u[:] = u
            for j in range(1, n_sub + 1):
                for d in range(n_dofs):
                    uj[d] = previous_u[d] + j / n_sub * (u[d] - previous_u[d])
                _canonical_substep(kind, fp, ip, scalars, uj, h, dt, phases, omegas, alpha, beta,
                                   error, drive, cosines, sines)
            if kind == AFO:
                near_zero = 0
                for i in range(3):
                    if abs(omegas[i]) < fp[F_ZERO_OMEGA]:
                        near_zero += 1
                scalars[S_ZERO_TIME] = scalars[S_ZERO_TIME] + dt if near_zero > 1 else 0.0
                if scalars[S_ZERO_TIME] >= fp[F_DWELL]:
                    omegas[:] = initial_omegas
                    alpha[:] = 0.0
                    beta[:] = 0.0
                    scalars[S_ZERO_TIME] = 0.0
                    scalars[S_RESETS] += 1.0
                    scalars[S_CANONICAL_LOCKED] = 0.0
            previous_u[:] = u
        phase, omega_now = _fundamental(kind, phases, omegas)
        # 3. the fundamental: Omega averaged over the last period (since the hand-over)
        omega_now_array[0] = omega_now
        scalars[S_FREQ_COUNT] = _statistics(omega_now_array, omega_now, dt, fp[F_STAT_PERIODS],
                                            int(scalars[S_FREQ_COUNT]), frequency_reference,
                                            frequency_sums, frequency_squares, omega_mean,
                                            omega_variance)
        omega = max(omega_mean[0], fp[F_FLOOR_OMEGA])
        scalars[S_OMEGA] = omega
        # 4. centred derivatives, evaluated between samples, and the LWR updates
        deriv_count = int(scalars[S_DERIV_COUNT])
        slot = deriv_count % max_window
        values[slot] = y
        value_phases[slot] = phase
        value_omegas[slot] = omega
        deriv_count += 1
        scalars[S_DERIV_COUNT] = deriv_count
        samples = fp[F_WINDOW_PERIODS] * 2.0 * math.pi / (max(omega, 1e-12) * dt)
        window_length = 2 * int(round((samples - 1.0) / 2.0)) + 1
        window_length = min(max(window_length, MIN_WINDOW), max_window)
        points = 1
        if fp[F_UPDATE_SPACING] > 0.0:
            spacing = fp[F_UPDATE_SPACING] * 2.0 * math.pi / n_kernels
            points = max(1, int(math.ceil(omega * dt / spacing - 1e-9)))
        if scalars[S_VALID_RUN] >= window_length:     # no gap in the window
            table = (window_length - MIN_WINDOW) // 2
            first = deriv_count - window_length
            centre = (first + (window_length - 1) // 2) % max_window
            omega_c = value_omegas[centre]
            forgetting = fp[F_LAMBDA]
            if fp[F_FORGET_SAMPLES] > 0.0:
                forgetting = fp[F_LAMBDA] ** (omega_c * dt / points * fp[F_FORGET_SAMPLES]
                                              / (2.0 * math.pi))
            # Only c_0..c_2 matter at the centre (x = 0): value, slope and curvature.
            terms = degree_terms if points > 1 else min(3, degree_terms)
            coefficients[:] = 0.0
            slot = first % max_window
            for j in range(window_length):
                for d in range(n_dofs):
                    v = values[slot, d]
                    for q in range(terms):
                        coefficients[q, d] += fit_matrices[table, q, j] * v
                slot = slot + 1 if slot + 1 < max_window else 0
            for point in range(points):
                x = (point + 0.5) / points - 0.5
                phase_c = value_phases[centre] + x * omega_c * dt
                for i in range(n_kernels):
                    psi[i] = math.exp(width * (math.cos(phase_c - centres[i]) - 1.0))
                for d in range(n_dofs):
                    yc = 0.0
                    ydc = 0.0
                    yddc = 0.0
                    power, below1, below2 = 1.0, 0.0, 0.0          # x^q, x^(q-1), x^(q-2)
                    for q in range(terms):
                        c = coefficients[q, d]
                        yc += c * power
                        ydc += q * c * below1
                        yddc += q * (q - 1) * c * below2
                        below2, below1, power = below1, power, power * x
                    ydc /= dt
                    yddc /= dt * dt
                    f_target = yddc / omega_c ** 2 - fp[F_ALPHA] * (fp[F_BETA] * (goal[d] - yc)
                                                                     - ydc / omega_c)
                    f_target /= amplitude[d]                  # regressed in units of r (r = 1)
                    for i in range(n_kernels):
                        e = f_target - weights[d, i]                                       # eq. 15
                        P[d, i] = P[d, i] / (forgetting + psi[i] * P[d, i])               # eq. 14
                        weights[d, i] += psi[i] * P[d, i] * e                              # eq. 13
        # 5. the DMP, with the weights learned so far
        if count > 0:
            dmp_step(dmp_y, dmp_s, goal, amplitude, weights, width, centres, fp[F_ALPHA], fp[F_BETA],
                     scalars[S_PREV_PHASE], scalars[S_PREV_OMEGA], dt, fp[F_MAX_PHASE_STEP],
                     f0, f_mid, f1)
        scalars[S_PREV_PHASE] = phase
        scalars[S_PREV_OMEGA] = omega
        scalars[S_COUNT] = count + 1
        out_y[k] = dmp_y
        out_phase[k] = phase
        out_fundamental[k] = omega / (2.0 * math.pi)
        out_hand_overs[k] = int(scalars[S_HAND_OVERS])
        for i in range(phases.shape[0]):
            out_oscillators[k, i] = abs(omegas[i]) / (2.0 * math.pi)
        if count % ip[I_EVERY] == 0:
            snapshots[written] = weights
            written += 1
    return written


class FastOnlineLearner:
    """The numba twin of :class:`wipelab.learning.online.OnlineLearner` (same constructor).

    Attributes
    ----------
    weights_ : ndarray, shape (d, N)
    goal_, amplitude_ : ndarray, shape (d,)
    omega_ : float
        Fundamental Omega (rad/s), the mean phase rate over the last period.
    """

    def __init__(self, n_dofs: int, dt: float, params: OnlineParameters = OnlineParameters(),
                 reference_dof: int = 0):
        p = params
        self.params = params
        self.dt = dt
        self.kind = AFS if p.canonical == "afs" else AFO
        c = p.afs if self.kind == AFS else p.afo
        self.offset = 0.0 if self.kind == AFS else 1.0
        n_osc = 1 if self.kind == AFS else 3
        n_coef = p.afs.n_terms + 1 if self.kind == AFS else 3
        layout = DetectorLayout.for_rate(dt, p.detector, p.min_frequency_hz, c.max_frequency_hz)
        self.fp = np.zeros(29)
        self.fp[F_FORGET_SAMPLES] = p.forgetting_samples_per_period or 0.0
        self.fp[F_STAT_PERIODS] = p.statistics_periods
        self.fp[[F_K, F_KW, F_NU, F_SCALE]] = (c.coupling, c.frequency_coupling, c.learning_rate,
                                               float(c.scale_with_frequency))
        self.fp[F_MAX_OMEGA] = 2.0 * math.pi * c.max_frequency_hz
        self.fp[[F_KAPPA, F_RESIDUAL_PERIODS, F_LOCKED_COUPLING]] = (c.residual_gain, c.residual_periods,
                                                                    c.locked_coupling)
        if self.kind == AFS:
            self.fp[F_MIN_OMEGA] = 2.0 * math.pi * c.min_frequency_hz
            initial = np.array([2.0 * math.pi * c.initial_frequency_hz])
        else:
            self.fp[F_ZERO_OMEGA] = 2.0 * math.pi * c.zero_frequency_hz
            self.fp[F_DWELL] = c.reset_dwell_s
            initial = 2.0 * math.pi * np.asarray(c.initial_frequencies_hz, dtype=np.float64)
        width = p.kernel_width
        self.fp[[F_NORM_RATE, F_NORM_OFFSET, F_ALPHA, F_BETA, F_LAMBDA, F_WIDTH, F_WINDOW_PERIODS,
                 F_FLOOR_OMEGA, F_MAX_PHASE_STEP]] = (
            dt / p.normaliser_time_constant_s, self.offset, p.alpha_s, p.beta_s, p.forgetting,
            width, p.derivative_window_periods, 2.0 * math.pi * p.min_frequency_hz,
            max_phase_step(width))
        self.fp[[F_CONFIRM, F_THRESHOLD, F_UPDATE_SPACING, F_STABLE_PERIODS, F_TOLERANCE]] = (
            p.detector.confirm, p.detector.threshold, p.update_spacing or 0.0,
            p.detector.stable_periods, p.detector.tolerance)
        self.fp[F_LOCK_SEARCH] = p.lock_search
        self.fp[F_RELOCK] = p.relock_tolerance or 0.0
        capacity = anchor_capacity(dt, p)
        self.ip = np.zeros(10, dtype=np.int64)
        self.ip[[I_KIND, I_REFERENCE, I_MEAN, I_NSUB, I_MAX_WINDOW]] = (
            self.kind, reference_dof, int(p.dof_coupling == "mean"), substep_count(dt, p.substep_hz),
            p.max_derivative_window)
        self.ip[[I_START_UP, I_DECIMATION, I_MIN_LAG, I_N_TERMS]] = (
            int(p.start_up), layout.decimation, layout.min_lag, p.afs.n_terms if self.kind == AFS else 3)
        self.scalars = np.zeros(19)
        self.previous_u = np.zeros(n_dofs)
        self.norm_high = np.zeros(n_dofs)
        self.norm_low = np.zeros(n_dofs)
        self.norm_seen = np.zeros((n_dofs, 2), dtype=np.bool_)
        self.phases = np.zeros(n_osc)
        self.omegas = initial.copy()
        self.initial_omegas = initial
        self.alpha = np.zeros((n_dofs, n_coef))
        self.beta = np.zeros((n_dofs, n_coef))
        self.stats_reference = np.zeros(n_dofs)
        self.sums = np.zeros((capacity, n_dofs))
        self.squares = np.zeros((capacity, n_dofs))
        self.frequency_reference = np.zeros(1)
        self.frequency_sums = np.zeros((capacity, 1))
        self.frequency_squares = np.zeros((capacity, 1))
        self.blocks = np.zeros((layout.capacity, n_dofs))
        self.block_sums = np.zeros(layout.max_lag + 1)
        self.block_pairs = compared_pairs(layout.max_lag, p.detector.confirm)
        self.block_accumulated = np.zeros(n_dofs)
        self.recent = np.zeros((recent_capacity(dt, p) if p.start_up else 1, n_dofs))
        w = p.max_derivative_window
        self.values = np.zeros((w, n_dofs))
        self.value_phases = np.zeros(w)
        self.value_omegas = np.zeros(w)
        self.fit_matrices = np.zeros(((w - MIN_WINDOW) // 2 + 1, p.derivative_degree + 1, w))
        for index, length in enumerate(range(MIN_WINDOW, w + 1, 2)):
            matrix = polynomial_fit_matrix(length, p.derivative_degree)
            self.fit_matrices[index, :matrix.shape[0], :length] = matrix
        self.weights_ = np.zeros((n_dofs, p.kernels))
        self.P = np.full((n_dofs, p.kernels), float(p.p0))
        self.dmp_y = np.zeros(n_dofs)
        self.dmp_s = np.zeros(n_dofs)
        self.goal_ = np.zeros(n_dofs)
        self.amplitude_ = np.ones(n_dofs)
        self.moving = np.zeros(n_dofs, dtype=np.bool_)
        self.centres = kernel_centres(p.kernels)

    @property
    def omega_(self) -> float:
        return float(self.scalars[S_OMEGA])

    @property
    def locked_(self) -> bool:
        """Whether the detected period has been handed to the canonical system."""
        return bool(self.scalars[S_LOCKED])

    @property
    def hand_overs_(self) -> int:
        """How often it has been (the start-up, then re-locks)."""
        return int(self.scalars[S_HAND_OVERS])

    def process(self, Y, valid, out_y, out_phase, out_fundamental, out_oscillators,
                out_hand_overs, every: int) -> list:
        """Learn from Y (n, d) (rows not ``valid`` are gaps); fill the per-sample outputs;
        return the weight snapshots taken."""
        self.ip[I_EVERY] = every
        count = int(self.scalars[S_COUNT])
        n_snapshots = (count + Y.shape[0] - 1) // every - (count - 1) // every if count else \
            (Y.shape[0] - 1) // every + 1
        snapshots = np.empty((n_snapshots,) + self.weights_.shape)
        written = _run(np.ascontiguousarray(Y, dtype=np.float64),
                       np.ascontiguousarray(valid, dtype=np.bool_), self.offset, self.dt, self.fp,
                       self.ip, self.scalars, self.previous_u, self.norm_high, self.norm_low,
                       self.norm_seen, self.phases, self.omegas, self.initial_omegas, self.alpha,
                       self.beta, self.stats_reference, self.sums, self.squares,
                       self.frequency_reference, self.frequency_sums, self.frequency_squares,
                       self.blocks, self.block_sums, self.block_pairs, self.block_accumulated,
                       self.recent,
                       self.values, self.value_phases, self.value_omegas, self.fit_matrices,
                       self.weights_, self.P, self.dmp_y, self.dmp_s, self.goal_, self.amplitude_,
                       self.moving, self.centres, out_y, out_phase, out_fundamental,
                       out_oscillators, out_hand_overs, snapshots)
        return list(snapshots[:written])


forget_stale_kernels(__name__)
