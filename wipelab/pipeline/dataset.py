"""Run one pipeline over every demonstration of a data set, in parallel processes.

A demo directory is any directory under DATA_DIR that holds ``left.mp4``, ``right.mp4`` or
``calibration.yaml`` (a demo missing one of them is still found, and reported as failed by
``track``). Each demo gets its own run directory ``OUT/runs/<demo>`` (so a second pass reuses
what the first finished), and the pipeline's one named input is replaced by the demo
directory. Paths are absolute, so every worker must see the same file system.

Executors: ``jobs = 1`` runs the demos one after the other in this process; ``jobs > 1``
uses a ``concurrent.futures.ProcessPoolExecutor`` (spawned processes); a ``scheduler``
address sends them to a Dask distributed cluster (every worker must see the same file
system paths and have wipelab installed). A demo that fails is reported with its error and
does not stop the others.
"""

from __future__ import annotations

import contextlib
import csv
import io
import os
import time
import traceback
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from wipelab.errors import InputError
from wipelab.pipeline.metrics import demo_metrics, is_key_metric, run_metrics
from wipelab.pipeline.spec import Pipeline
from wipelab.stage_output import staged_file

#: Files that mark a directory as a demonstration (DESIGN.md, "Demo directory").
DEMO_FILES = ("left.mp4", "right.mp4", "calibration.yaml")

#: Columns of the summary that every row has, before the metrics.
SUMMARY_COLUMNS = ("demo", "status", "seconds", "stages_run", "stages_reused")



@dataclass(frozen=True)
class DemoResult:
    """The outcome of the pipeline on one demo.

    Attributes
    ----------
    demo : str
        Path of the demo directory relative to DATA_DIR.
    ok : bool
    error : str
        One line saying what went wrong ("" when ok).
    seconds : float
        Wall time of the demo's pipeline run.
    stages_run, stages_reused : int
    metrics : dict[str, float]
        :func:`~wipelab.pipeline.metrics.demo_metrics` of the demo and
        :func:`~wipelab.pipeline.metrics.run_metrics` of its run directory.
    """

    demo: str
    ok: bool
    error: str = ""
    seconds: float = 0.0
    stages_run: int = 0
    stages_reused: int = 0
    metrics: dict[str, float] = field(default_factory=dict)


def find_demos(data_dir: str | os.PathLike) -> list[Path]:
    """Every demo directory under ``data_dir`` (itself included), sorted.

    Raises
    ------
    InputError
        ``data_dir`` is not a directory or holds no demo.
    """
    data_dir = Path(data_dir)
    if not data_dir.is_dir():
        raise InputError(f"{data_dir}: not a directory")
    demos = sorted(path for path in [data_dir, *data_dir.rglob("*")]
                   if path.is_dir() and any((path / name).exists() for name in DEMO_FILES))
    if not demos:
        raise InputError(f"{data_dir}: no demo directory inside (one holding "
                         f"{', '.join(DEMO_FILES)})")
    return demos


def demo_input_name(pipeline: Pipeline) -> str:
    """The pipeline input that each demo replaces: its only named input."""
    if len(pipeline.inputs) != 1:
        raise InputError(f"{pipeline.source}: a data set pipeline needs exactly one entry in "
                         f"[inputs] (the demo directory), it has {len(pipeline.inputs)}")
    return next(iter(pipeline.inputs))


@dataclass(frozen=True)
class DemoTask:
    """One demo to process: the pipeline with the demo as its input, and where to run it."""

    pipeline: Pipeline
    demo_dir: str   # absolute path of the demo directory
    demo: str       # its name in the summary (path relative to DATA_DIR)
    run_dir: str    # absolute path of its run directory


def dataset_tasks(pipeline: Pipeline, data_dir: str | os.PathLike,
                  out_dir: str | os.PathLike) -> list[DemoTask]:
    """One task per demo under ``data_dir``; demo ``a/b`` runs in ``out_dir/runs/a__b``.

    Raises
    ------
    InputError
        The pipeline has not exactly one named input, or ``data_dir`` holds no demo.
    """
    name = demo_input_name(pipeline)
    data_dir = Path(data_dir).resolve()
    runs = Path(out_dir).resolve() / "runs"
    tasks = []
    for demo in find_demos(data_dir):
        label = demo.relative_to(data_dir).as_posix() if demo != data_dir else demo.name
        tasks.append(DemoTask(pipeline.with_overrides(inputs=[f"{name}={demo}"]), str(demo),
                              label, str(runs / label.replace("/", "__"))))
    return tasks


