"""A run interrupted by Ctrl-C or killed keeps the stages it finished and resumes after them."""

import signal
import subprocess
import sys
import time

import pytest

from wipelab.pipeline.cache import RECORD_NAME, DigestMemo, read_record

from pipeline_testdata import LEARN_PIPELINE, published_files, write_wiping_trajectory

#: learn (about a second) -> adapt (several seconds of simulation): stopped inside adapt.
PIPELINE = LEARN_PIPELINE.split("[stages.rollout]")[0] + """
[stages.adapt]
input = "learn:model.json"
periods = 2
"""

WIPELAB = [sys.executable, "-c", "from wipelab.cli import main; main()"]


def start_run(pipeline_file, run_dir):
    return subprocess.Popen([*WIPELAB, "run", str(pipeline_file), "-o", str(run_dir)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


@pytest.mark.slow
@pytest.mark.parametrize("signal_number", [signal.SIGINT, signal.SIGKILL])
def test_interrupted_run_keeps_finished_stages_and_resumes(tmp_path, signal_number):
    write_wiping_trajectory(tmp_path / "trajectory.csv")
    pipeline_file = tmp_path / "p.toml"
    pipeline_file.write_text(PIPELINE)
    run_dir = tmp_path / "run"

    process = start_run(pipeline_file, run_dir)
    deadline = time.monotonic() + 60
    while not (run_dir / "learn" / RECORD_NAME).exists():
        assert process.poll() is None, process.communicate()
        assert time.monotonic() < deadline, "learn did not finish in time"
        time.sleep(0.05)
    time.sleep(1.0)  # adapt is simulating now
    assert process.poll() is None, "the run ended before it could be interrupted"
    process.send_signal(signal_number)
    _, stderr = process.communicate(timeout=60)

    if signal_number == signal.SIGINT:
        assert process.returncode == 130
        assert "interrupted: finished stages are kept" in stderr
    else:
        assert process.returncode == -signal.SIGKILL
    learn = read_record(run_dir / "learn")
    assert learn.outputs_intact(run_dir / "learn", DigestMemo())
    assert not (run_dir / "adapt" / RECORD_NAME).exists()
    assert [name for name in published_files(run_dir) if name.startswith("adapt/")] == []
    if signal_number == signal.SIGINT:  # SIGKILL leaves them, and the next run removes them
        assert list(run_dir.glob(".*.partial-*")) == []

    process = start_run(pipeline_file, run_dir)
    _, stderr = process.communicate(timeout=120)
    assert process.returncode == 0, stderr
    assert "[1/2] reused learn (cache hit)" in stderr
    assert "[2/2] running adapt (no cached result)" in stderr
    assert read_record(run_dir / "learn") == learn
    assert read_record(run_dir / "adapt").outputs_intact(run_dir / "adapt", DigestMemo())
    assert list(run_dir.glob(".*.partial-*")) == []
