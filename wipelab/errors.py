"""What the CLI makes of exceptions: bad input (:class:`InputError`) and a user's Ctrl-C."""

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager


class InputError(Exception):
    """Bad input or usage: the CLI prints ``error: <message>`` on one line and exits with 2.

    The message names the file (or option) and what is wrong with it, e.g.
    ``InputError("demo/left.mp4: cannot be decoded by OpenCV")``.
    """


def from_user_interrupt(error: BaseException) -> bool:
    """Whether ``error`` is a Ctrl-C: a KeyboardInterrupt, or an error it caused.

    Python runs the SIGINT handler between bytecodes; when that falls inside a call of a
    numba-compiled function, the KeyboardInterrupt surfaces as ``SystemError: ... returned a
    result with an exception set``, caused by the KeyboardInterrupt.
    """
    seen: BaseException | None = error
    while seen is not None:
        if isinstance(seen, KeyboardInterrupt):
            return True
        seen = seen.__cause__ or seen.__context__
    return False


@contextmanager
def interrupts_deferred() -> Iterator[None]:
    """Hold a Ctrl-C back until the block ends, then raise it as usual.

    For steps that must not be cut halfway, e.g. starting threads: a KeyboardInterrupt
    inside ``Thread.start`` leaves a thread that runs but that nobody joins, and a thread
    still inside FFmpeg when Python exits aborts the process. Only the main thread receives
    Ctrl-C; elsewhere the block runs as it is.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    received: list[tuple] = []
    previous = signal.signal(signal.SIGINT, lambda *args: received.append(args))
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
        if received:
            signal.raise_signal(signal.SIGINT)
