"""Test data for the logging tests: what the full recording logs, and how it is written.

Imported by name (``logs_testdata``) because the tests directory is not a package."""

from __future__ import annotations

import shutil
import sys
from pathlib import Path

import cv2
import numpy as np
import rerun as rr
import rerun.blueprint as rrb

from wipelab.logs import StageRecorder
from wipelab.logs.phase_chart import PhaseChart

FRAMES = 20
FPS = 10.0


def rerun_cli() -> str | None:
    """The ``rerun`` binary shipped in the rerun-sdk wheel of this interpreter's environment."""
    beside = Path(sys.executable).with_name("rerun")
    return str(beside) if beside.exists() else shutil.which("rerun")


def synthetic_frame(i: int, width: int = 160, height: int = 120) -> np.ndarray:
    img = np.full((height, width, 3), 40, np.uint8)
    cv2.circle(img, (20 + 5 * i, height // 2), 12, (0, 200, 255), -1)
    return img


#: What ``write_everything`` logs, for the round-trip tests to compare against.
K = np.array([[500.0, 0.0, 80.0], [0.0, 510.0, 60.0], [0.0, 0.0, 1.0]])
D = np.array([0.1, -0.05, 0.001, 0.002, 0.01])
SERIES_T = np.arange(50) / 25.0
SERIES = np.stack([np.sin(SERIES_T), np.cos(SERIES_T)], axis=1)
SERIES[7, 1] = np.nan
POINTS = np.random.default_rng(0).normal(size=(30, 3))
STRIP = np.stack([np.linspace(0, 1, 12), np.zeros(12), np.linspace(0, 0.5, 12)], axis=1)
QUAT = np.array([0.0, 0.0, np.sin(0.25), np.cos(0.25)])
PARAMETERS = {"kernels": 25, "mode": "online", "dofs": ["x", "y"], "lambda": 0.99}
PHASE = np.linspace(0.0, 2 * np.pi, 9)
CHART = PhaseChart.fitting(np.sin(PHASE), "y (m)")
LINES = np.array([[[10.0, 20.0], [30.0, 40.0]], [[30.0, 40.0], [50.0, 20.0]]])
SHAPES = [("robot/hand", "hand", [("box", [0.1, 0.0, 0.0], QUAT, [0.1, 0.07, 0.05], [90, 90, 90, 255]),
                                  ("sphere", [0.0, 0.0, 0.0], [0, 0, 0, 1], [0.05, 0.05, 0.05],
                                   [200, 200, 200, 255])])]
BLUEPRINT = rrb.Blueprint(rrb.Horizontal(rrb.Spatial3DView(origin="/", name="scene"),
                                         rrb.TimeSeriesView(origin="/oscillators", name="frequencies")))


def write_everything(directory: Path, h264_clip: Path, jpeg_bytes: bytes, input_file: Path,
                     parameters=PARAMETERS) -> StageRecorder:
    """One recording that uses every StageRecorder method once."""
    with StageRecorder(directory, stage="learn", parameters=parameters,
                       inputs={"trajectory": input_file}, blueprint=BLUEPRINT,
                       attachments={"trajectory.csv": input_file}) as rec:
        rec.scalars("/oscillators/frequency_hz", SERIES_T, SERIES, names=["omega_1", "omega_2"])
        rec.points3d("/track/particles", 0.5, POINTS, colors=(255, 0, 0), radii=0.01)
        rec.line_strip3d("/track/trajectory", 0.5, STRIP)
        rec.transforms(0.0, [("world", "base_link", [0.5, 0.0, 0.0], [0, 0, 0, 1]),
                             ("base_link", "left_optical", [0.1, 0.2, 1.5], QUAT)])
        rec.pose("/adapt/tcp_commanded", 1.0, "world", [0.6, 0.1, 0.9], QUAT)
        rec.arrow3d("/adapt/force", 1.0, [0.6, 0.1, 0.9], [0.0, 0.0, -0.2])
        rec.camera_calibration("/stereo/left/calibration", 0.0, K, D, 160, 120, "left_optical")
        rec.compressed_image("/stereo/left/image", 0.2, jpeg_bytes, "left_optical")
        rec.video("/stereo/left/video", h264_clip, np.arange(FRAMES) / FPS, frame_id="left_optical")
        rec.json("/model/learned", 2.0, {"weights": np.arange(3.0), "frequency_hz": 1.5},
                 schema_name="wipelab.Model",
                 schema={"type": "object", "properties": {"weights": {"type": "array"}}})
        rec.box3d("/robot/sponge", 0.5, [0.1, 0.07, 0.04], [0.6, 0.1, 0.85], QUAT, frame_id="hand")
        rec.box3d("/robot/sponge", 0.6, [0.1, 0.07, 0.04], None, frame_id="hand")
        rec.shapes("/robot/body", 0.0, SHAPES)
        rec.image_overlay("/stereo/left/overlay", 0.2, "left_optical", LINES, [[5.0, 6.0]])
        rec.events("/adapt/events", [0.0, 1.0], ["approach", "learning"])
        rec.states("/adapt/segment", [0.0, 1.0], ["approach", "learning"],
                   {"approach": (120, 120, 120), "learning": (70, 150, 230)})
        rec.phase_curves("/adapt/profile", 1.0, CHART, PHASE, {"learned_m": np.sin(PHASE)},
                         {"learned_m": (235, 90, 60)}, extra={"period": 1})
        rec.rerun.set_time("time", duration=1.5)
        rec.rerun.log("/custom/note", rr.TextLog("stage-specific record"))
    return rec
