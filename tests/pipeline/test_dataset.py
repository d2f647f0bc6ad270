"""``wipelab dataset``: five synthetic demos, one of them broken, in parallel processes and on
a Dask cluster: the broken one is reported, the others complete, the exit code says so."""

import csv
import json

import pytest
from click.testing import CliRunner

from wipelab.cli.pipeline_commands import dataset, synth_dataset
from wipelab.pipeline.cache import read_record
from wipelab.pipeline.dataset import DemoResult, find_demos, format_summary

from pipeline_testdata import published_files

#: Per demo: track the sponge in the stereo video, learn the movement from the demo's ground
#: truth (offline: a few seconds are enough), roll the model out.
PIPELINE = """
[pipeline]
name = "synthetic"

[inputs]
demo = "unused"

[stages.track]
input = "demo"
particles = 50

[stages.learn]
input = "demo:truth.csv"
mode = "offline"

[stages.rollout]
input = "learn:model.json"
periods = 1
"""

BROKEN = "line_1.6hz_seed0"


@pytest.fixture(scope="module")
def data_set(tmp_path_factory):
    """Five rendered demos (circle and line at 1.2 and 1.6 Hz, figure8 at 1.6 Hz); the left
    video of one is cut off after 3000 bytes."""
    root = tmp_path_factory.mktemp("dataset")
    data = root / "demos"
    runner = CliRunner()
    for pattern, frequencies in [("circle", ("1.2", "1.6")), ("line", ("1.2", "1.6")),
                                 ("figure8", ("1.6",))]:
        args = [str(data), "--pattern", pattern, "--duration", "3", "--fps", "15", "-j", "2",
                "-q"]
        for frequency in frequencies:
            args += ["--frequency", frequency]
        assert runner.invoke(synth_dataset, args).exit_code == 0
    video = data / BROKEN / "left.mp4"
    video.write_bytes(video.read_bytes()[:3000])
    (root / "synthetic.toml").write_text(PIPELINE)
    return root


def check_summary(out_dir, result):
    assert result.exit_code == 1, result.output
    with open(out_dir / "summary.csv") as f:
        rows = {row["demo"]: row for row in csv.DictReader(f)}
    assert sorted(rows) == ["circle_1.2hz_seed0", "circle_1.6hz_seed0", "figure8_1.6hz_seed0",
                            "line_1.2hz_seed0", BROKEN]
    broken = rows.pop(BROKEN)
    assert broken["status"] == "failed"
    assert f"{BROKEN}/left.mp4: cannot be decoded" in broken["error"]
    assert broken["learn.frequency_hz"] == "" and broken["demo.frequency_hz"] == ""
    for name, row in rows.items():
        assert row["status"] == "ok" and row["error"] == "" and row["stages_run"] == "3"
        truth_hz = float(name.split("_")[1].removesuffix("hz"))
        assert float(row["demo.frequency_hz"]) == truth_hz
        assert abs(float(row["learn.frequency_hz"]) - truth_hz) < 0.05 * truth_hz, (name, row)
        run_dir = out_dir / "runs" / name
        assert read_record(run_dir / "rollout") is not None
        model = json.loads((run_dir / "learn" / "model.json").read_text())
        assert model["frequency_hz"] == pytest.approx(float(row["learn.frequency_hz"]), rel=1e-5)
    printed = result.stdout.splitlines()
    assert printed[0].split()[:5] == ["demo", "status", "seconds", "stages_run", "stages_reused"]
    assert sum(" failed " in line for line in printed) == 1


def process(data_set, out_name, *options):
    out = data_set / out_name
    result = CliRunner().invoke(dataset, [str(data_set / "demos"), "--pipeline",
                                          str(data_set / "synthetic.toml"), "-o", str(out),
                                          *options])
    return out, result


@pytest.fixture(scope="module")
def in_processes(data_set):
    """The data set processed by two local worker processes (-j 2)."""
    return process(data_set, "out-j2", "-j", "2")


@pytest.fixture(scope="module")
def on_dask(data_set):
    """The data set processed on a Dask cluster of two worker processes on loopback."""
    from distributed import LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None) as cluster:
        return process(data_set, "out-dask", "--scheduler", cluster.scheduler_address, "-q")


@pytest.mark.slow
def test_parallel_processes(in_processes):
    out, result = in_processes
    check_summary(out, result)
    assert f"failed {BROKEN}: " in result.stderr
    assert "4 of 5 demos ok" in result.stderr


@pytest.mark.slow
def test_dask_cluster_on_loopback(on_dask):
    check_summary(*on_dask)
    assert on_dask[1].stderr == ""  # -q: the table (on stdout) says it all


@pytest.mark.slow
def test_every_demo_gives_the_same_bytes_whichever_executor_ran_it(in_processes, on_dask):
    (local, _), (dask, _) = in_processes, on_dask
    for run_dir in sorted((local / "runs").iterdir()):
        files = published_files(run_dir)
        if run_dir.name != BROKEN:
            assert {"track/track.csv", "track/track.mcap", "learn/model.json",
                    "rollout/rollout.csv"} <= set(files)
        assert files == published_files(dask / "runs" / run_dir.name), run_dir.name


def test_demo_directories_are_found_by_any_of_their_files(tmp_path):
    for name, files in [("a", ["left.mp4", "right.mp4", "calibration.yaml"]),
                        ("b/c", ["calibration.yaml"]), ("d", ["notes.txt"])]:
        (tmp_path / name).mkdir(parents=True)
        for file in files:
            (tmp_path / name / file).write_text("")
    assert [p.relative_to(tmp_path).as_posix() for p in find_demos(tmp_path)] == ["a", "b/c"]


def test_printed_summary_has_the_chosen_metrics_and_blank_cells_where_missing():
    results = [DemoResult("a", ok=True, seconds=1.25, stages_run=2,
                          metrics={"learn.frequency_hz": 1.0, "learn.other": 3.0}),
               DemoResult("b", ok=False, error="b/left.mp4: cannot be decoded", seconds=0.5)]
    lines = format_summary(results).splitlines()
    assert lines[0].split() == ["demo", "status", "seconds", "stages_run", "stages_reused",
                                "learn.frequency_hz", "error"]
    assert lines[1].split() == ["a", "ok", "1.2", "2", "0", "1"]
    assert lines[2].split()[:5] == ["b", "failed", "0.5", "0", "0"]
    assert lines[2].endswith("b/left.mp4: cannot be decoded")


def test_demo_metrics_name_a_synthetic_demos_frequency_and_nothing_else(tmp_path):
    from wipelab.pipeline.metrics import demo_metrics

    synthetic, recorded, broken = (tmp_path / name for name in ("synthetic", "recorded", "broken"))
    for folder in (synthetic, recorded, broken):
        folder.mkdir()
    (synthetic / "demo.toml").write_text("fps = 30\n[synth]\nfrequency_hz = 0.8\n")
    (recorded / "demo.toml").write_text('fps = 30\nsponge_colour = "yellow"\n')
    (broken / "demo.toml").write_text("[synth\nfrequency_hz = ")
    assert demo_metrics(synthetic) == {"demo.frequency_hz": 0.8}
    assert demo_metrics(recorded) == {} and demo_metrics(broken) == {}
    assert demo_metrics(tmp_path / "missing") == {}
