"""Pipelines: stages chained by a TOML file, cached by content, run over whole data sets.

- :mod:`~wipelab.pipeline.spec`: the pipeline file (stages, parameters, inputs, overrides).
- :mod:`~wipelab.pipeline.cache`: content hashes, cache keys, the per-stage record.
- :mod:`~wipelab.pipeline.invoke`: one stage through its own click command, in-process.
- :mod:`~wipelab.pipeline.runner`: a run directory, stage after stage, reusing cache hits.
- :mod:`~wipelab.pipeline.dataset`: a pipeline over every demo of a data set (processes, Dask).
- :mod:`~wipelab.pipeline.synth_grid`: a synthetic data set (patterns x frequencies x seeds).
- :mod:`~wipelab.pipeline.metrics`: the numbers a run produced.
- :mod:`~wipelab.pipeline.figures`, :mod:`~wipelab.pipeline.report`: the paper's figures.
- :mod:`~wipelab.pipeline.recordings`: a run's Rerun recordings, joined and opened.

Importing this package imports only the standard library and the pipeline file parser; the
stages, matplotlib, Dask and Rerun are imported where they are used.
"""

from wipelab.pipeline.cache import DigestMemo, StageRecord, read_record
from wipelab.pipeline.dataset import (DemoResult, DemoTask, dataset_tasks, find_demos,
                                      format_summary, run_dataset, write_summary_csv)
from wipelab.pipeline.metrics import run_metrics
from wipelab.pipeline.runner import StageOutcome, run_pipeline
from wipelab.pipeline.spec import STAGE_COMMANDS, Pipeline, StageSpec, load_pipeline

__all__ = [
    "STAGE_COMMANDS", "DemoResult", "DemoTask", "DigestMemo", "Pipeline", "StageOutcome",
    "StageRecord", "StageSpec", "dataset_tasks", "find_demos", "format_summary",
    "load_pipeline", "read_record", "run_dataset", "run_metrics", "run_pipeline",
    "write_summary_csv",
]
