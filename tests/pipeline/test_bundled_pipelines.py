"""The pipelines shipped in pipelines/ load, name only real options, and find their inputs."""

from pathlib import Path

import pytest

from wipelab.pipeline.invoke import build_argv, stage_command
from wipelab.pipeline.spec import file_parameter, load_pipeline

PIPELINES = Path(__file__).resolve().parents[2] / "pipelines"


@pytest.mark.parametrize("name", ["quickstart", "flat", "bowl", "sink", "wavy", "dataset"])
def test_bundled_pipeline_is_runnable_as_written(name):
    pipeline = load_pipeline(PIPELINES / f"{name}.toml")
    assert pipeline.name == name
    for path in pipeline.inputs.values():
        assert (path / "left.mp4").is_file() and (path / "calibration.yaml").is_file()
    for stage in pipeline.stages:
        argv = build_argv(stage, stage_command(stage.command), "IN", stage.name, True,
                          pipeline.source)
        assert argv[:3] == ["IN", "-o", stage.name]
        for value in stage.parameters.values():
            if file_parameter(value) is not None:
                assert file_parameter(value).is_file()
