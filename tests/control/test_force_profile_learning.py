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


def test_weights_do_not_depend_on_when_they_are_read():
    """Queued samples learned in one compiled pass when the weights are read give the weights
    of learning each sample at once (read after every update): across a change of Omega (a
    new fit window) and beyond the fit's history limit."""
    dt, n_kernels, goal = 1 / 120, 50, 0.9
    width = default_width(n_kernels)
    params = ProfileLearningParams(derivative_window=0.3)   # windows of 73 and 145 samples
    omegas = np.concatenate([np.full(1500, 2 * math.pi * 0.5), np.full(1500, 2 * math.pi * 0.25)])
    phases = np.cumsum(omegas * dt)
    rng = np.random.default_rng(1)
    heights = height(phases) + rng.normal(scale=1e-4, size=phases.size)
    every_sample, now_and_then, once = (ForceProfileLearner(n_kernels, width, 12.0, 3.0, goal,
                                                            1.0, dt, params) for _ in range(3))
    reads = {100, 1000, 1001, 2222}
    for k, (h, phase, omega) in enumerate(zip(heights, phases, omegas)):
        for learner in (every_sample, now_and_then, once):
            learner.update(h, phase, omega)
        at_once = every_sample.weights_
        if k in reads:
            np.testing.assert_array_equal(now_and_then.weights_, at_once)
    np.testing.assert_array_equal(once.weights_, every_sample.weights_)
    np.testing.assert_array_equal(now_and_then.weights_, every_sample.weights_)
    assert np.abs(once.weights_).max() > 0.1
    # the learned profile is the height's, after the change of Omega too
    error = once.waveform(COMPARISON_PHASES) - height(COMPARISON_PHASES)
    assert np.max(np.abs(error)) < 0.002
