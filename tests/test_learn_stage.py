"""``wipelab learn`` and ``wipelab rollout`` end to end through the CLI, files read back."""

import json
import re

import numpy as np
import pytest
from click.testing import CliRunner

from wipelab.cli import cli
from wipelab.learning import PeriodicModel
from wipelab.learning.signals import waveform_rms_percent, wiping_signal
from wipelab.logs import (StageRecorder, mcap_input_hashes, mcap_parameters, mcap_topics,
                          read_mcap_scalars, read_mcap_topic, read_rrd_scalars,
                          rrd_blueprint_views)
from wipelab.manifest import sha256_file
from wipelab.trajectory_csv import read_trajectory, write_trajectory

FREQUENCY_HZ = 0.8


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    """15 s of a 2-DOF wiping movement at 30 Hz (the rate of the paper's vision), plus z."""
    directory = tmp_path_factory.mktemp("demo")
    t = np.arange(0, 15, 1 / 30)
    Y, clean = wiping_signal(t, FREQUENCY_HZ, seed=11)
    path = directory / "track.csv"
    write_trajectory(path, t, {"x": Y[:, 0], "y": Y[:, 1], "z": np.full(t.size, 0.8),
                               "valid": np.ones(t.size, dtype=bool)})
    return path, t, clean


def _run(*args):
    return CliRunner().invoke(cli, [str(a) for a in args], catch_exceptions=False)


@pytest.fixture(scope="module")
def learned(demo, tmp_path_factory):
    out = tmp_path_factory.mktemp("runs") / "learn"
    result = _run("learn", demo[0], "-o", out, "--quiet")
    assert result.exit_code == 0, result.output
    return out


def test_learn_writes_a_model_that_reproduces_the_demonstration(demo, learned):
    path, t, clean = demo
    assert sorted(p.name for p in learned.iterdir()) == ["learn.mcap", "learn.rrd", "manifest.json",
                                                          "model.json"]
    model = PeriodicModel.from_dict(json.loads((learned / "model.json").read_text()))
    assert model.dofs == ("x", "y") and model.kernels == 25 and model.width == 62.5
    assert model.frequency_hz == pytest.approx(FREQUENCY_HZ, rel=0.01)
    assert model.source["sha256"] == sha256_file(path) and model.source["reference_dof"] == "x"
    _, y = model.rollout(t[-1] + 1 / 60, 30.0)
    last = t >= t[-1] - 1 / FREQUENCY_HZ
    assert waveform_rms_percent(y[last], clean[last]).max() <= 3.0


def test_learn_logs_figures_4_and_5_to_mcap_and_rerun(demo, learned):
    path, t, _ = demo
    mcap, rrd = learned / "learn.mcap", learned / "learn.rrd"
    topics = mcap_topics(mcap)
    expected = {"/input/trajectory", "/oscillators/frequency_hz", "/oscillators/fundamental_hz",
                "/dmp/x/waveform", "/dmp/y/waveform", "/dmp/x/weights", "/dmp/y/weights",
                "/dmp/x/period", "/dmp/y/period", "/model"}
    assert expected <= set(topics)
    assert topics["/dmp/x/waveform"]["schema"] == "wipelab.Scalars"
    assert topics["/input/trajectory"]["message_count"] == t.size
    times, fundamental, names = read_mcap_scalars(mcap, "/oscillators/fundamental_hz")
    assert names == ["fundamental"] and fundamental[-1, 0] == pytest.approx(FREQUENCY_HZ, rel=0.01)
    np.testing.assert_allclose(times, read_trajectory(path).t, atol=1e-9)
    _, waveform, names = read_mcap_scalars(mcap, "/dmp/x/waveform")
    assert names == ["input", "learned"]
    np.testing.assert_allclose(waveform[:, 0], read_trajectory(path).columns["x"])
    _, weights, names = read_mcap_scalars(mcap, "/dmp/y/weights")
    assert names[0] == "w_00" and weights.shape[1] == 25 and np.abs(weights[-1]).max() > 1.0
    (_, model_message), = read_mcap_topic(mcap, "/model")
    assert model_message == json.loads((learned / "model.json").read_text())
    assert mcap_parameters(mcap)["mode"] == "online"
    assert mcap_input_hashes(mcap) == {"trajectory": sha256_file(path)}
    rrd_t, rrd_fundamental = read_rrd_scalars(rrd, "/oscillators/fundamental_hz")
    np.testing.assert_allclose(rrd_fundamental[:, 0], fundamental[:, 0])
    views = rrd_blueprint_views(rrd)
    assert {("TimeSeries", "/oscillators"), ("TimeSeries", "/dmp/y/waveform"),
            ("2D", "/dmp/y/period")} <= set(views)
    # the last learned period over the phase is the model's waveform
    (_, last), = read_mcap_topic(mcap, "/dmp/y/period")[-1:]
    model = PeriodicModel.from_dict(json.loads((learned / "model.json").read_text()))
    np.testing.assert_allclose(last["learned"], model.waveform(last["phase_rad"])[:, 1], atol=1e-9)
    manifest = json.loads((learned / "manifest.json").read_text())
    assert manifest["stage"] == "learn" and manifest["inputs"]["trajectory"]["sha256"] == sha256_file(path)


