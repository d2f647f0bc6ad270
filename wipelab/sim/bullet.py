"""The ``pybullet`` module, imported without the build banner it prints.

PyBullet's C code prints "pybullet build time: ..." when it is imported (on stderr in the
3.2 wheels, on stdout in some builds); a command's output must carry only its own lines. The
banner is sent to ``/dev/null`` by pointing file descriptors 1 and 2 there during the import
(C's stdio buffers are flushed before they are pointed back, so that a buffered banner is not
written later). An import error still raises as usual.
"""

from __future__ import annotations

import ctypes
import os
import sys


def _import_quietly():
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
    try:
        with open(os.devnull, "wb") as null:
            os.dup2(null.fileno(), 1)
            os.dup2(null.fileno(), 2)
            try:
                import pybullet
            finally:
                ctypes.CDLL(None).fflush(None)
    finally:
        for fd, copy in zip((1, 2), saved):
            os.dup2(copy, fd)
            os.close(copy)
    return pybullet


pybullet = _import_quietly()

__all__ = ["pybullet"]
