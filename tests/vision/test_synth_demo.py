import tomllib

import av
import cv2
import numpy as np

from wipelab.stages.synth import SynthParams, synth
from wipelab.vision.calibration import load_calibration
from wipelab.vision.synthetic_rig import armar_wide_stereo_calibration
from wipelab.vision.video_io import StereoVideoReader


def test_demo_directory_reads_back_with_opencv(short_demo, short_truth):
    names = sorted(p.name for p in short_demo.iterdir())
    assert names == ["calibration.yaml", "demo.toml", "left.mp4", "manifest.json", "right.mp4",
                     "truth.csv"]
    t, centre, visible = short_truth
    for name in ("left.mp4", "right.mp4"):
        capture = cv2.VideoCapture(str(short_demo / name))
        assert capture.get(cv2.CAP_PROP_FPS) == 30
        assert int(capture.get(cv2.CAP_PROP_FRAME_COUNT)) == len(t) == 105
        ok, frame = capture.read()
        assert ok and frame.shape == (480, 640, 3)
        with av.open(str(short_demo / name)) as container:  # what the Rerun viewer can play
            context = container.streams.video[0].codec_context
            assert context.name == "h264" and not context.has_b_frames
    np.testing.assert_allclose(t, np.arange(105) / 30, atol=1e-6)
    metadata = tomllib.loads((short_demo / "demo.toml").read_text())
    assert metadata["sponge_colour"] == "yellow" and metadata["fps"] == 30
    calibration = load_calibration(short_demo / "calibration.yaml")
    np.testing.assert_allclose(calibration.K1, armar_wide_stereo_calibration().K1)


def test_truth_is_a_sponge_on_the_table_with_one_full_occlusion(short_demo, short_truth):
    t, centre, visible = short_truth
    calibration = load_calibration(short_demo / "calibration.yaml")
    distance = np.linalg.norm(centre - calibration.T_world_left[:3, 3], axis=1)
    assert 0.5 < distance.min() and distance.max() < 0.8  # the table is 0.5-0.8 m away
    assert np.ptp(centre[:, 2]) < 0.002  # the sponge slides on the table
    speed = np.linalg.norm(np.diff(centre, axis=0), axis=1) * 30
    assert speed.max() > 0.3  # it moves
    hidden = np.flatnonzero(visible == 0)
    assert len(hidden) >= 10 and np.all(np.diff(hidden) == 1)  # one stretch, >= 1/3 s
    passes = tomllib.loads((short_demo / "demo.toml").read_text())["synth"]["free_hand_passes"]
    assert len(passes) == 1
    t_in, t_out = passes[0]
    assert t_in < t[hidden[0]] and t[hidden[-1]] < t_out
    assert np.all(visible[(t < t_in) | (t > t_out)] == 1)


def test_images_show_the_sponge_where_truth_says(short_demo, short_truth):
    t, centre, visible = short_truth
    calibration = load_calibration(short_demo / "calibration.yaml")
    reader = StereoVideoReader(short_demo / "left.mp4", short_demo / "right.mp4")
    for k, (left, right) in enumerate(reader):
        if k % 20 or visible[k] < 1:
            continue
        for camera, frame in ((calibration.left, left), (calibration.right, right)):
            world_from_camera = calibration.T_world_left
            point = np.linalg.inv(world_from_camera) @ np.append(centre[k], 1.0)
            if camera is calibration.right:
                point = camera.T_cam_ref @ point
                u, v = cv2.projectPoints(point[:3], np.zeros(3), np.zeros(3), camera.K,
                                         camera.D)[0].ravel()
            else:
                u, v = camera.project(point[:3][None])[0]
            # below the sponge centre's image: the sponge's front face, yellow-olive
            b, g, r = frame[int(round(v)) + 6, int(round(u))].astype(int)
            assert r > b + 40 and g > b + 30, (k, b, g, r)


def test_same_seed_same_bytes_other_seed_other_motion(tmp_path):
    params = SynthParams(pattern="figure8", frequency_hz=1.0, duration=1.0, seed=3)
    synth(tmp_path / "a", params, quiet=True)
    synth(tmp_path / "b", params, quiet=True)
    for name in ("left.mp4", "right.mp4", "truth.csv", "calibration.yaml", "demo.toml"):
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes(), name
    synth(tmp_path / "c", SynthParams(pattern="figure8", frequency_hz=1.0, duration=1.0, seed=4),
          quiet=True)
    assert (tmp_path / "a" / "truth.csv").read_bytes() != (tmp_path / "c" / "truth.csv").read_bytes()


def test_a_tempo_step_changes_the_phase_rate_and_keeps_the_phase_continuous():
    from wipelab.vision.wiping_motion import WipingMotion, WipingMotionParams

    steady = WipingMotion(WipingMotionParams("circle", 1.0), 0.8, 0.03, seed=2)
    stepped = WipingMotion(WipingMotionParams("circle", 1.0, tempo_step=(5.0, 1.3)), 0.8, 0.03,
                           seed=2)
    t = np.arange(0.0, 10.0, 0.01)
    before, after = t < 5.0, t > 5.0
    np.testing.assert_array_equal(stepped.phase(t[before]), steady.phase(t[before]))
    rate = np.diff(stepped.phase(t)) / 0.01 / (2 * np.pi)
    steady_rate = np.diff(steady.phase(t)) / 0.01 / (2 * np.pi)
    np.testing.assert_allclose(rate[after[1:]] - steady_rate[after[1:]], 0.3, atol=1e-6)
    assert np.max(np.abs(np.diff(stepped.phase(t)))) < 2 * np.pi * 1.5 * 0.01
