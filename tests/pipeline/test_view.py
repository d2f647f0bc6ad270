"""``wipelab view``: every stage a recording of its own with its own layout, saved as one
file with nothing colliding; the no-display path; a SIGTERM leaves nothing behind."""

import os
import signal
import socket
import subprocess
import sys
import time
from collections import Counter

import numpy as np
import pyarrow as pa
import pytest
from click.testing import CliRunner
from rerun.chunk import RrdReader

from wipelab.cli.pipeline_commands import view
from wipelab.logs import TIMELINE, StageRecorder
from wipelab.pipeline.recordings import find_recordings, viewer_argv

@pytest.fixture
def run_dir(tmp_path):
    """A run directory with three stages' real recordings: adapt and replay both move the
    same robot frames and series at the same data times, as the real stages do."""
    t = np.linspace(0.0, 2.0, 21)
    for stage in ("track", "adapt", "replay"):
        (tmp_path / stage).mkdir()
        with StageRecorder(tmp_path / stage, stage=stage, parameters={"seed": 0}) as rec:
            if stage == "track":
                rec.scalars("/track/position", t, np.column_stack([t, t, t]), names=list("xyz"))
            else:
                rec.scalars("/robot/joint_states/position", t, np.sin(t) * (stage == "adapt"),
                            names=["elbow"])
                rec.transform_series(t, [("world", "hand", np.column_stack([t, t, t]),
                                          np.tile([0.0, 0.0, 0.0, 1.0], (t.size, 1)))])
    (tmp_path / ".learn.partial-x").mkdir()  # a killed stage's leftovers are not recordings
    (tmp_path / ".learn.partial-x" / "learn.rrd").write_bytes(b"")
    return tmp_path


def duplicate_rows(path) -> dict:
    """(recording, entity, component, time) -> count, where one entity has a component more
    than once at the same time in one recording."""
    reader = RrdReader(path)
    count = Counter()
    for store in reader.recordings():
        for chunk in reader.stream(store=store).to_chunks():
            batch = chunk.to_record_batch()
            if chunk.is_static or TIMELINE not in batch.schema.names:
                continue
            times = batch.column(TIMELINE).cast(pa.int64()).to_pylist()
            for name in (n for n in batch.schema.names if ":" in n):
                for ns, here in zip(times, batch.column(name).is_valid().to_pylist()):
                    count[(store.application_id, str(chunk.entity_path), name, ns)] += here
    return {key: n for key, n in count.items() if n > 1}


def check_saved_run(saved, stages) -> None:
    """One recording per stage, each with its own layout, and no duplicate rows."""
    reader = RrdReader(saved)
    recordings = {s.application_id for s in reader.recordings()}
    layouts = {s.application_id for s in reader.blueprints()}
    assert recordings == layouts == {f"wipelab_{stage}" for stage in stages}
    assert duplicate_rows(saved) == {}
    verified = subprocess.run([viewer_argv([])[0], "rrd", "verify", str(saved)],
                              capture_output=True, text=True)
    assert verified.returncode == 0, verified.stderr


def test_save_keeps_every_stage_a_recording_with_its_layout(run_dir):
    assert [p.relative_to(run_dir).as_posix() for p in find_recordings(run_dir)] == [
        "adapt/adapt.rrd", "replay/replay.rrd", "track/track.rrd"]
    result = CliRunner().invoke(view, [str(run_dir), "--save", str(run_dir / "all.rrd")])
    assert result.exit_code == 0, result.output
    assert "3 recording(s)" in result.output
    check_saved_run(run_dir / "all.rrd", ["track", "adapt", "replay"])
    # both robots are there, each on its own recording's clock
    reader = RrdReader(run_dir / "all.rrd")
    for store in reader.recordings():
        entities = {str(c.entity_path) for c in reader.stream(store=store).to_chunks()}
        assert ("/tf/hand" in entities) == (store.application_id != "wipelab_track")
    assert sorted(p.name for p in run_dir.iterdir()) == [".learn.partial-x", "adapt", "all.rrd",
                                                         "replay", "track"]


