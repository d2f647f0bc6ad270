"""Write a stage's files so that nothing half-written ever appears under a final name."""

from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path


@contextmanager
def staged_output(out_dir: str | os.PathLike) -> Iterator[Path]:
    """Yield a fresh temporary directory beside ``out_dir``; publish its files on success.

    Every file is written under the temporary directory first. When the ``with`` block ends
    without an exception, each file is moved into ``out_dir`` with an atomic ``os.replace``
    (files already in ``out_dir`` that the stage did not write are left alone). On any
    exception, KeyboardInterrupt included, the temporary directory is removed and
    ``out_dir`` is untouched.
    """
    out_dir = Path(out_dir)
    out_dir.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out_dir.name}.partial-", dir=out_dir.parent))
    try:
        yield tmp
        out_dir.mkdir(exist_ok=True)
        for path in sorted(tmp.rglob("*")):
            target = out_dir / path.relative_to(tmp)
            if path.is_dir():
                target.mkdir(exist_ok=True)
            else:
                os.replace(path, target)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
