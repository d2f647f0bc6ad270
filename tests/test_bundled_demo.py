"""The bundled demonstration (data/demo): tracked through its occlusion and learned within
1 % of the frequency it was rendered at, online and offline (track -> learn, through the CLI)."""

import json
import tomllib
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from wipelab.cli import cli
from wipelab.logs import read_mcap_scalars
from wipelab.trajectory_csv import read_trajectory

DEMO = Path(__file__).resolve().parents[1] / "data" / "demo"


def _run(*args):
    result = CliRunner().invoke(cli, [str(a) for a in args], catch_exceptions=False)
    assert result.exit_code == 0, result.output


@pytest.fixture(scope="module")
def tracked(tmp_path_factory):
    out = tmp_path_factory.mktemp("bundled") / "track"
    _run("track", DEMO, "-o", out, "-q")
    return out


@pytest.mark.parametrize("mode", ["online", "offline"])
def test_the_bundled_demo_is_learned_within_1_percent_through_its_occlusion(tracked, tmp_path,
                                                                           mode):
    synth = tomllib.loads((DEMO / "demo.toml").read_text())["synth"]
    (hidden_from, hidden_to), = synth["occlusions_hidden"]
    track = read_trajectory(tracked / "track.csv", required=("t", "x", "y", "valid"))
    hidden = (track.t > hidden_from + 0.1) & (track.t < hidden_to - 0.1)
    assert hidden.any() and not track.valid[hidden].any()

    _run("learn", tracked / "track.csv", "-o", tmp_path / "learn", "--mode", mode, "-q")
    model = json.loads((tmp_path / "learn" / "model.json").read_text())
    assert model["frequency_hz"] == pytest.approx(synth["frequency_hz"], rel=0.01)
    t, observed, _ = read_mcap_scalars(tmp_path / "learn" / "learn.mcap", "/input/valid")
    np.testing.assert_array_equal(observed[:, 0] > 0.5, track.valid)
