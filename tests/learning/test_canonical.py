"""The canonical systems: AFS and the AFO pool find the fundamental; the hand-over of a detected
period (locked series and pool); the gain schedule after it; the pool's logic step."""

import math

import numpy as np
import pytest

from wipelab.learning import (AFOParameters, AFSParameters, OnlineParameters, learn_online,
                              locked_series)
from wipelab.learning.afo import locked_pool, pool_fundamental, pool_logic_step, pool_substep
from wipelab.learning.afs import afs_lock, afs_substep
from wipelab.learning.harmonic import LOCK_NYQUIST_FRACTION
from wipelab.learning.signals import periods_to_tolerance, wiping_signal


@pytest.mark.parametrize("canonical, frequency_hz, rate_hz", [
    ("afs", 1.0, 500.0), ("afs", 0.5, 30.0), ("afs", 2.5, 100.0), ("afs", 3.0, 30.0),
    ("afo", 1.0, 500.0), ("afo", 2.0, 30.0),
])
def test_fundamental_within_1_percent_after_3_periods_and_stays(canonical, frequency_hz, rate_hz):
    t = np.arange(0, 12 / frequency_hz, 1 / rate_hz)
    Y, _ = wiping_signal(t, frequency_hz, noise=0.02, seed=4)
    _, history = learn_online(t, Y, OnlineParameters(canonical=canonical))
    assert periods_to_tolerance(t, history.fundamental_hz, frequency_hz) <= 3.0


def test_oscillators_alone_still_lock_when_no_period_is_detected():
    t = np.arange(0, 12, 1 / 500)
    Y, _ = wiping_signal(t, 1.0, seed=4)
    _, history = learn_online(t, Y, OnlineParameters(start_up=False))
    assert 3.0 < periods_to_tolerance(t, history.fundamental_hz, 1.0) <= 9.0


def test_afs_follows_a_frequency_step_faster_with_the_tempo_change_relock():
    """1 -> 1.25 Hz: with a change of tempo found, the detector's period is handed over again
    (2-2.5 periods); without, the AFS takes longer, unless the gain schedule speeds it up."""
    t = np.arange(0, 24, 1 / 100)
    Y, _ = wiping_signal(t, 1.0, seed=5, step_time_s=12.0, step_frequency_hz=1.25)
    unarmed = dict(change_threshold=None)
    scheduled = OnlineParameters(**unarmed, afs=AFSParameters(locked_coupling=0.5,
                                                              residual_gain=100.0))
    periods = [periods_to_tolerance(t, learn_online(t, Y, params)[1].fundamental_hz, 1.25,
                                    start_s=12.0)
               for params in (OnlineParameters(), scheduled, OnlineParameters(**unarmed))]
    assert periods[0] <= 2.5 and periods[1] <= 2.5 < periods[2] <= 3.5


def test_locked_series_finds_frequency_phase_and_coefficients():
    """u = 0.2 + cos(phi) + 0.3 cos(2 phi + 0.5) with phi = w t + 0.7; the DOF y lags by 1 rad."""
    dt, omega = 1 / 30, 2 * np.pi * 1.3
    t = dt * np.arange(-60, 1)
    phi = omega * t + 0.7
    U = np.column_stack([0.2 + np.cos(phi) + 0.3 * np.cos(2 * phi + 0.5), 0.5 * np.cos(phi - 1.0)])
    found, phase, alpha, beta = locked_series(U, dt, omega * 1.006, 10, 0, search=0.01)
    assert found == pytest.approx(omega, rel=1e-4)
    assert phase == pytest.approx(0.7, abs=1e-3)
    assert alpha[0, :3] == pytest.approx([0.2, 1.0, 0.3 * np.cos(0.5)], abs=2e-3)
    assert beta[0, :3] == pytest.approx([0.0, 0.0, -0.3 * np.sin(0.5)], abs=2e-3)
    assert (alpha[1, 1], beta[1, 1]) == pytest.approx((0.5 * np.cos(1.0), 0.5 * np.sin(1.0)), abs=2e-3)
    fitted = int(LOCK_NYQUIST_FRACTION * np.pi / (omega * dt))       # 4 at 1.3 Hz sampled at 30 Hz
    assert not alpha[:, fitted + 1:].any() and not beta[:, fitted + 1:].any()


def _afs_advance(state, gains, previous, current, dt):
    """One sample interval of the AFS with one Euler substep (input at its end)."""
    scratch = np.zeros((3, state.alpha.shape[1]))
    afs_substep(state, gains, np.asarray(current, dtype=float), dt, dt, 0, True,
                scratch[0, :len(current)], scratch[1], scratch[2])


