"""Runs of a boolean mask."""

import numpy as np

from wipelab.mask_runs import true_runs


def test_runs_are_the_maximal_stretches_of_true_with_exclusive_stops():
    mask = np.array([1, 1, 0, 0, 1, 0, 1, 1, 1], bool)
    assert true_runs(mask) == [(0, 2), (4, 5), (6, 9)]
    assert true_runs(np.zeros(4, bool)) == []
    assert true_runs(np.ones(3, bool)) == [(0, 3)]
    assert true_runs(np.array([], bool)) == []
