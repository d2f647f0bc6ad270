"""Write a stage's files so that nothing half-written ever appears under a final name.

Files are written into a temporary folder ``.<OUT>.partial-<random>`` beside the output and
moved into place when the stage succeeds. While a process writes into such a folder it
holds an exclusive ``flock`` on it, which the kernel releases when the process ends, even
by SIGKILL: a folder nobody holds a lock on is a leftover of a killed run, and it is removed
the next time the same output is written.
"""

from __future__ import annotations

import fcntl
import os
import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from wipelab.output_location import check_output_dir, check_output_file


@contextmanager
def staged_output(out_dir: str | os.PathLike) -> Iterator[Path]:
    """Yield a fresh temporary directory beside ``out_dir``; publish its files on success.

    ``out_dir`` is checked first (:func:`~wipelab.output_location.check_output_dir`). Every
    file is written under the temporary directory. When the ``with`` block ends without an
    exception, each file is moved into ``out_dir`` with an atomic ``os.replace`` (files
    already in ``out_dir`` that the stage did not write are left alone). On any exception,
    KeyboardInterrupt included, the temporary directory is removed and ``out_dir`` is
    untouched.
    """
    out_dir = check_output_dir(out_dir)
    with _partial_folder(out_dir) as tmp:
        yield tmp
        _check_targets(tmp, out_dir)
        out_dir.mkdir(exist_ok=True)
        for path in sorted(tmp.rglob("*")):
            target = out_dir / path.relative_to(tmp)
            if path.is_dir():
                target.mkdir(exist_ok=True)
            else:
                os.replace(path, target)


@contextmanager
def staged_file(out_file: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary path to write ``out_file`` under; move it into place on success.

    The same all-or-nothing rule as :func:`staged_output`, for a command whose output is
    one file (rollout's CSV, ``view --save``).
    """
    out_file = check_output_file(out_file)
    with _partial_folder(out_file) as tmp:
        yield tmp / out_file.name
        os.replace(tmp / out_file.name, out_file)


def remove_stale_partials(folder: Path, name: str | None = None) -> list[Path]:
    """Remove the ``.<name>.partial-*`` folders under ``folder`` that no process holds
    (every output's, when ``name`` is None); returns the removed ones."""
    pattern = f".{name}.partial-*" if name is not None else ".*.partial-*"
    removed = []
    for leftover in sorted(folder.glob(pattern)):
        if leftover.is_dir() and not leftover.is_symlink():
            with _lock(leftover, wait=False) as held:
                if held:
                    shutil.rmtree(leftover, ignore_errors=True)
                    removed.append(leftover)
    return removed


@contextmanager
def _partial_folder(output: Path) -> Iterator[Path]:
    """A new, locked ``.<name>.partial-*`` folder beside ``output``, removed at the end;
    the stale ones of the same output are removed first."""
    output.parent.mkdir(parents=True, exist_ok=True)
    remove_stale_partials(output.parent, output.name)
    tmp = Path(tempfile.mkdtemp(prefix=f".{output.name}.partial-", dir=output.parent))
    try:
        with _lock(tmp, wait=True):
            yield tmp
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


@contextmanager
def _lock(folder: Path, wait: bool) -> Iterator[bool]:
    """Hold an exclusive flock on ``folder``; yields False when another process holds it
    (only with ``wait=False``) or the folder is gone."""
    try:
        fd = os.open(folder, os.O_RDONLY | os.O_DIRECTORY)
    except OSError:
        yield False
        return
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX if wait else fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            yield False
            return
        yield True
    finally:
        os.close(fd)


def _check_targets(tmp: Path, out_dir: Path) -> None:
    """Before anything moves: no file may land where ``out_dir`` has a folder (or the
    reverse), which would leave the output half published."""
    for path in sorted(tmp.rglob("*")):
        target = out_dir / path.relative_to(tmp)
        (check_output_dir if path.is_dir() else check_output_file)(target)
