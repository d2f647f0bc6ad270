"""Reading a user's input file with errors that name it (the edge where InputError starts).

Every file a user hands in (a trajectory, a model, a surface and its mesh or heightfield, a
calibration, a run's metrics and logs) is read through these functions, so that a file that
is missing, unreadable, binary where text belongs, cut short or of the wrong shape ends in
one line ``error: <file>: <what is wrong>`` and never in a traceback.
"""

from __future__ import annotations

import json
import os
import tomllib
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from wipelab.errors import InputError, from_user_interrupt


@contextmanager
def reading(path: str | os.PathLike, what: str) -> Iterator[None]:
    """Whatever goes wrong in the ``with`` block is the fault of the file at ``path``.

    The block interprets one file (parses it, or takes values out of what was parsed); an
    exception there becomes ``InputError("<path>: <what> (<exception>)")``, e.g.
    ``InputError("m.obj: not a Wavefront OBJ mesh (line 3: ...)")``. A missing or unreadable
    file gets its own message; InputError and a Ctrl-C pass unchanged.
    """
    try:
        yield
    except InputError:
        raise
    except FileNotFoundError:
        raise InputError(f"{path}: file not found") from None
    except IsADirectoryError:
        raise InputError(f"{path}: is a directory, expected a file") from None
    except PermissionError:
        raise InputError(f"{path}: cannot be read (permission denied)") from None
    except UnicodeDecodeError as error:
        raise InputError(f"{path}: not a text file (byte 0x{error.object[error.start]:02x} "
                         f"at offset {error.start} is not {error.encoding})") from None
    except Exception as error:  # noqa: BLE001 -- the block only interprets the file
        if from_user_interrupt(error):
            raise
        raise InputError(f"{path}: {what} ({_describe(error)})") from None


def check_readable(path: str | os.PathLike) -> Path:
    """``path`` as a Path if it is a file the user may read, else InputError naming it (for
    files a library opens by name, whose own errors do not tell a missing or unreadable
    file from a broken one)."""
    with reading(path, "cannot be read"), open(path, "rb"):
        pass
    return Path(path)


def read_input_text(path: str | os.PathLike, encoding: str = "utf-8") -> str:
    """The text of an input file.

    Raises ``InputError("<file>: file not found")``, ``"<file>: not a text file (...)"`` or
    ``"<file>: cannot be read (...)"`` (unreadable, a directory).
    """
    with reading(path, "cannot be read"):
        return Path(path).read_text(encoding=encoding)


def read_input_json(path: str | os.PathLike, what: str = "not valid JSON") -> Any:
    """The parsed content of a JSON file; ``InputError("<file>: <what> (<where>)")`` when it
    is not JSON."""
    text = read_input_text(path)
    with reading(path, what):
        return json.loads(text)


def read_input_toml(path: str | os.PathLike) -> dict[str, Any]:
    """The parsed content of a TOML file; InputError naming it when it is not TOML."""
    text = read_input_text(path)
    with reading(path, "not valid TOML"):
        return tomllib.loads(text)


def read_input_npy(path: str | os.PathLike):
    """The array in a ``.npy`` file (no pickled objects); InputError naming it otherwise."""
    import numpy as np

    with reading(path, "not a .npy array"):
        return np.load(path, allow_pickle=False)


def _describe(error: BaseException) -> str:
    text = str(error).strip()
    if isinstance(error, (ValueError, KeyError)) and text:
        return text.strip("'\"") if isinstance(error, KeyError) else text
    return f"{type(error).__name__}: {text}" if text else type(error).__name__
