"""A run's Rerun recordings: find them, open them in the viewer, save them as one file.

Each stage writes its own ``<stage>.rrd``: one recording with application id
``wipelab_<stage>`` and the stage's default layout. ``wipelab view`` opens them side by side
in one viewer as they are, one recording per stage (the viewer's left panel lists them):

* every stage keeps its own layout: the viewer keeps one layout per application id;
* no two stages collide: track and learn run on the demonstration's clock, adapt and replay
  each on a simulated clock of its own, and adapt and replay both move the same robot
  (``/tf``, ``/robot``); in one recording they would share the timeline ``time`` and the
  robot would jump between two runs at every time stamp;
* nothing is rewritten or copied, so opening is instant and leaves no temporary file.

``--save`` writes them into one ``.rrd`` (the same recordings and layouts, for sharing) with
``rerun rrd merge``. The viewer is the ``rerun`` program of the rerun-sdk wheel; the native
viewer needs an ``ffmpeg`` executable on PATH to play the H.264 videos (the web viewer
decodes them in the browser).
"""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
from collections.abc import Sequence
from contextlib import contextmanager
from pathlib import Path

from wipelab.errors import InputError
from wipelab.input_files import check_readable
from wipelab.stage_output import staged_file


def find_recordings(path: str | os.PathLike) -> list[Path]:
    """The ``.rrd`` files at ``path``: the file itself, or every one under the directory
    (not in hidden folders such as a killed stage's leftovers), in path order.

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
    """Path of the Rerun executable: the binary the rerun-sdk wheel ships (what its ``rerun``
    script runs; started directly, it needs no Python and is the viewer's own process), else
    ``rerun`` on PATH."""
    try:
        import rerun_cli
    except ImportError:
        rerun_cli = None
    if rerun_cli is not None:
        folder = Path(rerun_cli.__file__).parent
        for binary in (folder / "Rerun.app" / "Contents" / "MacOS" / "Rerun", folder / "rerun",
                       folder / "rerun.exe"):
            if binary.is_file():
                return str(binary)
    program = shutil.which("rerun")
    if program is None:
        raise InputError("rerun: program not found (it comes with `pip install rerun-sdk`)")
    return program


@contextmanager
def terminated_as_exit():
    """Within the block a SIGTERM raises ``SystemExit(143)`` (instead of ending the process
    on the spot), so that ``finally`` blocks run: child processes are stopped and partial
    files removed."""
    def on_term(signum, frame):
        raise SystemExit(128 + signal.SIGTERM)

    previous = signal.signal(signal.SIGTERM, on_term)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def run_program(argv: Sequence[str]) -> int:
    """Run ``argv`` in a process group of its own and wait; its exit code. When this process
    is interrupted (Ctrl-C, or SIGTERM inside :func:`terminated_as_exit`), the whole group
    is stopped first (the viewer runs as a grandchild of ``rerun``)."""
    process = subprocess.Popen(list(argv), start_new_session=True)
    try:
        return process.wait()
    finally:
        if process.poll() is None:
            _stop_group(process)


def _stop_group(process: subprocess.Popen) -> None:
    for sig, wait_s in ((signal.SIGTERM, 5.0), (signal.SIGKILL, 5.0)):
        try:
            os.killpg(process.pid, sig)
        except ProcessLookupError:
            return
        try:
            process.wait(wait_s)
            return
        except subprocess.TimeoutExpired:
            continue


def save_recordings(recordings: Sequence[Path], out: str | os.PathLike) -> Path:
    """Write ``recordings`` (their recordings and layouts, each kept apart) into one ``.rrd``
    at ``out``, all or nothing (:func:`~wipelab.stage_output.staged_file`).

    Raises
    ------
    InputError
        A recording cannot be read or merged.
    """
    for path in recordings:
        _check_recording(path)
    with staged_file(out) as tmp:
        completed = subprocess.run([rerun_program(), "rrd", "merge", *map(str, recordings),
                                    "-o", str(tmp)], capture_output=True, text=True)
        if completed.returncode != 0 or not tmp.is_file():
            lines = [line for line in completed.stderr.splitlines() if line.strip()]
            raise InputError(f"{', '.join(map(str, recordings))}: cannot be merged "
                             f"({lines[-1].strip() if lines else 'rerun rrd merge failed'})")
    return Path(out)


def _check_recording(path: Path) -> None:
    """Read every chunk of the recording at ``path``; InputError naming it if it cannot be
    (missing, unreadable, not an .rrd, cut short)."""
    from rerun.chunk import RrdReader

    try:
        reader = RrdReader(check_readable(path))
        for store in reader.recordings() + reader.blueprints():
            reader.stream(store=store).flat_map(lambda chunk: []).to_chunks()
    except (RuntimeError, ValueError) as error:
        raise InputError(f"{path}: not a readable Rerun recording ({error})") from None


def has_display(environ: dict[str, str] | os._Environ = os.environ) -> bool:
    """True when a window can be opened ($DISPLAY or $WAYLAND_DISPLAY set)."""
    return bool(environ.get("DISPLAY") or environ.get("WAYLAND_DISPLAY"))


def viewer_argv(recordings: Sequence[Path], web: bool = False, port: int | None = None,
                web_port: int | None = None) -> list[str]:
    """The ``rerun`` command line that opens ``recordings`` (``web``: serve a web viewer),
    with the viewer's server on ``port`` and (``web``) the web page on ``web_port``."""
    options = (["--serve-web"] if web else []) + \
        (["--port", str(port)] if port is not None else []) + \
        (["--web-viewer-port", str(web_port)] if web and web_port is not None else [])
    return [rerun_program(), *options, *map(str, recordings)]


def how_to_open(recordings: Sequence[Path], path: str | os.PathLike) -> str:
    """What to tell a user who has no display."""
    files = " ".join(map(str, recordings))
    return "\n".join([
        "No display ($DISPLAY and $WAYLAND_DISPLAY are unset), so no viewer was started.",
        "To look at the recordings:",
        f"  on a machine with a display:   rerun {files}",
        f"  all stages in one file:        wipelab view {path} --save run.rrd   "
        f"(then: rerun run.rrd)",
        f"  in a browser, served from here: wipelab view {path} --web   "
        f"(or: rerun --serve-web {files})",
    ])
