"""End to end: ``wipelab synth`` then ``wipelab track`` through the CLI, files read back."""

import json
import shutil
import subprocess
import sys

import cv2
import numpy as np
import pytest
from click.testing import CliRunner

from wipelab.cli import cli
from wipelab.logs import mcap_attachments, mcap_topics, read_mcap_scalars, rrd_column
from wipelab.stages import track as track_stage
from wipelab.stages.track import LogVideos, open_demo
from wipelab.trajectory_csv import read_trajectory
from wipelab.vision.calibration import load_calibration
from wipelab.vision.projection import invert_transform
from wipelab.vision.video_io import H264Writer


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    path = tmp_path_factory.mktemp("stage") / "demo"
    result = CliRunner().invoke(cli, ["synth", str(path), "--pattern", "line", "--frequency",
                                      "1.5", "--duration", "2.5", "--seed", "5", "-q"])
    assert result.exit_code == 0, result.output
    return path


@pytest.fixture(scope="module")
def tracked(demo, tmp_path_factory):
    out = tmp_path_factory.mktemp("stage") / "track"
    result = CliRunner().invoke(cli, ["track", str(demo), "-o", str(out), "--particles", "80"])
    assert result.exit_code == 0, result.output
    assert "tracked" in result.output and "track.csv" in result.output
    return out


def test_track_writes_csv_logs_and_manifest(demo, tracked):
    assert sorted(p.name for p in tracked.iterdir()) == ["manifest.json", "track.csv",
                                                         "track.mcap", "track.rrd"]
    track = read_trajectory(tracked / "track.csv", required=("t", "x", "y", "z", "valid"))
    truth = read_trajectory(demo / "truth.csv", required=("t", "x", "y", "z"))
    np.testing.assert_allclose(track.t, truth.t, atol=1e-6)
    valid = track.valid
    visible = np.minimum(truth.columns["visible_left"], truth.columns["visible_right"])
    assert valid[visible == 1].mean() > 0.9 and not valid[visible == 0].any()
    error = np.linalg.norm(track.array(["x", "y", "z"])[valid] - truth.array(["x", "y", "z"])[valid],
                           axis=1)
    assert np.median(error) < 0.004
    offsets = track.array(["x_norm", "y_norm"])[valid & (track.t <= 10)]
    np.testing.assert_allclose(offsets.min(axis=0), [-1, -1], atol=1e-5)
    np.testing.assert_allclose(offsets.max(axis=0), [1, 1], atol=1e-5)

    topics = mcap_topics(tracked / "track.mcap")
    for topic, schema in [("/stereo/left/video", "foxglove.CompressedVideo"),
                          ("/stereo/right/calibration", "foxglove.CameraCalibration"),
                          ("/tf", "foxglove.FrameTransforms"),
                          ("/track/particles", "foxglove.PointCloud"),
                          ("/track/sponge", "foxglove.SceneUpdate"),
                          ("/stereo/left/overlay", "foxglove.ImageAnnotations"),
                          ("/track/position", "wipelab.Scalars")]:
        assert topics[topic]["schema"] == schema
    assert topics["/stereo/left/video"]["message_count"] == len(track.t)
    t, xyz, names = read_mcap_scalars(tracked / "track.mcap", "/track/position")
    assert names == ["x", "y", "z"] and len(t) == valid.sum()
    np.testing.assert_allclose(xyz, track.array(["x", "y", "z"])[valid], atol=1e-5)
    assert "calibration.yaml" in mcap_attachments(tracked / "track.mcap")

    times, points = rrd_column(tracked / "track.rrd", "/stereo/left/overlay",
                               "Points2D:positions")
    assert len(times) == len(track.t) and len(points[0]) > 0
    # the sponge box drawn over the image: 12 edges around where the tracked centre projects
    _, edges = rrd_column(tracked / "track.rrd", "/stereo/left/overlay", "LineStrips2D:strips")
    first = int(np.flatnonzero(valid)[0])
    assert len(edges[first]) == 12
    corners = np.array(edges[first]).reshape(-1, 2)
    calibration = load_calibration(demo / "calibration.yaml")
    T_left_world = invert_transform(calibration.T_track_left)
    centre = calibration.left.project(T_left_world[:3, :3] @ xyz[0] + T_left_world[:3, 3]) + 0.5
    assert (corners.min(axis=0) < centre).all() and (centre < corners.max(axis=0)).all()
    manifest = json.loads((tracked / "manifest.json").read_text())
    assert manifest["stage"] == "track"
    assert set(manifest["inputs"]) == {"calibration", "left_video", "right_video"}


def test_track_is_deterministic(demo, tracked, tmp_path):
    result = CliRunner().invoke(cli, ["track", str(demo), "-o", str(tmp_path / "again"),
                                      "--particles", "80", "-q"])
    assert result.exit_code == 0, result.output
    for name in ("track.csv", "track.mcap", "track.rrd"):
        assert (tmp_path / "again" / name).read_bytes() == (tracked / name).read_bytes(), name


