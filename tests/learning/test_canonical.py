"""The canonical systems: AFS and the AFO pool find the fundamental; the pool's logic step."""

import math

import numpy as np
import pytest

from wipelab.learning import (AdaptiveFourierSeries, AdaptiveOscillatorPool, AFOParameters,
                              AFSParameters, OnlineParameters, learn_online)
from wipelab.learning.signals import periods_to_tolerance, wiping_signal


@pytest.mark.parametrize("canonical, frequency_hz, rate_hz", [
    ("afs", 1.0, 500.0), ("afs", 0.5, 30.0), ("afs", 2.5, 100.0),
    ("afo", 1.0, 500.0), ("afo", 2.0, 30.0),
])
def test_fundamental_within_1_percent_and_stays(canonical, frequency_hz, rate_hz):
    t = np.arange(0, 12 / frequency_hz, 1 / rate_hz)
    Y, _ = wiping_signal(t, frequency_hz, noise=0.02, seed=4)
    _, history = learn_online(t, Y, OnlineParameters(canonical=canonical))
    assert periods_to_tolerance(t, history.fundamental_hz, frequency_hz) <= 8.0


def test_afs_follows_a_frequency_step():
    t = np.arange(0, 24, 1 / 100)
    Y, _ = wiping_signal(t, 1.0, seed=5, step_time_s=12.0, step_frequency_hz=1.25)
    _, history = learn_online(t, Y, OnlineParameters())
    assert periods_to_tolerance(t, history.fundamental_hz, 1.25, start_s=12.0) <= 8.0


def test_afs_learns_the_fourier_series_of_a_clean_signal():
    afs = AdaptiveFourierSeries(1, AFSParameters(initial_frequency_hz=1.1))
    dt = 0.002
    t = np.arange(0, 30, dt)
    u = np.cos(2 * np.pi * t) + 0.3 * np.cos(4 * np.pi * t + 0.5)
    for k in range(1, t.size):
        afs.advance(u[k - 1:k], u[k:k + 1], dt, 1)
    assert afs.omega_ == pytest.approx(2 * np.pi, rel=2e-3)
    assert afs.alpha_[0, 1] == pytest.approx(1.0, abs=0.05) and afs.beta_[0, 1] == 0.0
    assert math.hypot(afs.alpha_[0, 2], afs.beta_[0, 2]) == pytest.approx(0.3, abs=0.05)


def test_afo_pool_reports_the_middle_frequency_and_resets_when_two_sit_at_zero():
    pool = AdaptiveOscillatorPool(1, AFOParameters(reset_dwell_s=0.5))
    pool.omegas_ = np.array([0.01, -0.02, 2 * np.pi * 1.3])
    pool.phases_ = np.array([0.0, 1.0, 2.0])
    assert pool.fundamental == (pytest.approx(-1.0), pytest.approx(0.02))
    constant = np.array([1.0])
    steps = 0
    while pool.resets_ == 0 and steps < 100:
        pool.advance(constant, constant, 0.01, 1)
        steps += 1
    assert steps == 50                                               # after the 0.5 s dwell
    np.testing.assert_allclose(pool.omegas_, 2 * np.pi * np.array(AFOParameters().initial_frequencies_hz))


def test_paper_gains_warp_the_phase_at_low_frequency():
    """K = 20 exceeds Omega at 0.3 Hz: the published constant gains do not settle there."""
    t = np.arange(0, 12 / 0.3, 1 / 100)
    Y, _ = wiping_signal(t, 0.3, seed=2)
    _, paper = learn_online(t, Y, OnlineParameters(afs=AFSParameters.petric(), start_up=False))
    _, scaled = learn_online(t, Y, OnlineParameters(start_up=False))
    assert periods_to_tolerance(t, scaled.fundamental_hz, 0.3) < periods_to_tolerance(
        t, paper.fundamental_hz, 0.3)


def test_rejects_unknown_options():
    with pytest.raises(ValueError, match="dof_coupling"):
        AdaptiveFourierSeries(2, dof_coupling="sum")
    with pytest.raises(ValueError, match="M must be 3"):
        AdaptiveOscillatorPool(1, AFOParameters(initial_frequencies_hz=(0.1, 1.0)))
    with pytest.raises(ValueError, match="canonical"):
        OnlineParameters(canonical="pll")
