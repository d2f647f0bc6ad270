"""An independent stereo test-scene generator for the tracker (shares no code with
``wipelab synth``).

It renders randomised demo directories (left.mp4, right.mp4, calibration.yaml, truth.csv,
scene.json; no demo.toml) of a person wiping a table with a sponge, drawn with its own
camera and lens model (:mod:`.camera`, :mod:`.lens`), motion (:mod:`.motion`), scene plan
(:mod:`.plan`, :mod:`.distractors`), drawing (:mod:`.raster`, :mod:`.static_scene`,
:mod:`.actors`, :mod:`.render`), effects (:mod:`.effects`) and video writing
(:mod:`.video`), with numpy, OpenCV and PyAV only.

Seeds
-----
Seeds 0-9999 are for development: look at them, test on them, tune on them.
Seeds >= 10000 are the HELD-OUT set: the tracker benchmark reports on seeds 10000..10023
(and on); nobody looks at them or tunes the tracker on them.

Usage::

    from tests.stereo_scenes import render_scene
    render_scene("out/scene7", seed=7)                        # a >= 30 s scene
    render_scene("out/small7", seed=7, small=True)            # 320x240, a few seconds
    render_scene("out/s", seed=10003, pattern="figure8", frequency_hz=1.5)

    python -m tests.stereo_scenes OUT_DIR --seed N [--duration S] [--small] [--set FACTOR=VALUE]
    python -m tests.stereo_scenes.gallery OUT.png --seeds 0-11
"""

from tests.stereo_scenes.demo_dir import GENERATOR_VERSION, render_plan, render_scene
from tests.stereo_scenes.plan import ScenePlan, plan_scene

HELD_OUT_SEEDS_FROM = 10000

__all__ = ["render_scene", "render_plan", "plan_scene", "ScenePlan", "HELD_OUT_SEEDS_FROM",
           "GENERATOR_VERSION"]
