"""Option parsing shared by the command modules."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from pathlib import Path

import click

from wipelab.errors import InputError
from wipelab.output_location import check_output_dir, check_output_file

#: A path argument or option, given to the command as a pathlib.Path.
PATH = click.Path(path_type=Path, readable=False)

#: Ranges of ``synth`` and ``synth-dataset``: wiping frequency (Hz), length (s), frame rate,
#: and the number of parallel jobs of ``synth-dataset`` and ``dataset``.
SYNTH_FREQUENCY_HZ = click.FloatRange(min=0.05, max=5.0)
SYNTH_DURATION_S = click.FloatRange(min=1.0, max=3600.0)
FRAME_RATE = click.IntRange(min=1, max=240)
JOBS = click.IntRange(min=1)

#: False while a pipeline only test-parses its stages' command lines (their output folders
#: are made by the runner, inside a run directory that may not exist yet).
_CHECK_OUTPUTS: ContextVar[bool] = ContextVar("check_outputs", default=True)


class OutputLocation(click.Path):
    """Where a command writes: a folder of files (``kind="dir"``) or one file
    (``kind="file"``). Checked as soon as it is parsed, before any work
    (:mod:`wipelab.output_location`); a bad one is one line and exit code 2."""

    def __init__(self, kind: str):
        super().__init__(path_type=Path, readable=False)
        self.kind = kind

    def convert(self, value, param, ctx) -> Path:
        path = super().convert(value, param, ctx)
        if _CHECK_OUTPUTS.get():
            (check_output_dir if self.kind == "dir" else check_output_file)(path)
        return path


#: An output folder, an output file (see :class:`OutputLocation`).
OUTPUT_DIR = OutputLocation("dir")
OUTPUT_FILE = OutputLocation("file")


@contextmanager
def output_checks_deferred() -> Iterator[None]:
    """Parse command lines without checking their output locations (a pipeline's dry run)."""
    token = _CHECK_OUTPUTS.set(False)
    try:
        yield
    finally:
        _CHECK_OUTPUTS.reset(token)


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
