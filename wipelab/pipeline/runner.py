"""Run a pipeline into a run directory, reusing every stage whose cache key still holds.

Layout of a run directory::

    RUN_DIR/
      .wipelab-run.lock         held while a run uses the directory
      <stage>/                  what the stage's command wrote (manifest.json, *.mcap, ...)
        .wipelab-stage.json     the cache record, written last (see cache.py)

Stages run in the run directory as working directory, and read each other's files by paths
relative to it (``track/track.csv``), so two runs in different places write the same bytes.

Interruption: a stage's files appear only when it succeeds (``staged_output``) and its
record only after that, so Ctrl-C or a kill leaves the stages before it intact and no
half-written file under a final name; the next run reuses them, reruns the rest and
removes the temporary folders a killed stage left behind.

Everything that can be checked before a stage runs (the run directory as an output
location, the pipeline's inputs, file parameters and every stage's options) is checked
before the run directory is created or locked, so a bad run leaves nothing behind.
"""

from __future__ import annotations

import fcntl
import os
import shutil
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import wipelab
from wipelab.errors import InputError
from wipelab.input_files import reading
from wipelab.output_location import check_output_dir
from wipelab.pipeline.cache import (DigestMemo, StageRecord, code_files_in_use, package_root,
                                    read_record, remove_record, stage_key, write_record)
from wipelab.pipeline.spec import Pipeline, StageSpec, file_parameter
from wipelab.stage_output import remove_stale_partials

LOCK_NAME = ".wipelab-run.lock"


@dataclass(frozen=True)
class StageOutcome:
    """How one stage went in one run.

    Attributes
    ----------
    name, command : str
    reused : bool
        True for a cache hit (nothing ran).
    seconds : float
        Wall time of this run's execution, or of the run that made the reused outputs.
    """

    name: str
    command: str
    reused: bool
    seconds: float


def run_pipeline(pipeline: Pipeline, run_dir: str | os.PathLike, *, quiet: bool = False,
                 force: bool = False,
                 echo: Callable[[str], None] = print) -> list[StageOutcome]:
    """Run (or reuse) every stage of ``pipeline`` in order, inside ``run_dir``.

    Parameters
    ----------
    pipeline : Pipeline
    run_dir : path-like
        Created when missing.
    quiet : bool
        Print nothing, and pass ``--quiet`` to stages that have it.
    force : bool
        Run every stage even when its cache record holds.
    echo : callable
        Where progress lines go.

    Returns
    -------
    list of StageOutcome, one per stage.

    Raises
    ------
    InputError
        Bad pipeline parameters, a missing input, a stage's own input error, or the run
        directory in use by another run.
    """
    say = (lambda line: None) if quiet else echo
    run_dir = check_output_dir(run_dir).resolve()
    memo = DigestMemo()
    _check_before_running(pipeline, run_dir, memo)
    outcomes = []
    with _locked(run_dir), _working_directory(run_dir):
        remove_stale_partials(run_dir)
        total = len(pipeline.stages)
        for index, stage in enumerate(pipeline.stages, 1):
            input_arg, input_digest = _stage_input(pipeline, stage, run_dir, memo)
            key = stage_key(stage.name, stage.command, wipelab.__version__,
                            _keyed_parameters(pipeline, stage, memo), stage.output, input_digest)
            stage_dir = run_dir / stage.name
            record = read_record(stage_dir)
            if (not force and record is not None and record.key == key
                    and record.code_intact(memo) and record.outputs_intact(stage_dir, memo)):
                say(f"[{index}/{total}] reused {stage.name} (cache hit)")
                outcomes.append(StageOutcome(stage.name, stage.command, True, record.seconds))
                continue
            say(f"[{index}/{total}] running {stage.name} ({_why(record, key, memo)})")
            seconds = _execute(pipeline, stage, input_arg, stage_dir, quiet)
            root = package_root()
            write_record(stage_dir, StageRecord(
                key=key, stage=stage.name, command=stage.command,
                code={name: memo.file(root / name) for name in code_files_in_use()},
                parameters=dict(stage.parameters), input=input_arg, input_digest=input_digest,
                outputs=memo.files(stage_dir), seconds=round(seconds, 3)))
            say(f"[{index}/{total}] finished {stage.name} in {seconds:.1f} s")
            outcomes.append(StageOutcome(stage.name, stage.command, False, seconds))
    reused = [o.name for o in outcomes if o.reused]
    ran = [o.name for o in outcomes if not o.reused]
    say(f"run {run_dir}: ran {len(ran)} stage(s){': ' + ', '.join(ran) if ran else ''}; "
        f"reused {len(reused)}{': ' + ', '.join(reused) if reused else ''}")
    return outcomes


