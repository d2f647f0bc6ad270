"""``python -m tests.stereo_scenes OUT_DIR --seed N [--duration S] [--small]``: one scene."""

from __future__ import annotations

import argparse
import sys
import time

from tests.stereo_scenes.demo_dir import render_scene


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m tests.stereo_scenes",
                                     description="Render one randomised stereo test scene.")
    parser.add_argument("out_dir", help="demo directory to create (must not exist)")
    parser.add_argument("--seed", type=int, required=True,
                        help="scene seed; 0-9999 development, >= 10000 held out")
    parser.add_argument("--duration", type=float, default=None, help="seconds (default: 32, "
                        "or 2.5-5 with --small)")
    parser.add_argument("--small", action="store_true", help="320x240, a few seconds")
    args = parser.parse_args(argv)
    if args.duration is not None and not args.duration > 0:
        print("error: --duration: must be positive", file=sys.stderr)
        return 2
    start = time.perf_counter()
    try:
        path = render_scene(args.out_dir, args.seed, args.duration, args.small)
    except (FileExistsError, ValueError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(f"{path}: rendered in {time.perf_counter() - start:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
