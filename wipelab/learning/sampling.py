"""Put a recorded trajectory on the uniform time grid the learners assume."""

from __future__ import annotations

import numpy as np


def to_uniform(t: np.ndarray, Y: np.ndarray, valid: np.ndarray | None = None,
               jitter_tolerance: float = 0.01) -> tuple[np.ndarray, np.ndarray]:
    """Linear interpolation onto t0 + k dt, dt = the median sample interval.

    Rows flagged invalid are dropped first (their neighbours bridge the gap). When every
    interval is within ``jitter_tolerance`` (relative) of the median and no row is invalid,
    the samples are returned unchanged.

    Parameters
    ----------
    t : ndarray, shape (n,)
        Strictly increasing times (s).
    Y : ndarray, shape (n, d)
    valid : ndarray of bool, shape (n,), optional

    Returns
    -------
    t_uniform : ndarray, shape (m,)
    Y_uniform : ndarray, shape (m, d)
    """
    t = np.asarray(t, dtype=np.float64)
    Y = np.asarray(Y, dtype=np.float64)
    if valid is not None and not np.all(valid):
        t, Y = t[valid], Y[valid]
        resample = True
    else:
        resample = False
    steps = np.diff(t)
    dt = float(np.median(steps))
    if not resample and np.all(np.abs(steps - dt) <= jitter_tolerance * dt):
        return t, Y
    count = int(np.floor((t[-1] - t[0]) / dt + 1e-9)) + 1
    t_uniform = t[0] + dt * np.arange(count)
    return t_uniform, np.column_stack([np.interp(t_uniform, t, column) for column in Y.T])
