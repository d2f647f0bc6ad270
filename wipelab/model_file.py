"""Reading a model.json (``wipelab.periodic_dmp/1``) with errors that name the file.

A top-level module, light to import: learn/rollout use it without loading the simulator.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from wipelab.errors import InputError
from wipelab.input_files import read_input_text
from wipelab.learning.model import PeriodicModel


def read_model(path: str | os.PathLike) -> PeriodicModel:
    """Load a model file; ``InputError("<file>: <what is wrong>")`` if it is not a valid one."""
    path = Path(path)
    text = read_input_text(path)
    try:
        data = json.loads(text)
    except json.JSONDecodeError as error:
        raise InputError(f"{path}: not a model file (not JSON: {error.msg} at line "
                         f"{error.lineno})") from None
    try:
        return PeriodicModel.from_dict(data)
    except ValueError as error:
        raise InputError(f"{path}: {error}") from None