def test_learn_is_deterministic(demo, learned, tmp_path):
    assert _run("learn", demo[0], "-o", tmp_path / "again", "--quiet").exit_code == 0
    for name in ("model.json", "learn.mcap", "learn.rrd"):
        assert (tmp_path / "again" / name).read_bytes() == (learned / name).read_bytes(), name


def test_offline_mode_and_the_pool_of_oscillators(demo, tmp_path):
    result = _run("learn", demo[0], "-o", tmp_path / "off", "--mode", "offline", "--kernels", "30")
    assert result.exit_code == 0 and "learned 0.80" in result.output
    model = PeriodicModel.from_dict(json.loads((tmp_path / "off" / "model.json").read_text()))
    assert model.kernels == 30 and model.frequency_hz == pytest.approx(FREQUENCY_HZ, rel=1e-3)
    assert _run("learn", demo[0], "-o", tmp_path / "afo", "--canonical", "afo", "-q").exit_code == 0
    _, oscillators, names = read_mcap_scalars(tmp_path / "afo" / "learn.mcap", "/oscillators/frequency_hz")
    assert names == ["omega_1", "omega_2", "omega_3"] and oscillators.shape[1] == 3


def test_learn_reads_the_sponge_track_of_a_track_mcap(demo, tmp_path):
    path, t, _ = demo
    Y = read_trajectory(path).array(["x", "y", "z"])
    keep = np.ones(t.size, dtype=bool)
    keep[100:104] = False                                   # frames the tracker lost
    with StageRecorder(tmp_path, "track") as rec:
        rec.scalars("/track/position", t[keep], Y[keep], names=["x", "y", "z"])
    result = _run("learn", tmp_path / "track.mcap", "-o", tmp_path / "out", "-q", "--mode", "offline")
    assert result.exit_code == 0, result.output
    model = PeriodicModel.from_dict(json.loads((tmp_path / "out" / "model.json").read_text()))
    assert model.frequency_hz == pytest.approx(FREQUENCY_HZ, rel=1e-3)
    result = _run("learn", tmp_path / "out" / "learn.mcap", "-o", tmp_path / "o2")
    assert result.exit_code == 2 and "no /track/position messages (not a track.mcap)" in result.output
    (tmp_path / "junk.mcap").write_text("not mcap")
    result = _run("learn", tmp_path / "junk.mcap", "-o", tmp_path / "o3")
    assert result.exit_code == 2 and "junk.mcap: cannot be read as MCAP" in result.output


def test_rollout_modulates_frequency_amplitude_and_goal(learned, tmp_path):
    model = PeriodicModel.from_dict(json.loads((learned / "model.json").read_text()))
    base, fast = tmp_path / "base.csv", tmp_path / "fast.csv"
    assert _run("rollout", learned / "model.json", "-o", base, "--periods", "2", "--rate", "50").exit_code == 0
    assert _run("rollout", learned / "model.json", "-o", fast, "--periods", "2", "--rate", "100",
                "--frequency", 2 * model.frequency_hz).exit_code == 0
    a, b = read_trajectory(base), read_trajectory(fast)
    assert list(a.columns) == ["x", "y"] and a.t.size == int(np.ceil(2 / model.frequency_hz * 50 - 1e-9))
    np.testing.assert_allclose(b.array(["x", "y"]), a.array(["x", "y"]), atol=2e-6)
    shifted = tmp_path / "shifted.csv"
    assert _run("rollout", learned / "model.json", "-o", shifted, "--periods", "2", "--rate", "50",
                "--amplitude-scale", "0.5", "--goal", "0.2,-0.1").exit_code == 0
    c = read_trajectory(shifted).array(["x", "y"])
    np.testing.assert_allclose(c - [0.2, -0.1], 0.5 * (a.array(["x", "y"]) - model.goal), atol=2e-6)


def _csv(path, text):
    path.write_text(text)
    return path