def test_afs_holds_a_lock_on_the_series_of_its_input():
    dt, omega = 0.002, 2 * np.pi * 0.8
    t = dt * np.arange(-1250, 2500)
    u = np.column_stack([np.cos(omega * t) + 0.3 * np.cos(2 * omega * t + 0.5)])
    params = AFSParameters()
    afs, gains = params.new_state(1), params.gains()
    _, phase, alpha, beta = locked_series(u[:1251], dt, omega, 10, 0)
    afs_lock(afs, omega, phase + omega * dt, alpha, beta)        # Euler: leads by one substep
    for k in range(1251, t.size):
        _afs_advance(afs, gains, u[k - 1], u[k], dt)
        assert afs.omegas[0] == pytest.approx(omega, rel=1e-6)
    lead = np.mod(afs.phases[0] - omega * t[-1] + np.pi, 2 * np.pi) - np.pi
    assert lead == pytest.approx(omega * dt, abs=1e-6)


def test_locked_pool_carries_offset_fundamental_and_the_stronger_harmonic():
    alpha = np.array([[1.2, 0.9, 0.1, 0.3], [1.0, 0.2, 0.0, 0.05]])
    beta = np.array([[0.0, 0.0, 0.05, 0.2], [0.0, 0.6, 0.0, 0.1]])
    omegas, phases, pool_alpha, pool_beta = locked_pool(4.0, 0.3, alpha, beta, reference=0)
    np.testing.assert_allclose(omegas, [0.0, 4.0, 12.0])                # the 3rd harmonic is stronger
    assert pool_beta[0, 2] == 0.0
    for phi in (0.3, 1.1, 2.5):                                       # the pool reproduces terms 0, 1, 3
        pool_phases = phases + (omegas / 4.0) * (phi - 0.3)
        pool = pool_alpha @ np.cos(pool_phases) + pool_beta @ np.sin(pool_phases)
        angles = np.array([0.0, phi, 3 * phi])
        series = alpha[:, [0, 1, 3]] @ np.cos(angles) + beta[:, [0, 1, 3]] @ np.sin(angles)
        np.testing.assert_allclose(pool, series, atol=1e-12)


def test_afs_learns_the_fourier_series_of_a_clean_signal():
    params = AFSParameters(initial_frequency_hz=1.1)
    afs, gains = params.new_state(1), params.gains()
    dt = 0.002
    t = np.arange(0, 30, dt)
    u = np.cos(2 * np.pi * t) + 0.3 * np.cos(4 * np.pi * t + 0.5)
    for k in range(1, t.size):
        _afs_advance(afs, gains, u[k - 1:k], u[k:k + 1], dt)
    assert afs.omegas[0] == pytest.approx(2 * np.pi, rel=2e-3)
    assert afs.alpha[0, 1] == pytest.approx(1.0, abs=0.05) and afs.beta[0, 1] == 0.0
    assert math.hypot(afs.alpha[0, 2], afs.beta[0, 2]) == pytest.approx(0.3, abs=0.05)


def test_afo_pool_reports_the_middle_frequency_and_resets_when_two_sit_at_zero():
    params = AFOParameters(reset_dwell_s=0.5)
    pool, gains = params.new_state(1), params.gains()
    pool.omegas[:] = [0.01, -0.02, 2 * np.pi * 1.3]
    pool.phases[:] = [0.0, 1.0, 2.0]
    assert pool_fundamental(pool) == (pytest.approx(-1.0), pytest.approx(0.02))
    constant, scratch = np.array([1.0]), np.zeros((4, 3))
    steps = 0
    while pool.resets[0] == 0 and steps < 100:
        pool_substep(pool, gains, constant, 0.01, 0, True, scratch[0, :1], scratch[1], scratch[2],
                     scratch[3])
        pool_logic_step(pool, gains, 0.01)
        steps += 1
    assert steps == 50                                               # after the 0.5 s dwell
    np.testing.assert_allclose(pool.omegas, 2 * np.pi * np.array(AFOParameters().initial_frequencies_hz))


def test_paper_gains_warp_the_phase_at_low_frequency():
    """K = 20 exceeds Omega at 0.3 Hz: the published constant gains do not settle there."""
    t = np.arange(0, 12 / 0.3, 1 / 100)
    Y, _ = wiping_signal(t, 0.3, seed=2)
    _, paper = learn_online(t, Y, OnlineParameters(afs=AFSParameters.petric(), start_up=False))
    _, scaled = learn_online(t, Y, OnlineParameters(start_up=False))
    assert periods_to_tolerance(t, scaled.fundamental_hz, 0.3) < periods_to_tolerance(
        t, paper.fundamental_hz, 0.3)
