"""Put a recorded trajectory on the uniform time grid the learners assume."""

from __future__ import annotations

import numpy as np


def to_uniform(t: np.ndarray, Y: np.ndarray, valid: np.ndarray | None = None,
               jitter_tolerance: float = 0.01) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Linear interpolation onto t0 + k dt, dt = the median sample interval.

    Rows flagged invalid are dropped first and their neighbours bridge the gap; the grid
    samples that fall in a gap are flagged invalid in turn (a grid sample is valid when the
    recorded row nearest to it, within dt / 2, is). When every interval is within
    ``jitter_tolerance`` (relative) of the median and no row is invalid, the samples are
    returned unchanged.

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
    valid_uniform : ndarray of bool, shape (m,)
    """
    t = np.asarray(t, dtype=np.float64)
    Y = np.asarray(Y, dtype=np.float64)
    valid = np.ones(t.size, dtype=bool) if valid is None else np.asarray(valid, dtype=bool)
    steps = np.diff(t)
    dt = float(np.median(steps))
    if valid.all() and np.all(np.abs(steps - dt) <= jitter_tolerance * dt):
        return t, Y, valid
    t_valid, Y_valid = t[valid], Y[valid]
    count = int(np.floor((t_valid[-1] - t_valid[0]) / dt + 1e-9)) + 1
    t_uniform = t_valid[0] + dt * np.arange(count)
    Y_uniform = np.column_stack([np.interp(t_uniform, t_valid, column) for column in Y_valid.T])
    after = np.clip(np.searchsorted(t, t_uniform), 1, t.size - 1)
    nearest = np.where(t_uniform - t[after - 1] <= t[after] - t_uniform, after - 1, after)
    valid_uniform = valid[nearest] & (np.abs(t[nearest] - t_uniform) <= 0.5 * dt)
    return t_uniform, Y_uniform, valid_uniform
