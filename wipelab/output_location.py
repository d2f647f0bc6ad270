"""Where a command will write, checked before it does any work.

A command that computes for a minute and then finds that its output folder is a file, or
that it may not write there, wastes the minute and ends in a traceback. Every output
location is checked up front instead (by the CLI when it parses the option, see
:mod:`wipelab.cli.options`, and again by :func:`wipelab.stage_output.staged_output`), and a
bad one is an :class:`~wipelab.errors.InputError` naming it:

- a file where a directory goes (``-o track.csv`` for a stage folder),
- a directory where a file goes (rollout's CSV, ``view --save``),
- a path below a file (``-o notes.txt/out``),
- a place the user may not write (permission bits, a read-only file system).

Missing parent folders are not an error: they are created when the output is written
(``-o runs/today/track`` in a fresh clone), as ``mkdir -p`` would.
"""

from __future__ import annotations

import os
from pathlib import Path

from wipelab.errors import InputError


def check_output_dir(path: str | os.PathLike) -> Path:
    """``path`` as a Path if a command can write a folder of files there, else InputError.

    The folder may exist (files are added to it) or not (it is created, with its parents);
    its parent receives the temporary folder the files are written into first.
    """
    path = Path(path)
    if path.is_dir():
        _require_writable(path, path)
    elif path.exists() or path.is_symlink():
        raise InputError(f"{path}: exists and is not a directory")
    _require_creatable(path)
    return path


def check_output_file(path: str | os.PathLike) -> Path:
    """``path`` as a Path if a command can write (or replace) a file there, else InputError."""
    path = Path(path)
    if path.is_dir():
        raise InputError(f"{path}: is a directory, expected a file name")
    if path.name in ("", ".", ".."):
        raise InputError(f"{path}: expected a file name")
    _require_creatable(path)
    return path


def _require_creatable(path: Path) -> None:
    """The nearest existing folder above ``path`` is a directory the user may write in."""
    ancestor = path.absolute().parent
    while not ancestor.exists() and ancestor != ancestor.parent:
        if ancestor.is_symlink():
            raise InputError(f"{path}: {ancestor} is a broken symbolic link")
        ancestor = ancestor.parent
    if not ancestor.is_dir():
        raise InputError(f"{path}: {_shown(ancestor)} is not a directory")
    _require_writable(path, ancestor)


def _require_writable(path: Path, folder: Path) -> None:
    if not os.access(folder, os.W_OK | os.X_OK):
        where = "the folder" if folder == path else _shown(folder)
        raise InputError(f"{path}: cannot write there ({where} is not writable)")


def _shown(folder: Path) -> str:
    """``folder`` relative to the working directory when it is inside it."""
    try:
        return str(folder.relative_to(Path.cwd())) or "."
    except ValueError:
        return str(folder)
