"""What the C libraries and other packages print stays off the error path (as real processes:
FFmpeg and OpenCV write to the process's stderr, not to Python's), and ``-v`` brings it back.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from reliability_testdata import error_line, run_process, tree


def broken_demo(workspace: Path, video: bytes) -> None:
    shutil.copytree(workspace / "demo", workspace / "broken")
    (workspace / "broken" / "right.mp4").write_bytes(video)


def video_of(kind: str, workspace: Path) -> bytes:
    good = (workspace / "demo" / "right.mp4").read_bytes()
    return {"garbage": bytes(range(256)) * 64, "empty": b"", "cut-short": good[:len(good) // 2]}[kind]


@pytest.mark.parametrize("kind", ["garbage", "empty", "cut-short"])
def test_a_broken_video_is_one_line_without_ffmpeg_or_opencv_logs(kind, workspace):
    broken_demo(workspace, video_of(kind, workspace))
    before = tree(workspace)
    completed = run_process(["track", "broken", "-o", "out"], workspace)
    assert completed.returncode == 2
    error_line(completed.stderr, "broken/right.mp4", "cannot be decoded")
    assert tree(workspace) == before


def test_verbose_lets_ffmpeg_and_opencv_speak(workspace):
    broken_demo(workspace, b"")
    completed = run_process(["-v", "track", "broken", "-o", "out"], workspace)
    assert completed.returncode == 2
    lines = completed.stderr.splitlines()
    assert "moov atom not found" in completed.stderr and len(lines) >= 2
    assert lines[-1].startswith("error: broken/right.mp4: cannot be decoded")


def test_a_warning_of_another_package_is_hidden_unless_verbose(workspace):
    recording = (workspace / "learn.rrd").read_bytes()
    (workspace / "cut.rrd").write_bytes(recording[:4000])  # Rerun warns: no footer
    completed = run_process(["view", "cut.rrd", "--save", "joined.rrd"], workspace)
    assert completed.returncode == 2
    error_line(completed.stderr, "cut.rrd", "not a readable Rerun recording")
    completed = run_process(["--verbose", "view", "cut.rrd", "--save", "joined.rrd"], workspace)
    assert "RerunWarning" in completed.stderr
    assert not (workspace / "joined.rrd").exists()
