"""What the CLI makes of exceptions: bad input (:class:`InputError`) and a user's Ctrl-C."""


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
