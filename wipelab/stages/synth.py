"""The synth stage: render a synthetic stereo wiping demonstration with ground truth.

Writes the demo directory of DESIGN.md: ``left.mp4``, ``right.mp4`` (H.264), 
``calibration.yaml``, ``demo.toml``, ``truth.csv`` (t, x, y, z of the sponge centre in the
world frame, plus its yaw and the fraction of it each camera sees past the free hand) and
``manifest.json``. :func:`synth` is a plain function, so a data set is a loop over it.
"""

from __future__ import annotations

import os
import queue
import threading
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
from tqdm import tqdm

from wipelab.manifest import build_manifest, write_json
from wipelab.stage_output import staged_output
from wipelab.trajectory_csv import write_trajectory
from wipelab.vision.calibration import save_calibration
from wipelab.vision.sponge_box import SpongeBox
from wipelab.vision.synthetic_renderer import (SPONGE_BGR, CameraEffects, RenderParams,
                                                StereoRenderer, WipingScene, schedule_occlusions)
from wipelab.vision.synthetic_rig import (SceneLayout, armar_wide_stereo_calibration,
                                          camera_poses_in_world)
from wipelab.vision.synthetic_scene import StaticScene
from wipelab.vision.video_io import H264Writer
from wipelab.vision.wiping_motion import PATTERNS, WipingMotion, WipingMotionParams

#: Default movement size per pattern, metres (radius, half stroke, half width).
DEFAULT_AMPLITUDE = {"circle": 0.085, "line": 0.14, "figure8": 0.12}


@dataclass(frozen=True)
class SynthParams:
    """One synthetic demonstration.

    Attributes
    ----------
    pattern : str
        ``circle``, ``line`` or ``figure8``.
    frequency_hz : float
        Fundamental wiping frequency.
    duration : float
        Length of the recording, seconds.
    seed : int
        Seeds the motion's variation, the scene's textures, occlusions and noise.
    fps : int
        Frame rate, frames per second.
    amplitude : float or None
        Movement size, metres; None picks :data:`DEFAULT_AMPLITUDE` of the pattern.
    sponge_colour : str
        A key of :data:`wipelab.vision.synthetic_renderer.SPONGE_BGR`.
    sponge : SpongeBox
        Sponge dimensions, metres.
    layout : SceneLayout
        Table and camera placement.
    render : RenderParams
        Exposure, noise, lighting drift.
    tempo_step : tuple of float or None
        (time s, factor): the person wipes ``factor`` times as fast from then on.
    speed_variation : float
        Relative standard deviation of the person's instantaneous tempo (0: steady).
    """

    pattern: str = "circle"
    frequency_hz: float = 1.0
    duration: float = 30.0
    seed: int = 0
    fps: int = 30
    amplitude: float | None = None
    sponge_colour: str = "yellow"
    sponge: SpongeBox = field(default_factory=SpongeBox)
    layout: SceneLayout = field(default_factory=SceneLayout)
    render: RenderParams = field(default_factory=RenderParams)
    tempo_step: tuple[float, float] | None = None
    speed_variation: float = 0.04

    def __post_init__(self):
        if self.pattern not in PATTERNS:
            raise ValueError(f"pattern must be one of {', '.join(PATTERNS)}")
        if self.sponge_colour not in SPONGE_BGR:
            raise ValueError(f"sponge_colour must be one of {', '.join(SPONGE_BGR)}")
        if self.duration <= 0 or self.fps <= 0 or self.frequency_hz <= 0:
            raise ValueError("duration, fps and frequency_hz must be positive")


def _toml_value(value) -> str:
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if isinstance(value, float):
        return repr(round(value, 6))
    return str(value)


