"""Iterative learning of a height profile at a tempo, on a simulated contact (pure numpy)."""

import math

import numpy as np
import pytest

from wipelab.control.iterative_learning import (IterativeLearningParams, IterativeProfile,
                                                periodic_gaussian, phase_average,
                                                profile_phases)

DT = 1 / 120


def surface(phase):
    """The height (m) at which the sponge touches, along the path."""
    return 0.90 + 0.02 * np.sin(phase) + 0.008 * np.cos(3 * phase + 0.4)


def learn(stiffness: float, lag: float, frequency_hz: float, periods: int,
          params=IterativeLearningParams()):
    """Run the learning on a contact that pushes back with stiffness (N/m) times the
    penetration; the height follows its command ``lag`` seconds late (servo, filter); the
    profile starts 3 mm too low."""
    omega = 2 * math.pi * frequency_hz
    grid = profile_phases(params.grid)
    learning = IterativeProfile(surface(grid) - 0.003, omega, 10.0, params)
    phase, going_on = 0.0, True
    for _ in range(periods):
        end = phase + 2 * math.pi
        while phase < end:
            phase += omega * DT
            command = np.interp(phase - omega * lag, grid, learning.profile_, period=2 * math.pi)
            force = max(0.0, stiffness * (surface(phase) - command))
            learning.record(phase, force - 10.0)
        going_on = learning.end_of_period()
        if not going_on:
            break
    return learning


@pytest.mark.parametrize("stiffness", [800.0, 2000.0, 4000.0])
def test_force_error_falls_below_tolerance_whatever_the_contact_stiffness(stiffness):
    learning = learn(stiffness, lag=0.012, frequency_hz=1.0, periods=12)
    assert learning.errors_[0] > 2.0                     # pressing 3 mm too deep
    assert min(learning.errors_) < 0.5
    assert learning.stiffness_ == pytest.approx(stiffness, rel=0.3)


def test_stops_when_learned_and_keeps_the_best_profile():
    learning = learn(2000.0, lag=0.012, frequency_hz=1.0, periods=12)
    assert len(learning.errors_) < 12                    # stopped at the tolerance
    assert learning.errors_[-1] < IterativeLearningParams().tolerance
    grid = profile_phases(IterativeLearningParams().grid)
    # the best profile presses F0 / k_c below the surface, everywhere, a lag ahead of it
    pressed = surface(grid + 2 * math.pi * 1.0 * 0.012) - 10.0 / 2000.0
    assert np.max(np.abs(learning.best_ - pressed)) < 0.0005


def test_the_lead_compensates_the_lag_at_a_fast_tempo():
    """At 1.5 Hz a 40 ms lag turns the profile's third harmonic by 65 deg: learning without
    the lead barely corrects it, with the lead it is gone in a few periods."""
    with_lead = learn(2000.0, lag=0.04, frequency_hz=1.5, periods=8,
                      params=IterativeLearningParams(lead=0.04, tolerance=0.0, periods=8))
    without = learn(2000.0, lag=0.04, frequency_hz=1.5, periods=8,
                    params=IterativeLearningParams(lead=0.0, tolerance=0.0, periods=8))
    assert min(with_lead.errors_) < 0.5 * min(without.errors_)


def test_phase_average_and_gaussian_smoothing():
    phase = np.linspace(0, 4 * math.pi, 1000)
    averaged = phase_average(phase, np.sin(phase), 64)
    assert averaged == pytest.approx(np.sin(profile_phases(64)), abs=0.02)
    wave = np.sin(profile_phases(128)) + np.sin(20 * profile_phases(128))
    smooth = periodic_gaussian(wave, sigma=3.0)
    assert smooth == pytest.approx(np.sin(profile_phases(128)), abs=0.05)   # high harmonic gone
    assert periodic_gaussian(wave, 0.0) == pytest.approx(wave)
