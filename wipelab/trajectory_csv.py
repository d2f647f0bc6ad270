"""The Trajectory CSV of DESIGN.md: read it with validation at the edge, write it deterministically.

Format: a header row ``t,x,y,z`` (which columns are required depends on the reader: learn
needs ``t,x,y``), an optional ``valid`` column (0/1) and any extra numeric columns, which are
kept. Time in seconds since the start of the recording, strictly increasing; positions in
metres in the world frame (left-camera frame when the calibration has no ``T_world_left``).

Rows with ``valid = 0`` (e.g. frames where the tracker lost the sponge) may hold NaN in the
position columns; every other value must be finite. The one text column is track's
``quality`` (:data:`TEXT_COLUMNS`): how each row was measured.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from wipelab.errors import InputError
from wipelab.input_files import read_input_text

#: Name of the optional 0/1 column that flags usable rows.
VALID_COLUMN = "valid"
#: Columns that hold text rather than numbers (kept as str arrays).
TEXT_COLUMNS = ("quality",)


@dataclass(frozen=True)
class Trajectory:
    """A time series read from a Trajectory CSV.

    Attributes
    ----------
    path : str
        The file it was read from (for error messages).
    t : ndarray, shape (n,)
        Time in seconds, strictly increasing.
    columns : dict[str, ndarray of shape (n,)]
        Every numeric column but ``t``, in file order, as float64.
    text : dict[str, ndarray of shape (n,)]
        The text columns (:data:`TEXT_COLUMNS`) present, as str arrays.
    """

    path: str
    t: np.ndarray
    columns: dict[str, np.ndarray]
    text: dict[str, np.ndarray] = field(default_factory=dict)

    @property
    def valid(self) -> np.ndarray:
        """Rows usable for learning, shape (n,) bool: the ``valid`` column, or all True."""
        if VALID_COLUMN in self.columns:
            return self.columns[VALID_COLUMN] != 0
        return np.ones(self.t.shape, dtype=bool)

    def array(self, names: Sequence[str]) -> np.ndarray:
        """Stack the named columns, shape (n, len(names)); raises InputError for a missing one."""
        missing = [name for name in names if name not in self.columns]
        if missing:
            raise InputError(f"{self.path}: missing column(s) {', '.join(missing)} "
                             f"(has {', '.join(['t', *self.columns])})")
        return np.column_stack([self.columns[name] for name in names])


#: Largest magnitude of a value: the seconds and metres of a recording stay far below it,
#: and sums of squares of larger ones overflow float64.
MAX_MAGNITUDE = 1e9


def read_trajectory(path: str | os.PathLike, required: Sequence[str] = ("t", "x", "y"),
                    min_rows: int = 3) -> Trajectory:
    """Read and validate a Trajectory CSV.

    Parameters
    ----------
    path : path-like
        The CSV file.
    required : sequence of str
        Columns that must be present (``t`` is always required).
    min_rows : int
        Fewest data rows accepted.

    Raises
    ------
    InputError
        Naming the file: missing/unreadable, no or bad header, missing columns, a value that is
        not a number, NaN/inf or a magnitude above :data:`MAX_MAGNITUDE` (outside rows
        flagged ``valid = 0``), fewer than ``min_rows`` rows, time not strictly increasing.
    """
    name = str(path)
    text = read_input_text(path, encoding="utf-8-sig")
    lines = text.splitlines()
    if not lines or not lines[0].strip():
        raise InputError(f"{name}: empty file, expected a header row like t,x,y,z")
    header = [column.strip() for column in lines[0].split(",")]
    duplicates = sorted({column for column in header if header.count(column) > 1})
    if duplicates or "" in header:
        raise InputError(f"{name}: bad header {lines[0]!r} (empty or duplicate column names)")
    missing = [column for column in dict.fromkeys(("t", *required)) if column not in header]
    if missing:
        raise InputError(f"{name}: missing column(s) {', '.join(missing)} "
                         f"(header is {','.join(header)})")

    body = [line for line in lines[1:] if line.strip()]
    if len(body) < min_rows:
        raise InputError(f"{name}: too short, {len(body)} data row(s), need at least {min_rows}")
    text_index = [j for j, column in enumerate(header) if column in TEXT_COLUMNS]
    numeric_index = [j for j in range(len(header)) if j not in text_index]
    text = {}
    if text_index:
        cells = [line.split(",") for line in body]
        if any(len(row) != len(header) for row in cells):
            row = next(k for k, r in enumerate(cells) if len(r) != len(header))
            raise InputError(f"{name}: {len(cells[row])} values in data row {row + 1} but "
                             f"{len(header)} header columns")
        text = {header[j]: np.array([row[j].strip() for row in cells]) for j in text_index}
        body = [",".join(row[j] for j in numeric_index) for row in cells]
    try:
        data = np.loadtxt(body, delimiter=",", dtype=np.float64, ndmin=2)
    except ValueError as error:
        raise InputError(f"{name}: not a table of numbers ({error})") from None
    if data.shape[1] != len(numeric_index):
        raise InputError(f"{name}: {data.shape[1] + len(text_index)} values per row but "
                         f"{len(header)} header columns")

    columns = {header[j]: data[:, k].copy() for k, j in enumerate(numeric_index)}
    t = columns.pop("t")
    valid = np.ones(t.shape, dtype=bool)
    if VALID_COLUMN in columns:
        flags = columns[VALID_COLUMN]
        if not np.all((flags == 0) | (flags == 1)):
            raise InputError(f"{name}: column {VALID_COLUMN} must hold only 0 or 1")
        valid = flags == 1
        if not valid.any():
            raise InputError(f"{name}: no row has {VALID_COLUMN} = 1")
    for column, values in {"t": t, **columns}.items():
        rows = np.arange(t.size) if column == "t" else np.flatnonzero(valid)
        checked = values[rows]
        bad = ~np.isfinite(checked)
        if bad.any():
            raise InputError(f"{name}: column {column} has NaN or inf "
                             f"(data row {rows[bad][0] + 1})")
        huge = np.abs(checked) > MAX_MAGNITUDE
        if huge.any():
            raise InputError(f"{name}: column {column} holds {checked[huge][0]:g} (data row "
                             f"{rows[huge][0] + 1}); seconds and metres of a recording stay "
                             f"within +-{MAX_MAGNITUDE:g}")
    steps = np.diff(t)
    if np.any(steps <= 0):
        row = int(np.flatnonzero(steps <= 0)[0]) + 2
        raise InputError(f"{name}: time column t is not strictly increasing (data row {row})")
    return Trajectory(path=name, t=t, columns=columns, text=text)


def write_trajectory(path: str | os.PathLike, t: np.ndarray, columns: Mapping[str, np.ndarray],
                     float_format: str = "%.6f") -> None:
    """Write a Trajectory CSV deterministically (same arrays -> same bytes).

    The file is written under a temporary name beside ``path`` and renamed, so a partial
    file never appears under the final name.

    Parameters
    ----------
    path : path-like
        Output file.
    t : ndarray, shape (n,)
        Time in seconds.
    columns : mapping of str to ndarray of shape (n,)
        Written in mapping order after ``t``; bool and integer arrays (e.g. ``valid``) are
        written as integers, str arrays (:data:`TEXT_COLUMNS`) as they are, everything
        else with ``float_format``.
    float_format : str
        printf-style format of float values.
    """
    t = np.asarray(t, dtype=np.float64)
    names = list(columns)
    if "t" in names:
        raise ValueError("columns must not contain 't'; pass time as the t argument")
    arrays = [np.asarray(columns[name]) for name in names]
    for name, values in zip(names, arrays):
        if values.shape != t.shape:
            raise ValueError(f"column {name!r} has shape {values.shape}, expected {t.shape}")
    formats = [float_format] + ["%d" if values.dtype.kind in "biu" else
                                "%s" if values.dtype.kind in "US" else float_format
                                for values in arrays]
    row_format = ",".join(formats)
    rows = zip(t, *arrays)
    text = ",".join(["t", *names]) + "\n" + "".join(row_format % row + "\n" for row in rows)
    path = Path(path)
    tmp = path.with_name(f".{path.name}.partial-{os.getpid()}")
    try:
        tmp.write_text(text)
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)
