"""Logging off the frame loop: one thread that runs the logging calls in the order they came.

A live session hands each frame's logging (encoding the images, the MCAP messages, the
Rerun chunks) to this worker and goes on with the next frame: the frame loop waits for
tracking, learning and the robot only, and the logs are written while it waits for the next
frame. One worker, first in first out, so the files are written in the same order on every
run. When logging falls ``capacity`` calls behind, :meth:`LogWorker.submit` waits (the frame
loop slows down, and frames are then counted as late or dropped, never lost silently).
"""

from __future__ import annotations

import queue
import threading
from collections.abc import Callable

#: Calls the worker may fall behind before submit waits (about 3 s of frames).
DEFAULT_CAPACITY = 200


class LogWorker:
    """Runs submitted calls on one thread, in order (a context manager: leaving it waits
    for them all; an error of a call is raised in the caller's thread, at the next submit or
    at the end)."""

    def __init__(self, capacity: int = DEFAULT_CAPACITY):
        self._queue: queue.Queue = queue.Queue(capacity)
        self._error: BaseException | None = None
        self._thread = threading.Thread(target=self._run, daemon=True, name="wipelab-logs")

    def __enter__(self) -> "LogWorker":
        self._thread.start()
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        self._queue.put(None)
        self._thread.join()
        if self._error is not None and exc_type is None:
            raise self._error

    def submit(self, call: Callable, *args) -> None:
        """Run ``call(*args)`` on the worker after everything submitted before."""
        if self._error is not None:
            raise self._error
        self._queue.put((call, args))

    def wait(self) -> None:
        """Return when everything submitted so far has run."""
        done = threading.Event()
        self.submit(done.set)
        done.wait()
        if self._error is not None:
            raise self._error

    def _run(self) -> None:
        while (item := self._queue.get()) is not None:
            if self._error is None:
                call, args = item
                try:
                    call(*args)
                except BaseException as error:   # raised in the session's thread
                    self._error = error
