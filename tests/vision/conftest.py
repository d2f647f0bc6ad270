"""Shared fixtures of the vision tests: one short synthetic demonstration, rendered once."""

from __future__ import annotations

import numpy as np
import pytest

from wipelab.stages.synth import SynthParams, synth
from wipelab.trajectory_csv import read_trajectory

#: 3.5 s of circular wiping at 1.2 Hz with one full occlusion by the free hand.
SHORT_DEMO = SynthParams(pattern="circle", frequency_hz=1.2, duration=3.5, seed=7)


@pytest.fixture(scope="session")
def short_demo(tmp_path_factory):
    """Path of a rendered demo directory (do not modify it; copy it first)."""
    path = tmp_path_factory.mktemp("vision") / "demo"
    synth(path, SHORT_DEMO, quiet=True)
    return path


@pytest.fixture(scope="session")
def short_truth(short_demo):
    """truth.csv of the short demo: (t (n,), centre (n, 3), visible (n,))."""
    truth = read_trajectory(short_demo / "truth.csv", required=("t", "x", "y", "z"))
    visible = np.minimum(truth.columns["visible_left"], truth.columns["visible_right"])
    return truth.t, truth.array(["x", "y", "z"]), visible
