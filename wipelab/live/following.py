"""How well the robot's hand followed the person: its lag and when it started to follow.

Both movements normalised to the demonstration area (Fig. 3; the hand's through the
placement that put the demonstration in front of the robot), sampled at the frame times:

* lag: the delay tau (s) that best aligns the hand with the demonstration over the second
  half of the imitation (least squares over a grid of 1/4 frame; the paper reports about
  0.2 s between the demonstration and the learned waveform, Fig. 5);
* per period from the lock on (windows of one period of the learned frequency): the RMS of
  hand(t) - demonstration(t - tau) over both DOFs, as a fraction of the demonstration's mean
  peak-to-peak; the hand follows from the first window from which every later one is
  within :data:`FOLLOW_TOLERANCE`;
* periods until it follows: from the first tracked frame to the end of that window, in
  periods of the learned frequency.
"""

from __future__ import annotations

import math

import numpy as np

#: Largest RMS difference (of the peak-to-peak) of a period in which the hand follows.
FOLLOW_TOLERANCE = 0.10


def _shifted(t: np.ndarray, demo: np.ndarray, tau: float) -> np.ndarray:
    """demo(t - tau) (n, d) by linear interpolation between its valid samples (NaN outside
    them or across a gap longer than two samples)."""
    out = np.full((len(t), demo.shape[1]), np.nan)
    valid = np.isfinite(demo).all(axis=1)
    if valid.sum() < 2:
        return out
    tv = t[valid]
    query = t - tau
    inside = (query >= tv[0]) & (query <= tv[-1])
    right = np.clip(np.searchsorted(tv, query), 1, len(tv) - 1)
    dt = np.median(np.diff(t)) if len(t) > 1 else 1.0
    close = inside & (tv[right] - tv[right - 1] <= 2.5 * dt)
    for j in range(demo.shape[1]):
        out[close, j] = np.interp(query[close], tv, demo[valid, j])
    return out


def following_metrics(t: np.ndarray, demo: np.ndarray, hand: np.ndarray, frequency_hz: float,
                      lock_time: float, first_tracked: float, end_time: float) -> dict:
    """Lag and following of the hand (see the module docstring).

    Parameters
    ----------
    t : ndarray, shape (n,)
        Frame times (s).
    demo, hand : ndarray, shape (n, d)
        The demonstration (NaN where not tracked) and the hand, normalised.
    frequency_hz : float
        The learned frequency (the window length is one period).
    lock_time, first_tracked, end_time : float
        When the learner locked (the hand starts to imitate), the sponge was first tracked,
        imitation ended (s).
    """
    period = 1.0 / frequency_hz
    during = (t >= lock_time) & (t <= end_time)
    late = during & (t >= 0.5 * (lock_time + end_time))
    dt = float(np.median(np.diff(t)))
    lags = np.arange(0.0, 0.5 * period, 0.25 * dt)
    errors = []
    for tau in lags:
        shifted = _shifted(t, demo, tau)
        both = late & np.isfinite(shifted).all(axis=1)
        errors.append(np.mean((hand[both] - shifted[both]) ** 2) if both.sum() > 5 else np.inf)
    tau = float(lags[int(np.argmin(errors))])
    shifted = _shifted(t, demo, tau)
    valid = np.isfinite(demo).all(axis=1) & during
    span = float(np.mean(np.ptp(demo[valid], axis=0))) if valid.any() else math.nan
    windows = []
    start = lock_time
    while start + period <= end_time + 1e-9:
        inside = (t >= start) & (t < start + period) & np.isfinite(shifted).all(axis=1)
        rms = math.sqrt(np.mean((hand[inside] - shifted[inside]) ** 2)) / span \
            if inside.sum() > 2 else math.nan
        windows.append((start + period, rms))
        start += period
    follows_from = None
    for k in range(len(windows)):
        if all(rms <= FOLLOW_TOLERANCE for _, rms in windows[k:]):
            follows_from = windows[k][0]
            break
    steady = [rms for end, rms in windows if end > 0.5 * (lock_time + end_time)]
    return {"lag_s": tau, "tolerance": FOLLOW_TOLERANCE,
            "rms_per_period": [rms for _, rms in windows],
            "steady_rms": float(np.nanmean(steady)) if steady else None,
            "follows_from_s": follows_from,
            "periods_until_following": None if follows_from is None
            else (follows_from - first_tracked) * frequency_hz}
