"""``wipelab view``: joining a run's recordings into one, and the no-display path."""

import numpy as np
import pytest
from click.testing import CliRunner
from rerun.chunk import RrdReader

from wipelab.cli.pipeline_commands import view
from wipelab.logs import StageRecorder
from wipelab.pipeline.recordings import JOINED_RECORDING_ID, find_recordings, viewer_argv


@pytest.fixture
def run_dir(tmp_path):
    """A run directory with two stages' real recordings on the shared data-time timeline."""
    t = np.linspace(0.0, 2.0, 21)
    for stage, topic in [("track", "/track/x"), ("learn", "/oscillators/frequency_hz")]:
        (tmp_path / stage).mkdir()
        with StageRecorder(tmp_path / stage, stage=stage, parameters={"seed": 0}) as rec:
            rec.scalars(topic, t, np.sin(t), names=["value"])
    (tmp_path / ".learn.partial-x").mkdir()  # a killed stage's leftovers are not recordings
    (tmp_path / ".learn.partial-x" / "learn.rrd").write_bytes(b"")
    return tmp_path


def rows_per_entity(path):
    rows = {}
    for chunk in RrdReader(path).stream().to_chunks():
        if not chunk.is_static:
            rows[str(chunk.entity_path)] = rows.get(str(chunk.entity_path), 0) + chunk.num_rows
    return rows


def test_save_joins_all_stages_into_one_recording(run_dir):
    assert [p.relative_to(run_dir).as_posix() for p in find_recordings(run_dir)] == [
        "learn/learn.rrd", "track/track.rrd"]
    result = CliRunner().invoke(view, [str(run_dir), "--save", str(run_dir / "all.rrd")])
    assert result.exit_code == 0, result.output
    assert "2 recording(s) joined" in result.output
    reader = RrdReader(run_dir / "all.rrd")
    recordings = [s for s in reader.recordings() if s.kind == "recording"]
    assert {s.recording_id for s in recordings} == {JOINED_RECORDING_ID}
    # Both stages number their chunks from 1; a store keeps one chunk per id, so the join
    # must re-identify them or the second stage's data would vanish.
    rows = rows_per_entity(run_dir / "all.rrd")
    assert rows == {"/track/x": 21, "/oscillators/frequency_hz": 21}


def test_without_a_display_it_says_how_to_open_them_and_exits_0(run_dir):
    result = CliRunner().invoke(view, [str(run_dir)],
                                env={"DISPLAY": None, "WAYLAND_DISPLAY": None})
    assert result.exit_code == 0, result.output
    assert result.output.startswith("No display ($DISPLAY and $WAYLAND_DISPLAY are unset)")
    files = f"{run_dir / 'learn' / 'learn.rrd'} {run_dir / 'track' / 'track.rrd'}"
    assert f"rerun {files}" in result.output
    assert "--serve-web" in result.output


def test_viewer_command_line(run_dir):
    files = find_recordings(run_dir / "track")
    argv = viewer_argv(files, web=True)
    assert argv[0].endswith("rerun") and argv[1:] == ["--serve-web", str(files[0])]


def test_a_path_without_recordings_is_an_input_error(tmp_path):
    result = CliRunner().invoke(view, [str(tmp_path)])
    assert result.exit_code != 0
    assert f"{tmp_path}: no .rrd recording inside" in str(result.exception)
