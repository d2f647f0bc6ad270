"""Reading a model.json (``wipelab.periodic_dmp/1``) with errors that name the file."""

from __future__ import annotations

import json
import os
from pathlib import Path

from wipelab.errors import InputError
from wipelab.learning import PeriodicModel


def read_model(path: str | os.PathLike) -> PeriodicModel:
    """Load a model file; InputError("<file>: <what is wrong>") if it is not a valid one."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: model file does not exist")
    try:
        data = json.loads(path.read_text())
    except UnicodeDecodeError:
        raise InputError(f"{path}: not a model file (not UTF-8 text)") from None
    except json.JSONDecodeError as error:
        raise InputError(f"{path}: not a model file (invalid JSON: {error.msg} at line "
                         f"{error.lineno})") from None
    try:
        return PeriodicModel.from_dict(data)
    except ValueError as error:
        raise InputError(f"{path}: {error}") from None
