"""Charts over the phase in a Rerun 2D view: ticks, coordinates, gaps."""

import math

import numpy as np
import pytest

from wipelab.logs.phase_chart import PhaseChart, nice_ticks


@pytest.mark.parametrize("low, high, expected", [
    (0.0, 9.3, [0.0, 2.0, 4.0, 6.0, 8.0, 10.0]),
    (-18.2, 13.9, [-20.0, -10.0, 0.0, 10.0, 20.0]),
    (0.897, 0.931, [0.89, 0.9, 0.91, 0.92, 0.93, 0.94]),
])
def test_nice_ticks_are_round_and_cover_the_range(low, high, expected):
    np.testing.assert_allclose(nice_ticks(low, high), expected, atol=1e-12)


def test_chart_coordinates_put_phase_right_and_values_up():
    chart = PhaseChart.fitting([0.0, 10.0], "|F| (N)")
    low, high = chart.y_ticks[0], chart.y_ticks[-1]
    points = chart.to_chart(np.array([0.0, math.pi, 2 * math.pi, 2 * math.pi + 1.0]),
                            np.array([low, high, low, high]))
    np.testing.assert_allclose(points[:, 0], [0.0, chart.width / 2, chart.width,
                                              1.0 / (2 * math.pi) * chart.width])
    np.testing.assert_allclose(points[:, 1], [chart.height, 0.0, chart.height, 0.0])


def test_a_gap_in_a_curve_stays_a_gap():
    chart = PhaseChart.fitting([-1.0, 1.0], "y")
    phase = np.linspace(0.0, 2 * math.pi, 20)
    values = np.sin(phase)
    values[8:11] = np.nan
    values[15] = np.nan     # a single point between two gaps draws nothing
    values[17] = np.nan
    strips = chart.strips(phase, values)
    assert [len(s) for s in strips] == [8, 4, 2]


def test_a_flat_curve_still_gets_a_value_range():
    chart = PhaseChart.fitting(np.full(5, 3.0), "y")
    assert chart.y_ticks[0] < 3.0 < chart.y_ticks[-1]
