"""The adapt and replay stages end to end on the simulated robot, and their CLI errors."""

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from mcap.reader import make_reader

from wipelab.cli import cli
from wipelab.learning import PeriodicModel
from wipelab.logs import read_mcap_scalars, read_mcap_topic
from wipelab.logs.palette import segment_colour
from wipelab.sim.adaptation import Adaptation, AdaptationParams
from wipelab.sim.path import at_frequency, with_kernels
from wipelab.sim.surfaces import flat_surface
from wipelab.sim.task import TaskOptions, build_task, place_task
from wipelab.stages.adapt import AdaptParams, run_adapt
from wipelab.stages.replay import ReplayParams, RunResult, run_replay

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
    z = at_frequency(model, metrics["hold_frequency_hz"]).waveform(np.linspace(0, 2 * np.pi,
                                                                           64))[:, 2]
    assert np.ptp(z) == pytest.approx(profile["learned_height_range_m"], rel=0.05)
    assert json.loads((out / "metrics.json").read_text()) == json.loads(json.dumps(metrics))


def test_adapt_records_its_tempos_and_where_it_placed_the_robot(adapted):
    out, metrics = adapted
    demonstrated = circle_model().frequency_hz
    assert metrics["demonstrated_frequency_hz"] == pytest.approx(demonstrated)
    assert metrics["learning_frequency_hz"] == pytest.approx(demonstrated / 4)
    # refined at the learning tempo, then at the demonstrated one (the arm can follow it)
    assert [stage["frequency_hz"] for stage in metrics["tempos"]] == pytest.approx(
        [demonstrated / 4, demonstrated])
    assert metrics["hold_frequency_hz"] == pytest.approx(demonstrated)
    assert metrics["max_frequency_hz"] > demonstrated
    fast = metrics["tempos"][1]["rms_force_error_n"]
    assert fast[-1] < fast[0] and min(fast) < 0.8
    placement = metrics["placement"]
    assert placement["chosen_by"] == "search" and placement["center"] == [0.58, -0.28]
    manifest = json.loads((out / "manifest.json").read_text())
    model = json.loads((out / "adapted_model.json").read_text())
    assert manifest["placement"] == placement == model["surface"]["placement"]
    assert model["surface"]["tempos_hz"] == pytest.approx([demonstrated / 4, demonstrated])


def test_adapt_logs_read_back(adapted):
    out, _ = adapted
    with open(out / "adapt.mcap", "rb") as f:
        reader = make_reader(f, validate_crcs=True)
        summary = reader.get_summary()
        topics = {c.topic for c in summary.channels.values()}
        schemas = {s.name for s in summary.schemas.values()}
    assert {"/tf", "/robot/joint_states/position", "/adapt/wrench", "/adapt/tcp_height",
            "/adapt/contact_height", "/adapt/force_norm", "/adapt/contact", "/adapt/tcp_commanded",
            "/adapt/tcp_actual", "/adapt/force_arrow", "/adapt/learned_profile", "/adapt/profile",
            "/adapt/segment", "/adapt/events", "/robot/body", "/robot/sponge"} <= topics
    assert {"foxglove.FrameTransforms", "foxglove.PoseInFrame"} <= schemas
    from rerun.chunk import RrdReader

    entities = {chunk.to_record_batch().schema.metadata[b"rerun:entity_path"].decode()
                for chunk in RrdReader(out / "adapt.rrd").stream()}
    assert {"/adapt/tcp_height", "/adapt/force_norm", "/robot/sponge", "/tf_static",
            "/adapt/placement", "/scene/platform_footprint"} <= entities
    assert any(e.startswith("/armar3b/") for e in entities)      # the robot from the URDF
    # the F/T calibration records nothing: it is named, and the series break there
    states = [m["state"] for _, m in read_mcap_topic(out / "adapt.mcap", "/adapt/segment")]
    assert states[:4] == ["approach", "F/T calibration", "approach", "learning"]
    refining = [state for state in states if state.startswith("refining at ")]
    assert len(refining) == 2 and len({segment_colour(state) for state in (
        "approach", "learning", refining[0], "learned profile")}) == 4   # its own colour
    t, force, _ = read_mcap_scalars(out / "adapt.mcap", "/adapt/force_norm")
    gap = np.argmax(np.diff(t))
    assert np.isnan(force[gap]).all() and not np.isnan(force[gap + 1]).any()
    profiles = [m for _, m in read_mcap_topic(out / "adapt.mcap", "/adapt/profile")]
    assert [m["period"] for m in profiles] == list(range(1, len(profiles) + 1))
    last = np.array(profiles[-1]["learned_mm"]) - np.array(profiles[-1]["surface_mm"])
    assert np.sqrt(np.nanmean(last ** 2)) < 3.0       # the learned profile is the surface
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["stage"] == "adapt" and "model" in manifest["inputs"]
    placement = read_mcap_topic(out / "adapt.mcap", "/adapt/placement")
    assert [message for _, message in placement] == [manifest["placement"]]


def test_adapt_is_deterministic(model_file, adapted, tmp_path):
    out, _ = adapted
    run_adapt(model_file, tmp_path / "again", AdaptParams(surface="flat", periods=4), quiet=True)
    for name in ("adapted_model.json", "metrics.json", "adapt.mcap", "adapt.rrd"):
        assert (tmp_path / "again" / name).read_bytes() == (out / name).read_bytes(), name


