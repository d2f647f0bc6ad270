"""The ``pybullet`` module, imported without the build banner it prints on stdout.

PyBullet's C code prints "pybullet build time: ..." with ``printf`` when it is imported; a
command's stdout must carry only its own output. The banner is sent to ``/dev/null`` by
pointing file descriptor 1 there during the import (and flushing C's stdio buffer before
pointing it back, so that a buffered banner is not written later).
"""

from __future__ import annotations

import ctypes
import os
import sys


def _import_quietly():
    sys.stdout.flush()
    saved = os.dup(1)
    try:
        with open(os.devnull, "wb") as null:
            os.dup2(null.fileno(), 1)
            try:
                import pybullet
            finally:
                ctypes.CDLL(None).fflush(None)
    finally:
        os.dup2(saved, 1)
        os.close(saved)
    return pybullet


pybullet = _import_quietly()

__all__ = ["pybullet"]
