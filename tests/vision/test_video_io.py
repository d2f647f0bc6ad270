import cv2
import numpy as np
import pytest

import wipelab.vision.video_io as video_io
from wipelab.errors import InputError
from wipelab.vision.video_io import H264Writer, ReplayedStart, StereoVideoReader, probe_video


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


def _with_capture(monkeypatch, capture) -> None:
    """The reader's decoders open files with ``capture`` instead of cv2.VideoCapture."""

    class Cv2WithCapture:
        VideoCapture = staticmethod(capture)

        def __getattr__(self, name):
            return getattr(cv2, name)

    monkeypatch.setattr(video_io, "cv2", Cv2WithCapture())


def _counting_decodes(monkeypatch) -> list:
    """Record each file opened for decoding from now on."""
    opened, capture = [], cv2.VideoCapture

    def counted(path, *args):
        opened.append(path)
        return capture(path, *args)

    _with_capture(monkeypatch, counted)
    return opened


def test_a_pass_after_a_short_one_replays_its_frames_and_goes_on_decoding(tmp_path,
                                                                          monkeypatch):
    """The warm-up reads 5 of 12 pairs; the next pass from the start gets those 5 from
    memory (the same arrays) and the other 7 from the same decoding: each file is decoded
    once, and the 12 pairs are a fresh decoding's."""
    _video(tmp_path / "l.mp4", 12)
    _video(tmp_path / "r.mp4", 12)
    fresh = list(StereoVideoReader(tmp_path / "l.mp4", tmp_path / "r.mp4"))
    reader = StereoVideoReader(tmp_path / "l.mp4", tmp_path / "r.mp4")
    opened = _counting_decodes(monkeypatch)
    replayed = ReplayedStart(reader, budget=10**9)
    warmup = []
    for k, pair in enumerate(replayed):
        warmup.append(pair)
        if k == 4:
            break
    again = list(replayed.frames(keep=False))
    replayed.close()
    assert len(opened) == 2  # one decoder per file, for both passes
    assert len(again) == 12 and all(a[0] is w[0] and a[1] is w[1] for a, w in zip(again, warmup))
    assert all(np.array_equal(a[0], f[0]) and np.array_equal(a[1], f[1])
               for a, f in zip(again, fresh))


def test_a_last_pass_left_midway_leaves_the_next_pass_whole(tmp_path, monkeypatch):
    """The last pass lets go of what it replays; left after 2 pairs (an error in the
    tracker, say), a pass after it decodes from the start and gives all 12 pairs."""
    _video(tmp_path / "l.mp4", 12)
    _video(tmp_path / "r.mp4", 12)
    reader = StereoVideoReader(tmp_path / "l.mp4", tmp_path / "r.mp4")
    opened = _counting_decodes(monkeypatch)
    replayed = ReplayedStart(reader, budget=10**9)
    for k, _ in enumerate(replayed):
        if k == 4:
            break
    for k, _ in enumerate(replayed.frames(keep=False)):
        if k == 1:
            break
    grey = [int(left[24, 32, 0]) for left, _ in replayed]
    replayed.close()
    assert len(grey) == 12 and np.all(np.diff(grey) > 10)
    assert len(opened) == 4


@pytest.mark.parametrize("budget_pairs", [0, 3])
def test_a_pass_beyond_the_budget_makes_the_next_decode_from_the_start(tmp_path, monkeypatch,
                                                                       budget_pairs):
    """Frames beyond the budget are not kept: the next pass decodes the video again from its
    first frame, and still gives every pair once, in order."""
    _video(tmp_path / "l.mp4", 12)
    _video(tmp_path / "r.mp4", 12)
    reader = StereoVideoReader(tmp_path / "l.mp4", tmp_path / "r.mp4")
    opened = _counting_decodes(monkeypatch)
    replayed = ReplayedStart(reader, budget=budget_pairs * 2 * 64 * 48 * 3)
    first = [int(left[24, 32, 0]) for left, _ in replayed]  # 12 > budget_pairs
    second = [int(left[24, 32, 0]) for left, _ in replayed.frames(keep=False)]
    third = [int(left[24, 32, 0]) for left, _ in replayed]  # after a pass that kept nothing
    replayed.close()
    assert first == second == third and len(first) == 12 and np.all(np.diff(first) > 10)
    assert len(opened) == 6


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

    _with_capture(monkeypatch, FailingCapture)
    with pytest.raises(InputError, match=r"r\.mp4: cannot be decoded at frame 5 of 12: .*injected"):
        for _ in reader:
            pass
