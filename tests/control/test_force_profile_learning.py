"""Online force-profile learning (eqs. 13-15) and its convergence criterion."""

import math

import numpy as np
import pytest

from wipelab.control import (COMPARISON_PHASES, ConvergenceMonitor, ForceProfileLearner,
                             ProfileLearningParams)
from wipelab.learning import default_width


def height(phase):
    return 0.85 + 0.02 * np.sin(phase) + 0.006 * np.cos(2 * phase)


def test_learns_a_periodic_height_profile_in_a_few_periods():
    dt, omega = 1 / 120, 2 * math.pi * 0.25
    learner = ForceProfileLearner(25, default_width(25), 12.0, 3.0, goal=0.9, amplitude=1.0,
                                  dt=dt)
    monitor = ConvergenceMonitor(ProfileLearningParams(tolerance=0.001))
    phase, period_end = 0.0, 2 * math.pi
    while monitor.periods_ < 6 and not monitor.converged:
        phase += omega * dt
        learner.update(height(phase), phase, omega)
        if phase >= period_end:
            period_end += 2 * math.pi
            monitor.end_of_period(learner.waveform(COMPARISON_PHASES))
    assert monitor.converged and monitor.periods_ <= 3
    error = learner.waveform(COMPARISON_PHASES) - height(COMPARISON_PHASES)
    # the locally constant fit of eqs. 13-15 smooths the profile by about a kernel width
    assert np.max(np.abs(error)) < 0.002
    assert np.sqrt(np.mean(error ** 2)) < 0.0012


def test_convergence_needs_min_periods_and_small_changes():
    monitor = ConvergenceMonitor(ProfileLearningParams(tolerance=0.002, min_periods=2,
                                                       stable_periods=1))
    wave = np.zeros(8)
    assert math.isinf(monitor.end_of_period(wave))
    assert not monitor.converged
    assert monitor.end_of_period(wave + 0.005) == pytest.approx(0.005)
    assert not monitor.converged
    monitor.end_of_period(wave + 0.006)
    assert monitor.converged


def test_reference_choice_is_checked():
    assert ProfileLearningParams().reference == "learned"
    assert ProfileLearningParams(reference="start").reference == "start"
    with pytest.raises(ValueError, match="reference must be one of start, learned"):
        ProfileLearningParams(reference="surface")


def _reference_weights(heights, phases, omegas, dt, params, n_kernels, width, goal):
    """Per-sample learning with the learning package's numpy pieces (the reference the
    compiled learner must match)."""
    from wipelab.learning import IncrementalLWR, forcing_target, kernel_activations
    from wipelab.learning.derivatives import CentredDerivatives

    lwr = IncrementalLWR(n_kernels, 1, forgetting=params.forgetting)
    derivatives = CentredDerivatives(1, dt, params.derivative_window, degree=3, max_window=1001)
    for height_k, phase, omega in zip(heights, phases, omegas):
        derivatives.push(np.array([height_k]), phase, omega)
        estimate = derivatives.centre(omega)
        if estimate is None:
            continue
        y, yd, ydd, centre_phase, centre_omega = estimate
        target = forcing_target(y, yd, ydd, centre_omega, goal, 12.0, 3.0)
        lwr.update(kernel_activations(centre_phase, n_kernels, width), np.array([1.0]), target)
    return lwr.weights_[0]


def test_compiled_learning_matches_the_per_sample_reference():
    """Queued samples learned in one compiled pass give the weights of learning each sample
    at once with the numpy reference: across a change of Omega (a new fit window), beyond the
    fit's history limit, whenever the weights are read."""
    dt, n_kernels, goal = 1 / 120, 50, 0.9
    width = default_width(n_kernels)
    params = ProfileLearningParams(derivative_window=0.3)   # windows of 73 and 145 samples
    omegas = np.concatenate([np.full(1500, 2 * math.pi * 0.5), np.full(1500, 2 * math.pi * 0.25)])
    phases = np.cumsum(omegas * dt)
    rng = np.random.default_rng(1)
    heights = height(phases) + rng.normal(scale=1e-4, size=phases.size)
    learner = ForceProfileLearner(n_kernels, width, 12.0, 3.0, goal, 1.0, dt, params)
    reads = {100, 1000, 1001, 2222}
    for k, (h, phase, omega) in enumerate(zip(heights, phases, omegas)):
        learner.update(h, phase, omega)
        if k in reads:
            assert learner.weights_ == pytest.approx(_reference_weights(
                heights[:k + 1], phases[:k + 1], omegas[:k + 1], dt, params, n_kernels, width,
                goal), rel=1e-9, abs=1e-12)
    expected = _reference_weights(heights, phases, omegas, dt, params, n_kernels, width, goal)
    assert np.abs(expected).max() > 0.1
    assert learner.weights_ == pytest.approx(expected, rel=1e-9, abs=1e-12)
