"""Data time: seconds since the start of a recording, as MCAP nanoseconds.

Every log record carries data time, never wall-clock time, so a rerun of a stage on the
same inputs writes the same bytes.
"""

from __future__ import annotations

import numpy as np


def seconds_to_ns(t: float) -> int:
    """One data time in seconds -> integer nanoseconds (MCAP ``log_time``).

    Raises
    ------
    ValueError
        If ``t`` is not finite or negative (MCAP times are unsigned).
    """
    return int(seconds_array_to_ns(np.asarray([t], dtype=float))[0])


def seconds_array_to_ns(t: np.ndarray) -> np.ndarray:
    """Data times ``t`` (n,) in seconds -> int64 nanoseconds (n,), rounded to the nearest ns."""
    t = np.asarray(t, dtype=float)
    if t.ndim != 1:
        raise ValueError(f"time stamps must be a 1-D array, got shape {t.shape}")
    if not np.all(np.isfinite(t)):
        raise ValueError("time stamps must be finite")
    if t.size and t.min() < 0.0:
        raise ValueError(f"time stamps must be >= 0 s (data time since the recording start), got {t.min()}")
    return np.round(t * 1e9).astype(np.int64)
