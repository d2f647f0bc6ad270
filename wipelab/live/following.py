"""How well the robot's hand followed the person: its lag, and from when it followed.

Both movements are normalised to the demonstration area (Fig. 3; the hand's through the
placement that put the demonstration in front of the robot) and sampled at the frame times:

* lag: the delay tau (s) that best aligns the hand with the demonstration from a period
  after the lock to the end of the imitation (from the lock if that holds too few tracked
  frames; least squares, tau on a grid of a quarter frame from -1/4 to +1/2 period; the
  paper reports about 0.2 s between the demonstration and the learned waveform, Fig. 5);
* the error at time t: the RMS over the next period of hand(t') - demonstration(t' - tau)
  (both DOFs), as a fraction of the demonstration's mean peak-to-peak;
* the hand follows from the first frame from which the error stays within
  :data:`FOLLOW_TOLERANCE` for a period (every window starting in the next period);
  ``periods_until_following`` counts the periods of the learned frequency from the first
  tracked frame to then; ``following_fraction`` is the share of the windows from then to the
  end of imitation within the tolerance (a demonstration that the tracker loses for a while
  throws the learner, and the hand, off for a few periods).
"""

from __future__ import annotations

import math

import numpy as np

#: Largest RMS difference (of the peak-to-peak) over a period in which the hand follows.
FOLLOW_TOLERANCE = 0.10


def shifted(t: np.ndarray, values: np.ndarray, tau: float) -> np.ndarray:
    """values(t - tau) (n, d) by linear interpolation between the finite rows of ``values``
    (n, d) at times ``t`` (n,); NaN outside them or across a gap of more than two samples."""
    out = np.full((len(t), values.shape[1]), np.nan)
    finite = np.isfinite(values).all(axis=1)
    if finite.sum() < 2:
        return out
    tv = t[finite]
    query = t - tau
    right = np.clip(np.searchsorted(tv, query), 1, len(tv) - 1)
    dt = float(np.median(np.diff(t)))
    close = (query >= tv[0]) & (query <= tv[-1]) & (tv[right] - tv[right - 1] <= 2.5 * dt)
    for j in range(values.shape[1]):
        out[close, j] = np.interp(query[close], tv, values[finite, j])
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
        The learned frequency (the error's window is one period).
    lock_time, first_tracked, end_time : float
        When the learner locked (the hand starts to imitate), the sponge was first tracked,
        imitation ended (s).
    """
    period = 1.0 / frequency_hz
    dt = float(np.median(np.diff(t)))
    late = (t >= 0.5 * (lock_time + end_time)) & (t <= end_time)
    tracked = np.isfinite(demo).all(axis=1)
    fitted = (t >= lock_time + period) & (t <= end_time)
    if (fitted & tracked).sum() < 10:
        fitted = (t >= lock_time) & (t <= end_time)
    lags = np.arange(-0.25 * period, 0.5 * period, 0.25 * dt)
    costs = []
    for tau in lags:
        aligned = shifted(t, demo, tau)
        both = fitted & np.isfinite(aligned).all(axis=1)
        costs.append(np.mean((hand[both] - aligned[both]) ** 2) if both.sum() > 5 else np.inf)
    tau = float(lags[int(np.argmin(costs))])
    aligned = shifted(t, demo, tau)
    during = (t >= lock_time) & (t <= end_time)
    observed = tracked & during
    span = float(np.mean(np.ptp(demo[observed], axis=0))) if observed.sum() > 2 else math.nan
    squared = np.sum((hand - aligned) ** 2, axis=1) / hand.shape[1]
    usable = np.isfinite(squared) & during
    frames = int(round(period / dt))
    starts = np.flatnonzero(during & (t + period <= end_time + 1e-9))
    error = np.full(len(t), np.nan)
    for k in starts:
        window = usable[k:k + frames]
        if window.sum() > 0.5 * frames:
            error[k] = math.sqrt(np.mean(squared[k:k + frames][window])) / span
    follows_from, fraction = None, None
    for k in starts:
        ahead = (t >= t[k]) & (t <= t[k] + period) & np.isfinite(error)
        if error[k] <= FOLLOW_TOLERANCE and np.all(error[ahead] <= FOLLOW_TOLERANCE):
            follows_from = float(t[k])
            after = error[starts[starts >= k]]
            after = after[np.isfinite(after)]
            fraction = float(np.mean(after <= FOLLOW_TOLERANCE))
            break
    steady = error[late]
    return {"lag_s": tau, "tolerance": FOLLOW_TOLERANCE,
            "steady_rms": float(np.nanmean(steady)) if np.isfinite(steady).any() else None,
            "follows_from_s": follows_from, "following_fraction": fraction,
            "periods_until_following": None if follows_from is None
            else (follows_from - first_tracked) * frequency_hz,
            "periods_after_lock": None if follows_from is None
            else (follows_from - lock_time) * frequency_hz}
