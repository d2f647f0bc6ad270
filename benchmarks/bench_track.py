"""Benchmark of the track stage on synthetic demonstrations, with a CamShift baseline.

For each pattern (circle, line, figure8) at 0.5, 1 and 1.5 Hz and each seed, renders a
demonstration with ``wipelab synth`` (cached in the work directory), then on the same
videos runs

* the wipelab tracker (colour particle filter + refinement; decoding included in the
  timing), and
* the baseline: OpenCV CamShift in each image + ``cv2.triangulatePoints``,

and reports, against truth.csv (the centre of the sponge box, the point both trackers are
asked for):

* accuracy: 3D RMS and 95th-percentile error of the frames each tracker marks valid;
* robustness: share of *visible* frames (nothing hides the sponge but the hand holding
  it) marked invalid; time from the end of each full occlusion (the first frame in which
  both cameras see part of the sponge again) to the first valid frame;
* speed: stereo frame pairs per second, decoding included;
* learnability: ``wipelab learn`` (offline and online) on the track, frequency error
  relative to the demonstrated frequency (and on truth.csv, for the learner's own error).

Usage::

    python benchmarks/bench_track.py [--seeds 1] [--duration 60] [--workdir DIR]
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wipelab.stages.learn import LearnParams, learn
from wipelab.stages.synth import SynthParams, synth
from wipelab.stages.track import TrackParams, _csv_columns, open_demo, run_tracker
from wipelab.trajectory_csv import read_trajectory, write_trajectory
from wipelab.vision.camshift_baseline import CamShiftBaseline
from wipelab.vision.colour_model import ColourSource
from wipelab.vision.tracker import SpongeTracker, TrackerParams

PATTERNS = ("circle", "line", "figure8")
FREQUENCIES_HZ = (0.5, 1.0, 1.5)
VISIBLE = 0.999  # a frame is visible when the free hand hides none of the sponge


@dataclass
class Run:
    """One tracker on one demo."""

    rms_mm: float
    p95_mm: float
    invalid_visible_pct: float
    regain_s: float
    fps: float
    cpu_ms: float  # CPU time of all the process's threads per frame pair
    main_ms: float  # CPU time of the tracking (main) thread per frame pair: decoding is not in it


def demo_dir(workdir: Path, pattern: str, frequency_hz: float, seed: int, duration: float) -> Path:
    """Render (once) and return the demo directory of one configuration."""
    path = workdir / f"{pattern}_{frequency_hz:g}hz_seed{seed}_{duration:g}s"
    if not (path / "truth.csv").is_file():
        synth(path, SynthParams(pattern=pattern, frequency_hz=frequency_hz, duration=duration,
                                seed=seed), quiet=True)
    return path


def score(points: np.ndarray, valid: np.ndarray, truth, fps: float, cpu_ms: float,
          main_ms: float) -> Run:
    """Accuracy and robustness of points (n, 3) marked valid (n,) against truth."""
    T = truth.array(["x", "y", "z"])
    error = np.linalg.norm(points[valid] - T[valid], axis=1) * 1000.0
    seen = np.minimum(truth.columns["visible_left"], truth.columns["visible_right"])
    visible = seen >= VISIBLE
    hidden = seen == 0.0
    # end of each full occlusion: the first frame in which both cameras see part of it again
    ends = np.flatnonzero(hidden[:-1] & ~hidden[1:]) + 1
    regain = []
    for end in ends:
        after = np.flatnonzero(valid[end:])
        regain.append(truth.t[end + after[0]] - truth.t[end] if len(after) else np.inf)
    return Run(float(np.sqrt(np.mean(error ** 2))), float(np.percentile(error, 95)),
               float(100.0 * np.mean(~valid[visible])), float(max(regain)), fps, cpu_ms,
               main_ms)


def run_wipelab(path: Path, particles: int, csv_path: Path) -> tuple[Run, Path]:
    demo = open_demo(path)
    tracker = SpongeTracker(demo.calibration, ColourSource(name="yellow"),
                            TrackerParams(particles=particles))
    start, cpu, main = time.perf_counter(), time.process_time(), time.thread_time()
    result = run_tracker(tracker, demo.reader, TrackParams(particles=particles), quiet=True)
    elapsed, cpu = time.perf_counter() - start, time.process_time() - cpu
    main = time.thread_time() - main
    write_trajectory(csv_path, result.t, _csv_columns(result))
    truth = read_trajectory(path / "truth.csv", required=("t", "x", "y", "z"))
    n = len(result.t)
    return (score(result.poses[:, :3], result.valid, truth, n / elapsed, 1000 * cpu / n,
                  1000 * main / n), csv_path)


def run_baseline(path: Path) -> Run:
    demo = open_demo(path)
    baseline = CamShiftBaseline(demo.calibration, ColourSource(name="yellow"))
    n = demo.reader.frame_count
    points, valid = np.full((n, 3), np.nan), np.zeros(n, bool)
    start, cpu, main = time.perf_counter(), time.process_time(), time.thread_time()
    for k, (left, right) in enumerate(demo.reader):
        points[k], valid[k] = baseline.step(left, right)
    elapsed, cpu = time.perf_counter() - start, time.process_time() - cpu
    main = time.thread_time() - main
    truth = read_trajectory(path / "truth.csv", required=("t", "x", "y", "z"))
    return score(points, valid, truth, n / elapsed, 1000 * cpu / n, 1000 * main / n)


def learned_frequency_error(csv_path: Path, frequency_hz: float, mode: str, workdir: Path) -> float:
    """Relative error (%) of the frequency ``wipelab learn`` finds in a trajectory CSV."""
    with tempfile.TemporaryDirectory(dir=workdir) as out:
        model = learn(csv_path, Path(out) / "learn", LearnParams(mode=mode), quiet=True)
    return 100.0 * abs(model.frequency_hz - frequency_hz) / frequency_hz


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, default=1, help="seeds per configuration")
    parser.add_argument("--duration", type=float, default=60.0, help="seconds per demo")
    parser.add_argument("--particles", type=int, default=100)
    parser.add_argument("--workdir", type=Path,
                        default=Path(tempfile.gettempdir()) / "wipelab-bench-track",
                        help="where demos are rendered (and reused by later runs)")
    args = parser.parse_args()
    args.workdir.mkdir(parents=True, exist_ok=True)

    print(f"load average at start: {' '.join(f'{v:.1f}' for v in os.getloadavg())} "
          f"on {os.cpu_count()} cores (fps is wall clock, decoding included; cpu ms is the "
          f"CPU time of all threads per frame pair, main ms that of the tracking thread, "
          f"decoding runs on two others)")
    header = (f"{'demo':<22} | {'ours: rms':>9} {'p95':>6} {'inv%':>5} {'regain':>6} {'fps':>5} "
              f"{'cpu ms':>6} {'main':>5} | {'CamShift: rms':>13} {'p95':>6} {'inv%':>5} {'regain':>6} "
              f"{'fps':>5} {'cpu ms':>6} | {'learn off%':>10} {'on%':>6} {'truth off%':>10} "
              f"{'on%':>6}")
    print(header)
    print("-" * len(header))
    ours_all, base_all, learn_all = [], [], []
    for pattern in PATTERNS:
        for frequency_hz in FREQUENCIES_HZ:
            for seed in range(args.seeds):
                path = demo_dir(args.workdir, pattern, frequency_hz, seed, args.duration)
                ours, csv_path = run_wipelab(path, args.particles,
                                             path.parent / f"{path.name}.track.csv")
                base = run_baseline(path)
                errors = [learned_frequency_error(csv, frequency_hz, mode, args.workdir)
                          for csv in (csv_path, path / "truth.csv")
                          for mode in ("offline", "online")]
                ours_all.append(ours)
                base_all.append(base)
                learn_all.append(errors)
                name = f"{pattern} {frequency_hz:g} Hz s{seed}"
                print(f"{name:<22} | {ours.rms_mm:7.2f}mm {ours.p95_mm:6.2f} "
                      f"{ours.invalid_visible_pct:5.2f} {ours.regain_s:5.2f}s {ours.fps:5.0f} "
                      f"{ours.cpu_ms:6.2f} {ours.main_ms:5.2f} | {base.rms_mm:11.2f}mm "
                      f"{base.p95_mm:6.2f} {base.invalid_visible_pct:5.2f} "
                      f"{base.regain_s:5.2f}s {base.fps:5.0f} {base.cpu_ms:6.2f} "
                      f"| {errors[0]:10.3f} {errors[1]:6.2f} {errors[2]:10.3f} {errors[3]:6.2f}",
                      flush=True)
    print("-" * len(header))

    def summary(runs: list[Run]) -> str:
        rms = np.array([r.rms_mm for r in runs])
        return (f"rms mean {rms.mean():.2f} mm, worst {rms.max():.2f} mm; "
                f"invalid visible frames worst {max(r.invalid_visible_pct for r in runs):.2f} %; "
                f"regain worst {max(r.regain_s for r in runs):.2f} s; "
                f"fps mean {np.mean([r.fps for r in runs]):.0f}, "
                f"CPU {np.mean([r.cpu_ms for r in runs]):.2f} ms per frame pair "
                f"(main thread {np.mean([r.main_ms for r in runs]):.2f} ms)")

    learn_all = np.array(learn_all)
    print(f"wipelab : {summary(ours_all)}")
    print(f"CamShift: {summary(base_all)}")
    print(f"learn frequency error, worst: on track offline {learn_all[:, 0].max():.3f} %, "
          f"online {learn_all[:, 1].max():.2f} %; on truth offline {learn_all[:, 2].max():.3f} %, "
          f"online {learn_all[:, 3].max():.2f} %")


if __name__ == "__main__":
    main()
