"""Writing a camera's frames to an .mp4 file with the codec a plan chose.

* ``h264``: PyAV / libx264, yuv420p, constant-quality ``crf``, optional B-frames, one thread
  (deterministic bytes);
* ``mp4v`` (MPEG-4 part 2) and ``mjpg`` (Motion JPEG): OpenCV's ``cv2.VideoWriter`` at its
  default quality, or PyAV's ``mpeg4`` / ``mjpeg`` encoders at a chosen bit rate.
"""

from __future__ import annotations

from fractions import Fraction

import av
import cv2
import numpy as np

FOURCC = {"mp4v": "mp4v", "mjpg": "MJPG"}
PYAV_CODEC = {"h264": "libx264", "mp4v": "mpeg4", "mjpg": "mjpeg"}


class VideoFile:
    """An .mp4 file being written frame by frame (BGR uint8 frames); use as a context manager."""

    def __init__(self, path: str, video, width: int, height: int):
        self.video = video
        self.path = str(path)
        if video.writer == "opencv":
            # MJPG: FFmpeg warns that it stores it in .mp4 under the mp4v tag; it is MJPEG
            self._cv = cv2.VideoWriter(self.path, cv2.CAP_FFMPEG,
                                       cv2.VideoWriter_fourcc(*FOURCC[video.codec]),
                                       float(video.fps), (width, height))
            if not self._cv.isOpened():
                raise RuntimeError(f"{self.path}: OpenCV cannot write {video.codec}")
            return
        self._container = av.open(self.path, "w", options={"fflags": "+bitexact"})
        stream = self._container.add_stream(PYAV_CODEC[video.codec], rate=Fraction(video.fps))
        stream.width, stream.height = width, height
        stream.pix_fmt = "yuvj420p" if video.codec == "mjpg" else "yuv420p"
        stream.thread_count = 1
        if video.codec == "h264":
            stream.options = {"crf": str(video.crf), "bf": str(video.bframes),
                              "preset": video.preset, "threads": "1"}
        else:
            stream.bit_rate = int(video.bits_per_pixel * width * height * video.fps)
            stream.codec_context.flags |= av.codec.context.Flags.bitexact
        self._stream = stream

    def write(self, frame: np.ndarray):
        if self.video.writer == "opencv":
            self._cv.write(frame)
            return
        packet_frame = av.VideoFrame.from_ndarray(frame, format="bgr24")
        for packet in self._stream.encode(packet_frame):
            self._container.mux(packet)

    def close(self):
        if self.video.writer == "opencv":
            self._cv.release()
            return
        for packet in self._stream.encode():
            self._container.mux(packet)
        self._container.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
