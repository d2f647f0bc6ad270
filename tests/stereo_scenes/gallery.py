"""``python -m tests.stereo_scenes.gallery OUT.png --seeds 0-11 [--small]``: a contact sheet.

One row per seed: the first left frame, a mid-demo left frame and the left frame in the
middle of the first full occlusion, with effects (no codec), each labelled.
"""

from __future__ import annotations

import argparse
import sys

import cv2
import numpy as np

from tests.stereo_scenes.effects import FrameEffects
from tests.stereo_scenes.plan import plan_scene
from tests.stereo_scenes.render import SceneRenderer

THUMB_WIDTH = 480


def parse_seeds(text: str) -> list[int]:
    """``"0-3,7"`` -> [0, 1, 2, 3, 7]."""
    seeds = []
    for part in text.split(","):
        lo, _, hi = part.partition("-")
        seeds.extend(range(int(lo), int(hi or lo) + 1))
    return seeds


def _thumb(image, label):
    h, w = image.shape[:2]
    thumb = cv2.resize(image, (THUMB_WIDTH, int(round(h * THUMB_WIDTH / w))),
                       interpolation=cv2.INTER_AREA)
    thumb = cv2.copyMakeBorder(thumb, 0, max(0, 360 - thumb.shape[0]), 0, 0,
                               cv2.BORDER_CONSTANT, value=(0, 0, 0))[:360]
    cv2.rectangle(thumb, (0, 0), (THUMB_WIDTH, 24), (0, 0, 0), -1)
    cv2.putText(thumb, label, (5, 16), cv2.FONT_HERSHEY_SIMPLEX, 0.4, (255, 255, 255), 1,
                cv2.LINE_AA)
    return thumb


def seed_row(seed: int, small: bool) -> np.ndarray:
    """The three labelled thumbnails of one seed, side by side."""
    plan = plan_scene(seed, small=small)
    renderer = SceneRenderer(plan)
    c = plan.cameras
    effects = FrameEffects(plan.effects, plan.duration, (c.width, c.height),
                           np.random.default_rng([seed, 102]))
    occlusion = next(o for o in plan.occlusions if o.kind == "full")
    times = [0.0, 0.5 * plan.duration, 0.5 * (occlusion.covered_from + occlusion.covered_to)]
    thumbs = []
    for name, t in zip(("first", "mid", "occluded"), times):
        index = int(round(t * renderer.fps))
        left, _, row = renderer.frame(index)
        label = (f"{seed} {name} {row[0]:.1f}s {plan.sponge.colour}"
                 f"{'+' + plan.sponge.pad if plan.sponge.pad else ''} {plan.motion.pattern} "
                 f"{plan.table.texture} k1={plan.cameras.D1[0]:.2f} "
                 f"vis {row[5]:.2f}/{row[6]:.2f}")
        thumbs.append(_thumb(effects.apply(left, row[0], 0), label))
    return np.hstack(thumbs)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m tests.stereo_scenes.gallery")
    parser.add_argument("out_png")
    parser.add_argument("--seeds", default="0-11", help="e.g. 0-11 or 3,5,10000-10003")
    parser.add_argument("--small", action="store_true", help="the small (320x240) scenes")
    args = parser.parse_args(argv)
    try:
        seeds = parse_seeds(args.seeds)
    except ValueError:
        print(f"error: --seeds: expected ranges like 0-11 or 3,5, got {args.seeds!r}",
              file=sys.stderr)
        return 2
    sheet = np.vstack([seed_row(seed, args.small) for seed in seeds])
    if not cv2.imwrite(args.out_png, sheet):
        print(f"error: {args.out_png}: cannot write the image", file=sys.stderr)
        return 2
    print(args.out_png)
    return 0


if __name__ == "__main__":
    sys.exit(main())
