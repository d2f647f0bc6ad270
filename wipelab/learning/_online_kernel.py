"""The online learner's per-sample loop compiled with numba (the fast path of learn_online).

It runs exactly the algorithm of :class:`wipelab.learning.online.OnlineLearner`, which
composes the numpy reference classes (normaliser, canonical system, period statistics,
centred derivatives, IncrementalLWR, PeriodicDMP); tests hold the two to the same outputs.
Fused into one loop over samples, a step costs a few microseconds instead of ~200 us.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from wipelab.learning.derivatives import MIN_WINDOW, savgol_centre_coefficients
from wipelab.learning._dmp_kernel import dmp_step
from wipelab.learning.dmp import max_phase_step
from wipelab.learning.kernels import kernel_centres
from wipelab.learning.normalise import CLIP, WARM
from wipelab.learning.online import OnlineParameters, anchor_capacity
from wipelab.learning.oscillators import R_FADE, REFERENCE_OMEGA, substep_count

AFS, AFO = 0, 1

# Indices into the float parameter vector.
F_K, F_KW, F_NU, F_SCALE, F_MIN_OMEGA, F_MAX_OMEGA, F_ZERO_OMEGA, F_DWELL, F_NORM_RATE, \
    F_NORM_OFFSET, F_ALPHA, F_BETA, F_LAMBDA, F_WIDTH, F_WINDOW_PERIODS, F_FLOOR_OMEGA, \
    F_MAX_PHASE_STEP, F_STAT_PERIODS, F_FORGET_SAMPLES = range(19)
# Indices into the integer parameter vector.
I_KIND, I_REFERENCE, I_MEAN, I_NSUB, I_MAX_WINDOW, I_CAPACITY, I_EVERY = range(7)
# Indices into the scalar state vector.
S_COUNT, S_PREV_PHASE, S_PREV_OMEGA, S_OMEGA, S_ZERO_TIME, S_RESETS, S_STATS_COUNT, \
    S_DERIV_COUNT = range(8)


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
def _canonical_substep(kind, fp, ip, u, h, dt, phases, omegas, alpha, beta, error, drive,
                       cosines, sines):
    """One Euler substep of the AFS (alpha, beta: (d, M + 1)) or AFO pool (alpha, beta: (d, 3)).

    cosines, sines: scratch arrays of length M + 1 (or 3).
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
        sin_phi, cos_phi = math.sin(phases[i]), math.cos(phases[i])
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
def _prefix(sums, count, back, out):
    """Copy the prefix sum ending ``back`` samples before the newest into out (zeros before start)."""
    index = count - 1 - back
    if index < 0:
        out[:] = 0.0
    else:
        out[:] = sums[index % sums.shape[0]]


