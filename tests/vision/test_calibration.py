import cv2
import numpy as np
import pytest

from wipelab.errors import InputError
from wipelab.vision.calibration import load_calibration, save_calibration
from wipelab.vision.synthetic_rig import armar_wide_stereo_calibration


def _write(path, **entries):
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_WRITE)
    for key, value in entries.items():
        fs.write(key, value)
    fs.release()


def _valid_entries():
    calibration = armar_wide_stereo_calibration()
    return dict(image_width=640, image_height=480, K1=calibration.K1,
                D1=calibration.D1.reshape(1, -1), K2=calibration.K2,
                D2=calibration.D2.reshape(1, -1), R=calibration.R,
                T=calibration.T.reshape(3, 1))


def test_round_trip_keeps_every_number(tmp_path):
    calibration = armar_wide_stereo_calibration()
    save_calibration(tmp_path / "c.yaml", calibration)
    loaded = load_calibration(tmp_path / "c.yaml")
    assert loaded.image_size == (640, 480)
    for name in ("K1", "D1", "K2", "D2", "R", "T", "T_world_left"):
        np.testing.assert_allclose(getattr(loaded, name), getattr(calibration, name), atol=1e-12)
    assert loaded.track_frame == "world"
    assert loaded.baseline == pytest.approx(0.09)


def test_without_world_pose_tracks_in_the_left_camera_frame(tmp_path):
    _write(tmp_path / "c.yaml", **_valid_entries())
    loaded = load_calibration(tmp_path / "c.yaml")
    assert loaded.T_world_left is None and loaded.track_frame == "left_optical"


def test_rodrigues_vector_is_accepted_for_R(tmp_path):
    entries = _valid_entries()
    entries["R"] = cv2.Rodrigues(entries["R"])[0]
    _write(tmp_path / "c.yaml", **entries)
    np.testing.assert_allclose(load_calibration(tmp_path / "c.yaml").R, _valid_entries()["R"],
                               atol=1e-9)


@pytest.mark.parametrize("change, message", [
    (lambda e: e.pop("K2"), "missing key K2"),
    (lambda e: e.pop("image_width"), "missing key image_width"),
    (lambda e: e.update(K1=np.eye(3, 4)), "K1 must be a 3x3 matrix, got 3x4"),
    (lambda e: e.update(D2=np.zeros((1, 6))), "D2 must be a 1xN or Nx1 vector"),
    (lambda e: e.update(R=np.diag([1.0, 1.0, 2.0])), "R is not a rotation matrix"),
    (lambda e: e.update(T=np.zeros((3, 1))), "T is zero"),
    (lambda e: e.update(T=np.zeros((2, 2))), "T must be a 3x1 vector, got 2x2"),
    (lambda e: e.update(T_world_left=np.eye(3)), "T_world_left must be a 4x4 matrix, got 3x3"),
    (lambda e: e.update(image_height=-4), "image_height must be a positive integer"),
    (lambda e: e.update(K1=np.array([[500.0, 0, 320], [0, 0, 240], [0, 0, 1]])),
     "K1 is not a camera matrix"),
])
def test_bad_calibration_raises_one_clear_error(tmp_path, change, message):
    entries = _valid_entries()
    change(entries)
    _write(tmp_path / "c.yaml", **entries)
    with pytest.raises(InputError, match=message) as error:
        load_calibration(tmp_path / "c.yaml")
    assert str(error.value).startswith(str(tmp_path / "c.yaml"))
    assert "\n" not in str(error.value)


def test_missing_or_foreign_file(tmp_path):
    with pytest.raises(InputError, match="file not found"):
        load_calibration(tmp_path / "none.yaml")
    (tmp_path / "c.yaml").write_text("this is not: [valid\n")
    with pytest.raises(InputError, match="not an OpenCV FileStorage file"):
        load_calibration(tmp_path / "c.yaml")
