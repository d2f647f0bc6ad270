"""Setup shared by every test."""

import signal


def pytest_configure(config):
    """Ctrl-C must reach what the interrupt tests interrupt. A background job of a
    non-interactive shell (a CI runner's, ``nohup ... &``) starts with SIGINT ignored; the
    processes it starts inherit that, and Python then raises no KeyboardInterrupt (8 tests
    failed so). Python's own handler is put back here, and the commands the tests start get
    the default disposition."""
    if signal.getsignal(signal.SIGINT) == signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)