def process_demo(task: DemoTask) -> DemoResult:
    """Run the pipeline on one demo; never raises for a failure of the demo itself.

    Top-level so that process pools and Dask can ship it to another process.
    """
    from wipelab.pipeline.runner import run_pipeline

    start = time.perf_counter()
    try:  # what the stages print would interleave between demos: the summary says it all
        with contextlib.redirect_stdout(io.StringIO()):
            outcomes = run_pipeline(task.pipeline, task.run_dir, quiet=True)
    except InputError as error:
        return DemoResult(task.demo, ok=False, error=str(error),
                          seconds=time.perf_counter() - start)
    except Exception as error:  # a failing demo must not stop the data set: report it
        where = traceback.extract_tb(error.__traceback__)[-1]
        return DemoResult(task.demo, ok=False,
                          error=f"{type(error).__name__}: {error} "
                                f"({Path(where.filename).name}:{where.lineno})",
                          seconds=time.perf_counter() - start)
    return DemoResult(task.demo, ok=True, seconds=time.perf_counter() - start,
                      stages_run=sum(not o.reused for o in outcomes),
                      stages_reused=sum(o.reused for o in outcomes),
                      metrics=demo_metrics(task.demo_dir) | run_metrics(task.run_dir))


def run_dataset(tasks: Sequence[DemoTask], jobs: int = 1, scheduler: str | None = None,
                on_result: Callable[[DemoResult], None] = lambda result: None,
                ) -> list[DemoResult]:
    """Process every task; results sorted by demo.

    Parameters
    ----------
    tasks : sequence of DemoTask
        From :func:`dataset_tasks`.
    jobs : int
        Parallel processes on this machine (ignored with ``scheduler``).
    scheduler : str or None
        Address of a Dask distributed scheduler, e.g. ``tcp://127.0.0.1:8786``.
    on_result : callable
        Called with each result as it arrives (progress).
    """
    if jobs < 1:
        raise InputError(f"-j {jobs}: need at least 1 job")
    if scheduler is not None:
        results = _on_dask(tasks, scheduler)
    elif jobs == 1:
        results = map(process_demo, tasks)
    else:
        results = _in_process_pool(tasks, jobs)
    collected = []
    for result in results:
        on_result(result)
        collected.append(result)
    return sorted(collected, key=lambda result: result.demo)


def summary_rows(results: Sequence[DemoResult]) -> tuple[list[str], list[dict[str, str]]]:
    """Header and rows of the summary table: one row per demo, one column per metric."""
    metric_names = sorted({name for result in results for name in result.metrics})
    header = [*SUMMARY_COLUMNS, *metric_names, "error"]
    rows = []
    for result in results:
        row = {"demo": result.demo, "status": "ok" if result.ok else "failed",
               "seconds": f"{result.seconds:.1f}", "stages_run": str(result.stages_run),
               "stages_reused": str(result.stages_reused), "error": result.error}
        row.update({name: f"{result.metrics[name]:.6g}" if name in result.metrics else ""
                    for name in metric_names})
        rows.append(row)
    return header, rows


def write_summary_csv(path: str | os.PathLike, results: Sequence[DemoResult]) -> None:
    """Write the summary table, every metric, as CSV (all or nothing, see staged_file)."""
    header, rows = summary_rows(results)
    text = io.StringIO()
    writer = csv.DictWriter(text, fieldnames=header, lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    with staged_file(path) as tmp:
        tmp.write_text(text.getvalue())


def format_summary(results: Sequence[DemoResult]) -> str:
    """The summary as an aligned text table, with the key metrics (the CSV has them all)."""
    header, rows = summary_rows(results)
    header = [name for name in header
              if name in SUMMARY_COLUMNS or name == "error" or is_key_metric(name)]
    table = [header] + [[row[name] for name in header] for row in rows]
    widths = [max(len(line[i]) for line in table) for i in range(len(header) - 1)]
    return "\n".join("  ".join([*(cell.ljust(w) for cell, w in zip(line, widths)), line[-1]])
                     .rstrip() for line in table)


def _in_process_pool(tasks: Sequence[DemoTask], jobs: int) -> Iterator[DemoResult]:
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor, as_completed
    from concurrent.futures.process import BrokenProcessPool

    context = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(max_workers=jobs, mp_context=context) as pool:
        futures = {pool.submit(process_demo, task): task for task in tasks}
        for future in as_completed(futures):
            try:
                yield future.result()
            except BrokenProcessPool:
                yield DemoResult(futures[future].demo, ok=False,
                                 error="a worker process died (crash or out of memory)")


def _on_dask(tasks: Sequence[DemoTask], address: str) -> Iterator[DemoResult]:
    from distributed import Client, as_completed

    try:
        client = Client(address, timeout="10s")
    except OSError as error:
        raise InputError(f"--scheduler {address}: cannot connect ({error})") from None
    with client:
        futures = {client.submit(process_demo, task, pure=False): task for task in tasks}
        for future in as_completed(futures):
            try:
                yield future.result()
            except Exception as error:  # e.g. KilledWorker: the demo is lost, not the data set
                yield DemoResult(futures[future].demo, ok=False,
                                 error=f"{type(error).__name__}: {error}")
