"""Fixtures of the reliability tests: the session's real artefacts and a workspace per case."""

from __future__ import annotations

import shutil
import stat
import tempfile
from pathlib import Path

import pytest

from reliability_testdata import Unprivileged, link_artefacts, make_artefacts, tree

#: Files of the ``unprivileged`` folder its user may not read.
UNREADABLE = ("demo_calibration/calibration.yaml", "demo_video/left.mp4", "secret.csv",
              "secret.json", "secret.toml", "secret.rrd")


@pytest.fixture(scope="session")
def artefacts(tmp_path_factory) -> Path:
    """A folder with a rendered demo, its track, the learned, adapted and replayed model and
    a run directory (see reliability_testdata.STAGE_RUNS); never modified by a test."""
    folder = tmp_path_factory.mktemp("artefacts")
    make_artefacts(folder)
    return folder


@pytest.fixture
def workspace(tmp_path, artefacts, monkeypatch) -> Path:
    """The working directory of a case: links to the artefacts (reliability_testdata.LINKS)
    and whatever the case puts there. Afterwards the artefacts must be untouched."""
    link_artefacts(tmp_path, artefacts)
    monkeypatch.chdir(tmp_path)
    before = tree(artefacts)
    yield tmp_path
    assert tree(artefacts) == before, "a command changed the artefacts"


@pytest.fixture(scope="session")
def unprivileged(artefacts):
    """(how to run as an unprivileged user, a folder where it may read everything but the
    ``UNREADABLE`` files, may not write in ``locked/`` and may write in ``open/``, and the
    environment with its home)."""
    runner = Unprivileged.find()
    if runner is None:
        pytest.skip("running as root without setpriv: no user that permission bits apply to")
    folder = Path(tempfile.mkdtemp(prefix="wipelab-unprivileged-"))
    home = Path(tempfile.mkdtemp(prefix="wipelab-home-"))  # numba caches there
    home.chmod(0o777)
    try:
        (folder / "locked").mkdir()
        (folder / "locked" / "old.csv").write_text("t,x\n")
        (folder / "open").mkdir()
        for name in ("demo_calibration", "demo_video"):
            shutil.copytree(artefacts / "demo", folder / name)
        for name, source in (("learn.rrd", "learn/learn.rrd"), ("model.json", "learn/model.json"),
                             ("secret.csv", "track/track.csv"), ("secret.json", "learn/model.json"),
                             ("secret.rrd", "learn/learn.rrd")):
            shutil.copyfile(artefacts / source, folder / name)
        (folder / "secret.toml").write_text('type = "flat"\n')
        (folder / "p.toml").write_text('[inputs]\ntrajectory = "secret.csv"\n'
                                       '[stages.learn]\ninput = "trajectory"\n')
        for path in [folder, *folder.rglob("*")]:
            path.chmod(0o755 if path.is_dir() else 0o644)
        for name in UNREADABLE:
            (folder / name).chmod(0)
        (folder / "open").chmod(0o777)
        if runner.prefix == ():  # not root: take away the write permission instead
            (folder / "locked").chmod(stat.S_IRUSR | stat.S_IXUSR)
        yield runner, folder, {"HOME": str(home)}
    finally:
        (folder / "locked").chmod(0o755)
        shutil.rmtree(folder)
        shutil.rmtree(home)
