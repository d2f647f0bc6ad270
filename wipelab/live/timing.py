"""Keeping up with the video: the session's clock, per-frame latency, late and dropped frames.

Latency of a frame: from when its pair arrived (became available to the session: a file's
frame at its time in the video, a camera's when grabbed) to the robot's first command computed
with it, so time spent waiting in the frame buffer counts. A frame is late when a newer pair
had arrived already when the session took it; dropped when the buffer overflowed (see
:mod:`wipelab.live.frames`). The real-time factor is the session time covered over the wall
time it took; ``busy`` is the fraction of that wall time spent working (the rest waiting for
frames or for the clock).
"""

from __future__ import annotations

import time

import numpy as np


class SessionClock:
    """Wall time against session time. ``realtime``: :meth:`wait_until` sleeps until the
    session time is due (``--speed 1``); otherwise it returns at once (``--speed max``)."""

    def __init__(self, realtime: bool, start: float | None = None):
        self.realtime = realtime
        self.start = time.perf_counter() if start is None else start
        self.waited = 0.0

    def elapsed(self) -> float:
        """Wall seconds since the start."""
        return time.perf_counter() - self.start

    def wait_until(self, t: float) -> None:
        """Return when session time ``t`` (s) is due."""
        if not self.realtime:
            return
        delay = self.start + t - time.perf_counter()
        if delay > 0:
            time.sleep(delay)
            self.waited += delay


class FrameTimes:
    """Per-frame latency and late frames of a session."""

    def __init__(self):
        self.latencies: list[float] = []
        self.imitating: list[bool] = []
        self.late = 0

    def add(self, arrived: float, commanded: float, late: bool, imitating: bool) -> None:
        """A frame that arrived at ``arrived`` and drove the robot's command at
        ``commanded`` (``time.perf_counter()`` seconds); ``imitating``: the robot imitated
        the movement learned with it (after the lock)."""
        self.latencies.append(commanded - arrived)
        self.imitating.append(bool(imitating))
        self.late += bool(late)

    def summary(self, dropped: int, expected: int, session_s: float, wall_s: float,
                imitation_wall_s: float, busy_s: float) -> dict:
        """metrics.json's ``timing``: latency p50 / p99 / max (ms) of every frame and of the
        frames the robot imitated with; frames processed, late and dropped (and their share
        of the frames the source delivered or dropped); frames per second of the frame loop
        (``imitation_wall_s`` long); for the whole session (``session_s`` of session time in
        ``wall_s``), the real-time factor and the fraction of the wall time spent working
        (``busy_s``; the rest waiting for frames or the clock)."""
        latency = np.asarray(self.latencies) * 1000.0
        processed = len(self.latencies)
        total = max(expected, processed + dropped, 1)
        return {
            "frames": processed, "late_frames": self.late, "dropped_frames": dropped,
            "dropped_fraction": dropped / total, "late_fraction": self.late / total,
            "latency_ms": _percentiles(latency),
            "latency_imitating_ms": _percentiles(latency[np.array(self.imitating, bool)]),
            "frames_per_second": processed / imitation_wall_s if imitation_wall_s > 0 else None,
            "session_time_s": session_s, "wall_time_s": wall_s,
            "real_time_factor": session_s / wall_s if wall_s > 0 else None,
            "busy_fraction": busy_s / wall_s if wall_s > 0 else None,
        }

def _percentiles(values_ms: np.ndarray) -> dict:
    """p50, p99 and max (ms) of latencies (None without any)."""
    if not len(values_ms):
        return {"p50": None, "p99": None, "max": None}
    return {"p50": float(np.percentile(values_ms, 50)), "p99": float(np.percentile(values_ms, 99)),
            "max": float(values_ms.max())}
