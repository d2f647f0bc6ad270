"""The simulating stages run BLAS on one thread and give the threads back afterwards."""

import os
import subprocess
import sys

import numpy as np
import scipy.linalg  # noqa: F401  (both OpenBLAS libraries loaded before the tests set limits)
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
    assert len(inside) >= 2, "SciPy's OpenBLAS (numba's) is not limited"
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


@pytest.mark.parametrize("preset, expected", [(None, 1), ("2", 2)])
def test_a_command_starts_its_blas_libraries_on_one_thread_unless_told(preset, expected):
    code = ("from wipelab.blas_threads import start_with_one_blas_thread\n"
            "start_with_one_blas_thread()\n"
            "import numpy, scipy.linalg\n"
            "from threadpoolctl import threadpool_info\n"
            "print(sorted({p['num_threads'] for p in threadpool_info()"
            " if p['user_api'] == 'blas'}))")
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
    if preset is not None:
        env["OPENBLAS_NUM_THREADS"] = preset
    done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                          check=True)
    assert done.stdout.strip() == f"[{expected}]"
