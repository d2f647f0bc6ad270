"""Video files: read a synchronised stereo pair with OpenCV, write H.264 with PyAV.

H.264 without B-frames (``bf=0``) is what the Rerun viewer plays from an ``AssetVideo``;
libx264 output is deterministic, so the same frames give the same bytes.
"""

from __future__ import annotations

import atexit
import os
import queue
import threading
from collections.abc import Iterator
from dataclasses import dataclass
from fractions import Fraction

import av
import cv2
import numpy as np

from wipelab.errors import InputError, interrupts_deferred
from wipelab.input_files import check_readable
from wipelab.thread_priority import run_as_helper


@dataclass(frozen=True)
class VideoInfo:
    """What a video file holds, as OpenCV reports it."""

    path: str
    frame_count: int
    fps: float
    width: int
    height: int


def probe_video(path: str | os.PathLike) -> VideoInfo:
    """Open a video with OpenCV and read its header and first frame.

    Raises
    ------
    InputError
        Missing file, a file OpenCV cannot decode, no frames, or no frame rate.
    """
    name = str(check_readable(path))
    capture = cv2.VideoCapture(name, cv2.CAP_FFMPEG)
    try:
        if not capture.isOpened():
            raise InputError(f"{name}: cannot be decoded by OpenCV (not a video file?)")
        ok, frame = capture.read()
        if not ok or frame is None:
            raise InputError(f"{name}: no decodable frame")
        count = int(round(capture.get(cv2.CAP_PROP_FRAME_COUNT)))
        fps = float(capture.get(cv2.CAP_PROP_FPS))
    finally:
        capture.release()
    if count <= 0:
        raise InputError(f"{name}: the container does not tell its frame count")
    if not np.isfinite(fps) or fps <= 0:
        raise InputError(f"{name}: the container does not tell its frame rate")
    return VideoInfo(name, count, fps, frame.shape[1], frame.shape[0])


def _decode(path: str, out: queue.Queue, stop: threading.Event) -> None:
    # one FFmpeg thread per file: the two files already decode in parallel, and FFmpeg's
    # own frame threads would only add synchronisation (about a quarter more CPU time)
    # a decoder that fails hands its error over: the reader must not wait for it forever
    run_as_helper()  # the thread that uses the frames comes first
    capture = cv2.VideoCapture(path, cv2.CAP_FFMPEG, [cv2.CAP_PROP_N_THREADS, 1])
    try:
        while not stop.is_set():
            ok, frame = capture.read()
            out.put(frame if ok else None)
            if not ok:
                return
    except Exception as error:  # noqa: BLE001 - any failure ends this file's frames
        out.put(error)
    finally:
        capture.release()


class StereoVideoReader:
    """Decode a left/right pair frame by frame, each file on its own thread.

    Checks up front that both files open, hold the same number of frames at the same frame
    rate and image size (``expected_size`` when given, e.g. the calibration's); while
    iterating, a file that ends early (truncated) raises InputError.

    Parameters
    ----------
    left, right : path-like
    expected_size : tuple of int or None
        (width, height) both videos must have.
    """

    def __init__(self, left: str | os.PathLike, right: str | os.PathLike,
                 expected_size: tuple[int, int] | None = None, prefetch: int = 8):
        self.left = probe_video(left)
        self.right = probe_video(right)
        if self.left.frame_count != self.right.frame_count:
            raise InputError(f"{self.right.path}: {self.right.frame_count} frames but "
                             f"{self.left.path} has {self.left.frame_count}")
        if abs(self.left.fps - self.right.fps) > 1e-3 * self.left.fps:
            raise InputError(f"{self.right.path}: {self.right.fps:g} fps but "
                             f"{self.left.path} has {self.left.fps:g} fps")
        for info in (self.left, self.right):
            if expected_size is not None and (info.width, info.height) != tuple(expected_size):
                raise InputError(f"{info.path}: frames are {info.width}x{info.height}, the "
                                 f"calibration is for {expected_size[0]}x{expected_size[1]}")
        self.prefetch = prefetch

    @property
    def frame_count(self) -> int:
        return self.left.frame_count

    @property
    def fps(self) -> float:
        return self.left.fps

    def __iter__(self) -> Iterator[tuple[np.ndarray, np.ndarray]]:
        """Yield (left, right) BGR uint8 frames, shape (h, w, 3) each, read-only (whoever
        gets them may hand them on, e.g. to a thread encoding them, while others use them).

        The decoders stop when the iteration ends, fails or is interrupted, and at the
        latest when the program exits (a decoder thread still inside FFmpeg then would
        abort the process).
        """
        decoders = _Decoders((self.left.path, self.right.path), self.prefetch)
        try:
            decoders.start()
            for index in range(self.frame_count):
                frames = [q.get() for q in decoders.queues]
                for frame, info in zip(frames, (self.left, self.right)):
                    if frame is None:
                        raise InputError(f"{info.path}: truncated, decoding stopped at frame "
                                         f"{index} of {info.frame_count}")
                    if isinstance(frame, Exception):
                        raise InputError(f"{info.path}: cannot be decoded at frame {index} of "
                                         f"{info.frame_count}: {frame}") from frame
                    frame.flags.writeable = False
                yield frames[0], frames[1]
        finally:
            decoders.stop()


