"""End to end: ``wipelab live`` on a small scene of the independent generator (320x240, 60 fps,
7 s; a development seed), as fast as it goes: every file is written and read back, the other
commands take over from them, a rerun writes the same bytes, two video files given as cameras
give the same track, and imitation learning ends on --learn-periods, SIGUSR1 and Enter."""

import json
import signal
import subprocess
import sys

import numpy as np
import pytest
from click.testing import CliRunner

from tests.stereo_scenes import render_scene
from wipelab.cli import cli
from wipelab.logs import mcap_topics, read_mcap_scalars, read_mcap_topic, rrd_blueprint_views
from wipelab.model_file import read_model
from wipelab.pipeline.recordings import rerun_program
from wipelab.trajectory_csv import read_trajectory

#: A development seed whose sponge the tracker finds early (its colour named as a user would).
SEED, COLOUR = 22, "purple"
FAST = ["--speed", "max", "--color", COLOUR, "--replay-periods", "1"]


def live(*argv) -> None:
    result = CliRunner().invoke(cli, ["live", *map(str, argv), "-q"])
    assert result.exit_code == 0, (result.output, result.exception)


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    path = tmp_path_factory.mktemp("live") / "scene"
    render_scene(path, seed=SEED, small=True, duration=7.0, frequency_hz=1.5)
    return path


@pytest.fixture(scope="module")
def session(scene, tmp_path_factory):
    out = tmp_path_factory.mktemp("live") / "out"
    live(scene, "-o", out, *FAST)
    return out


def metrics_of(out):
    return json.loads((out / "metrics.json").read_text())


def test_live_writes_the_batch_stages_files_and_its_logs(scene, session):
    assert sorted(p.name for p in session.iterdir()) == [
        "adapted_model.json", "live.mcap", "live.rrd", "manifest.json", "metrics.json",
        "model.json", "track.csv"]
    frames = int(json.loads((scene / "scene.json").read_text())["frame_count"])
    metrics = metrics_of(session)
    imitation = metrics["imitation"]
    track = read_trajectory(session / "track.csv", required=("t", "x", "y", "z", "valid",
                                                              "x_norm", "y_norm"))
    stop_frame = round(imitation["stop_s"] * metrics["frames"]["fps"])
    assert len(track.t) == metrics["frames"]["total"] == stop_frame + 1 <= frames
    assert metrics["frames"]["dropped"] == 0 and "timing" not in metrics   # no wall clock
    assert track.valid[track.t >= imitation["first_tracked_s"]].mean() > 0.6
    truth = read_trajectory(scene / "truth.csv", required=("t", "x", "y", "z"))
    error = np.linalg.norm(track.array(["x", "y"])[track.valid]
                           - truth.array(["x", "y"])[:len(track.t)][track.valid], axis=1)
    assert np.median(error) < 0.03   # the colour region's centre (no sponge size given)
    model = read_model(session / "model.json")
    assert model.dofs == ("x", "y") and model.frequency_hz == pytest.approx(1.5, rel=0.03)
    assert imitation["stop_reason"] in ("converged", "end of the video")
    assert imitation["lock_s"] < imitation["stop_s"]
    adapted = read_model(session / "adapted_model.json")
    assert "z" in adapted.dofs and adapted.surface["spec"] == "flat"
    assert metrics["adapt"]["learning"]["converged"] and metrics["safety_stop"] is None
    assert metrics["replay"]["rms_force_error_n"] < 2.0
    assert metrics["replay"]["contact_fraction"] > 0.99
    following = metrics["following"]
    assert following["follows_from_s"] is not None and abs(following["lag_s"]) < 0.3
    manifest = json.loads((session / "manifest.json").read_text())
    assert manifest["stage"] == "live" and set(manifest["inputs"]) == {
        "calibration", "left_video", "right_video"}

    topics = mcap_topics(session / "live.mcap")
    for topic, schema in [("/stereo/left/video", "foxglove.CompressedVideo"),
                          ("/stereo/right/overlay", "foxglove.ImageAnnotations"),
                          ("/track/sponge", "foxglove.SceneUpdate"),
                          ("/tf", "foxglove.FrameTransforms"),
                          ("/oscillators/model_frequency_hz", "wipelab.Scalars"),
                          ("/live/imitation/x", "wipelab.Scalars"),
                          ("/live/force_norm", "wipelab.Scalars"),
                          ("/live/segment", "wipelab.State")]:
        assert topics[topic]["schema"] == schema, topic
    t, values, names = read_mcap_scalars(session / "live.mcap", "/oscillators/model_frequency_hz")
    assert values[-1, 0] == pytest.approx(model.frequency_hz, rel=0.01)
    t, values, names = read_mcap_scalars(session / "live.mcap", "/live/imitation/x")
    assert names == ["demonstrated", "learned", "robot"]
    assert t[0] >= imitation["lock_s"] - 1e-9   # MCAP log times are whole nanoseconds
    assert {("2D", "/stereo/left"), ("2D", "/stereo/right"), ("3D", "/"),
            ("TimeSeries", "/oscillators"), ("TimeSeries", "/live/imitation/x"),
            ("TimeSeries", "/live/tcp_height"), ("TimeSeries", "/live/force_norm")} <= \
        set(rrd_blueprint_views(session / "live.rrd"))
    verified = subprocess.run([rerun_program(), "rrd", "verify", str(session / "live.rrd")],
                              capture_output=True, text=True)
    assert verified.returncode == 0, verified.stderr
    # the track's frame has a place in the robot's world from the start (provisional, from the
    # first tracked point), then the demonstration area's once the learner has locked
    placed = [t for t, message in read_mcap_topic(session / "live.mcap", "/tf")
              for transform in message["transforms"]
              if transform["child_frame_id"] == "demonstration"]
    assert len(placed) == 2 and placed[0] == 0
    assert placed[1] / 1e9 == pytest.approx(imitation["lock_s"], abs=0.1)


