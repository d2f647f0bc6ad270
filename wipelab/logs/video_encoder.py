"""Encoding camera frames for the logs while they arrive (a live session has no video file).

H.264 Annex B, one access unit per frame, no B-frames and no look-ahead (``zerolatency``):
each frame's packet is ready as soon as the frame is encoded, which is what Rerun's
``VideoStream`` and Foxglove's ``CompressedVideo`` play. One encoder thread (libx264 is then
deterministic: the same frames give the same bytes) and the ``superfast`` preset: about 2 ms
per 640x480 frame on the development machine.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np

#: Key frame interval (frames): a viewer that joins late or seeks decodes from the last one.
KEY_FRAME_INTERVAL = 30


class LiveVideoEncoder:
    """H.264 encoder of BGR frames of one camera.

    Parameters
    ----------
    size : tuple of int
        (width, height) in pixels; odd sizes are cropped by one pixel (yuv420p).
    fps : float
        Frame rate (Hz) written into the stream's timing.
    crf : int
        x264 constant rate factor (lower: better quality, bigger).
    """

    def __init__(self, size: tuple[int, int], fps: float, crf: int = 23):
        import av

        width, height = (int(v) // 2 * 2 for v in size)
        context = av.CodecContext.create("libx264", "w")
        context.width, context.height = width, height
        context.pix_fmt = "yuv420p"
        context.time_base = Fraction(1, 1000)
        context.framerate = Fraction(round(fps * 1000), 1000)
        context.options = {"preset": "superfast", "tune": "zerolatency", "crf": str(crf),
                           "bf": "0", "threads": "1", "g": str(KEY_FRAME_INTERVAL)}
        self._context = context
        self._av = av

    def encode(self, frame_bgr: np.ndarray, t: float) -> list[bytes]:
        """The access units (Annex B bytes) of one frame (h, w, 3) uint8 shown at ``t`` (s)."""
        height, width = self._context.height, self._context.width
        frame = self._av.VideoFrame.from_ndarray(
            np.ascontiguousarray(frame_bgr[:height, :width]), format="bgr24")
        frame.pts = int(round(t * 1000))
        return [bytes(packet) for packet in self._context.encode(frame)]