class ReplayedStart:
    """Passes over a stereo video, each from its first frame, that decode its start once:
    the frame pairs a pass decodes are kept, up to ``budget`` bytes, and the next pass
    replays them from memory before it goes on decoding where the decoding stopped (the
    track stage reads the first seconds to find the sponge, then tracks from the start).
    A pass that reaches beyond what could be kept makes the next pass decode from the start
    again. The pairs are the reader's (read-only), the same as a new decoding would give.

    Parameters
    ----------
    reader : StereoVideoReader
    budget : int
        Bytes of frame pairs kept at most.
    """

    def __init__(self, reader: StereoVideoReader, budget: int):
        self.reader = reader
        self.budget = budget
        self._kept: list[tuple[np.ndarray, np.ndarray]] = []
        self._decoding: Iterator | None = None  # a pass's decoding, after the kept pairs
        self._all_kept = False  # every pair ``_decoding`` gave is in ``_kept``

    @property
    def frame_count(self) -> int:
        return self.reader.frame_count

    @property
    def fps(self) -> float:
        return self.reader.fps

    def __iter__(self) -> Iterator[tuple[np.ndarray, np.ndarray]]:
        """A pass that keeps what it decodes for the next."""
        return self.frames(keep=True)

    def frames(self, keep: bool = True) -> Iterator[tuple[np.ndarray, np.ndarray]]:
        """A pass from the first frame pair; ``keep`` False: the last pass, which lets go of
        each kept pair once it has handed it on (and keeps nothing)."""
        if not self._all_kept:
            self.close()
            self._decoding, self._all_kept = iter(self.reader), True
        decoding = self._decoding
        if keep:
            yield from self._kept
        else:  # nothing after this pass replays: from now on, nothing is kept
            pending = self._kept[::-1]
            self._kept, self._all_kept = [], False
            while pending:
                yield pending.pop()
        for pair in decoding:  # not closed when this pass is left: the next one goes on
            if self._all_kept:
                if (len(self._kept) + 1) * (pair[0].nbytes + pair[1].nbytes) <= self.budget:
                    self._kept.append(pair)
                else:
                    self._kept, self._all_kept = [], False
            yield pair

    def close(self) -> None:
        """Stop decoding and let go of the kept pairs."""
        if self._decoding is not None:
            self._decoding.close()
        self._decoding, self._kept, self._all_kept = None, [], False


class _Decoders:
    """One decoding thread per file, each filling its queue until told to stop."""

    running: set[_Decoders] = set()

    def __init__(self, paths: tuple[str, ...], prefetch: int):
        self.halt = threading.Event()
        self.queues = [queue.Queue(prefetch) for _ in paths]
        self.threads = [threading.Thread(target=_decode, args=(path, q, self.halt), daemon=True)
                        for path, q in zip(paths, self.queues)]

    def start(self) -> None:
        with interrupts_deferred():   # both threads started, or none
            _Decoders.running.add(self)
            for thread in self.threads:
                thread.start()

    def stop(self) -> None:
        self.halt.set()
        for q in self.queues:  # unblock the decoders so that they can see the stop flag
            while not q.empty():
                q.get_nowait()
        for thread in self.threads:
            if thread.is_alive():
                thread.join(timeout=5.0)
        _Decoders.running.discard(self)


@atexit.register
def _stop_running_decoders() -> None:
    for decoders in list(_Decoders.running):
        decoders.stop()


class H264Writer:
    """Encode BGR frames to an H.264 MP4 (yuv420p, no B-frames) with PyAV.

    Parameters
    ----------
    path : path-like
    fps : int
    size : tuple of int
        (width, height); both even.
    crf : int
        x264 constant rate factor (lower: better quality, bigger file).
    preset : str
        x264 speed preset.
    """

    def __init__(self, path: str | os.PathLike, fps: int, size: tuple[int, int], crf: int = 18,
                 preset: str = "veryfast"):
        self._container = av.open(str(path), mode="w")
        stream = self._container.add_stream("libx264", rate=Fraction(fps))
        stream.width, stream.height = size
        stream.pix_fmt = "yuv420p"
        # one encoder thread: the tracker and the decoders already keep the cores busy
        stream.options = {"crf": str(crf), "preset": preset, "bf": "0", "threads": "1"}
        self._stream = stream

    def write(self, frame_bgr: np.ndarray) -> None:
        """Append one frame, shape (h, w, 3) uint8."""
        # OpenCV's BGR -> I420 is several times faster than FFmpeg's swscale in the encoder
        frame = av.VideoFrame.from_ndarray(cv2.cvtColor(frame_bgr, cv2.COLOR_BGR2YUV_I420),
                                           format="yuv420p")
        self._container.mux(self._stream.encode(frame))

    def close(self) -> None:
        """Flush the encoder and finish the file."""
        self._container.mux(self._stream.encode(None))
        self._container.close()

    def __enter__(self) -> "H264Writer":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
