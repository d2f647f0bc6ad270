"""Numba's cache is refreshed when a module a kernel uses changes, not only the kernel's file."""

import importlib

from wipelab.numba_cache import dependency_files, forget_stale_kernels, refresh_cache


def test_cache_files_go_when_a_dependency_changes_and_stay_otherwise(tmp_path):
    kernel, helper = tmp_path / "kernel.py", tmp_path / "helper.py"
    kernel.write_text("def loop(): ...\n")
    helper.write_text("def step(): return 1\n")
    cache = tmp_path / "__pycache__"
    cache.mkdir()
    cached = [cache / "kernel.loop-1.py311.nbi", cache / "kernel.loop-1.py311.1.nbc"]
    others = cache / "helper.step-1.py311.nbi"
    for path in (*cached, others):
        path.write_bytes(b"compiled")

    assert refresh_cache(kernel, [kernel, helper], cache)          # nothing recorded yet
    assert not any(path.exists() for path in cached) and others.exists()
    for path in cached:
        path.write_bytes(b"compiled again")
    assert not refresh_cache(kernel, [kernel, helper], cache)      # unchanged sources
    assert all(path.exists() for path in cached)
    helper.write_text("def step(): return 2\n")
    assert refresh_cache(kernel, [kernel, helper], cache)          # a dependency changed
    assert not any(path.exists() for path in cached)


def test_the_online_kernel_depends_on_every_module_compiled_into_its_loop():
    module = importlib.import_module("wipelab.learning.online_kernel")
    names = {path.name for path in dependency_files(module)}
    assert {"online_kernel.py", "period_detector.py", "harmonic.py", "afo.py", "afs.py",
            "oscillators.py", "dmp.py", "derivatives.py", "tempo.py", "position_fit.py",
            "limit_cycle.py", "lwr.py", "normalise.py"} <= names
    assert not forget_stale_kernels(module.__name__)              # checked at import already
    refinement = importlib.import_module("wipelab.vision.pose_refinement")
    assert "_likelihood_kernel.py" in {path.name for path in dependency_files(refinement)}
