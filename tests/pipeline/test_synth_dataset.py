"""``wipelab synth-dataset``: a grid of synthetic demos through the synth stage's function."""

import tomllib

from click.testing import CliRunner

from wipelab.cli.pipeline_commands import synth_dataset
from wipelab.pipeline.dataset import find_demos


def test_grid_of_demos_is_rendered_once_and_kept_on_rerun(tmp_path):
    args = [str(tmp_path), "--pattern", "circle", "--pattern", "line", "--frequency", "1.5",
            "--seed", "4", "--duration", "1", "--fps", "10", "-q"]
    result = CliRunner().invoke(synth_dataset, args)
    assert result.exit_code == 0, result.output
    demos = find_demos(tmp_path)
    assert [d.name for d in demos] == ["circle_1.5hz_seed4", "line_1.5hz_seed4"]
    for demo, pattern in zip(demos, ["circle", "line"]):
        meta = tomllib.loads((demo / "demo.toml").read_text())["synth"]
        assert (meta["pattern"], meta["frequency_hz"], meta["seed"]) == (pattern, 1.5, 4)
        assert (demo / "left.mp4").stat().st_size > 0 and (demo / "truth.csv").is_file()
    stamp = (demos[0] / "left.mp4").stat().st_mtime_ns
    result = CliRunner().invoke(synth_dataset, args)
    assert result.exit_code == 0 and (demos[0] / "left.mp4").stat().st_mtime_ns == stamp


def test_unknown_pattern_is_an_input_error(tmp_path):
    result = CliRunner().invoke(synth_dataset, [str(tmp_path), "--pattern", "zigzag"])
    assert result.exit_code != 0
    assert "--pattern zigzag: unknown (one of circle, line, figure8)" in str(result.exception)