@njit(cache=True)
def _run(Y, offset, dt, fp, ip, scalars, previous_u, norm_high, norm_low, norm_seen, phases, omegas,
         initial_omegas, alpha, beta, stats_reference, sums, squares, values, value_phases,
         value_omegas, savgol, weights, P, dmp_y, dmp_s, goal, amplitude, centres,
         out_y, out_phase, out_fundamental, out_oscillators, snapshots):
    """Process Y (n, d) sample by sample; returns the number of weight snapshots written."""
    n, n_dofs = Y.shape
    kind = ip[I_KIND]
    n_sub = ip[I_NSUB]
    h = dt / n_sub
    capacity = ip[I_CAPACITY]
    max_window = ip[I_MAX_WINDOW]
    n_kernels = centres.shape[0]
    width = fp[F_WIDTH]
    u = np.empty(n_dofs)
    uj = np.empty(n_dofs)
    error = np.empty(n_dofs)
    drive = np.empty(phases.shape[0])
    cosines = np.empty(alpha.shape[1])
    sines = np.empty(alpha.shape[1])
    extended = np.empty(n_dofs + 1)
    last_sum = np.empty(n_dofs + 1)
    last_square = np.empty(n_dofs + 1)
    s0 = np.empty(n_dofs + 1)
    q0 = np.empty(n_dofs + 1)
    s1 = np.empty(n_dofs + 1)
    q1 = np.empty(n_dofs + 1)
    psi = np.empty(n_kernels)
    f0 = np.empty(n_dofs)
    f_mid = np.empty(n_dofs)
    f1 = np.empty(n_dofs)
    written = 0
    for k in range(n):
        y = Y[k]
        count = int(scalars[S_COUNT])
        # 1. running normaliser
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
        if count == 0:
            previous_u[:] = u
            dmp_y[:] = y
            dmp_s[:] = 0.0
        # 2. canonical system over the sample interval
        for j in range(1, n_sub + 1):
            for d in range(n_dofs):
                uj[d] = previous_u[d] + j / n_sub * (u[d] - previous_u[d])
            _canonical_substep(kind, fp, ip, uj, h, dt, phases, omegas, alpha, beta, error, drive,
                               cosines, sines)
        previous_u[:] = u
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
        phase, omega_now = _fundamental(kind, phases, omegas)
        # 3. period statistics: anchor, amplitude and the mean phase rate
        extended[:n_dofs] = y
        extended[n_dofs] = omega_now
        stats_count = int(scalars[S_STATS_COUNT])
        if stats_count == 0:
            stats_reference[:] = extended
        _prefix(sums, stats_count, 0, last_sum)
        _prefix(squares, stats_count, 0, last_square)
        slot = stats_count % capacity
        for d in range(n_dofs + 1):
            z = extended[d] - stats_reference[d]
            sums[slot, d] = last_sum[d] + z
            squares[slot, d] = last_square[d] + z * z
        stats_count += 1
        scalars[S_STATS_COUNT] = stats_count
        window = min(fp[F_STAT_PERIODS] * 2.0 * math.pi / (max(omega_now, 1e-12) * dt), float(stats_count),
                     float(capacity - 2))
        whole = int(window)
        fraction = window - whole
        _prefix(sums, stats_count, whole, s0)
        _prefix(squares, stats_count, whole, q0)
        _prefix(sums, stats_count, whole + 1, s1)
        _prefix(squares, stats_count, whole + 1, q1)
        _prefix(sums, stats_count, 0, last_sum)
        _prefix(squares, stats_count, 0, last_square)
        for d in range(n_dofs + 1):
            total = (last_sum[d] - s0[d]) + fraction * (s0[d] - s1[d])
            total_square = (last_square[d] - q0[d]) + fraction * (q0[d] - q1[d])
            mean = total / window
            variance = max(total_square / window - mean * mean, 0.0)
            if d < n_dofs:
                goal[d] = stats_reference[d] + mean
                spread = math.sqrt(2.0 * variance)
                amplitude[d] = spread if spread > 0.0 else 1.0
            else:
                omega = max(stats_reference[d] + mean, fp[F_FLOOR_OMEGA])
        scalars[S_OMEGA] = omega
        # 4. centred derivatives and the LWR update
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
        if deriv_count >= window_length:
            table = (window_length - MIN_WINDOW) // 2
            first = deriv_count - window_length
            centre = (first + (window_length - 1) // 2) % max_window
            phase_c = value_phases[centre]
            omega_c = value_omegas[centre]
            for i in range(n_kernels):
                psi[i] = math.exp(width * (math.cos(phase_c - centres[i]) - 1.0))
            forgetting = fp[F_LAMBDA]
            if fp[F_FORGET_SAMPLES] > 0.0:
                forgetting = fp[F_LAMBDA] ** (omega_c * dt * fp[F_FORGET_SAMPLES] / (2.0 * math.pi))
            for d in range(n_dofs):
                yc = 0.0
                ydc = 0.0
                yddc = 0.0
                for j in range(window_length):
                    v = values[(first + j) % max_window, d]
                    yc += savgol[table, 0, j] * v
                    ydc += savgol[table, 1, j] * v
                    yddc += savgol[table, 2, j] * v
                ydc /= dt
                yddc /= dt * dt
                f_target = yddc / omega_c ** 2 - fp[F_ALPHA] * (fp[F_BETA] * (goal[d] - yc) - ydc / omega_c)
                f_target /= amplitude[d]                      # regressed in units of r (r = 1)
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
        self.fp = np.zeros(19)
        self.fp[F_FORGET_SAMPLES] = p.forgetting_samples_per_period or 0.0
        self.fp[F_STAT_PERIODS] = p.statistics_periods
        self.fp[[F_K, F_KW, F_NU, F_SCALE]] = (c.coupling, c.frequency_coupling, c.learning_rate,
                                               float(c.scale_with_frequency))
        self.fp[F_MAX_OMEGA] = 2.0 * math.pi * c.max_frequency_hz
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
        capacity = anchor_capacity(dt, p)
        self.ip = np.zeros(7, dtype=np.int64)
        self.ip[[I_KIND, I_REFERENCE, I_MEAN, I_NSUB, I_MAX_WINDOW, I_CAPACITY]] = (
            self.kind, reference_dof, int(p.dof_coupling == "mean"), substep_count(dt, p.substep_hz),
            p.max_derivative_window, capacity)
        self.scalars = np.zeros(8)
        self.previous_u = np.zeros(n_dofs)
        self.norm_high = np.zeros(n_dofs)
        self.norm_low = np.zeros(n_dofs)
        self.norm_seen = np.zeros((n_dofs, 2), dtype=np.bool_)
        self.phases = np.zeros(n_osc)
        self.omegas = initial.copy()
        self.initial_omegas = initial
        self.alpha = np.zeros((n_dofs, n_coef))
        self.beta = np.zeros((n_dofs, n_coef))
        self.stats_reference = np.zeros(n_dofs + 1)
        self.sums = np.zeros((capacity, n_dofs + 1))
        self.squares = np.zeros((capacity, n_dofs + 1))
        w = p.max_derivative_window
        self.values = np.zeros((w, n_dofs))
        self.value_phases = np.zeros(w)
        self.value_omegas = np.zeros(w)
        self.savgol = np.zeros(((w - MIN_WINDOW) // 2 + 1, 3, w))
        for index, length in enumerate(range(MIN_WINDOW, w + 1, 2)):
            self.savgol[index, :, :length] = savgol_centre_coefficients(length, p.derivative_degree)
        self.weights_ = np.zeros((n_dofs, p.kernels))
        self.P = np.full((n_dofs, p.kernels), float(p.p0))
        self.dmp_y = np.zeros(n_dofs)
        self.dmp_s = np.zeros(n_dofs)
        self.goal_ = np.zeros(n_dofs)
        self.amplitude_ = np.ones(n_dofs)
        self.centres = kernel_centres(p.kernels)

    @property
    def omega_(self) -> float:
        return float(self.scalars[S_OMEGA])

    def process(self, Y, out_y, out_phase, out_fundamental, out_oscillators, every: int) -> list:
        """Learn from Y (n, d); fill the per-sample outputs; return the weight snapshots taken."""
        self.ip[I_EVERY] = every
        count = int(self.scalars[S_COUNT])
        n_snapshots = (count + Y.shape[0] - 1) // every - (count - 1) // every if count else \
            (Y.shape[0] - 1) // every + 1
        snapshots = np.empty((n_snapshots,) + self.weights_.shape)
        written = _run(np.ascontiguousarray(Y, dtype=np.float64), self.offset, self.dt, self.fp,
                       self.ip, self.scalars, self.previous_u, self.norm_high, self.norm_low, self.norm_seen,
                       self.phases, self.omegas, self.initial_omegas, self.alpha, self.beta,
                       self.stats_reference, self.sums, self.squares, self.values,
                       self.value_phases, self.value_omegas, self.savgol, self.weights_, self.P,
                       self.dmp_y, self.dmp_s, self.goal_, self.amplitude_, self.centres,
                       out_y, out_phase, out_fundamental, out_oscillators, snapshots)
        return list(snapshots[:written])
