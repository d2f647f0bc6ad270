"""Numba's on-disk cache, kept in step with every wipelab module a kernel module calls into.

Numba keys a cached function (``@njit(cache=True)``) on its own source file only. A kernel
that calls functions of other modules (the online learner's loop calls the period detector,
the harmonic fit, the AFO pool, ...) would therefore run stale compiled code after one of
those changed. Each kernel module calls :func:`forget_stale_kernels` at its end: when the
sources of the module and of the wipelab modules it uses, directly or through each other,
differ from those recorded beside its cache, its cache files are deleted and numba compiles
afresh on the first call.

Only the in-tree cache (``__pycache__`` beside the source, numba's default when writable) is
managed; where that is not writable numba caches elsewhere and nothing is done.
"""

from __future__ import annotations

import hashlib
import sys
import types
from collections.abc import Iterable
from pathlib import Path

PACKAGE = "wipelab"


def forget_stale_kernels(module_name: str) -> bool:
    """Delete the cached kernels of module ``module_name`` (and of the functions of other
    modules it compiles, ``njit(cache=True)(function)``) whose sources, or the sources of
    what they use, changed since they were cached; True if something was deleted."""
    module = sys.modules[module_name]
    owners = {module_name} | {value.py_func.__module__ for value in vars(module).values()
                              if hasattr(value, "py_func")}
    deleted = False
    for name in sorted(owners):
        owner = sys.modules[name]
        source = Path(owner.__file__)
        try:
            deleted |= refresh_cache(source, dependency_files(owner), source.parent / "__pycache__")
        except OSError:
            pass
    return deleted


def dependency_files(module: types.ModuleType) -> list[Path]:
    """Source files of ``module`` and of the wipelab modules it uses, transitively: those of
    the functions, compiled functions, classes and modules its globals name."""
    seen: dict[str, Path] = {}
    pending = [module.__name__]
    while pending:
        name = pending.pop()
        if name in seen or name not in sys.modules:
            continue
        current = sys.modules[name]
        seen[name] = Path(current.__file__)
        pending.extend(_used_module_names(vars(current).values()))
    return sorted(seen.values())


def _used_module_names(objects: Iterable[object]) -> set[str]:
    names = set()
    for value in objects:
        value = getattr(value, "py_func", value)       # a numba dispatcher: the Python function
        name = value.__name__ if isinstance(value, types.ModuleType) else \
            getattr(value, "__module__", None)
        if isinstance(name, str) and (name == PACKAGE or name.startswith(PACKAGE + ".")):
            names.add(name)
    return names


def refresh_cache(source: Path, dependencies: Iterable[Path], cache_dir: Path) -> bool:
    """Delete ``cache_dir``'s numba files of ``source`` (``<stem>.*.nbi``, ``<stem>.*.nbc``)
    when the digest of ``dependencies`` differs from the one recorded in
    ``<stem>.sources.sha256`` (or none is), and record the new one; True if it deleted."""
    digest = hashlib.sha256()
    for path in dependencies:
        digest.update(path.name.encode() + b"\0" + path.read_bytes() + b"\0")
    record = cache_dir / f"{source.stem}.sources.sha256"
    if record.is_file() and record.read_text() == digest.hexdigest():
        return False
    stale = [path for pattern in (f"{source.stem}.*.nbi", f"{source.stem}.*.nbc")
             for path in cache_dir.glob(pattern)]
    for path in stale:
        path.unlink(missing_ok=True)
    cache_dir.mkdir(exist_ok=True)
    record.write_text(digest.hexdigest())
    return bool(stale)
