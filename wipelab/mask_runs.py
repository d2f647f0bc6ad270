"""Runs of a boolean mask: the stretches where it holds, as (start, stop) index pairs."""

from __future__ import annotations

import numpy as np


def true_runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """The maximal runs of ``True`` in a 1-D mask, as (start, stop) pairs with ``stop``
    exclusive, in order."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], np.asarray(mask, bool).astype(np.int8),
                                                   [0]])))
    return [(int(start), int(stop)) for start, stop in zip(edges[::2], edges[1::2])]
