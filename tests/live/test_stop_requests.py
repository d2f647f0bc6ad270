"""The user's word ends imitation learning: SIGUSR1 or a line on stdin; an ending stdin is
not a request, and the signal's previous handler is back afterwards."""

import io
import os
import signal
import sys
import time

from wipelab.live.stop_requests import StopRequests


def wait_for(condition, timeout=5.0):
    deadline = time.monotonic() + timeout
    while not condition() and time.monotonic() < deadline:
        time.sleep(0.01)


def test_sigusr1_is_a_request_and_the_previous_handler_comes_back():
    before = signal.getsignal(signal.SIGUSR1)
    with StopRequests(stdin=False) as requests:
        assert requests.reason is None
        os.kill(os.getpid(), signal.SIGUSR1)
        wait_for(lambda: requests.reason is not None)
        assert requests.reason == "SIGUSR1"
    assert signal.getsignal(signal.SIGUSR1) is before


def test_a_line_on_stdin_is_a_request_and_an_ending_stdin_is_not(monkeypatch):
    monkeypatch.setattr(sys, "stdin", io.StringIO("\n"))
    with StopRequests() as requests:
        wait_for(lambda: requests.reason is not None)
        assert requests.reason == "Enter"
    monkeypatch.setattr(sys, "stdin", io.StringIO(""))
    with StopRequests() as requests:
        time.sleep(0.2)
        assert requests.reason is None
