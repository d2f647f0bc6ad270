"""The frame feed of a live session: every pair at --speed max, a file's pairs at their frame
rate, a slow session's pairs late or dropped (counted, and missing from the numbers), errors
of the source raised to the session."""

import time

import numpy as np
import pytest

from wipelab.errors import InputError
from wipelab.live.frames import FrameFeed
from wipelab.live.sources import is_stream


def pairs(n: int):
    """n tiny pairs whose pixels hold their index."""
    def make():
        for k in range(n):
            image = np.full((4, 4, 3), k, np.uint8)
            yield image, image.copy()
    return make


def take_all(feed: FrameFeed, work_s: float = 0.0) -> list:
    taken = []
    feed.start()
    try:
        while (pair := feed.next()) is not None:
            taken.append(pair)
            time.sleep(work_s)
    finally:
        feed.stop()
    return taken


def test_at_max_speed_every_pair_comes_in_order_however_slow_the_session():
    feed = FrameFeed(pairs(50), fps=30.0, realtime=False, paced=False, buffer_seconds=0.1)
    taken = take_all(feed, work_s=0.002)
    assert [p.index for p in taken] == list(range(50)) and feed.dropped == 0
    assert all(int(p.left[0, 0, 0]) == p.index for p in taken)


def test_a_paced_file_delivers_each_pair_at_its_time():
    feed = FrameFeed(pairs(12), fps=30.0, realtime=True, paced=True)
    taken = take_all(feed)
    due = feed.start_time + np.arange(12) / 30.0
    arrived = np.array([p.arrived for p in taken])
    assert np.all(arrived >= due - 1e-6) and np.all(arrived < due + 0.02)


def test_a_slow_session_finds_pairs_waiting_and_the_overflow_is_dropped_and_counted():
    """Pairs at 100 Hz, a session that needs 30 ms per pair, a buffer of 5 pairs: most pairs
    are dropped, the counts add up and the numbers of the taken ones have gaps."""
    feed = FrameFeed(pairs(60), fps=100.0, realtime=True, paced=True, buffer_seconds=0.05)
    taken = take_all(feed, work_s=0.03)
    indices = [p.index for p in taken]
    assert indices == sorted(indices) and indices[0] == 0
    assert feed.dropped > 20 and len(taken) + feed.dropped == 60
    assert np.max(np.diff(indices)) > 1


def test_an_error_of_the_source_reaches_the_session():
    def broken():
        yield np.zeros((2, 2, 3), np.uint8), np.zeros((2, 2, 3), np.uint8)
        raise InputError("left.mp4: truncated")

    feed = FrameFeed(broken, fps=30.0, realtime=False, paced=False)
    feed.start()
    assert feed.next().index == 0
    with pytest.raises(InputError, match="truncated"):
        feed.next()
    feed.stop()


def test_devices_and_streams_are_told_from_files():
    assert is_stream("0") and is_stream("rtsp://camera/1")
    assert not is_stream("left.mp4") and not is_stream("videos/0.avi")
