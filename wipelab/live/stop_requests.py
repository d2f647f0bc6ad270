"""The user's word to end imitation learning: Enter on stdin, or the signal SIGUSR1.

A live session cannot stop on Ctrl-C: that aborts the whole command (nothing is written).
Enter (a line on stdin) or ``kill -USR1 PID`` ends imitation learning instead, and the session
goes on to learn the surface. A stdin that ends (``< /dev/null``, a closed pipe) is not a
request, and a terminal is not read from by a command running in the background (reading it
would stop the process).
"""

from __future__ import annotations

import io
import os
import signal
import sys
import threading


class StopRequests:
    """Listens for the user's stop request while it is open (a context manager).

    Parameters
    ----------
    stdin : bool
        Read lines from stdin on a background thread (Enter ends imitation learning).
    """

    def __init__(self, stdin: bool = True):
        self.reason: str | None = None
        self._stdin = stdin
        self._previous = None

    def __enter__(self) -> "StopRequests":
        if threading.current_thread() is threading.main_thread():
            self._previous = signal.signal(signal.SIGUSR1, self._on_signal)
        if self._stdin and _may_read_stdin():
            threading.Thread(target=self._read_lines, daemon=True,
                             name="wipelab-stdin").start()
        return self

    def __exit__(self, *exc) -> None:
        if self._previous is not None:
            signal.signal(signal.SIGUSR1, self._previous)
            self._previous = None

    def _on_signal(self, signum, frame) -> None:
        self.reason = self.reason or "SIGUSR1"

    def _read_lines(self) -> None:
        try:
            line = sys.stdin.readline()
        except (OSError, ValueError):   # no usable stdin (closed, captured)
            return
        if line:
            self.reason = self.reason or "Enter"


def _may_read_stdin() -> bool:
    """Whether stdin may be read: not a terminal (a pipe, a file), or the terminal of a
    process in the foreground."""
    try:
        fd = sys.stdin.fileno()
    except io.UnsupportedOperation:   # a stream in memory
        return True
    except (AttributeError, ValueError, OSError):   # none, or closed
        return False
    if not os.isatty(fd):
        return True
    try:
        return os.tcgetpgrp(fd) == os.getpgrp()
    except OSError:
        return False
