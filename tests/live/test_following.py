"""The robot's following of the person: lag and from when it follows, on synthetic movements
whose delay and error are known."""

import numpy as np
import pytest

from wipelab.live.following import following_metrics


def movement(t, delay=0.0):
    phase = 2 * np.pi * 0.8 * (t - delay)
    return np.column_stack([np.cos(phase), 0.6 * np.sin(phase) + 0.2 * np.sin(2 * phase)])


def test_a_delayed_copy_follows_with_its_delay():
    t = np.arange(0, 20, 1 / 30)
    demo = movement(t)
    demo[(t > 9) & (t < 9.5)] = np.nan   # not tracked there
    hand = movement(t, delay=0.2)
    hand[t < 6.0] += 0.5                 # not yet following
    metrics = following_metrics(t, demo, hand, 0.8, lock_time=3.0, first_tracked=1.0,
                                end_time=20.0)
    assert metrics["lag_s"] == pytest.approx(0.2, abs=0.01)
    # the first window of a period whose RMS is within 10 % (a few strayed samples at its start)
    assert 5.7 <= metrics["follows_from_s"] <= 6.0
    assert metrics["periods_until_following"] == pytest.approx(
        (metrics["follows_from_s"] - 1.0) * 0.8)
    assert metrics["steady_rms"] < 0.01 and metrics["following_fraction"] == 1.0


def test_a_hand_that_strays_later_still_followed_from_the_start_but_for_less_of_the_time():
    t = np.arange(0, 20, 1 / 30)
    demo = movement(t)
    hand = demo.copy()
    hand[(t > 12) & (t < 14)] *= 1.5
    metrics = following_metrics(t, demo, hand, 0.8, lock_time=2.0, first_tracked=0.0,
                                end_time=20.0)
    assert metrics["lag_s"] == pytest.approx(0.0, abs=0.01)
    assert metrics["follows_from_s"] == pytest.approx(2.0)
    assert 0.6 < metrics["following_fraction"] < 0.9   # windows touching 12-14 s
