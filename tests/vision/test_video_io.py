import cv2
import numpy as np
import pytest

import wipelab.vision.video_io as video_io
from wipelab.errors import InputError
from wipelab.vision.video_io import H264Writer, StereoVideoReader, probe_video


def _video(path, frames, fps=30, size=(64, 48)):
    with H264Writer(path, fps, size) as writer:
        for k in range(frames):
            writer.write(np.full((size[1], size[0], 3), (k * 20) % 240, np.uint8))


def test_pair_is_read_frame_by_frame(tmp_path):
    _video(tmp_path / "l.mp4", 12)
    _video(tmp_path / "r.mp4", 12)
    reader = StereoVideoReader(tmp_path / "l.mp4", tmp_path / "r.mp4", (64, 48))
    frames = list(reader)
    assert reader.frame_count == 12 and reader.fps == 30 and len(frames) == 12
    grey = [int(left[24, 32, 0]) for left, _ in frames]
    assert np.all(np.diff(grey) > 10)  # in order, none skipped or repeated


@pytest.mark.parametrize("right_frames, right_fps, size, message", [
    (10, 30, None, "10 frames but .*l.mp4 has 12"),
    (12, 25, None, "25 fps but .*l.mp4 has 30 fps"),
    (12, 30, (640, 480), "frames are 64x48, the calibration is for 640x480"),
])
def test_mismatched_pair_is_refused(tmp_path, right_frames, right_fps, size, message):
    _video(tmp_path / "l.mp4", 12)
    _video(tmp_path / "r.mp4", right_frames, fps=right_fps)
    with pytest.raises(InputError, match=message):
        StereoVideoReader(tmp_path / "l.mp4", tmp_path / "r.mp4", size)


def test_unreadable_missing_and_truncated_files(tmp_path):
    (tmp_path / "text.mp4").write_text("not a video")
    with pytest.raises(InputError, match="text.mp4: cannot be decoded by OpenCV"):
        probe_video(tmp_path / "text.mp4")
    with pytest.raises(InputError, match="none.mp4: file not found"):
        probe_video(tmp_path / "none.mp4")
    _video(tmp_path / "l.mp4", 60, size=(320, 240))
    data = (tmp_path / "l.mp4").read_bytes()
    # keep the header (moov at the end is lost with the tail): a file cut short
    (tmp_path / "cut.mp4").write_bytes(data[: len(data) // 2])
    with pytest.raises(InputError, match="cut.mp4"):
        probe_video(tmp_path / "cut.mp4")


def test_a_decoder_that_fails_midway_is_one_clear_error_not_a_hang(tmp_path, monkeypatch):
    """FFmpeg raising inside a decoding thread (injected after 5 real frames of the right
    file) reaches the reader as an InputError naming the file and frame; before, the reader
    waited for that thread's next frame forever."""
    _video(tmp_path / "l.mp4", 12)
    _video(tmp_path / "r.mp4", 12)
    reader = StereoVideoReader(tmp_path / "l.mp4", tmp_path / "r.mp4")

    class FailingCapture:
        def __init__(self, path, *args):
            self.capture = cv2.VideoCapture(path, *args)
            self.frames, self.fails = 0, "r.mp4" in path

        def read(self):
            self.frames += 1
            if self.fails and self.frames > 5:
                raise cv2.error("injected decoder failure")
            return self.capture.read()

        def release(self):
            self.capture.release()

    class Cv2WithFailingCapture:
        VideoCapture = FailingCapture

        def __getattr__(self, name):
            return getattr(cv2, name)

    monkeypatch.setattr(video_io, "cv2", Cv2WithFailingCapture())
    with pytest.raises(InputError, match=r"r\.mp4: cannot be decoded at frame 5 of 12: .*injected"):
        for _ in reader:
            pass