def test_the_other_commands_take_over_from_a_live_session(session, tmp_path):
    model = read_model(session / "model.json")
    runner = CliRunner()
    learned = runner.invoke(cli, ["learn", str(session / "track.csv"), "-o",
                                  str(tmp_path / "learn"), "-q"])
    assert learned.exit_code == 0, learned.output
    batch = read_model(tmp_path / "learn" / "model.json")
    assert batch.frequency_hz == pytest.approx(model.frequency_hz, rel=0.02)
    replayed = runner.invoke(cli, ["replay", str(session / "adapted_model.json"), "-o",
                                   str(tmp_path / "replay"), "--frequency-scale", "1", "--mode",
                                   "learned", "--periods", "1", "--warmup-periods", "0", "-q"])
    assert replayed.exit_code == 0, replayed.output
    scored = json.loads((tmp_path / "replay" / "metrics.json").read_text())["scales"]["1"]
    assert scored["learned"]["rms_force_error_n"] < 3.0


def test_a_rerun_at_max_speed_writes_the_same_bytes(scene, session, tmp_path):
    live(scene, "-o", tmp_path / "again", *FAST)
    for path in session.iterdir():
        assert (tmp_path / "again" / path.name).read_bytes() == path.read_bytes(), path.name


def test_two_video_files_as_cameras_give_the_same_session(scene, session, tmp_path):
    out = tmp_path / "cameras"
    live("--camera", f"{scene}/left.mp4,{scene}/right.mp4", "--calibration",
         scene / "calibration.yaml", "-o", out, *FAST)
    for name in ("track.csv", "model.json"):
        assert (out / name).read_bytes() == (session / name).read_bytes(), name
    adapted = [json.loads((folder / "adapted_model.json").read_text()) for folder in (out, session)]
    assert adapted[0]["source"]["parameters"]["source"] != adapted[1]["source"]["parameters"]["source"]
    assert [{k: v for k, v in a.items() if k != "source"} for a in adapted][0] == \
        {k: v for k, v in adapted[1].items() if k != "source"}


def test_learn_periods_end_imitation_learning(scene, tmp_path):
    live(scene, "-o", tmp_path / "out", *FAST, "--learn-periods", "2", "--no-stop-on-convergence")
    imitation = metrics_of(tmp_path / "out")["imitation"]
    assert imitation["stop_reason"] == "learn-periods"
    assert 2.0 <= imitation["periods_since_lock"] < 2.1


@pytest.mark.parametrize("how", ["SIGUSR1", "Enter"])
def test_the_users_word_ends_imitation_learning(scene, tmp_path, how):
    """Sent when the robot starts to imitate (the line on stderr says so): imitation learning
    ends there, well before the end of the video, and the robot goes on to the surface."""
    out = tmp_path / "out"
    process = subprocess.Popen(
        [sys.executable, "-m", "wipelab", "live", str(scene), "-o", str(out), *FAST,
         "--no-stop-on-convergence"], stdin=subprocess.PIPE, stderr=subprocess.PIPE,
        stdout=subprocess.DEVNULL, text=True)
    for line in process.stderr:
        if "the robot imitates" in line:
            break
    if how == "SIGUSR1":
        process.send_signal(signal.SIGUSR1)
    else:
        process.stdin.write("\n")
        process.stdin.flush()
    process.stderr.read()
    assert process.wait(timeout=120) == 0
    imitation = metrics_of(out)["imitation"]
    assert imitation["stop_reason"] == how
    assert imitation["stop_s"] < 6.0 and (out / "adapted_model.json").is_file()
