"""How a live session's stereo frames arrive: :class:`FrameFeed`.

Every source (:mod:`wipelab.live.sources`: a demo directory, two cameras) goes through one
feed: a thread reads frame pairs from the source and hands them to the session through a
buffer (a second of pairs), as a camera driver does.

* ``realtime`` (``--speed 1``): a pair is available from its arrival time on (a file's frame
  k at k / fps after the start; a camera's when it was grabbed). A session that falls
  behind finds several pairs waiting: it takes the oldest (late: a newer one has arrived
  already), and when more than a buffer full are waiting the oldest are dropped. Dropped pairs
  are counted and leave a gap in the frame numbers (the learner is told these samples were
  not observed); nothing is skipped silently.
* otherwise (``--speed max``): every pair is delivered, as fast as the session takes them
  (the reading thread waits for room in the buffer): the same frames on every run.

A pair's number is its index on the source's clock (time = index / fps): a file's frame
index, a camera's count of grabbed pairs.
"""

from __future__ import annotations

import math
import threading
import time
from collections import deque
from collections.abc import Callable, Iterator
from dataclasses import dataclass

import numpy as np

from wipelab.errors import interrupts_deferred

#: Seconds of pairs a feed holds for the session before it drops the oldest (real time):
#: the tracker's one-off work when it finds the sponge takes up to about half a second.
BUFFER_SECONDS = 1.0


@dataclass(frozen=True)
class FramePair:
    """One synchronised stereo pair.

    Attributes
    ----------
    index : int
        Frame number on the source's clock (time = index / fps).
    left, right : ndarray, shape (h, w, 3)
        BGR uint8 images.
    arrived : float
        ``time.perf_counter()`` when the pair became available to the session (s): in real
        time when it arrived, otherwise when the session took it.
    """

    index: int
    left: np.ndarray
    right: np.ndarray
    arrived: float


class FrameFeed:
    """Frame pairs from ``pairs``, read on a thread and handed over through a buffer.

    Parameters
    ----------
    pairs : callable
        Returns the iterator of (left, right) BGR pairs (called on the reading thread); it
        may raise (e.g. InputError for a truncated video): the error is raised to the
        session by :meth:`next`.
    fps : float
        Frame rate of the source (Hz).
    realtime : bool
        See the module docstring.
    paced : bool
        Hold pair k back until k / fps after :meth:`start` (a file played at its frame rate;
        a camera paces itself).
    buffer_seconds : float
        Pairs held (this many seconds of them) before the oldest are dropped (real time
        only).
    close : callable, optional
        Called when the feed stops (releases cameras).
    """

    def __init__(self, pairs: Callable[[], Iterator[tuple[np.ndarray, np.ndarray]]],
                 fps: float, realtime: bool, paced: bool, buffer_seconds: float = BUFFER_SECONDS,
                 close: Callable[[], None] | None = None):
        self.fps = float(fps)
        self.realtime, self.paced = realtime, paced
        self.buffer = max(1, math.ceil(buffer_seconds * self.fps))
        self.dropped = 0
        self._pairs, self._close = pairs, close
        self._queue: deque[FramePair | BaseException | None] = deque()
        self._ready = threading.Condition()
        self._halt = threading.Event()
        self._thread = threading.Thread(target=self._read, daemon=True, name="wipelab-frames")
        self.start_time = math.nan

    def start(self) -> None:
        """Start reading (the source's clock starts now)."""
        self.start_time = time.perf_counter()
        with interrupts_deferred():
            self._thread.start()

    def next(self) -> FramePair | None:
        """The oldest waiting pair (blocks until one arrives); None at the end of the source."""
        with self._ready:
            while not self._queue:
                self._ready.wait()
            item = self._queue.popleft()
            self._ready.notify_all()
        if isinstance(item, BaseException):
            raise item
        if item is not None and not self.realtime:   # no clock: it arrives when taken
            item = FramePair(item.index, item.left, item.right, time.perf_counter())
        return item

    def waiting(self) -> int:
        """Pairs waiting in the buffer (a session that finds any is behind)."""
        with self._ready:
            return sum(isinstance(item, FramePair) for item in self._queue)

    def stop(self) -> None:
        """Stop reading and release the source (idempotent)."""
        self._halt.set()
        with self._ready:
            self._queue.clear()
            self._ready.notify_all()
        if self._thread.ident is not None:
            self._thread.join(timeout=10.0)
        if self._close is not None:
            self._close()
            self._close = None

    def _read(self) -> None:
        try:
            for index, (left, right) in enumerate(self._pairs()):
                if self._halt.is_set():
                    return
                arrived = self._arrival(index)
                if arrived is None:
                    return
                self._put(FramePair(index, left, right, arrived))
            self._put(None)
        except BaseException as error:  # handed to the session
            self._put(error)

    def _arrival(self, index: int) -> float | None:
        """When pair ``index`` becomes available (waits for it when paced); None if stopped."""
        now = time.perf_counter()
        if not self.paced:
            return now
        due = self.start_time + index / self.fps
        if due > now and self._halt.wait(due - now):
            return None
        return max(due, now)

    def _put(self, item) -> None:
        with self._ready:
            if isinstance(item, FramePair):
                while not self.realtime and len(self._queue) >= self.buffer \
                        and not self._halt.is_set():
                    self._ready.wait()
                while self.realtime and len(self._queue) >= self.buffer:
                    self._queue.popleft()
                    self.dropped += 1
            self._queue.append(item)
            self._ready.notify_all()
