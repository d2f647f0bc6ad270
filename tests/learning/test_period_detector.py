"""The start-up period detector: fast, accurate, the common period, silent on non-periodic input."""

import numpy as np
import pytest

from wipelab.learning import PeriodDetectorParameters
from wipelab.learning.period_detector import (add_block, compared_pairs, detector_restart,
                                              detector_update, first_period_lag, new_detector)


class PeriodDetector:
    """The compiled detector with its settings, for driving it sample by sample."""

    def __init__(self, n_dofs, dt, params, min_hz, max_hz):
        self.settings, self.state = new_detector(n_dofs, dt, params, min_hz, max_hz)

    def update(self, y):
        return detector_update(self.settings, self.state, np.asarray(y, dtype=float)) > 0.0

    def restart(self):
        detector_restart(self.state)

    @property
    def period_s_(self):
        return self.state.period_s[0] or None
from wipelab.learning.signals import HarmonicShape, wiping_signal


def _first_detection(t, Y, rate_hz):
    """(time of detection in s or None, detector) for samples Y (n, d)."""
    detector = PeriodDetector(Y.shape[1], 1 / rate_hz, PeriodDetectorParameters(), 0.1, 10.0)
    for k in range(t.size):
        if detector.update(Y[k]):
            return t[k], detector
    return None, detector


@pytest.mark.parametrize("frequency_hz, rate_hz", [(0.3, 30.0), (3.0, 30.0), (1.0, 500.0)])
def test_finds_the_period_within_0_5_percent_after_about_two_periods(frequency_hz, rate_hz):
    t = np.arange(0, 6 / frequency_hz, 1 / rate_hz)
    Y, _ = wiping_signal(t, frequency_hz, seed=7)
    found_s, detector = _first_detection(t, Y, rate_hz)
    assert 2.0 <= found_s * frequency_hz <= 2.3
    assert 1 / detector.period_s_ == pytest.approx(frequency_hz, rel=5e-3)


def test_keeps_holding_the_period_and_restarts_after_a_gap():
    """After the start-up it supervises: the estimate it holds follows the input; a restart
    forgets everything and finds the period again about two periods later."""
    rate_hz, frequency_hz = 30.0, 1.0
    t = np.arange(0, 12, 1 / rate_hz)
    Y, _ = wiping_signal(t, frequency_hz, seed=5)
    detector = PeriodDetector(2, 1 / rate_hz, PeriodDetectorParameters(), 0.1, 10.0)
    held = [detector.period_s_ for k in range(180) if detector.update(Y[k])]
    assert len(held) > 50 and np.allclose(1 / np.array(held), frequency_hz, rtol=5e-3)
    detector.restart()
    assert detector.period_s_ is None
    again = next(k for k in range(180, t.size) if detector.update(Y[k]))
    assert 2.0 <= (again - 180) / rate_hz * frequency_hz <= 2.3


def test_finds_the_common_period_of_a_figure_eight():
    """x at f, y at 2 f: the first dip of the pooled difference function is 1 / f."""
    eight = (HarmonicShape(0.5, 0.1, (1.0,), (0.0,)), HarmonicShape(0.1, 0.05, (0.0, 1.0), (0.0, 0.3)))
    t = np.arange(0, 8, 1 / 100)
    Y, _ = wiping_signal(t, 0.7, seed=1, shapes=eight)
    _, detector = _first_detection(t, Y, 100.0)
    assert 1 / detector.period_s_ == pytest.approx(0.7, rel=5e-3)


def test_forgets_a_start_at_rest():
    """Only the last (1 + confirm) periods are compared: a still start does not delay it."""
    rate_hz, frequency_hz = 100.0, 1.0
    t = np.arange(0, 9, 1 / rate_hz)
    moving = t >= 4.0
    Y, _ = wiping_signal(t - 4.0, frequency_hz, seed=2)
    still = int((~moving).sum())
    Y[~moving] = Y[moving][0] + 0.001 * np.random.default_rng(0).standard_normal((still, 2))
    found_s, detector = _first_detection(t, Y, rate_hz)
    assert (found_s - 4.0) * frequency_hz <= 2.3
    assert 1 / detector.period_s_ == pytest.approx(frequency_hz, rel=5e-3)


def test_stays_silent_on_a_random_walk():
    rng = np.random.default_rng(3)
    t = np.arange(0, 30, 1 / 25)
    Y = 0.01 * np.cumsum(rng.standard_normal((t.size, 2)), axis=0)
    found_s, detector = _first_detection(t, Y, 25.0)
    assert found_s is None and detector.period_s_ is None


def test_sliding_sums_equal_the_direct_sums():
    rng = np.random.default_rng(4)
    blocks_in = rng.standard_normal((40, 2))
    max_lag, confirm = 12, 0.7
    pairs = compared_pairs(max_lag, confirm)
    blocks = np.zeros((max_lag + int(pairs[-1]) + 1, 2))
    sums = np.zeros(max_lag + 1)
    for n, block in enumerate(blocks_in):
        add_block(blocks, sums, pairs, n, block)
    n = blocks_in.shape[0]
    for tau in range(1, max_lag + 1):
        k = np.arange(n - pairs[tau], n)
        assert sums[tau] == pytest.approx(((blocks_in[k] - blocks_in[k - tau]) ** 2).sum(), rel=1e-9)


def test_waits_for_the_far_side_of_the_dip():
    """A dip at the last known lag is not reported before the next lag is known."""
    sums = np.array([0.0, 4.0, 4.0, 0.1, 0.05])        # D' dips from lag 3, still falling at 4
    pairs = np.ones(5, dtype=np.int64)
    assert first_period_lag(sums, pairs, 5, 2, 0.1) == 0.0          # lags 1..4 known
    sums = np.append(sums, 3.0)
    pairs = np.ones(6, dtype=np.int64)
    before, at, after = 0.1, 0.05, 3.0                                 # parabola through lags 3, 4, 5
    expected = 4 + 0.5 * (before - after) / (before - 2 * at + after)
    assert first_period_lag(sums, pairs, 6, 2, 0.1) == pytest.approx(expected)


def test_rejects_bad_parameters():
    with pytest.raises(ValueError, match="threshold"):
        PeriodDetectorParameters(threshold=1.5)
    with pytest.raises(ValueError, match="confirm"):
        PeriodDetectorParameters(confirm=0.0)
