"""``wipelab run``: stages in order, caching by content, reproducible bytes, clear errors."""

import fcntl
import json

import pytest
from click.testing import CliRunner

from wipelab.cli import cli
from wipelab.errors import InputError
from wipelab.pipeline.cache import RECORD_NAME, read_record
from wipelab.pipeline.invoke import build_argv, check_arguments, stage_command
from wipelab.pipeline.runner import LOCK_NAME, run_pipeline
from wipelab.pipeline.spec import load_pipeline

from pipeline_testdata import published_files, write_wiping_trajectory


def run(pipeline, run_dir, **overrides):
    lines = []
    outcomes = run_pipeline(pipeline.with_overrides(**overrides), run_dir, echo=lines.append)
    return {o.name: o.reused for o in outcomes}, lines


def test_first_run_runs_every_stage_and_an_unchanged_rerun_reuses_them(learn_pipeline_file,
                                                                        tmp_path):
    pipeline = load_pipeline(learn_pipeline_file)
    run_dir = tmp_path / "run"
    reused, _ = run(pipeline, run_dir)
    assert reused == {"learn": False, "rollout": False}
    model = json.loads((run_dir / "learn" / "model.json").read_text())
    assert model["format"] == "wipelab.periodic_dmp/1"
    assert abs(model["frequency_hz"] - 1.2) < 0.02
    assert (run_dir / "rollout" / "rollout.csv").read_text().startswith("t,")
    record = read_record(run_dir / "learn")
    assert record.input == str(learn_pipeline_file.parent / "trajectory.csv")
    assert set(record.outputs) >= {"model.json", "learn.mcap", "learn.rrd", "manifest.json"}
    assert read_record(run_dir / "rollout").input == "learn/model.json"

    reused, lines = run(pipeline, run_dir)
    assert reused == {"learn": True, "rollout": True}
    assert "[1/2] reused learn (cache hit)" in lines
    assert lines[-1].endswith("ran 0 stage(s); reused 2: learn, rollout")


def test_a_changed_parameter_reruns_its_stage_and_the_stages_after_it(learn_pipeline_file,
                                                                        tmp_path):
    pipeline = load_pipeline(learn_pipeline_file)
    run_dir = tmp_path / "run"
    run(pipeline, run_dir)
    reused, lines = run(pipeline, run_dir, sets=["rollout.periods=3"])
    assert reused == {"learn": True, "rollout": False}
    assert "[2/2] running rollout (inputs or parameters changed)" in lines
    reused, _ = run(pipeline, run_dir, sets=["learn.kernels=30"])
    assert reused == {"learn": False, "rollout": False}  # a new model.json: rollout reruns
    assert json.loads((run_dir / "learn" / "model.json").read_text())["kernels"] == 30


def test_changed_input_or_tampered_output_is_not_up_to_date(learn_pipeline_file, tmp_path):
    pipeline = load_pipeline(learn_pipeline_file)
    run_dir = tmp_path / "run"
    run(pipeline, run_dir)
    (run_dir / "rollout" / "rollout.csv").write_text("t,x\n0,0\n")
    reused, lines = run(pipeline, run_dir)
    assert reused == {"learn": True, "rollout": False}
    assert "[2/2] running rollout (cached outputs missing or modified)" in lines
    write_wiping_trajectory(learn_pipeline_file.parent / "trajectory.csv", frequency_hz=0.9)
    reused, _ = run(pipeline, run_dir)
    assert reused == {"learn": False, "rollout": False}


def test_two_fresh_runs_in_different_places_write_identical_bytes(learn_pipeline_file, tmp_path):
    pipeline = load_pipeline(learn_pipeline_file)
    run(pipeline, tmp_path / "a")
    run(pipeline, tmp_path / "elsewhere" / "b")
    first, second = published_files(tmp_path / "a"), published_files(tmp_path / "elsewhere" / "b")
    assert sorted(first) == sorted(second)
    assert all(name.endswith((".csv", ".json", ".mcap", ".rrd")) for name in first)
    assert [name for name in first if first[name] != second[name]] == []


def test_cli_run_reports_progress_and_bad_options_without_running_anything(learn_pipeline_file,
                                                                           tmp_path):
    runner = CliRunner()
    run_dir = tmp_path / "run"
    result = runner.invoke(cli, ["run", str(learn_pipeline_file), "-o", str(run_dir),
                                 "--set", "learn.kernel=30"])
    assert result.exit_code == 2
    assert result.stderr.startswith(f"error: {learn_pipeline_file}: stage learn: learn has no "
                                    f"option 'kernel' (options: ")
    assert not (run_dir / "learn").exists()

    result = runner.invoke(cli, ["run", str(learn_pipeline_file), "-o", str(run_dir),
                                 "--set", "rollout.periods=many"])
    assert result.exit_code == 2
    assert result.stderr == (f"error: {learn_pipeline_file}: stage rollout: --periods: 'many' "
                             f"is not a valid float\n")
    assert not (run_dir / "learn").exists()

    result = runner.invoke(cli, ["run", str(learn_pipeline_file), "-o", str(run_dir), "-q"])
    assert result.exit_code == 0, result.output
    assert result.stderr == ""
    result = runner.invoke(cli, ["run", str(learn_pipeline_file), "-o", str(run_dir)])
    assert result.exit_code == 0
    assert "[2/2] reused rollout (cache hit)" in result.stderr


def test_missing_input_and_busy_run_directory_are_input_errors(learn_pipeline_file, tmp_path):
    pipeline = load_pipeline(learn_pipeline_file)
    with pytest.raises(InputError,
                       match=r"stage learn: input 'trajectory' \(.*nope\.csv\) not found"):
        run(pipeline, tmp_path / "run", inputs=[f"trajectory={tmp_path / 'nope.csv'}"])
    run_dir = tmp_path / "busy"
    run_dir.mkdir()
    with open(run_dir / LOCK_NAME, "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        with pytest.raises(InputError, match="another wipelab run is using this directory"):
            run(pipeline, run_dir)
    assert not (run_dir / "learn" / RECORD_NAME).exists()


def test_a_killed_stage_s_temporary_folder_is_removed_by_the_next_run(learn_pipeline_file,
                                                                      tmp_path):
    run_dir = tmp_path / "run"
    leftover = run_dir / ".learn.partial-x1y2"  # what staged_output leaves when killed
    leftover.mkdir(parents=True)
    (leftover / "model.json").write_text("{")
    reused, _ = run(load_pipeline(learn_pipeline_file), run_dir)
    assert reused == {"learn": False, "rollout": False}
    assert not leftover.exists()


def test_a_synth_stage_takes_no_input_and_writes_into_its_folder(tmp_path):
    (tmp_path / "p.toml").write_text('[stages.demo]\ncommand = "synth"\nduration = 2\n')
    pipeline = load_pipeline(tmp_path / "p.toml")
    stage = pipeline.stage("demo")
    command = stage_command("synth")
    assert build_argv(stage, command, None, "demo", True, "p.toml") == [
        "demo", "--duration", "2", "--quiet"]
    check_arguments(stage, command, "p.toml")
