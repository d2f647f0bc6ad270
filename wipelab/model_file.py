"""Reading a model.json (``wipelab.periodic_dmp/1``) with errors that name the file.

A top-level module, light to import: learn/rollout use it without loading the simulator.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from wipelab.errors import InputError
from wipelab.input_files import read_input_json
from wipelab.learning.model import PeriodicModel
from wipelab.trajectory_csv import MAX_MAGNITUDE

#: Frequencies (Hz) a model of a wiping movement may have: far beyond both ends of what
#: a person does, but a rollout of one period still has a sensible number of samples.
FREQUENCY_RANGE_HZ = (1e-3, 1e3)


def read_model(path: str | os.PathLike) -> PeriodicModel:
    """Load a model file; ``InputError("<file>: <what is wrong>")`` if it is not a valid one."""
    path = Path(path)
    data = read_input_json(path, "not a model file, not JSON")
    try:
        model = PeriodicModel.from_dict(data)
    except ValueError as error:
        raise InputError(f"{path}: {error}") from None
    low, high = FREQUENCY_RANGE_HZ
    if not low <= model.frequency_hz <= high:
        raise InputError(f"{path}: frequency_hz is {model.frequency_hz:g}, expected {low:g} to "
                         f"{high:g} Hz")
    for name in ("goal", "amplitude", "weights"):
        if np.abs(getattr(model, name)).max() > MAX_MAGNITUDE:
            raise InputError(f"{path}: {name} holds values beyond +-{MAX_MAGNITUDE:g}")
    return model