def _demo_toml(params: SynthParams, frame_count: int, occlusions) -> str:
    sponge = params.sponge
    top = {"fps": params.fps, "frame_count": frame_count, "sponge_colour": params.sponge_colour,
           "sponge_size": [sponge.length, sponge.width, sponge.height],
           "notes": "synthetic demonstration rendered by wipelab synth; truth.csv holds the "
                    "sponge-box centre in the world frame"}
    synth = {"pattern": params.pattern, "frequency_hz": params.frequency_hz,
             "duration": params.duration, "seed": params.seed,
             "amplitude": params.amplitude or DEFAULT_AMPLITUDE[params.pattern],
             "free_hand_passes": [[e.t_in, e.t_out] for e in occlusions]}
    if params.tempo_step is not None:
        synth["tempo_step"] = list(params.tempo_step)
    lines = ["# wipelab demonstration metadata"]
    lines += [f"{key} = {_toml_value(value)}" for key, value in top.items()]
    lines += ["", "[synth]"] + [f"{key} = {_toml_value(value)}" for key, value in synth.items()]
    return "\n".join(lines) + "\n"


def _encode(path: Path, fps: int, size: tuple[int, int], frames: queue.Queue,
            errors: list) -> None:
    try:
        with H264Writer(path, fps, size) as writer:
            while (frame := frames.get()) is not None:
                writer.write(frame)
    except BaseException as error:  # reported by the rendering thread
        errors.append(error)
        while frames.get() is not None:
            pass


def synth(out_dir: str | os.PathLike, params: SynthParams = SynthParams(),
          quiet: bool = False) -> Path:
    """Render a demonstration into ``out_dir`` (created; files appear only on success).

    Returns
    -------
    Path
        ``out_dir``.
    """
    layout = params.layout
    calibration = armar_wide_stereo_calibration(layout)
    T_world_left, T_world_right = camera_poses_in_world(calibration)
    frame_count = int(round(params.duration * params.fps))
    times = np.arange(frame_count) / params.fps
    amplitude = params.amplitude or DEFAULT_AMPLITUDE[params.pattern]
    motion = WipingMotion(WipingMotionParams(params.pattern, params.frequency_hz,
                                             amplitude=amplitude, tempo_step=params.tempo_step,
                                             speed_variation=params.speed_variation),
                          layout.table_height, params.sponge.height, params.seed)
    occlusions = schedule_occlusions(params.duration, np.random.default_rng([params.seed, 0x0CC]))
    eye = 0.5 * (T_world_left[:3, 3] + T_world_right[:3, 3])
    scene = WipingScene(motion, params.sponge, occlusions, eye)
    static = StaticScene(layout, params.seed)
    colour = SPONGE_BGR[params.sponge_colour]
    renderers, effects = [], []
    for index, (camera, T_world_cam) in enumerate(((calibration.left, T_world_left),
                                                   (calibration.right, T_world_right))):
        background = static.render_background(camera, T_world_cam)
        renderers.append(StereoRenderer(camera, T_world_cam, background, scene, colour,
                                        params.render))
        effects.append(CameraEffects(params.render, background.shape, params.seed * 2 + index))

    visible = np.ones((frame_count, 2))
    with staged_output(out_dir) as tmp:
        queues = [queue.Queue(16), queue.Queue(16)]
        errors: list = []
        encoders = [threading.Thread(target=_encode, args=(tmp / name, params.fps,
                                                           layout.image_size, q, errors))
                    for name, q in zip(("left.mp4", "right.mp4"), queues)]
        try:
            for encoder in encoders:
                encoder.start()
            for k in tqdm(range(frame_count), desc="synth", unit="frame", disable=quiet,
                          leave=False):
                if errors:
                    break
                for view in range(2):
                    image, visible[k, view] = renderers[view].render(times[k])
                    queues[view].put(effects[view].apply(image, times[k]))
        finally:  # also on Ctrl-C: an encoder left waiting would keep the program alive
            for q in queues:
                q.put(None)
            for encoder in encoders:
                if encoder.ident is not None:
                    encoder.join()
        if errors:
            raise errors[0]
        save_calibration(tmp / "calibration.yaml", calibration)
        (tmp / "demo.toml").write_text(_demo_toml(params, frame_count, occlusions))
        centre, yaw = motion.pose(times)
        write_trajectory(tmp / "truth.csv", times,
                         {"x": centre[:, 0], "y": centre[:, 1], "z": centre[:, 2], "yaw": yaw,
                          "visible_left": visible[:, 0], "visible_right": visible[:, 1]},
                         float_format="%.7f")
        parameters = asdict(params)
        write_json(tmp / "manifest.json", build_manifest("synth", {}, parameters, params.seed))
    return Path(out_dir)
