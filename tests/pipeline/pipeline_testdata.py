"""Test data of the pipeline tests: a demonstration trajectory, pipelines, file comparisons."""

from pathlib import Path

import numpy as np

from wipelab.trajectory_csv import write_trajectory

#: learn -> rollout on a trajectory CSV: the fastest real stages, for the engine tests.
LEARN_PIPELINE = """
[pipeline]
name = "learn-rollout"

[inputs]
trajectory = "trajectory.csv"

[stages.learn]
input = "trajectory"

[stages.rollout]
input = "learn:model.json"
periods = 2
"""


#: learn -> adapt (slowed down: several seconds of simulation, time to interrupt it) ->
#: a short replay: every stage that works on the simulated robot, kept small.
ROBOT_PIPELINE = LEARN_PIPELINE.split("[stages.rollout]")[0] + """
[stages.adapt]
input = "learn:model.json"
periods = 2
slowdown = 6

[stages.replay]
input = "adapt:adapted_model.json"
frequency_scale = [1.0, 2.0]
mode = ["learned+compliance"]
periods = 1
warmup_periods = 0
"""


def write_wiping_trajectory(path: Path, frequency_hz: float = 1.2, duration: float = 15.0,
                            rate_hz: float = 30.0, seed: int = 0) -> Path:
    """A noisy circular wiping movement on a table, as track would write it (t, x, y, z)."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, duration, 1.0 / rate_hz)
    phase = 2.0 * np.pi * frequency_hz * t
    columns = {"x": 0.55 + 0.08 * np.cos(phase), "y": -0.25 + 0.08 * np.sin(phase),
               "z": np.full_like(t, 0.82)}
    columns = {k: v + rng.normal(0.0, 0.001, t.shape) for k, v in columns.items()}
    write_trajectory(path, t, columns)
    return path


def published_files(run_dir: Path) -> dict[str, bytes]:
    """Every file a run published (hidden bookkeeping files aside), by relative path."""
    return {p.relative_to(run_dir).as_posix(): p.read_bytes()
            for p in sorted(run_dir.rglob("*"))
            if p.is_file() and not any(part.startswith(".")
                                       for part in p.relative_to(run_dir).parts)}
