"""Opening a live session's source: a demo directory, or two cameras and their calibration.

Everything is checked before the session starts (InputError naming the file or option): the
demo directory as ``track`` checks it; each camera (an OpenCV device index, a stream URL or
a video file) opens and delivers frames of the calibration's size, and its frame rate is
known (reported, or ``--fps``). Video files given as cameras are played at their frame rate
at ``--speed 1`` (as cameras would deliver them) and may run at ``--speed max``; devices and
streams deliver at their own rate (``--speed 1`` only).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from wipelab.errors import InputError
from wipelab.input_files import check_readable
from wipelab.live.frames import FrameFeed
from wipelab.stages.track import open_demo
from wipelab.vision.calibration import StereoCalibration, load_calibration


@dataclass(frozen=True)
class LiveSource:
    """Where the frames come from: a demo directory, or two cameras (OpenCV device indices,
    stream URLs or video files) with their calibration file."""

    demo: Path | None = None
    cameras: tuple[str, str] | None = None
    calibration: Path | None = None

    def describe(self) -> str:
        return str(self.demo) if self.demo is not None else ",".join(self.cameras)


@dataclass
class OpenedSource:
    """A checked source: the frame feed (not started), the calibration and its file, the
    demo's metadata, the input files for the manifest."""

    feed: FrameFeed
    calibration: StereoCalibration
    calibration_path: Path
    metadata: dict
    inputs: dict


def open_source(source: LiveSource, realtime: bool, fps: float | None = None) -> OpenedSource:
    """Check the source and open it (the feed is not started yet); InputError naming what
    is wrong. ``realtime``: ``--speed 1``; ``fps``: of cameras that do not report theirs."""
    if source.demo is not None:
        demo = open_demo(source.demo)
        return OpenedSource(demo_feed(demo.reader, realtime), demo.calibration,
                            demo.calibration_path, demo.metadata,
                            {"left_video": demo.left, "right_video": demo.right,
                             "calibration": demo.calibration_path})
    calibration = load_calibration(source.calibration)
    if not realtime and any(is_stream(spec) for spec in source.cameras):
        raise InputError("--speed: max needs video files (a camera delivers frames at its "
                         "own rate); use --speed 1")
    captures, rate, files = _open_cameras(source.cameras, calibration.image_size, fps)
    feed = FrameFeed(lambda: camera_pairs(captures), rate, realtime, paced=realtime and files,
                     close=lambda: [capture.release() for capture in captures])
    inputs = {"calibration": source.calibration}
    if files:
        inputs |= {"left_video": Path(source.cameras[0]), "right_video": Path(source.cameras[1])}
    return OpenedSource(feed, calibration, source.calibration, {}, inputs)


def _open_cameras(specs, size: tuple[int, int], fps: float | None
                  ) -> tuple[list[cv2.VideoCapture], float, bool]:
    """The two captures (released again on an error), their frame rate (``fps`` or the
    left one's) and whether both are video files."""
    opened = []
    try:
        for spec in specs:
            opened.append(open_capture(spec, size))
        rate = fps or max(opened[0][1], 0.0)
        if not rate > 0:
            raise InputError(f"--camera: {specs[0]}: the camera does not report its frame "
                             "rate; give it with --fps")
    except BaseException:
        for capture, _, _ in opened:
            capture.release()
        raise
    return [capture for capture, _, _ in opened], rate, all(f for _, _, f in opened)


def demo_feed(reader, realtime: bool) -> FrameFeed:
    """The pairs of a demo directory's videos (a :class:`~wipelab.vision.video_io.
    StereoVideoReader`), at their frame rate when ``realtime``."""
    return FrameFeed(lambda: iter(reader), reader.fps, realtime, paced=realtime)


def is_stream(spec: str) -> bool:
    """Whether a ``--camera`` entry names a device or a stream (an OpenCV device index, a
    URL) rather than a video file."""
    return spec.isdigit() or "://" in spec


def open_capture(spec: str, expected_size: tuple[int, int]):
    """An OpenCV capture of one ``--camera`` entry, checked: it opens and delivers frames of
    the calibration's size (InputError otherwise). Returns (capture, fps, is_file)."""
    stream = is_stream(spec)
    if not stream:
        check_readable(spec)
    capture = cv2.VideoCapture(int(spec)) if spec.isdigit() else \
        cv2.VideoCapture(spec, cv2.CAP_FFMPEG)
    if not capture.isOpened():
        raise InputError(f"--camera: {spec}: cannot be opened by OpenCV")
    width = int(capture.get(cv2.CAP_PROP_FRAME_WIDTH))
    height = int(capture.get(cv2.CAP_PROP_FRAME_HEIGHT))
    if (width, height) != tuple(expected_size):
        capture.release()
        raise InputError(f"--camera: {spec}: frames are {width}x{height}, the calibration is "
                         f"for {expected_size[0]}x{expected_size[1]}")
    fps = float(capture.get(cv2.CAP_PROP_FPS))
    return capture, fps, not stream


def camera_pairs(captures) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """Pairs from two OpenCV captures: both grabbed first (as close in time as the devices
    allow), then decoded; ends when either ends."""
    while True:
        grabbed = [capture.grab() for capture in captures]
        if not all(grabbed):
            return
        frames = [capture.retrieve()[1] for capture in captures]
        if any(frame is None for frame in frames):
            return
        yield frames[0], frames[1]
