"""Reading a user's input file with errors that name it (the edge where InputError starts)."""

from __future__ import annotations

import os
from pathlib import Path

from wipelab.errors import InputError


def read_input_text(path: str | os.PathLike, encoding: str = "utf-8") -> str:
    """The text of an input file.

    Raises ``InputError("<file>: file not found")`` or
    ``InputError("<file>: cannot be read (<error>)")`` (unreadable, a directory, not text).
    """
    try:
        return Path(path).read_text(encoding=encoding)
    except FileNotFoundError:
        raise InputError(f"{path}: file not found") from None
    except (OSError, UnicodeDecodeError) as error:
        raise InputError(f"{path}: cannot be read ({error.__class__.__name__}: {error})") from None
