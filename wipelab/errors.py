"""The one exception type that means "the user gave us something we cannot use"."""


class InputError(Exception):
    """Bad input or usage: the CLI prints ``error: <message>`` on one line and exits with 2.

    The message names the file (or option) and what is wrong with it, e.g.
    ``InputError("demo/left.mp4: cannot be decoded by OpenCV")``.
    """