def test_replay_holds_the_force_at_the_demonstrated_tempo_where_the_baselines_do_not(
        adapted, tmp_path):
    out, adapt_metrics = adapted
    params = ReplayParams(frequency_scales=(1.0, 1.5), modes=("learned+compliance", "planar"),
                          periods=1)
    metrics = run_replay(out / "adapted_model.json", tmp_path / "replay", params, quiet=True)
    assert {"metrics.json", "replay.mcap", "replay.rrd", "manifest.json"} <= {
        p.name for p in (tmp_path / "replay").iterdir()}
    demonstrated, fastest = metrics["demonstrated_frequency_hz"], metrics["max_frequency_hz"]
    assert demonstrated == pytest.approx(circle_model().frequency_hz)
    assert metrics["placement"]["base"] == adapt_metrics["placement"]["base"]
    for scale, runs in metrics["scales"].items():
        for run in runs.values():        # each run says its tempo in Hz, and if the arm limited it
            asked = float(scale) * demonstrated
            assert run["requested_frequency_hz"] == pytest.approx(asked)
            assert run["frequency_hz"] == pytest.approx(min(asked, fastest))
            assert run["arm_limited"] == (asked > fastest)
    at1, faster = metrics["scales"]["1"], metrics["scales"]["1.5"]
    assert at1["learned+compliance"]["rms_force_error_n"] <= 1.0
    assert faster["learned+compliance"]["rms_force_error_n"] <= 1.5
    for run in (at1["learned+compliance"], faster["learned+compliance"]):
        assert run["contact_fraction"] >= 0.99 and run["peak_force_n"] <= 30.0
        assert run["safety_stop"] is None and run["tracking_error_rms_m"] < 0.002
    assert at1["planar"]["safety_stop"] or at1["planar"]["contact_fraction"] < 0.5
    # |F| over the phase, one curve per tempo and mode, in the logs, at the tempo each ran at
    curves = {mode: [m for _, m in read_mcap_topic(tmp_path / "replay" / "replay.mcap",
                                                   f"/replay/force_by_phase/{mode}")]
              for mode in ("learned_compliance", "planar")}
    for mode, mode_curves in zip(("learned+compliance", "planar"), curves.values()):
        assert [m["scale"] for m in mode_curves] == [1.0, 1.5]
        assert [m["frequency_hz"] for m in mode_curves] == pytest.approx(
            [metrics["scales"][s][mode]["frequency_hz"] for s in ("1", "1.5")])
    for curve in curves["learned_compliance"]:
        assert np.nanmean(np.array(curve["force_n"], dtype=float)) == pytest.approx(10.0, abs=1.5)
    for curve in curves["planar"]:
        assert np.isfinite(np.array(curve["force_n"], dtype=float)).any()


def test_a_replay_run_stopped_in_its_warm_up_is_scored_and_drawn_up_to_the_stop():
    stopped = RunResult(1.0, "planar", 1.0, 1.0, motion_start=5.0, start=6.0, end=5.5,
                        planned=1.0, stop_reason="|F| = 80 N exceeded the safety limit")
    assert stopped.scored() == (5.0, 5.5)
    assert replace(stopped, end=7.0).scored() == (6.0, 7.0)


def test_refining_at_the_demonstrated_tempo_holds_the_force_on_a_bowl(model_file, tmp_path):
    """The paper's profile, learned at a quarter of the tempo, against the one refined by
    iterative learning at the learning tempo and at 1x, both replayed at 1x."""
    errors = {}
    for tempos in ((), (1.0,)):
        out = tmp_path / f"adapt{len(tempos)}"
        run_adapt(model_file, out, AdaptParams(surface="bowl", periods=4, tempos=tempos,
                                               hold_periods=0), quiet=True)
        replayed = run_replay(out / "adapted_model.json", tmp_path / f"replay{len(tempos)}",
                              ReplayParams(frequency_scales=(1.0,), modes=("learned",),
                                           periods=1), quiet=True)
        errors[tempos] = replayed["scales"]["1"]["learned"]["rms_force_error_n"]
    assert errors[(1.0,)] < 1.0 and errors[(1.0,)] < 0.5 * errors[()]


def test_adaptation_steps_one_control_period_at_a_time(tmp_path):
    """``wipelab live`` steps the adapt algorithm: stepping it by hand is running it."""
    surface = flat_surface()
    placed = place_task(with_kernels(circle_model(), 50), surface, TaskOptions())
    runs = []
    for stepped in (False, True):
        task = build_task(placed.model, surface, placed.options, plan=placed.plan)
        run = Adaptation(task, placed.model, AdaptationParams(periods=2, tempos=(),
                                                              hold_periods=0))
        if stepped:
            lengths = []
            while run.step():
                lengths.append(len(task.session.trace))
            assert np.all(np.diff(lengths[-500:]) == 1)     # one control period per step
        else:
            run.run()
        runs.append((task.session.trace.arrays()["tcp_cmd"], run.adapted_model({}, None)))
        task.close()
    assert np.array_equal(runs[0][0], runs[1][0])
    assert runs[0][1].to_dict() == runs[1][1].to_dict()


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
