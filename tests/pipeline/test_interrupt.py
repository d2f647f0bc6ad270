"""A run interrupted by Ctrl-C or killed keeps the stages it finished and resumes after them."""

import signal
import subprocess
import sys
import time

import pytest

from wipelab.pipeline.cache import RECORD_NAME, DigestMemo, read_record

from pipeline_testdata import published_files

WIPELAB = [sys.executable, "-c", "from wipelab.cli import main; main()"]


def start_run(pipeline_file, run_dir, stderr_file):
    """``wipelab run`` in a new process, its stderr going to ``stderr_file``."""
    with open(stderr_file, "w") as stderr:
        return subprocess.Popen([*WIPELAB, "run", str(pipeline_file), "-o", str(run_dir)],
                                stdout=subprocess.DEVNULL, stderr=stderr)


def wait_for(process, stderr_file, text, timeout=60.0):
    deadline = time.monotonic() + timeout
    while text not in stderr_file.read_text():
        assert process.poll() is None, stderr_file.read_text()
        assert time.monotonic() < deadline, f"no {text!r} in time"
        time.sleep(0.05)


@pytest.mark.slow
@pytest.mark.parametrize("signal_number", [signal.SIGINT, signal.SIGKILL])
def test_interrupted_run_keeps_finished_stages_and_resumes(tmp_path, signal_number, robot_run):
    pipeline_file, reference_run = robot_run
    run_dir = tmp_path / "run"

    log = tmp_path / "stderr.txt"
    process = start_run(pipeline_file, run_dir, log)
    wait_for(process, log, "[2/3] running adapt")
    time.sleep(0.5)  # adapt is simulating now: it takes several seconds
    assert process.poll() is None, "the run ended before it could be interrupted"
    process.send_signal(signal_number)
    process.wait(timeout=60)
    stderr = log.read_text()

    if signal_number == signal.SIGINT:
        assert process.returncode == 130, stderr
        assert "interrupted: finished stages are kept" in stderr
    else:
        assert process.returncode == -signal.SIGKILL, stderr
    learn = read_record(run_dir / "learn")
    assert learn.outputs_intact(run_dir / "learn", DigestMemo())
    assert not (run_dir / "adapt" / RECORD_NAME).exists()
    assert [name for name in published_files(run_dir) if not name.startswith("learn/")] == []
    if signal_number == signal.SIGINT:  # a kill may leave a temporary folder; see below
        assert list(run_dir.glob(".*.partial-*")) == []

    process = start_run(pipeline_file, run_dir, log)
    assert process.wait(timeout=120) == 0, log.read_text()
    stderr = log.read_text()
    assert "[1/3] reused learn (cache hit)" in stderr
    assert "[2/3] running adapt (no cached result)" in stderr
    assert "[3/3] running replay (no cached result)" in stderr
    assert read_record(run_dir / "learn") == learn
    assert read_record(run_dir / "adapt").outputs_intact(run_dir / "adapt", DigestMemo())
    assert list(run_dir.glob(".*.partial-*")) == []
    # byte for byte what a run that nothing interrupted wrote
    assert published_files(run_dir) == published_files(reference_run)
