"""Option parsing shared by the command modules."""

from __future__ import annotations

from pathlib import Path

import click

from wipelab.errors import InputError

#: A path argument or option, given to the command as a pathlib.Path.
PATH = click.Path(path_type=Path)


def comma_separated(option: str, text: str | None, count: int | None = None,
                    kind: type = float) -> tuple | None:
    """'0.5,0.1' -> (0.5, 0.1); None stays None.

    ``kind`` converts each part (float or int); with ``count`` the number of parts is
    checked too. Anything else raises InputError naming the option.
    """
    if text is None:
        return None
    try:
        values = tuple(kind(part) for part in text.split(","))
    except ValueError:
        values = ()
    if not values or (count is not None and len(values) != count):
        amount = f"{count} " if count is not None else ""
        noun = "integers" if kind is int else "numbers"
        raise InputError(f"{option}: expected {amount}comma-separated {noun}, got {text!r}")
    return values