@pytest.mark.parametrize("make, message", [
    (lambda d: d / "missing.csv", "missing.csv: file not found"),
    (lambda d: _csv(d / "cols.csv", "t,x\n" + "".join(f"{k / 30},{k}\n" for k in range(50))),
     r"cols.csv: missing column\(s\) y"),
    (lambda d: _csv(d / "nan.csv", "t,x,y\n0,1,2\n0.1,nan,2\n0.2,1,2\n"), "nan.csv: column x has NaN or inf"),
    (lambda d: _csv(d / "short.csv", "t,x,y\n0,1,2\n0.1,2,2\n0.2,1,2\n0.3,2,3\n"),
     "short.csv: too short, 4 valid rows"),
    (lambda d: _csv(d / "time.csv", "t,x,y\n0,1,2\n0.2,1,2\n0.1,1,2\n"), "time.csv: time column t is not"),
    (lambda d: _csv(d / "noise.csv", "t,x,y\n" + "".join(
        f"{k / 30},{v[0]},{v[1]}\n" for k, v in enumerate(np.random.default_rng(0).standard_normal((600, 2))))),
     r"noise.csv: the movement of x,y is not periodic \(periodicity 0\.\d\d < 0\.7\)"),
    (lambda d: _csv(d / "brief.csv", "t,x,y\n" + "".join(
        f"{k / 30},{np.cos(k / 30 * 2 * np.pi)},{np.sin(k / 30 * 2 * np.pi)}\n" for k in range(60))),
     r"brief.csv: too short, [12]\.\d periods of 1 Hz, need at least 3"),
])
def test_bad_trajectories_exit_2_with_one_line_and_write_nothing(tmp_path, make, message):
    out = tmp_path / "out"
    result = CliRunner().invoke(cli, ["learn", str(make(tmp_path)), "-o", str(out), "-q"])
    assert result.exit_code == 2
    lines = result.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ")
    assert re.search(message, lines[0]), lines[0]
    assert not out.exists() and not any(p.name.startswith(".out") for p in tmp_path.iterdir())


def test_gaps_in_the_track_are_skipped_online_and_offline(tmp_path):
    """20 s at 0.8 Hz with the sponge lost over 8-9.5 s (NaN rows flagged valid = 0)."""
    t = np.arange(0, 20, 1 / 30)
    Y, clean = wiping_signal(t, FREQUENCY_HZ, seed=2)
    valid = ~((t >= 8.0) & (t < 9.5))
    Y[~valid] = np.nan
    path = tmp_path / "track.csv"
    write_trajectory(path, t, {"x": Y[:, 0], "y": Y[:, 1], "valid": valid})
    for mode in ("online", "offline"):
        result = _run("learn", path, "-o", tmp_path / mode, "--mode", mode, "-q")
        assert result.exit_code == 0, result.output
        model = PeriodicModel.from_dict(json.loads((tmp_path / mode / "model.json").read_text()))
        assert model.frequency_hz == pytest.approx(FREQUENCY_HZ, rel=2e-3), mode
        _, y = model.rollout(t[-1] + 1 / 60, 30.0)
        last = t >= t[-1] - 1 / FREQUENCY_HZ
        assert waveform_rms_percent(y[last], clean[last]).max() <= 3.0, mode
    logged_t, logged, _ = read_mcap_scalars(tmp_path / "online" / "learn.mcap", "/input/valid")
    np.testing.assert_array_equal(logged[:, 0], valid)
    _, hand_overs, _ = read_mcap_scalars(tmp_path / "online" / "learn.mcap", "/learner/hand_overs")
    assert hand_overs[0, 0] == 0 and hand_overs[-1, 0] >= 1


def test_a_track_too_gappy_to_lock_online_is_fitted_offline_and_says_so(tmp_path):
    """0.5 Hz over 8 s, lost for 1.5 s in the middle: never two periods without a gap."""
    t = np.arange(0, 8, 1 / 30)
    valid = ~((t > 3.0) & (t < 4.5))
    path = tmp_path / "gappy.csv"
    write_trajectory(path, t, {"x": np.where(valid, np.cos(np.pi * t), np.nan),
                               "y": np.where(valid, np.sin(np.pi * t), np.nan), "valid": valid})
    result = CliRunner().invoke(cli, ["learn", str(path), "-o", str(tmp_path / "out"), "-q"])
    assert result.exit_code == 0, result.output
    assert re.fullmatch(r"learn: \S*gappy.csv: online learning never locked onto a period .*"
                        r"fitted offline to the whole recording\n", result.stderr)
    model = PeriodicModel.from_dict(json.loads((tmp_path / "out" / "model.json").read_text()))
    assert model.frequency_hz == pytest.approx(0.5, rel=0.01)
    assert model.source["online_never_locked"] is True


def test_bad_options_and_models_exit_2(demo, learned, tmp_path):
    result = _run("learn", demo[0], "-o", tmp_path / "o", "--dofs", "x,x")
    assert result.exit_code == 2 and "--dofs: need distinct column names" in result.output
    not_a_model = _csv(tmp_path / "model.json", json.dumps({"format": "wipelab.other/1"}))
    for model, message in ((demo[0], "not JSON"), (not_a_model, "format is 'wipelab.other/1'"),
                           (tmp_path / "none.json", "none.json: file not found")):
        result = _run("rollout", model, "-o", tmp_path / "r.csv")
        assert result.exit_code == 2 and message in result.output and not (tmp_path / "r.csv").exists()
    result = _run("rollout", learned / "model.json", "-o", tmp_path / "r.csv", "--goal", "1,2,3")
    assert result.exit_code == 2 and "--goal: need 2 finite numbers (x,y)" in result.output
    result = _run("rollout", learned / "model.json", "-o", tmp_path / "r.csv", "--frequency", "-1")
    assert result.exit_code == 2 and "--frequency: must be a positive number" in result.output
