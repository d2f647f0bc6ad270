import numpy as np
import pytest

from wipelab.vision.demonstration_area import measure_demonstration_area


def test_area_is_measured_in_the_window_and_normalises_to_unit_offsets():
    t = np.arange(0, 20, 0.1)
    xy = np.column_stack([0.7 + 0.1 * np.cos(t), 0.05 * np.sin(t)])
    xy[t > 10] *= 2.0  # the movement grows after the window
    valid = np.ones(t.size, bool)
    area = measure_demonstration_area(t, xy, valid, (0.0, 10.0))
    inside = t <= 10
    np.testing.assert_allclose(area.lower_left, xy[inside].min(axis=0))
    np.testing.assert_allclose(area.upper_right, xy[inside].max(axis=0))
    offsets = area.normalise(xy[inside])
    assert offsets.min() == pytest.approx(-1.0) and offsets.max() == pytest.approx(1.0)
    assert np.abs(area.normalise(area.centre[None])).max() == 0.0
    assert area.window == (0.0, 10.0)


def test_invalid_frames_are_ignored_and_an_empty_window_falls_back_to_everything():
    t = np.arange(10.0)
    xy = np.column_stack([t, -t]).astype(float)
    valid = t % 2 == 0
    xy[~valid] = np.nan
    area = measure_demonstration_area(t, xy, valid, (100.0, 200.0))
    np.testing.assert_allclose(area.lower_left, [0, -8])
    np.testing.assert_allclose(area.upper_right, [8, 0])
    assert area.window == (0.0, 9.0)


def test_straight_stroke_keeps_a_finite_normalisation():
    t = np.arange(50.0)
    xy = np.column_stack([np.full(50, 0.6), 0.1 * np.sin(t)])
    area = measure_demonstration_area(t, xy, np.ones(50, bool), (0, 50))
    assert np.all(np.isfinite(area.normalise(xy)))
