"""A synthetic data set: one ``synth`` demonstration per (pattern, frequency, seed).

Each demo is rendered by :func:`wipelab.stages.synth.synth` (the same function as
``wipelab synth``) into ``OUT_DIR/<pattern>_<frequency>hz_seed<seed>/``. A demo that is
already complete (its ``manifest.json``, which synth publishes with its other files, is
there) is kept, so an interrupted generation resumes.
"""

from __future__ import annotations

import itertools
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

from wipelab.errors import InputError
from wipelab.output_location import check_output_dir


@dataclass(frozen=True)
class GridPoint:
    """One demo of the grid."""

    pattern: str
    frequency_hz: float  # fundamental wiping frequency
    seed: int

    @property
    def name(self) -> str:
        """Directory name, e.g. ``circle_0.8hz_seed3``."""
        return f"{self.pattern}_{self.frequency_hz:g}hz_seed{self.seed}"


def grid_points(patterns: Sequence[str], frequencies_hz: Sequence[float],
                seeds: Sequence[int]) -> list[GridPoint]:
    """Every combination, in pattern, frequency, seed order."""
    from wipelab.vision.wiping_motion import PATTERNS

    if not patterns or not frequencies_hz or not seeds:
        raise InputError("synth-dataset: give at least one --pattern, --frequency and --seed")
    for pattern in patterns:
        if pattern not in PATTERNS:
            raise InputError(f"--pattern {pattern}: unknown (one of {', '.join(PATTERNS)})")
    for frequency_hz in frequencies_hz:
        if not frequency_hz > 0:
            raise InputError(f"--frequency {frequency_hz:g}: must be positive")
    return [GridPoint(p, float(f), int(s))
            for p, f, s in itertools.product(patterns, frequencies_hz, seeds)]


def render_point(out_dir: str, point: GridPoint, duration: float, fps: int) -> str:
    """Render one demo (top-level so that a process pool can run it); returns its path."""
    from wipelab.stages.synth import SynthParams, synth

    try:
        params = SynthParams(pattern=point.pattern, frequency_hz=point.frequency_hz,
                             duration=duration, seed=point.seed, fps=fps)
    except ValueError as error:
        raise InputError(f"synth-dataset: {error}") from None
    return str(synth(Path(out_dir) / point.name, params, quiet=True))


def missing_points(out_dir: str | os.PathLike, points: Sequence[GridPoint]) -> list[GridPoint]:
    """The points whose demo is not complete yet; InputError when one of their folders
    cannot be written (checked before any is rendered)."""
    out_dir = Path(out_dir)
    todo = [p for p in points if not (out_dir / p.name / "manifest.json").is_file()]
    for point in todo:
        check_output_dir(out_dir / point.name)
    return todo


def synth_grid(out_dir: str | os.PathLike, points: Sequence[GridPoint], duration: float,
               fps: int, jobs: int = 1,
               on_done: Callable[[str], None] = lambda path: None) -> list[Path]:
    """Render every grid point that is not already complete; returns all demo directories.

    Parameters
    ----------
    out_dir : path-like
        Parent directory of the demos.
    points : sequence of GridPoint
    duration : float
        Length of each demo, seconds.
    fps : int
        Frame rate, frames per second.
    jobs : int
        Demos rendered in parallel processes.
    on_done : callable
        Called with each demo's path when it is rendered (progress).
    """
    out_dir = Path(out_dir)
    if jobs < 1:
        raise InputError(f"-j {jobs}: need at least 1 job")
    todo = missing_points(out_dir, points)
    if jobs <= 1 or len(todo) <= 1:
        for point in todo:
            on_done(render_point(str(out_dir), point, duration, fps))
    else:
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor, as_completed

        with ProcessPoolExecutor(jobs, mp_context=multiprocessing.get_context("spawn")) as pool:
            futures = [pool.submit(render_point, str(out_dir), p, duration, fps) for p in todo]
            for future in as_completed(futures):
                on_done(future.result())
    return [out_dir / point.name for point in points]
