"""Derivative estimates, running normalisation, period statistics, uniform resampling."""

import numpy as np
import pytest

from wipelab.learning.derivatives import CentredDerivatives, savgol_centre_coefficients, window_for
from wipelab.learning.normalise import (new_period_window, new_running_range, period_statistics,
                                        running_normalise)
from wipelab.learning.sampling import to_uniform


@pytest.mark.parametrize("window", [5, 7, 21, 101])
def test_centred_fit_is_exact_for_quartics(window):
    j = np.arange(window) - (window - 1) / 2
    y = 0.3 - 0.2 * j + 0.05 * j ** 2 + 0.01 * j ** 3 - 0.002 * j ** 4
    value, first, second = savgol_centre_coefficients(window, 4) @ y
    assert (value, first, second) == pytest.approx((0.3, -0.2, 0.1), abs=1e-9)


def test_window_follows_the_period_and_stays_odd_and_bounded():
    assert window_for(2 * np.pi, 0.002, 0.125, 101) == 63          # 1 Hz at 500 Hz: 62.5 samples
    assert window_for(2 * np.pi * 3, 1 / 30, 0.125, 101) == 5       # never below 5
    assert window_for(2 * np.pi * 0.1, 0.002, 0.125, 101) == 101    # capped


def test_centred_derivatives_pair_estimates_with_the_centre_sample():
    dt, omega = 0.01, 2 * np.pi
    derivatives = CentredDerivatives(1, dt, 0.125, 4, 101)
    for k in range(40):
        t = k * dt
        derivatives.push(np.array([np.sin(omega * t)]), phase=omega * t, omega=omega)
    y, yd, ydd, phase, _ = derivatives.centre(omega)
    t_c = phase / omega
    assert y[0] == pytest.approx(np.sin(omega * t_c), abs=1e-5)
    assert yd[0] == pytest.approx(omega * np.cos(omega * t_c), rel=1e-4)
    assert ydd[0] == pytest.approx(-omega ** 2 * np.sin(omega * t_c), rel=1e-3)
    assert t_c == pytest.approx(39 * dt - 6 * dt)                   # window 13 -> 6 samples late


def test_estimates_between_samples_follow_the_local_polynomial():
    dt, omega = 0.05, 2 * np.pi * 0.5
    derivatives = CentredDerivatives(1, dt, 0.125, 4, 101)           # window of 5 samples
    quartic = lambda t: 0.3 - 0.2 * t + 0.5 * t ** 2 + 0.1 * t ** 3 - 0.4 * t ** 4
    for k in range(9):
        derivatives.push(np.array([quartic(k * dt)]), phase=omega * k * dt, omega=omega)
    y, yd, ydd, phases, omega_c = derivatives.between(omega, 4)
    t_x = (6 + (np.arange(4) + 0.5) / 4 - 0.5) * dt                # around the centre sample 6
    np.testing.assert_allclose(y[:, 0], quartic(t_x), atol=1e-12)
    np.testing.assert_allclose(yd[:, 0], -0.2 + t_x + 0.3 * t_x ** 2 - 1.6 * t_x ** 3, atol=1e-9)
    np.testing.assert_allclose(ydd[:, 0], 1.0 + 0.6 * t_x - 4.8 * t_x ** 2, atol=1e-8)
    np.testing.assert_allclose(phases, omega * t_x)
    centre = derivatives.centre(omega)
    single = derivatives.between(omega, 1)
    for a, b in zip(centre[:3], single[:3]):
        np.testing.assert_allclose(a, b[0], atol=1e-12)
    assert omega_c == omega


def _statistics(window, value, omega, dt):
    mean, variance = np.zeros(1), np.zeros(1)
    period_statistics(window, np.array([value]), omega, dt, 1.0, mean, variance)
    return mean[0], np.sqrt(2 * variance[0])


def test_period_statistics_restart():
    window = new_period_window(1, 50)
    for value in (5.0, 5.0, 5.0):
        _statistics(window, value, 2 * np.pi, 0.1)
    window.count[0] = 0
    assert _statistics(window, 1.0, 2 * np.pi, 0.1) == (1.0, 0.0)    # the past is forgotten


def test_normaliser_waits_for_one_swing_then_maps_the_range_to_unit():
    t = np.arange(0, 3, 0.01)
    y = 0.6 + 0.1 * np.cos(2 * np.pi * t)
    for tau, tolerance in ((1e6, 1e-5), (10.0, 0.25)):    # the range relaxes 10 % per second
        state, u = new_running_range(1), np.zeros((t.size, 1))
        for k, v in enumerate(y):
            running_normalise(state, np.array([v]), k == 0, 0.01 / tau, 0.0, u[k])
        assert not u[:50].any()                                      # before the first swing
        np.testing.assert_allclose(u[100:, 0], np.cos(2 * np.pi * t[100:]), atol=tolerance)


def test_period_statistics_are_exact_over_a_fractional_period():
    dt, frequency = 0.01, 1 / 0.937                                  # 93.7 samples per period
    window = new_period_window(1, 400)
    for k in range(300):
        mean, amplitude = _statistics(window, 2.0 + 0.5 * np.sin(2 * np.pi * frequency * k * dt),
                                      2 * np.pi * frequency, dt)
    assert mean == pytest.approx(2.0, abs=2e-3) and amplitude == pytest.approx(0.5, rel=1e-2)


def test_to_uniform_bridges_invalid_rows_flags_them_and_keeps_uniform_data():
    t = np.arange(10) * 0.1
    Y = np.column_stack([t, 2 * t])
    same_t, same_Y, same_valid = to_uniform(t, Y)
    assert same_t is t and same_Y is Y and same_valid.all()
    valid = np.ones(10, dtype=bool)
    valid[4:6] = False
    Y_bad = Y.copy()
    Y_bad[4:6] = np.nan
    t_u, Y_u, valid_u = to_uniform(t, Y_bad, valid)
    np.testing.assert_allclose(t_u, t)
    np.testing.assert_allclose(Y_u, Y, atol=1e-12)
    np.testing.assert_array_equal(valid_u, valid)


def test_to_uniform_resamples_jittered_times_and_flags_the_grid_samples_in_a_gap():
    rng = np.random.default_rng(3)
    t = np.arange(40) * 0.1 + rng.uniform(-0.003, 0.003, 40)
    t[0] = 0.0
    valid = np.ones(40, dtype=bool)
    valid[20:25] = False                                  # 2.0-2.4 s not observed
    t_u, Y_u, valid_u = to_uniform(t, np.column_stack([np.sin(t)]), valid)
    assert np.allclose(np.diff(t_u), np.median(np.diff(t)))
    np.testing.assert_array_equal(np.flatnonzero(~valid_u), np.arange(20, 25))
    np.testing.assert_allclose(Y_u[valid_u, 0], np.sin(t_u[valid_u]), atol=2e-3)
