"""Test data of the reliability tests: the real artefacts every command reads, how to run
wipelab in-process and as a process, and what "nothing left behind" means.

The artefacts are made once per session by the commands themselves, each from the one
before, with the command lines of :data:`STAGE_RUNS` (run in the artefacts folder, paths
relative to it): they are both the inputs of the bad-input cases and the reference outputs
the interruption tests compare with byte for byte.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from dataclasses import dataclass, replace
from pathlib import Path

from click.testing import CliRunner, Result

from wipelab.cli import cli
from wipelab.library_logs import QUIET_ENVIRONMENT
from wipelab.pipeline.cache import DigestMemo, read_record, write_record

#: wipelab as a process (the console script's entry point, this interpreter).
WIPELAB = [sys.executable, "-c", "from wipelab.cli import main; main()"]

#: stage -> (output it writes, command line that makes it). Short and small: a 5 s demo
#: (7.5 periods at 1.5 Hz), 2 adapt periods slowed down 6 times, one replay period per scale;
#: the same demo live, as fast as it goes.
STAGE_RUNS: dict[str, tuple[str, list[str]]] = {
    "synth": ("demo", ["synth", "demo", "--duration", "5", "--frequency", "1.5", "--seed", "1"]),
    "track": ("track", ["track", "demo", "-o", "track", "--particles", "60"]),
    "learn": ("learn", ["learn", "track/track.csv", "-o", "learn"]),
    "adapt": ("adapt", ["adapt", "learn/model.json", "-o", "adapt", "--periods", "2",
                        "--slowdown", "6"]),
    "replay": ("replay", ["replay", "adapt/adapted_model.json", "-o", "replay",
                          "--frequency-scale", "1", "2", "--mode", "learned+compliance",
                          "--periods", "1", "--warmup-periods", "0"]),
    "live": ("live", ["live", "demo", "-o", "live", "--speed", "max", "--replay-periods", "1"]),
}

#: learn -> rollout on the tracked demo: the run directory `report` and `view` read (the
#: adapt output is added to it as a finished stage).
RUN_PIPELINE = """
[pipeline]
name = "short"

[inputs]
trajectory = "track/track.csv"

[stages.learn]
input = "trajectory"

[stages.rollout]
input = "learn:model.json"
periods = 2
"""

#: Files of the artefacts that the cases read under a short name in their workspace.
LINKS = {
    "demo": "demo",
    "track.csv": "track/track.csv",
    "track.mcap": "track/track.mcap",
    "model.json": "learn/model.json",
    "learn.mcap": "learn/learn.mcap",
    "adapted.json": "adapt/adapted_model.json",
    "learn.rrd": "learn/learn.rrd",
    "run": "run",
}


def invoke(argv: list[str]) -> Result:
    """``wipelab ARGV`` in this process (the working directory is the caller's)."""
    return CliRunner().invoke(cli, argv)


def run_process(argv: list[str], cwd: Path, prefix: tuple[str, ...] = (),
                env: dict[str, str] | None = None,
                timeout: float = 120.0) -> subprocess.CompletedProcess:
    """``wipelab ARGV`` as a process in ``cwd`` (``env`` added to the environment), stdout
    and stderr captured as text."""
    return subprocess.run([*prefix, *WIPELAB, *argv], cwd=cwd, capture_output=True, text=True,
                          env=user_environment() | (env or {}), timeout=timeout)


def user_environment() -> dict[str, str]:
    """This process's environment without the variables that silence the libraries (the
    in-process runs set them), as in a user's shell."""
    return {k: v for k, v in os.environ.items() if k not in QUIET_ENVIRONMENT}


def make_artefacts(folder: Path) -> None:
    """Run :data:`STAGE_RUNS` and the :data:`RUN_PIPELINE` in ``folder``, in this process."""
    previous = os.getcwd()
    os.chdir(folder)
    try:
        for output, argv in STAGE_RUNS.values():
            result = invoke([*argv, "-q"])
            assert result.exit_code == 0, result.output
        Path("pipeline.toml").write_text(RUN_PIPELINE)
        result = invoke(["run", "pipeline.toml", "-o", "run", "-q"])
        assert result.exit_code == 0, result.output
        _add_stage(Path("run"), Path("adapt"), "adapt")
    finally:
        os.chdir(previous)


def _add_stage(run_dir: Path, stage_output: Path, command: str) -> None:
    """Put a standalone stage's output into a run directory as a finished stage of it (what
    a pipeline with that stage would hold, without running the stage twice)."""
    shutil.copytree(stage_output, run_dir / command)
    learn = read_record(run_dir / "learn")
    write_record(run_dir / command, replace(
        learn, key=command, stage=command, command=command, parameters={},
        input=None, input_digest=None, outputs=DigestMemo().files(run_dir / command)))


def link_artefacts(workspace: Path, artefacts: Path) -> None:
    """Symbolic links :data:`LINKS` in ``workspace`` to the (read-only) artefacts."""
    for name, target in LINKS.items():
        (workspace / name).symlink_to(artefacts / target)


def tree(root: Path) -> dict[str, tuple]:
    """Every entry under ``root`` (hidden ones included) with its kind, and for a file its
    size and modification time: what must be the same after a refused command."""
    entries = {}
    for path in sorted(root.rglob("*")):
        relative = path.relative_to(root).as_posix()
        if path.is_symlink():
            entries[relative] = ("link", os.readlink(path))
        elif path.is_dir():
            entries[relative] = ("dir",)
        else:
            stat = path.stat()
            entries[relative] = ("file", stat.st_size, stat.st_mtime_ns)
    return entries


def output_files(folder: Path) -> dict[str, bytes]:
    """The files under ``folder`` by relative path, with their bytes."""
    return {p.relative_to(folder).as_posix(): p.read_bytes()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def leftovers(folder: Path) -> list[str]:
    """Temporary ``.*.partial-*`` entries anywhere under ``folder``."""
    return sorted(p.relative_to(folder).as_posix() for p in folder.rglob(".*.partial-*"))


def error_line(stderr: str, names: str, says: str) -> str:
    """The one line of ``stderr``, checked: ``error: ...`` naming ``names`` and saying
    ``says``; no traceback."""
    assert "Traceback" not in stderr, stderr
    lines = stderr.split("\n")
    assert lines[-1] == "" and len(lines) == 2, f"not exactly one line:\n{stderr}"
    line = lines[0]
    assert line.startswith("error: "), line
    assert names in line, f"{line!r} does not name {names!r}"
    assert says in line, f"{line!r} does not say {says!r}"
    return line


@dataclass(frozen=True)
class Unprivileged:
    """How to run a process as a user that permission bits apply to: as is when this is
    not root, else under ``setpriv`` as ``nobody``."""

    prefix: tuple[str, ...]

    @staticmethod
    def find() -> Unprivileged | None:
        if os.geteuid() != 0:
            return Unprivileged(())
        setpriv = shutil.which("setpriv")
        if setpriv is None:
            return None
        return Unprivileged((setpriv, "--reuid=65534", "--regid=65534", "--clear-groups"))