def test_the_one_recording_the_old_join_made_had_duplicate_rows(run_dir, tmp_path):
    """What the duplicate-row check finds: adapt and replay merged into one recording (as
    the earlier ``wipelab view`` did) give two rows per robot entity and time."""
    from rerun.chunk import ChunkStore

    chunks = []
    for stage in ("adapt", "replay"):
        reader = RrdReader(run_dir / stage / f"{stage}.rrd")
        chunks += [c.with_entity_path(c.entity_path)
                   for c in reader.stream(store=reader.recordings()[0]).to_chunks()]
    ChunkStore.from_chunks(chunks).write_rrd(tmp_path / "joined.rrd", application_id="wipelab",
                                             recording_id="joined")
    duplicates = duplicate_rows(tmp_path / "joined.rrd")
    assert {entity for _, entity, _, _ in duplicates} == {"/robot/joint_states/position",
                                                          "/tf/hand"}


@pytest.mark.slow
def test_a_real_run_saved_as_one_file_has_no_duplicate_rows(robot_run, tmp_path):
    _, run = robot_run
    result = CliRunner().invoke(view, [str(run), "--save", str(tmp_path / "run.rrd")])
    assert result.exit_code == 0, result.output
    check_saved_run(tmp_path / "run.rrd", ["learn", "adapt", "replay"])


def test_without_a_display_it_says_how_to_open_them_and_exits_0(run_dir):
    result = CliRunner().invoke(view, [str(run_dir)],
                                env={"DISPLAY": None, "WAYLAND_DISPLAY": None})
    assert result.exit_code == 0, result.output
    assert result.output.startswith("No display ($DISPLAY and $WAYLAND_DISPLAY are unset)")
    files = " ".join(str(run_dir / s / f"{s}.rrd") for s in ("adapt", "replay", "track"))
    assert f"rerun {files}" in result.output
    assert "--serve-web" in result.output


def test_viewer_command_line(run_dir):
    files = find_recordings(run_dir / "track")
    argv = viewer_argv(files, web=True, port=9000, web_port=9001)
    assert argv[0].endswith("rerun")
    assert argv[1:] == ["--serve-web", "--port", "9000", "--web-viewer-port", "9001", str(files[0])]


def test_a_path_without_recordings_is_an_input_error(tmp_path):
    result = CliRunner().invoke(view, [str(tmp_path)])
    assert result.exit_code != 0
    assert f"{tmp_path}: no .rrd recording inside" in str(result.exception)


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _listening(port: int) -> bool:
    with socket.socket() as s:
        return s.connect_ex(("127.0.0.1", port)) == 0


def test_sigterm_stops_the_viewer_and_leaves_no_file(run_dir, tmp_path):
    """The real web viewer serves the run; a SIGTERM to ``wipelab view`` stops it (its whole
    process group) and leaves no temporary file, in TMPDIR or in the run."""
    scratch = tmp_path / "tmp"
    scratch.mkdir()
    before = sorted(p.relative_to(run_dir) for p in run_dir.rglob("*"))
    port, web_port = _free_port(), _free_port()
    process = subprocess.Popen(
        [sys.executable, "-m", "wipelab", "view", str(run_dir), "--web", "--port", str(port),
         "--web-port", str(web_port)],
        env={**os.environ, "TMPDIR": str(scratch)}, stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL, start_new_session=True)
    try:
        deadline = time.monotonic() + 60.0
        while not (_listening(port) and _listening(web_port)):
            assert process.poll() is None, "the viewer stopped on its own"
            assert time.monotonic() < deadline, "the viewer never served the run"
            time.sleep(0.2)
        process.send_signal(signal.SIGTERM)
        assert process.wait(30) == 128 + signal.SIGTERM
        deadline = time.monotonic() + 10.0
        while _listening(port) or _listening(web_port):
            assert time.monotonic() < deadline, "the viewer kept running"
            time.sleep(0.2)
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
    assert list(scratch.iterdir()) == []
    assert sorted(p.relative_to(run_dir) for p in run_dir.rglob("*")) == before
