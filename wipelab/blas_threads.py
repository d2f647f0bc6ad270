"""BLAS on one thread while a simulating stage runs.

The matrix products of ``wipelab adapt`` and ``wipelab replay`` are small (the largest, the
limit-cycle tables of :class:`~wipelab.sim.path.PathGenerator`, are 4097 x 50 by 50 x 3).
OpenBLAS splits such a product over its threads, which then spin while they wait for the
next one: in ``wipelab adapt`` (40 s simulated, 2 cores, load 2.5) that took 0.75 s of its
2.75 s of CPU, and as much wall-clock time. On one thread the results are the same bytes
(each element of a product is summed in the same order).

Two OpenBLAS libraries are involved: NumPy's, and SciPy's, through which numba's compiled
kernels call BLAS (numba loads it when it starts compiling or loading kernels). A limit
applies to the libraries loaded when it is set, so :func:`single_threaded_blas` loads
SciPy's first. An OpenBLAS library also spins its threads for a while when it is loaded
(0.15 s of CPU for the two): :func:`start_with_one_blas_thread` avoids that in a process
that has not imported NumPy yet.
"""

from __future__ import annotations

import functools
import os

from threadpoolctl import threadpool_limits


def start_with_one_blas_thread() -> None:
    """OpenBLAS libraries loaded from now on start with one thread (``OPENBLAS_NUM_THREADS``,
    unless it is set already): for a command that imports NumPy after this."""
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")


def single_threaded_blas(function):
    """Decorator: ``function`` runs with the BLAS libraries on one thread (their former
    limits restored when it returns or raises)."""
    @functools.wraps(function)
    def on_one_thread(*args, **kwargs):
        import scipy.linalg  # noqa: F401  (SciPy's OpenBLAS, numba's: limited too)

        with threadpool_limits(limits=1, user_api="blas"):
            return function(*args, **kwargs)
    return on_one_thread