def _check_before_running(pipeline: Pipeline, run_dir: Path, memo: DigestMemo) -> None:
    """Raise InputError for anything wrong that shows before a stage runs: an input from
    outside the run that is missing, a file parameter that is missing, an option a stage's
    command does not have or a value it cannot parse. Nothing is created before this."""
    from wipelab.pipeline.invoke import check_arguments, stage_command

    for stage in pipeline.stages:
        if pipeline.upstream(stage) is None:
            _stage_input(pipeline, stage, run_dir, memo)
        _keyed_parameters(pipeline, stage, memo)
        check_arguments(stage, stage_command(stage.command), pipeline.source)


def _stage_input(pipeline: Pipeline, stage: StageSpec, run_dir: Path,
                 memo: DigestMemo) -> tuple[str | None, str | None]:
    """The input argument (relative inside the run directory) and its content hash."""
    path = pipeline.resolve_input(stage, run_dir)
    if path is None:
        return None, None
    if not path.exists():
        raise InputError(f"{pipeline.source}: stage {stage.name}: input {stage.input!r} "
                         f"({path}) not found")
    argument = path.relative_to(run_dir).as_posix() if path.is_relative_to(run_dir) else str(path)
    with reading(path, "cannot be read"):
        return argument, memo.content(path)


def _keyed_parameters(pipeline: Pipeline, stage: StageSpec, memo: DigestMemo) -> dict:
    """The parameters as they enter the key: a file by its content and its neighbours'."""
    keyed = {}
    for key, value in stage.parameters.items():
        path = file_parameter(value)
        if path is None:
            keyed[key] = value
        elif not path.is_file():
            raise InputError(f"{pipeline.source}: stage {stage.name}: {key}: {path} not found")
        else:  # a surface TOML names its heightfield beside it: the folder is the content
            with reading(path, "cannot be read"):
                keyed[key] = {"file": path.name, "sha256": memo.file(path),
                              "beside": {p.name: memo.file(p)
                                         for p in sorted(path.parent.iterdir())
                                         if p.is_file() and not p.name.startswith(".")}}
    return keyed


def _execute(pipeline: Pipeline, stage: StageSpec, input_arg: str | None, stage_dir: Path,
             quiet: bool) -> float:
    """Clear the stage folder, run the stage's command into it, return the wall time."""
    from wipelab.pipeline.invoke import build_argv, run_command, stage_command

    command = stage_command(stage.command)
    output = stage.name if stage.output is None else f"{stage.name}/{stage.output}"
    argv = build_argv(stage, command, input_arg, output, quiet, pipeline.source)
    if stage_dir.is_dir() and not stage_dir.is_symlink():
        remove_record(stage_dir)
        shutil.rmtree(stage_dir)
    elif stage_dir.exists() or stage_dir.is_symlink():  # not ours: a stage folder goes here
        stage_dir.unlink()
    if stage.output is not None:
        stage_dir.mkdir()
    start = time.perf_counter()
    run_command(command, argv, stage.name, pipeline.source)
    return time.perf_counter() - start


def _why(record: StageRecord | None, key: str, memo: DigestMemo) -> str:
    if record is None:
        return "no cached result"
    if record.key != key:
        return "inputs or parameters changed"
    if not record.code_intact(memo):
        return "code changed"
    return "cached outputs missing or modified"


@contextmanager
def _locked(run_dir: Path) -> Iterator[None]:
    """Hold an exclusive lock on ``run_dir`` (released by the kernel even on SIGKILL)."""
    run_dir.mkdir(parents=True, exist_ok=True)
    with open(run_dir / LOCK_NAME, "w") as lock:
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise InputError(f"{run_dir}: another wipelab run is using this directory") from None
        yield


#: The working directory belongs to the process: runs in threads of one process (a Dask
#: worker with several threads) take turns.
_WORKING_DIRECTORY_LOCK = threading.Lock()


@contextmanager
def _working_directory(path: Path) -> Iterator[None]:
    with _WORKING_DIRECTORY_LOCK:
        previous = os.getcwd()
        os.chdir(path)
        try:
            yield
        finally:
            os.chdir(previous)