def _mpeg4_copy(demo, tmp_path):
    """The demo with its videos re-encoded as MPEG-4 part 2, which Rerun can't play."""
    copy = _copy(demo, tmp_path)
    for name in ("left.mp4", "right.mp4"):
        capture = cv2.VideoCapture(str(demo / name))
        writer = cv2.VideoWriter(str(copy / name), cv2.VideoWriter_fourcc(*"mp4v"), 30,
                                 (640, 480))
        while (frame := capture.read()[1]) is not None:
            writer.write(frame)
        writer.release()
    return copy


def test_any_opencv_readable_codec_is_tracked_and_logged_as_h264(demo, tmp_path):
    copy = _mpeg4_copy(demo, tmp_path)
    result = CliRunner().invoke(cli, ["track", str(copy), "-o", str(tmp_path / "out"), "-q"])
    assert result.exit_code == 0, result.output
    track = read_trajectory(tmp_path / "out" / "track.csv", required=("t", "x", "y", "z"))
    assert track.valid.sum() > 30
    topics = mcap_topics(tmp_path / "out" / "track.mcap")
    assert topics["/stereo/right/video"]["message_count"] == len(track.t)


def test_a_playable_video_is_logged_as_it_is_unless_it_is_heavy(demo, tmp_path, monkeypatch):
    """The synth demo's H.264 (no B-frames, a few hundred kbit/s) goes into the logs as it
    is; a video heavier than LOGGED_AS_IT_IS_MAX_BITRATE is logged as a preview: the logs of
    a high-quality demo would otherwise be as large as its videos, twice."""
    opened = open_demo(demo)
    light = LogVideos(opened, tmp_path)
    assert light.paths == [opened.left, opened.right] and light.scale == 1.0
    monkeypatch.setattr(track_stage, "LOGGED_AS_IT_IS_MAX_BITRATE", 1e4)
    heavy = LogVideos(opened, tmp_path)
    try:
        assert heavy.paths == [tmp_path / "left.mp4", tmp_path / "right.mp4"]
        assert heavy.size == (320, 240) and heavy.scale == 0.5   # 640x480, at most 480 wide
    finally:
        heavy.close()


def test_a_preview_that_cannot_be_encoded_fails_the_run(demo, tmp_path):
    videos = LogVideos(open_demo(_mpeg4_copy(demo, tmp_path)), tmp_path)
    frame = next(iter(open_demo(demo).reader))[0]
    videos.write(frame, frame)
    videos.write(frame / 255.0, frame / 255.0)   # not 8-bit: x264's input cannot be made
    with pytest.raises(cv2.error):
        for _ in range(20):   # the encoder's thread fails; a later frame or the end says so
            videos.write(frame, frame)
        videos.close()


def _copy(demo, tmp_path):
    copy = tmp_path / "copy"
    shutil.copytree(demo, copy)
    return copy


def _shorter_video(path, frames):
    capture = cv2.VideoCapture(str(path))
    images = [capture.read()[1] for _ in range(frames)]
    with H264Writer(path, 30, (640, 480)) as writer:
        for image in images:
            writer.write(image)


@pytest.mark.parametrize("breakage, options, message", [
    (lambda d: (d / "calibration.yaml").unlink(), [], r"calibration.yaml: file not found"),
    (lambda d: (d / "calibration.yaml").write_text(
        (d / "calibration.yaml").read_text().replace("K2:", "K3:")), [], "missing key K2"),
    (lambda d: (d / "left.mp4").write_bytes(b"garbage"), [], "left.mp4: cannot be decoded"),
    (lambda d: _shorter_video(d / "right.mp4", 10), [], "right.mp4: 10 frames but .*left.mp4 has 75"),
    (lambda d: None, ["--color", "blue"], "--color blue: this colour never shows"),
    (lambda d: None, ["--hsv", "20,100"], "--hsv: expected six integers"),
    (lambda d: None, ["--roi", "600,400,100,100"], "--roi: region .* does not fit"),
    (lambda d: None, ["--color", "yellow", "--hsv", "1,2,3,4,5,6"], "give only one of them"),
])
def test_bad_input_is_one_line_exit_2_and_nothing_written(demo, tmp_path, breakage, options,
                                                          message):
    broken = _copy(demo, tmp_path)
    breakage(broken)
    out = tmp_path / "out"
    result = CliRunner().invoke(cli, ["track", str(broken), "-o", str(out), "-q", *options])
    assert result.exit_code == 2
    lines = result.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ")
    assert __import__("re").search(message, lines[0]), lines[0]
    assert not out.exists()


def test_the_track_command_does_not_load_the_simulator_or_numba():
    """Importing the track command loads no compiled kernel: numba's import (~0.2 s) and
    kernel loading (~0.6 s) stay out of every run that needs none (no known sponge box, no
    still things of the sponge's colour)."""
    script = ("import sys, wipelab.cli, wipelab.stages.track, wipelab.vision.tracker\n"
              "print(sorted(m for m in ('pybullet', 'wipelab.sim.world', 'wipelab.learning',"
              " 'numba') if m in sys.modules))\n"
              "from wipelab.sim import SimWorld, build_task, load_surface\n"
              "print(SimWorld.__module__, build_task.__module__, load_surface.__module__)\n")
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split("\n")[:2] == [
        "[]", "wipelab.sim.world wipelab.sim.task wipelab.sim.surfaces"]
