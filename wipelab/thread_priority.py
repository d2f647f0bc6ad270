"""Helper threads below the thread they serve.

The track stage runs its tracker on the main thread and, beside it, a decoding thread per
video, the previews' encoder and the table's stereo fits: more busy threads than a small
machine has cores. The tracker is the one everything waits on; at equal priority the
scheduler shares the cores evenly, and the tracker's thread spent a fifth of its time
preempted (2 cores: 0.9 s of a 5.6 s pass, 960x540 mp4v). With the helpers a few nice
levels lower, they take the cores the tracker leaves idle, and the command ran 5-6 % faster
(1280x720 MJPG and 960x540 mp4v development scenes, three runs each); what they compute is
the same.
"""

from __future__ import annotations

import os
import threading

#: Nice levels a helper thread runs below the process (Linux: niceness is per thread).
HELPER_NICENESS = 10


def run_as_helper() -> None:
    """Lower the calling thread's priority by :data:`HELPER_NICENESS` (a no-op where
    threads cannot be given their own priority)."""
    try:
        thread = threading.get_native_id()
        os.setpriority(os.PRIO_PROCESS, thread,
                       os.getpriority(os.PRIO_PROCESS, thread) + HELPER_NICENESS)
    except (AttributeError, OSError):  # no per-thread niceness here (macOS, Windows)
        pass
