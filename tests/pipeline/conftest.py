"""Fixtures of the pipeline tests."""

from pathlib import Path

import pytest

from pipeline_testdata import LEARN_PIPELINE, ROBOT_PIPELINE, write_wiping_trajectory

from wipelab.pipeline.runner import run_pipeline
from wipelab.pipeline.spec import load_pipeline


@pytest.fixture
def learn_pipeline_file(tmp_path) -> Path:
    """``tmp_path/pipeline/p.toml`` (learn -> rollout) with its trajectory beside it."""
    folder = tmp_path / "pipeline"
    folder.mkdir()
    write_wiping_trajectory(folder / "trajectory.csv")
    path = folder / "p.toml"
    path.write_text(LEARN_PIPELINE)
    return path


@pytest.fixture(scope="session")
def robot_run(tmp_path_factory) -> tuple[Path, Path]:
    """The robot pipeline file and a run directory of it that nothing interrupted."""
    folder = tmp_path_factory.mktemp("robot")
    write_wiping_trajectory(folder / "trajectory.csv")
    pipeline_file = folder / "p.toml"
    pipeline_file.write_text(ROBOT_PIPELINE)
    run_pipeline(load_pipeline(pipeline_file), folder / "run", quiet=True)
    return pipeline_file, folder / "run"
