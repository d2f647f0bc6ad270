"""Writing one scene as a demo directory (DESIGN.md, "Demo directory"), without demo.toml.

Files: ``left.mp4``, ``right.mp4``, ``calibration.yaml`` (OpenCV FileStorage; ``T_world_left``
in most scenes), ``truth.csv`` (``t,x,y,z,yaw,visible_left,visible_right``) and ``scene.json``
(every randomised factor; the tracker never reads it). Everything is written into a
temporary sibling directory and renamed into place at the end.
"""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import cv2
import numpy as np

from tests.stereo_scenes.effects import FrameEffects
from tests.stereo_scenes.plan import ScenePlan, plan_scene
from tests.stereo_scenes.render import SceneRenderer
from tests.stereo_scenes.video import VideoFile

TRUTH_HEADER = "t,x,y,z,yaw,visible_left,visible_right"


def write_calibration(path: Path, plan: ScenePlan):
    """calibration.yaml of a plan's cameras (x_right = R x_left + T)."""
    c = plan.cameras
    T_world_left, T_world_right = np.array(c.T_world_left), np.array(c.T_world_right)
    T_right_left = np.linalg.inv(T_world_right) @ T_world_left
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_WRITE)
    fs.write("image_width", int(c.width))
    fs.write("image_height", int(c.height))
    fs.write("K1", np.array(c.K1))
    fs.write("D1", np.array(c.D1).reshape(1, 5))
    fs.write("K2", np.array(c.K2))
    fs.write("D2", np.array(c.D2).reshape(1, 5))
    fs.write("R", T_right_left[:3, :3])
    fs.write("T", T_right_left[:3, 3].reshape(3, 1))
    if plan.write_T_world_left:
        fs.write("T_world_left", T_world_left)
    fs.release()


def _truth_line(row) -> str:
    t, x, y, z, yaw, vl, vr = row
    return f"{t:.6f},{x:.6f},{y:.6f},{z:.6f},{yaw:.6f},{vl:.4f},{vr:.4f}"


def render_plan(out_dir: str | os.PathLike, plan: ScenePlan, progress=None) -> Path:
    """Renders a plan into the demo directory ``out_dir`` (which must not exist yet)."""
    out = Path(out_dir)
    if out.exists():
        raise FileExistsError(f"{out}: already exists")
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.parent / f".{out.name}.partial-{os.getpid()}"
    if tmp.exists():
        shutil.rmtree(tmp)
    tmp.mkdir()
    try:
        renderer = SceneRenderer(plan)
        c = plan.cameras
        effects = FrameEffects(plan.effects, plan.duration, (c.width, c.height),
                               np.random.default_rng([plan.seed, 102]))
        rows = []
        with VideoFile(tmp / "left.mp4", plan.video, c.width, c.height) as left, \
                VideoFile(tmp / "right.mp4", plan.video, c.width, c.height) as right:
            for index in range(renderer.frame_count):
                image_left, image_right, row = renderer.frame(index)
                left.write(effects.apply(image_left, row[0], 0))
                right.write(effects.apply(image_right, row[0], 1))
                rows.append(row)
                if progress is not None:
                    progress(index + 1, renderer.frame_count)
        (tmp / "truth.csv").write_text(
            "\n".join([TRUTH_HEADER] + [_truth_line(r) for r in rows]) + "\n")
        write_calibration(tmp / "calibration.yaml", plan)
        info = plan.to_json()
        info["frame_count"] = renderer.frame_count
        info["generator"] = "tests.stereo_scenes"
        info["generator_version"] = GENERATOR_VERSION
        (tmp / "scene.json").write_text(json.dumps(info, indent=1, sort_keys=True) + "\n")
        os.replace(tmp, out)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return out


#: Changes whenever the same seed renders a different scene (``scene.json`` records it, so
#: that a benchmark renders a scene again rather than reuse one of an earlier generator).
#: 2: the holding hand keeps one grip on the sponge all demonstration (it jumped to another
#: side of the sponge whenever another side faced away from the shoulder).
GENERATOR_VERSION = 2


def render_scene(out_dir: str | os.PathLike, seed: int, duration: float | None = None,
                 small: bool = False, progress=None, **overrides) -> Path:
    """Plans scene ``seed`` (with ``overrides``, see :mod:`tests.stereo_scenes.plan`) and
    renders it into the demo directory ``out_dir``; returns its path."""
    return render_plan(out_dir, plan_scene(seed, duration, small, **overrides), progress)
