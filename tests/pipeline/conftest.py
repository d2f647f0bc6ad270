"""Fixtures of the pipeline tests."""

from pathlib import Path

import pytest

from pipeline_testdata import LEARN_PIPELINE, write_wiping_trajectory


@pytest.fixture
def learn_pipeline_file(tmp_path) -> Path:
    """``tmp_path/pipeline/p.toml`` (learn -> rollout) with its trajectory beside it."""
    folder = tmp_path / "pipeline"
    folder.mkdir()
    write_wiping_trajectory(folder / "trajectory.csv")
    path = folder / "p.toml"
    path.write_text(LEARN_PIPELINE)
    return path
