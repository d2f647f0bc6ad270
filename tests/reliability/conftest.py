"""Fixtures of the reliability tests: the session's real artefacts and a workspace per case."""

from __future__ import annotations

from pathlib import Path

import pytest

from reliability_testdata import link_artefacts, make_artefacts, tree


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
