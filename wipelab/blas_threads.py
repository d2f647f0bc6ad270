"""BLAS on one thread while a simulating stage runs.

The matrix products of ``wipelab adapt`` and ``wipelab replay`` are small (the largest, the
limit-cycle tables of :class:`~wipelab.sim.path.PathGenerator`, are 4097 x 50 by 50 x 3).
OpenBLAS splits such a product over its threads, which then spin while they wait for the
next one: in ``wipelab adapt`` (40 s simulated, 2 cores, load 2.5) that took 0.75 s of its
2.75 s of CPU, and as much wall-clock time. On one thread the results are the same bytes
(each element of a product is summed in the same order).
"""

from __future__ import annotations

import functools

from threadpoolctl import threadpool_limits


def single_threaded_blas(function):
    """Decorator: ``function`` runs with the BLAS libraries on one thread (their former
    limits restored when it returns or raises)."""
    @functools.wraps(function)
    def on_one_thread(*args, **kwargs):
        with threadpool_limits(limits=1, user_api="blas"):
            return function(*args, **kwargs)
    return on_one_thread
