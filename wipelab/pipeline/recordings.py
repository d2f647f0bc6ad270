"""A run's Rerun recordings: find them, join them into one, open them in the viewer.

Every stage writes its own ``<stage>.rrd`` with data time on the timeline ``time``. Joined
under one recording id they appear as one recording in which all stages share that
timeline: the tracked sponge, the oscillators and the DMP of the same demonstration line up.
The viewer is the ``rerun`` program of the rerun-sdk wheel.
"""

from __future__ import annotations

import os
import shutil
import sys
from collections.abc import Sequence
from pathlib import Path

from wipelab.errors import InputError
from wipelab.input_files import check_readable
from wipelab.stage_output import staged_file

#: Recording id of a joined recording.
JOINED_RECORDING_ID = "wipelab-run"


def find_recordings(path: str | os.PathLike) -> list[Path]:
    """The ``.rrd`` files at ``path``: the file itself, or every one under the directory.

    Raises
    ------
    InputError
        ``path`` does not exist or holds no ``.rrd`` file.
    """
    path = Path(path)
    if path.is_file():
        if path.suffix != ".rrd":
            raise InputError(f"{path}: not a Rerun recording (.rrd)")
        return [path]
    if not path.is_dir():
        raise InputError(f"{path}: no such file or directory")
    found = sorted(p for p in path.rglob("*.rrd")
                   if not any(part.startswith(".") for part in p.relative_to(path).parts))
    if not found:
        raise InputError(f"{path}: no .rrd recording inside")
    return found


def rerun_program() -> str:
    """Path of the ``rerun`` executable (beside this Python's, or on PATH)."""
    beside = Path(sys.executable).with_name("rerun")
    program = str(beside) if beside.exists() else shutil.which("rerun")
    if program is None:
        raise InputError("rerun: program not found (it comes with `pip install rerun-sdk`)")
    return program


def join_recordings(recordings: Sequence[Path], out: str | os.PathLike) -> Path:
    """Write the chunks of ``recordings`` as one recording (shared timelines) to ``out``.

    Each stage's reproducible ``.rrd`` numbers its chunks from 1, and a Rerun store keeps
    one chunk per id, so every chunk gets a fresh id here (``Chunk.with_entity_path`` mints
    one; rows, timelines and components are kept). The stages' own blueprints are left out
    (each lays out one stage); the viewer arranges the joined recording by itself. Written
    all or nothing (:func:`~wipelab.stage_output.staged_file`).
    """
    from rerun.chunk import ChunkStore, RrdReader

    out = Path(out)
    chunks, application_id = [], "wipelab"
    for path in recordings:
        try:
            reader = RrdReader(check_readable(path))
            stores = reader.recordings()
            if stores:
                application_id = stores[0].application_id
                chunks += [chunk.with_entity_path(chunk.entity_path)
                           for chunk in reader.stream(store=stores[0]).to_chunks()]
        except (RuntimeError, ValueError) as error:
            raise InputError(f"{path}: not a readable Rerun recording ({error})") from None
    with staged_file(out) as tmp:
        ChunkStore.from_chunks(chunks).write_rrd(tmp, application_id=application_id,
                                                 recording_id=JOINED_RECORDING_ID)
    return out


def has_display(environ: dict[str, str] | os._Environ = os.environ) -> bool:
    """True when a window can be opened ($DISPLAY or $WAYLAND_DISPLAY set)."""
    return bool(environ.get("DISPLAY") or environ.get("WAYLAND_DISPLAY"))


def viewer_argv(recordings: Sequence[Path], web: bool = False) -> list[str]:
    """The ``rerun`` command line that opens ``recordings`` (``web``: serve a web viewer)."""
    return [rerun_program(), *(["--serve-web"] if web else []), *map(str, recordings)]


def how_to_open(recordings: Sequence[Path], path: str | os.PathLike) -> str:
    """What to tell a user who has no display."""
    files = " ".join(map(str, recordings))
    return "\n".join([
        "No display ($DISPLAY and $WAYLAND_DISPLAY are unset), so no viewer was started.",
        "To look at the recordings:",
        f"  on a machine with a display:   rerun {files}",
        f"  all stages as one recording:   wipelab view {path} --save run.rrd   "
        f"(then: rerun run.rrd)",
        f"  in a browser, served from here: wipelab view {path} --web   "
        f"(or: rerun --serve-web {files})",
    ])
