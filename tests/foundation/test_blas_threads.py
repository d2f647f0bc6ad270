"""The simulating stages run BLAS on one thread and give the threads back afterwards."""

import numpy as np
import pytest
from threadpoolctl import threadpool_info, threadpool_limits

from wipelab.blas_threads import single_threaded_blas
from wipelab.stages.adapt import run_adapt
from wipelab.stages.replay import run_replay


def blas_threads() -> list[int]:
    return [pool["num_threads"] for pool in threadpool_info() if pool["user_api"] == "blas"]


def test_inside_one_thread_outside_as_before():
    assert blas_threads(), "numpy's BLAS is not visible to threadpoolctl"

    @single_threaded_blas
    def product():
        inside = blas_threads()
        return np.ones((400, 50)) @ np.ones((50, 3)), inside

    with threadpool_limits(limits=2, user_api="blas"):
        result, inside = product()
        assert blas_threads() == [2] * len(inside)
    assert inside == [1] * len(inside) and result[0, 0] == 50.0


def test_restored_when_the_function_raises():
    @single_threaded_blas
    def failing():
        raise ValueError("bad model")

    with threadpool_limits(limits=2, user_api="blas"):
        with pytest.raises(ValueError):
            failing()
        assert set(blas_threads()) == {2}


@pytest.mark.parametrize("stage", [run_adapt, run_replay])
def test_the_stages_are_wrapped(stage):
    assert stage.__wrapped__.__name__ == stage.__name__
    assert stage.__code__ is single_threaded_blas(lambda: None).__code__
