"""A standalone command interrupted by Ctrl-C or killed leaves no output, and run again it
writes the same bytes as a run that nothing interrupted (cf. tests/pipeline/test_interrupt.py
for ``wipelab run``).

Each command runs three times in a fresh folder, with the inputs and command line it had
when the session's artefacts were made (reliability_testdata.STAGE_RUNS): SIGINT while it
computes (its progress bar is up), SIGKILL while it writes (its ``.OUT.partial-*`` folder
exists), then to the end. The kill leaves the partial folder behind; the last run removes
it and publishes the artefact's bytes.
"""

from __future__ import annotations

import signal
import subprocess
import time
from pathlib import Path

import pytest

from reliability_testdata import STAGE_RUNS, WIPELAB, leftovers, output_files, user_environment

#: What each command reads: folders of the artefacts, linked under the same name.
INPUTS = {"synth": [], "track": ["demo"], "learn": ["track"], "adapt": ["learn"],
          "replay": ["adapt"], "live": ["demo"]}


def start(argv: list[str], cwd: Path, stderr_file: Path) -> subprocess.Popen:
    with open(stderr_file, "w") as stderr:
        return subprocess.Popen([*WIPELAB, *argv], cwd=cwd, stdout=subprocess.DEVNULL,
                                stderr=stderr, env=user_environment())


def wait_until(process: subprocess.Popen, ready, what: str, timeout: float = 120.0) -> None:
    deadline = time.monotonic() + timeout
    while not ready():
        assert process.poll() is None, f"the command ended before {what}"
        assert time.monotonic() < deadline, f"no {what} in {timeout} s"
        time.sleep(0.002)


@pytest.mark.parametrize("stage", list(STAGE_RUNS))
def test_an_interrupted_command_leaves_nothing_and_reruns_to_the_same_bytes(stage, artefacts,
                                                                          tmp_path):
    output, argv = STAGE_RUNS[stage]
    for name in INPUTS[stage]:
        (tmp_path / name).symlink_to(artefacts / name)
    log = tmp_path.parent / f"{tmp_path.name}-stderr.txt"

    process = start(argv, tmp_path, log)  # Ctrl-C while it computes
    wait_until(process, lambda: f"{stage}:" in log.read_text(), "progress bar")
    process.send_signal(signal.SIGINT)
    assert process.wait(timeout=60) == 130, log.read_text()
    last_line = log.read_text().rstrip().split("\n")[-1].split("\r")[-1]
    assert last_line == "interrupted: no output of the unfinished work was written"
    assert not (tmp_path / output).exists() and leftovers(tmp_path) == []

    process = start([*argv, "-q"], tmp_path, log)  # killed while it writes
    wait_until(process, lambda: leftovers(tmp_path), "partial folder")
    process.kill()
    assert process.wait(timeout=60) == -signal.SIGKILL
    assert not (tmp_path / output).exists()
    # one partial folder (and, killed while it wrote a file there, that file's partial)
    assert len({name.split("/")[0] for name in leftovers(tmp_path)}) == 1

    process = start([*argv, "-q"], tmp_path, log)  # to the end
    assert process.wait(timeout=120) == 0, log.read_text()
    assert leftovers(tmp_path) == []
    assert output_files(tmp_path / output) == output_files(artefacts / output)


def test_a_ctrl_c_between_drawing_a_bar_and_timing_it_still_ends_on_its_own_line(tmp_path,
                                                                                  monkeypatch):
    """tqdm draws a new bar before it stamps its start time; a Ctrl-C in between (CI on
    2026-11-27, ``live``) left the bar and the message on one line."""
    from click.testing import CliRunner
    from tqdm import tqdm

    from wipelab.cli import cli

    draw = tqdm.refresh

    def drawn_then_interrupted(bar, *args, **kwargs):
        draw(bar, *args, **kwargs)
        raise KeyboardInterrupt

    monkeypatch.setattr(tqdm, "refresh", drawn_then_interrupted)
    result = CliRunner().invoke(cli, ["synth", str(tmp_path / "demo"), "--duration", "1"])
    assert result.exit_code == 130, result.stderr
    assert result.stderr.startswith("\rsynth:")
    last_line = result.stderr.rstrip().split("\n")[-1].split("\r")[-1]
    assert last_line == "interrupted: no output of the unfinished work was written"
    assert list(tmp_path.iterdir()) == []
