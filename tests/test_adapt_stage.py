"""The adapt and replay stages end to end on the simulated robot, and their CLI errors."""

import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from mcap.reader import make_reader

from wipelab.cli import cli
from wipelab.learning import PeriodicModel
from wipelab.stages.adapt import AdaptParams, run_adapt
from wipelab.stages.replay import ReplayParams, run_replay

from sim.sim_models import circle_model


@pytest.fixture(scope="module")
def model_file(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("model") / "model.json"
    path.write_text(json.dumps(circle_model().to_dict()))
    return path


@pytest.fixture(scope="module")
def adapted(model_file, tmp_path_factory):
    out = tmp_path_factory.mktemp("adapt") / "flat"
    metrics = run_adapt(model_file, out, AdaptParams(surface="flat", periods=4), quiet=True)
    return out, metrics


def test_adapt_on_flat_converges_and_learns_the_surface(adapted):
    out, metrics = adapted
    assert metrics["safety_stop"] is None
    assert metrics["learning"]["converged"] and metrics["learning"]["periods"] <= 4
    profile = metrics["profile_hold"]
    assert profile["true_height_range_m"] >= 0.03       # the unknown grasp at work
    assert profile["rms_height_error_m"] <= 0.0015
    assert metrics["force_hold"]["rms_force_error_n"] <= 1.5
    assert metrics["force_hold"]["contact_fraction"] >= 0.99
    model = PeriodicModel.from_dict(json.loads((out / "adapted_model.json").read_text()))
    assert model.dofs == ("x", "y", "z", "z_per_hz") and model.surface["spec"] == "flat"
    # z learned on 50 kernels, the demonstrated x-y refitted onto them
    assert model.kernels == 50 and metrics["kernels"]["model"] == 25
    assert metrics["kernels"]["xy_refit_error_m"] < 1e-4
    z = model.waveform(np.linspace(0, 2 * np.pi, 64))[:, 2]
    assert np.ptp(z) == pytest.approx(profile["learned_height_range_m"], rel=0.05)
    assert json.loads((out / "metrics.json").read_text()) == json.loads(json.dumps(metrics))


def test_adapt_logs_read_back(adapted):
    out, _ = adapted
    with open(out / "adapt.mcap", "rb") as f:
        reader = make_reader(f, validate_crcs=True)
        summary = reader.get_summary()
        topics = {c.topic for c in summary.channels.values()}
        schemas = {s.name for s in summary.schemas.values()}
    assert {"/tf", "/robot/joint_states/position", "/adapt/wrench", "/adapt/height",
            "/adapt/force_norm", "/adapt/contact", "/adapt/tcp_commanded", "/adapt/tcp_actual",
            "/adapt/force_arrow", "/adapt/learned_profile", "/adapt/segment"} <= topics
    assert {"foxglove.FrameTransforms", "foxglove.PoseInFrame"} <= schemas
    from rerun.chunk import RrdReader

    entities = {chunk.to_record_batch().schema.metadata[b"rerun:entity_path"].decode()
                for chunk in RrdReader(out / "adapt.rrd").stream()}
    assert {"/adapt/height", "/adapt/force_norm", "/robot/sponge", "/tf_static"} <= entities
    assert any(e.startswith("/armar3b/") for e in entities)      # the robot from the URDF
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["stage"] == "adapt" and "model" in manifest["inputs"]


def test_adapt_is_deterministic(model_file, adapted, tmp_path):
    out, _ = adapted
    run_adapt(model_file, tmp_path / "again", AdaptParams(surface="flat", periods=4), quiet=True)
    for name in ("adapted_model.json", "metrics.json", "adapt.mcap", "adapt.rrd"):
        assert (tmp_path / "again" / name).read_bytes() == (out / name).read_bytes(), name


def test_replay_holds_the_force_where_the_baseline_does_not(adapted, tmp_path):
    out, _ = adapted
    params = ReplayParams(frequency_scales=(1.0, 3.0), modes=("learned+compliance", "planar"),
                          periods=1)
    metrics = run_replay(out / "adapted_model.json", tmp_path / "replay", params, quiet=True)
    assert {"metrics.json", "replay.mcap", "replay.rrd", "manifest.json"} <= {
        p.name for p in (tmp_path / "replay").iterdir()}
    at1, at3 = metrics["scales"]["1"], metrics["scales"]["3"]
    assert at1["learned+compliance"]["rms_force_error_n"] <= 1.5
    assert at3["learned+compliance"]["rms_force_error_n"] <= 2.0
    for run in (at1["learned+compliance"], at3["learned+compliance"]):
        assert run["contact_fraction"] >= 0.99 and run["peak_force_n"] <= 30.0
    assert at1["planar"]["rms_force_error_n"] > 3 * at1["learned+compliance"]["rms_force_error_n"]


def _invoke(*args):
    return CliRunner().invoke(cli, [str(a) for a in args])


def _one_error_line(result, text):
    assert result.exit_code == 2, result.output
    lines = [line for line in result.output.splitlines() if line.startswith("error:")]
    assert len(lines) == 1 and text in lines[0], result.output


def test_cli_bad_model_format(tmp_path):
    bad = tmp_path / "m.json"
    bad.write_text(json.dumps({"format": "wipelab.trajectory/1"}))
    _one_error_line(_invoke("adapt", bad, "-o", tmp_path / "o"), "expected 'wipelab.periodic_dmp/1'")
    bad.write_text("{not json")
    _one_error_line(_invoke("replay", bad, "-o", tmp_path / "o"), "not a model file")


def test_cli_unknown_surface_and_bad_heightfield(model_file, tmp_path):
    _one_error_line(_invoke("adapt", model_file, "-o", tmp_path / "o", "--surface", "marble"),
                    "unknown surface 'marble'")
    np.save(tmp_path / "h.npy", np.zeros(10))
    (tmp_path / "s.toml").write_text('type = "heightfield"\nfile = "h.npy"\n')
    _one_error_line(_invoke("adapt", model_file, "-o", tmp_path / "o", "--surface",
                            tmp_path / "s.toml"), "must be a 2-D array")
    assert not (tmp_path / "o").exists()


def test_cli_bad_kernel_count(model_file, tmp_path):
    _one_error_line(_invoke("adapt", model_file, "-o", tmp_path / "o", "--kernels", "3"),
                    "--kernels: must be in [5, 200]")


def test_cli_refuses_a_surface_the_arm_cannot_reach_and_says_why(model_file, tmp_path):
    (tmp_path / "high.toml").write_text('type = "flat"\nheight = 1.35\n')
    _one_error_line(_invoke("adapt", model_file, "-o", tmp_path / "o", "--surface",
                            tmp_path / "high.toml"),
                    "the arm cannot reach the movement (20 x 20 cm) on the surface 'high' "
                    "(1.35-1.35 m high; the arm wipes surfaces")
    assert not (tmp_path / "o").exists()
    _one_error_line(_invoke("adapt", model_file, "-o", tmp_path / "o", "--center", "0.95,-0.65"),
                    "does not fit on the surface 'flat' there")


def test_cli_replay_needs_an_adapted_model_for_the_learned_modes(model_file, tmp_path):
    _one_error_line(_invoke("replay", model_file, "-o", tmp_path / "o", "--mode", "learned"),
                    "has no learned z")
