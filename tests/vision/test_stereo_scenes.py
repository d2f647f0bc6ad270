"""The independent stereo test-scene generator (tests/stereo_scenes): its lens model against
OpenCV, the demo directories it writes (determinism, calibration, truth against the decoded
images, occlusions) and its video codecs."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from tests.stereo_scenes import __main__ as scenes_cli
from tests.stereo_scenes import plan_scene, render_scene
from tests.stereo_scenes.actors import grip
from tests.stereo_scenes.camera import Camera, Canvas, look_at
from tests.stereo_scenes.lens import distort, monotonic_radius, undistort
from tests.stereo_scenes.motion import RAMP_S, WipingMotion
from tests.stereo_scenes.plan import NAMED_HSV, Video
from tests.stereo_scenes.render import Scene
from tests.stereo_scenes.video import VideoFile
from wipelab.vision.calibration import load_calibration

REPO = Path(__file__).resolve().parents[2]
STRONG_BARREL = np.array([-0.45, 0.13, 0.0012, -0.0009, -0.012])
SMALL_SCENE = dict(seed=3, duration=3.5, small=True, codec="h264")


@pytest.fixture(scope="module")
def scene_dir(tmp_path_factory) -> Path:
    """A small rendered scene (H.264), shared by the tests that only read it."""
    return render_scene(tmp_path_factory.mktemp("scenes") / "scene", **SMALL_SCENE)


def read_truth(path: Path) -> dict[str, np.ndarray]:
    lines = path.read_text().splitlines()
    header = lines[0].split(",")
    values = np.array([[float(v) for v in line.split(",")] for line in lines[1:]])
    return {name: values[:, i] for i, name in enumerate(header)}


def decode(path: Path) -> list[np.ndarray]:
    capture = cv2.VideoCapture(str(path))
    frames = []
    while True:
        ok, frame = capture.read()
        if not ok:
            return frames
        frames.append(frame)


def test_projection_matches_opencv_with_strong_distortion():
    K = np.array([[560.0, 0, 655.0], [0, 561.0, 352.0], [0, 0, 1]])
    T_world_cam = look_at(np.array([-0.4, 0.3, 1.6]), np.array([0.6, 0.1, 0.8]), 0.05)
    camera = Camera(1280, 720, K, STRONG_BARREL, T_world_cam)
    rng = np.random.default_rng(0)
    # rays out to where the model stops being monotonic (the planner keeps images inside)
    reach = monotonic_radius(STRONG_BARREL) / 1.2
    radius, angle = reach * np.sqrt(rng.uniform(0, 1, 500)), rng.uniform(0, 2 * np.pi, 500)
    xy = np.column_stack([radius * np.cos(angle), radius * np.sin(angle)])
    depth = rng.uniform(0.3, 3.0, (500, 1))
    points = np.hstack([xy * depth, depth]) @ T_world_cam[:3, :3].T + T_world_cam[:3, 3]
    ours = camera.project(points)
    T = np.linalg.inv(T_world_cam)
    theirs, _ = cv2.projectPoints(points, cv2.Rodrigues(T[:3, :3])[0], T[:3, 3], K, STRONG_BARREL)
    assert np.abs(ours - theirs[:, 0, :]).max() < 0.05
    # the inverse model (used to build the resampling maps) undoes it
    assert np.abs(undistort(distort(xy, STRONG_BARREL), STRONG_BARREL) - xy).max() < 1e-9


def test_canvas_maps_send_each_pixel_through_the_lens():
    K = np.array([[300.0, 0, 162.0], [0, 300.0, 118.0], [0, 0, 1]])
    camera = Camera(320, 240, K, STRONG_BARREL, np.eye(4))
    canvas = Canvas(camera, 1.5)
    v, u = np.mgrid[0:240:7, 0:320:7]
    x = (canvas.map_x[v, u] - canvas.K[0, 2]) / canvas.K[0, 0]
    y = (canvas.map_y[v, u] - canvas.K[1, 2]) / canvas.K[1, 1]
    back = distort(np.stack([x, y], axis=-1), STRONG_BARREL) * [300.0, 300.0] + [162.0, 118.0]
    assert np.abs(back - np.stack([u, v], axis=-1)).max() < 0.01


def test_scene_directory_is_a_demo_directory(scene_dir):
    names = sorted(p.name for p in scene_dir.iterdir())
    assert names == ["calibration.yaml", "left.mp4", "right.mp4", "scene.json", "truth.csv"]
    truth = read_truth(scene_dir / "truth.csv")
    info = json.loads((scene_dir / "scene.json").read_text())
    assert list(truth) == ["t", "x", "y", "z", "yaw", "visible_left", "visible_right"]
    assert len(truth["t"]) == info["frame_count"] == round(3.5 * info["video"]["fps"])
    assert np.allclose(np.diff(truth["t"]), 1 / info["video"]["fps"], atol=2e-6)
    for name in ("left.mp4", "right.mp4"):
        capture = cv2.VideoCapture(str(scene_dir / name))
        assert capture.get(cv2.CAP_PROP_FPS) == pytest.approx(info["video"]["fps"])
        assert len(decode(scene_dir / name)) == info["frame_count"]
    # the sponge's bottom rests on the table
    half_height = info["sponge"]["height"] / 2
    assert np.all(truth["z"] >= info["table"]["height"] + half_height - 1e-6)
    assert np.all(truth["z"] < info["table"]["height"] + half_height + 0.004)


def test_same_seed_gives_identical_files(scene_dir, tmp_path):
    """Also across processes: the CLI in a fresh interpreter writes the same bytes."""
    again = tmp_path / "again"
    subprocess.run([sys.executable, "-m", "tests.stereo_scenes", str(again), "--seed", "3",
                    "--duration", "3.5", "--small", "--set", "codec=h264"], check=True,
                   cwd=REPO, capture_output=True)
    for name in ("truth.csv", "scene.json", "calibration.yaml", "left.mp4", "right.mp4"):
        assert (again / name).read_bytes() == (scene_dir / name).read_bytes(), name


def test_calibration_loads_with_wipelab_and_matches_the_cameras(scene_dir):
    info = json.loads((scene_dir / "scene.json").read_text())
    calibration = load_calibration(scene_dir / "calibration.yaml")
    cams = info["cameras"]
    assert calibration.image_size == (cams["width"], cams["height"])
    T_right_left = np.linalg.inv(cams["T_world_right"]) @ np.array(cams["T_world_left"])
    assert np.allclose(calibration.R, T_right_left[:3, :3], atol=1e-8)
    assert np.allclose(calibration.T, T_right_left[:3, 3], atol=1e-8)
    assert calibration.baseline == pytest.approx(cams["baseline"], rel=1e-8)
    if info["write_T_world_left"]:
        assert np.allclose(calibration.T_world_left, cams["T_world_left"])
    else:
        assert calibration.T_world_left is None


def _sponge_or_hand(patch_bgr: np.ndarray, colour: str, skin_bgr) -> bool:
    hsv = cv2.cvtColor(patch_bgr, cv2.COLOR_BGR2HSV).reshape(-1, 3).astype(int)
    (h0, s0, v0), (h1, _, _) = NAMED_HSV[colour]
    hue = hsv[:, 0]
    in_hue = (hue >= h0) & (hue <= h1) if h0 <= h1 else (hue >= h0) | (hue <= h1)
    sponge = in_hue & (hsv[:, 1] >= s0 - 20) & (hsv[:, 2] >= v0 - 30)
    skin_hsv = cv2.cvtColor(np.uint8([[skin_bgr]]), cv2.COLOR_BGR2HSV)[0, 0].astype(int)
    hue_gap = np.minimum(np.abs(hue - skin_hsv[0]), 180 - np.abs(hue - skin_hsv[0]))
    hand = (hue_gap <= 8) & (np.abs(hsv[:, 1] - skin_hsv[1]) <= 70)
    return bool(np.any(sponge | hand))


@pytest.mark.parametrize("seed", [3, 11])
def test_truth_centre_lands_on_the_sponge_or_the_hand(seed, scene_dir, tmp_path):
    path = scene_dir if seed == 3 else render_scene(tmp_path / "s", seed, 3.0, small=True)
    info = json.loads((path / "scene.json").read_text())
    truth = read_truth(path / "truth.csv")
    calibration = load_calibration(path / "calibration.yaml")
    T_left_world = np.linalg.inv(info["cameras"]["T_world_left"])
    centres = np.column_stack([truth["x"], truth["y"], truth["z"]])
    left_points = centres @ T_left_world[:3, :3].T + T_left_world[:3, 3]
    visible = np.minimum(truth["visible_left"], truth["visible_right"]) == 1.0
    assert visible.mean() > 0.5
    for camera, name in ((calibration.left, "left.mp4"), (calibration.right, "right.mp4")):
        pixels = camera.project(left_points)
        frames = decode(path / name)
        misses = []
        for k in np.nonzero(visible)[0]:
            u, v = np.round(pixels[k]).astype(int)
            patch = frames[k][max(v - 2, 0):v + 3, max(u - 2, 0):u + 3]
            if not _sponge_or_hand(patch, info["sponge"]["colour"], info["person"]["skin_bgr"]):
                misses.append(k)
        assert not misses, f"{name}: frames {misses} show neither sponge nor hand at the truth"


def test_full_occlusions_hide_the_sponge_in_both_cameras(scene_dir):
    info = json.loads((scene_dir / "scene.json").read_text())
    truth = read_truth(scene_dir / "truth.csv")
    full = [o for o in info["occlusions"] if o["kind"] == "full"]
    assert full, "every scene has a full occlusion"
    for event in full:
        hidden = (truth["t"] >= event["covered_from"]) & (truth["t"] <= event["covered_to"])
        assert hidden.sum() >= 0.5 * info["video"]["fps"] - 1
        assert np.all(truth["visible_left"][hidden] == 0.0)
        assert np.all(truth["visible_right"][hidden] == 0.0)
        before = truth["t"] < event["start"]
        assert np.all(truth["visible_left"][before] == 1.0)
    inside = (truth["visible_left"] > 0) & (truth["visible_left"] < 1)
    assert inside.any(), "the arm covers the sponge partly while it comes in and goes out"


@pytest.mark.parametrize("codec,writer", [("h264", "pyav"), ("mp4v", "opencv"), ("mp4v", "pyav"),
                                          ("mjpg", "opencv"), ("mjpg", "pyav")])
def test_every_codec_is_deterministic_and_read_back_by_opencv(codec, writer, tmp_path):
    video = Video(codec, writer, 25, 23 if codec == "h264" else None,
                  2 if codec == "h264" else None, "veryfast" if codec == "h264" else None,
                  0.6 if writer == "pyav" and codec != "h264" else None)
    rng = np.random.default_rng(1)
    frames = [cv2.GaussianBlur(rng.integers(0, 255, (120, 160, 3), dtype=np.uint8), (0, 0), 3)
              for _ in range(12)]
    for name in ("v.mp4", "again.mp4"):
        with VideoFile(tmp_path / name, video, 160, 120) as out:
            for frame in frames:
                out.write(frame)
    if codec != "h264":  # libx264's bytes depend on what the process encoded before; the
        # scene test above checks H.264 across fresh processes instead
        assert (tmp_path / "v.mp4").read_bytes() == (tmp_path / "again.mp4").read_bytes()
    capture = cv2.VideoCapture(str(tmp_path / "v.mp4"))
    assert int(capture.get(cv2.CAP_PROP_FRAME_COUNT)) == 12
    assert capture.get(cv2.CAP_PROP_FPS) == pytest.approx(25)
    decoded = decode(tmp_path / "v.mp4")
    assert len(decoded) == 12
    error = np.mean([np.abs(a.astype(int) - b).mean() for a, b in zip(decoded, frames)])
    assert error < 12


def test_overrides_set_factors_and_unknown_ones_are_refused():
    plan = plan_scene(1234, small=True, pattern="figure8", frequency_hz=1.5, colour="blue")
    assert (plan.motion.pattern, plan.motion.frequency_hz, plan.sponge.colour) == \
        ("figure8", 1.5, "blue")
    other = plan_scene(1234, small=True)
    assert plan.cameras == other.cameras or plan.motion.pattern != other.motion.pattern
    assert plan.table.height == other.table.height
    with pytest.raises(ValueError, match="unknown scene override"):
        plan_scene(1, small=True, colour_of_the_sky="blue")


def test_cli_refuses_an_existing_directory(tmp_path, capsys):
    assert scenes_cli.main([str(tmp_path), "--seed", "1", "--small"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and "already exists" in err and err.count("\n") == 1


@pytest.mark.parametrize("pattern", ["circle", "line", "figure8", "ellipse"])
def test_motion_keeps_the_nominal_frequency_and_the_sponge_on_the_table(pattern):
    motion = WipingMotion(pattern, 1.1, 0.3, 0.6, (0.7, 0.1), 0.4, 0.8, np.array([0.05, 0.03, 0.02]),
                          0.2, 0.5, 40.0, np.random.default_rng(5))
    start = 0.5 + RAMP_S
    t = np.arange(start, 40.0, 0.01)
    rate = np.gradient(motion.phase(t), t) / (2 * np.pi)
    assert (motion.phase(40.0) - motion.phase(start)) / (2 * np.pi) / (40.0 - start) == \
        pytest.approx(1.1, rel=1e-3)
    assert 0.0 < np.abs(rate / 1.1 - 1).max() < 0.07        # the tempo wanders, about +-5 %
    assert np.ptp(motion.phase(np.arange(0.0, 0.5, 0.01))) == 0.0   # still at the start
    centre, R, _ = motion.pose(t[::10])
    lowest = centre[:, 2] - np.einsum("nij,j->n", np.abs(R[:, 2:3, :]), [0.05, 0.03, 0.02])
    assert np.allclose(lowest, 0.8, atol=1e-12)               # the bottom touches the table
    along = (centre[:, :2] - [0.7, 0.1]) @ [np.cos(0.4), np.sin(0.4)]
    assert 0.25 < np.ptp(along) < 0.36                        # 0.3 m across, with drift


def test_the_hand_keeps_its_grip_on_the_sponge_all_demonstration():
    # scene 47 wipes a wide figure-8: "away from the shoulder" points along the sponge's
    # length in some poses and across it in others; a person does not change grip for that
    plan = plan_scene(47, duration=30.0)
    scene = Scene(plan)
    states = [scene.state(t) for t in np.linspace(0.0, 30.0, 121)]
    per_pose = {tuple(grip(plan.person, [(s.centre, s.R)], plan.table.height)) for s in states}
    assert len(per_pose) > 1
    palm = np.array([s.R.T @ (s.hand.palm.centre - s.centre) for s in states])  # sponge frame
    assert np.ptp(palm, axis=0).max() < 1e-9
    assert np.linalg.norm(palm[0, :2]) > 0.01  # on the rear part of the top face, not the middle
