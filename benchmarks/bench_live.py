"""Benchmark of ``wipelab live``: keeping up with the video, the robot following the person,
tempo changes, the end result against the batch pipeline, and speed.

Demos
-----
* **synth**: ``wipelab synth`` demonstrations (circle 1 Hz, line 0.8 Hz, figure8 1.2 Hz;
  30 s; the sponge's size known from demo.toml);
* **held out**: scenes of the independent generator (``tests/stereo_scenes``, no code shared
  with synth) with seeds from 10000 on, which nobody looks at while tuning (32 s; random
  colour, codec, frame rate, cameras, occlusions; ``--color`` names the sponge's colour);
* **tempo**: synth circles at 1 Hz whose tempo steps by +30 % or -30 % (x 1/1.3) at 15 s, the
  tempo otherwise steady (the other demos' wanders by 4 %).

Tables
------
(a) real time: ``--speed 1`` with the viewer streaming to a file sink (``rerun --save``, a
    second process receiving the gRPC stream, as a viewer would): frames, dropped and late
    (%), latency p50 / p99 from a frame's arrival to the robot's command, over every frame
    and over the frames the robot imitated with, real-time factor and busy fraction of the
    whole session (imitation, then the robot alone);
(b) following (same runs): periods from the first tracked frame, and from the start of the
    movement in truth.csv, until the robot's hand follows the demonstration's normalised
    movement (:mod:`wipelab.live.following`), its lag (s) and steady RMS (% of p-p);
(c) tempo steps (a steady person: no tempo wander, one step): periods after the step until
    the model frequency, and the fundamental the robot's phase runs at, are within 1 % of the
    new tempo for good (learn's criterion in ``bench_learn.py``);
(d) against the batch pipeline on the same demo (``track`` -> ``learn`` -> ``adapt`` ->
    ``replay --frequency-scale 1 --mode learned``; live with ``--no-stop-on-convergence`` so
    that both see the whole demonstration, ``--replay-scale 1``): the model frequency's
    difference, and RMS(|F| - F0) of the adapted model wiping at the demonstrated tempo;
(e) ``--speed max``: frame-loop frames per second, the whole command's wall time, and
    whether a rerun writes the same bytes.

Usage::

    python benchmarks/bench_live.py [--held-out 4] [--workdir DIR] [--quick]
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from tests.stereo_scenes import HELD_OUT_SEEDS_FROM, render_scene  # noqa: E402
from wipelab.learning.signals import periods_to_tolerance  # noqa: E402
from wipelab.logs import read_mcap_scalars  # noqa: E402
from wipelab.pipeline.recordings import rerun_program  # noqa: E402
from wipelab.stages.synth import SynthParams, synth  # noqa: E402
from wipelab.trajectory_csv import read_trajectory  # noqa: E402

WIPELAB = [sys.executable, "-m", "wipelab"]
SYNTH = (("circle", 1.0, 1), ("line", 0.8, 2), ("figure8", 1.2, 3))
PATTERNS = ("circle", "line", "figure8")
TEMPO_STEP_S = 15.0
#: The model frequency is "following" the new tempo within this (relative).
TEMPO_TOLERANCE = 0.01


@dataclass
class Demo:
    name: str
    kind: str
    path: Path
    colour: str | None
    frequency_hz: float          # nominal (after the step for a tempo demo)
    step: tuple[float, float] | None = None


def synth_demo(workdir: Path, pattern: str, frequency_hz: float, seed: int,
               step: tuple[float, float] | None = None) -> Demo:
    name = f"synth {pattern} {frequency_hz:g}Hz" + ("" if step is None else
                                                    f" x{step[1]:.2f}@{step[0]:g}s")
    path = workdir / (name.replace(" ", "_") + ("_steady" if step else ""))
    if not (path / "truth.csv").is_file():
        synth(path, SynthParams(pattern=pattern, frequency_hz=frequency_hz, duration=30.0,
                                seed=seed, tempo_step=step,
                                speed_variation=0.0 if step else 0.04), quiet=True)
    return Demo(name, "tempo" if step else "synth", path, None,
                frequency_hz * (step[1] if step else 1.0), step)


def held_out_demo(workdir: Path, index: int) -> Demo:
    seed = HELD_OUT_SEEDS_FROM + index
    pattern = PATTERNS[index % 3]
    frequency = round(0.5 + (index * 3 % 8) / 7.0, 3)
    path = workdir / f"heldout_{seed}_{pattern}_{frequency:g}hz"
    if not (path / "scene.json").is_file():
        render_scene(path, seed, duration=32.0, pattern=pattern, frequency_hz=frequency)
    colour = json.loads((path / "scene.json").read_text())["sponge"]["colour"]
    return Demo(f"{seed} {pattern} {frequency:g}Hz", "held out", path, colour, frequency)


def command(demo: Demo, out: Path, *options: str) -> list[str]:
    colour = ["--color", demo.colour] if demo.colour else []
    return [*WIPELAB, "live", str(demo.path), "-o", str(out), "-q", *colour, *options]


def run(argv: list[str]) -> tuple[float, subprocess.CompletedProcess]:
    start = time.perf_counter()
    done = subprocess.run(argv, capture_output=True, text=True)
    return time.perf_counter() - start, done


def metrics_of(out: Path) -> dict | None:
    path = out / "metrics.json"
    return json.loads(path.read_text()) if path.is_file() else None


def motion_start(demo: Demo) -> float:
    """When the sponge starts to move in truth.csv (s): its speed first above a fifth of its
    median."""
    truth = read_trajectory(demo.path / "truth.csv", required=("t", "x", "y"))
    speed = np.linalg.norm(np.diff(truth.array(["x", "y"]), axis=0), axis=1)
    return float(truth.t[1:][np.argmax(speed > 0.2 * np.median(speed))])


def realtime_run(demo: Demo, workdir: Path, port: int) -> dict | None:
    """--speed 1, streaming to ``rerun --save`` listening on ``port``."""
    out = workdir / "realtime" / demo.path.name
    shutil.rmtree(out, ignore_errors=True)
    sink = workdir / "realtime" / f"{demo.path.name}.stream.rrd"
    receiver = subprocess.Popen([rerun_program(), "--port", str(port), "--save", str(sink)],
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                start_new_session=True)
    try:
        time.sleep(2.0)
        _, done = run(command(demo, out, "--viewer", f"connect={port}",
                              "--no-stop-on-convergence"))
    finally:
        os.killpg(receiver.pid, signal.SIGTERM)
        receiver.wait(10)
    if done.returncode != 0:
        print(f"  {demo.name}: {done.stderr.strip().splitlines()[-1]}", flush=True)
        return None
    metrics = metrics_of(out)
    metrics["stream_mb"] = sink.stat().st_size / 1e6 if sink.is_file() else 0.0
    metrics["out"] = out
    return metrics


def tempo_periods(demo: Demo, out: Path) -> tuple[float, float]:
    """Periods after the step until the model frequency and the fundamental stay within
    TEMPO_TOLERANCE of the new tempo."""
    results = []
    for topic in ("/oscillators/model_frequency_hz", "/oscillators/fundamental_hz"):
        t, values, _ = read_mcap_scalars(out / "live.mcap", topic)
        results.append(periods_to_tolerance(t, values[:, 0], demo.frequency_hz,
                                            start_s=demo.step[0], tolerance=TEMPO_TOLERANCE))
    return results[0], results[1]


def batch_pipeline(demo: Demo, workdir: Path) -> tuple[float, float] | None:
    """(model frequency Hz, replay RMS(|F| - F0) at 1x, mode learned) of the batch stages."""
    out = workdir / "batch" / demo.path.name
    shutil.rmtree(out, ignore_errors=True)
    colour = ["--color", demo.colour] if demo.colour else []
    steps = [["track", str(demo.path), "-o", str(out / "track"), *colour],
             ["learn", str(out / "track" / "track.csv"), "-o", str(out / "learn")],
             ["adapt", str(out / "learn" / "model.json"), "-o", str(out / "adapt")],
             ["replay", str(out / "adapt" / "adapted_model.json"), "-o", str(out / "replay"),
              "--frequency-scale", "1", "--mode", "learned"]]
    for step in steps:
        _, done = run([*WIPELAB, *step, "-q"])
        if done.returncode != 0:
            print(f"  batch {demo.name}: {done.stderr.strip().splitlines()[-1]}", flush=True)
            return None
    model = json.loads((out / "learn" / "model.json").read_text())
    replay = json.loads((out / "replay" / "metrics.json").read_text())
    return model["frequency_hz"], replay["scales"]["1"]["learned"]["rms_force_error_n"]


def max_speed_runs(demo: Demo, workdir: Path) -> tuple[float, float, bool] | None:
    """(frame-loop frames/s, whole command s, a rerun writes the same bytes)."""
    outs = [workdir / "max" / f"{demo.path.name}_{k}" for k in (1, 2)]
    walls, rates = [], []
    for out in outs:
        shutil.rmtree(out, ignore_errors=True)
        wall, done = run([a for a in command(demo, out, "--speed", "max") if a != "-q"])
        if done.returncode != 0:
            return None
        walls.append(wall)
        rates.append(float(done.stdout.split(" frames/s")[0].rsplit(" ", 1)[-1]))
    same = all((outs[0] / p.name).read_bytes() == (outs[1] / p.name).read_bytes()
               for p in outs[0].iterdir())
    return max(rates), min(walls), same


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--held-out", type=int, default=4, help="held-out scenes")
    parser.add_argument("--quick", action="store_true", help="one demo of each kind")
    parser.add_argument("--port", type=int, default=9931, help="port of the stream's receiver")
    parser.add_argument("--workdir", type=Path,
                        default=Path(tempfile.gettempdir()) / "wipelab-bench-live",
                        help="where demos are rendered (and reused by later runs)")
    args = parser.parse_args()
    args.workdir.mkdir(parents=True, exist_ok=True)
    synths = SYNTH[:1] if args.quick else SYNTH
    demos = [synth_demo(args.workdir, p, f, s) for p, f, s in synths]
    demos += [held_out_demo(args.workdir, i) for i in range(1 if args.quick else args.held_out)]
    steps = ((TEMPO_STEP_S, 1.3),) if args.quick else ((TEMPO_STEP_S, 1.3),
                                                        (TEMPO_STEP_S, 1 / 1.3))
    demos += [synth_demo(args.workdir, "circle", 1.0, 4, step) for step in steps]

    print(f"load average at start: {' '.join(f'{v:.1f}' for v in os.getloadavg())} on "
          f"{os.cpu_count()} cores")
    print("\n(a) real time (--speed 1, viewer streaming to `rerun --save`) and (b) following")
    header = (f"{'demo':<30} | {'frames':>6} {'drop%':>5} {'late%':>5} {'p50':>5} {'p99':>6} "
              f"{'p50i':>5} {'p99i':>6} {'RTF':>5} {'busy':>4} | {'P(trk)':>6} {'P(mov)':>6} "
              f"{'lag s':>5} {'rms%':>5} | {'stop':<16}")
    print(header + "\n" + "-" * len(header))
    realtime = {}
    for demo in demos:
        m = realtime_run(demo, args.workdir, args.port)
        if m is None:
            continue
        realtime[demo.name] = m
        timing, following = m["timing"], m["following"]
        everything, imitating = timing["latency_ms"], timing["latency_imitating_ms"]
        from_motion = (None if following["follows_from_s"] is None else
                       (following["follows_from_s"] - motion_start(demo))
                       * m["imitation"]["frequency_hz"])
        print(f"{demo.name:<30} | {timing['frames']:6d} {100 * timing['dropped_fraction']:5.1f} "
              f"{100 * timing['late_fraction']:5.1f} {everything['p50']:5.1f} "
              f"{everything['p99']:6.1f} {imitating['p50']:5.1f} {imitating['p99']:6.1f} "
              f"{timing['real_time_factor']:5.3f} {timing['busy_fraction']:4.2f} | "
              f"{_number(following['periods_until_following']):>6} {_number(from_motion):>6} "
              f"{following['lag_s']:5.2f} {_number(following['steady_rms'], 100):>5} | "
              f"{m['imitation']['stop_reason']:<16}", flush=True)
    print(f"load average now: {' '.join(f'{v:.1f}' for v in os.getloadavg())}")

    print(f"\n(c) tempo steps at {TEMPO_STEP_S:g} s: periods after the step until within "
          f"{100 * TEMPO_TOLERANCE:g} % of the new tempo for good")
    print(f"{'demo':<30} | {'model frequency':>15} {'fundamental':>11}")
    for demo in (d for d in demos if d.step and d.name in realtime):
        model_p, fundamental_p = tempo_periods(demo, realtime[demo.name]["out"])
        print(f"{demo.name:<30} | {model_p:15.2f} {fundamental_p:11.2f}", flush=True)

    print("\n(d) against the batch pipeline (track -> learn -> adapt -> replay 1x learned)")
    print(f"{'demo':<30} | {'f live Hz':>9} {'f batch':>8} {'diff %':>6} | "
          f"{'RMS live N':>10} {'RMS batch':>9}")
    for demo in (d for d in demos if d.kind != "tempo" and d.name in realtime):
        batch = batch_pipeline(demo, args.workdir)
        m = realtime[demo.name]
        if batch is None or "replay" not in m:
            continue
        f_live, f_batch = m["imitation"]["frequency_hz"], batch[0]
        print(f"{demo.name:<30} | {f_live:9.4f} {f_batch:8.4f} "
              f"{100 * (f_live - f_batch) / f_batch:6.2f} | "
              f"{m['replay']['rms_force_error_n']:10.2f} {batch[1]:9.2f}", flush=True)

    print("\n(e) --speed max")
    print(f"{'demo':<30} | {'frames/s':>8} {'command s':>9} {'rerun identical':>15}")
    for demo in demos[:len(synths) + (1 if args.quick else args.held_out)]:
        result = max_speed_runs(demo, args.workdir)
        if result is not None:
            print(f"{demo.name:<30} | {result[0]:8.0f} {result[1]:9.1f} {str(result[2]):>15}",
                  flush=True)
    print(f"load average at the end: {' '.join(f'{v:.1f}' for v in os.getloadavg())}")


def _number(value, scale: float = 1.0) -> str:
    return "-" if value is None else f"{scale * value:.2f}"


if __name__ == "__main__":
    main()
