"""Fixtures for the logging tests: a small H.264 clip, a JPEG, an input file, a full recording."""

from __future__ import annotations

from pathlib import Path

import av
import cv2
import pytest

from logs_testdata import FPS, FRAMES, synthetic_frame, write_everything
from wipelab.logs import StageRecorder


@pytest.fixture(scope="session")
def h264_clip(tmp_path_factory) -> Path:
    """A 2 s, 10 fps, 160x120 H.264 MP4 without B-frames."""
    path = tmp_path_factory.mktemp("video") / "left.mp4"
    with av.open(str(path), "w") as container:
        stream = container.add_stream("libx264", rate=int(FPS))
        stream.width, stream.height, stream.pix_fmt = 160, 120, "yuv420p"
        stream.options = {"bf": "0", "g": "10"}
        for i in range(FRAMES):
            for packet in stream.encode(av.VideoFrame.from_ndarray(synthetic_frame(i), format="bgr24")):
                container.mux(packet)
        for packet in stream.encode():
            container.mux(packet)
    return path


@pytest.fixture(scope="session")
def jpeg_bytes() -> bytes:
    ok, data = cv2.imencode(".jpg", synthetic_frame(3))
    assert ok
    return data.tobytes()


@pytest.fixture(scope="session")
def input_file(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("inputs") / "trajectory.csv"
    path.write_text("t,x,y\n0,0,0\n0.1,0.01,0.02\n")
    return path


@pytest.fixture(scope="session")
def recording(tmp_path_factory, h264_clip, jpeg_bytes, input_file) -> StageRecorder:
    return write_everything(tmp_path_factory.mktemp("rec"), h264_clip, jpeg_bytes, input_file)
