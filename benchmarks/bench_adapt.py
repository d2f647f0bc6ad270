"""Adapt/replay benchmark: force-profile learning on flat, bowl and sink; replay at 1x/2x/3x
beside two baselines; simulation speed.

    python benchmarks/bench_adapt.py [--surfaces flat bowl sink] [--periods 3] [--keep DIR]

1. A movement model is learned from a synthetic demonstration (a circular wipe of 10 cm radius
   at 1 Hz, tracked at 30 Hz with 2 mm noise, somewhere in a camera's world frame) with
   ``wipelab learn --mode offline``.
2. ``wipelab adapt`` on each surface (defaults: F0 = 10 N, |F| feedback, Omega / 4, the
   unknown grasp of the simulator): periods to convergence, learned height against the true
   contact height (sponge compression at F0 accounted for), force, contact, coverage.
3. ``wipelab replay --frequency-scale 1 2 3`` of each adapted model, all four modes: the
   learned profile alone, with compliance on top, and the baselines compliance alone and the
   planar (unadapted) path.
4. Speed: simulated seconds per wall-clock second of the control loop alone (headless, no
   logging) and of each stage end to end (with MCAP/Rerun logging).

Prints the tables; targets in brackets.
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
WIPELAB = [sys.executable, "-c", "from wipelab.cli import main; main()"]
F0 = 10.0


def wipelab(*args: str) -> float:
    """Run ``wipelab ARGS`` in a new process; returns the wall time (s)."""
    start = time.perf_counter()
    done = subprocess.run([*WIPELAB, *args], capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit(f"wipelab {' '.join(args)} failed ({done.returncode}):\n{done.stderr}")
    return time.perf_counter() - start


def table(header: list[str], rows: list[list]) -> str:
    widths = [max(len(str(r[i])) for r in [header, *rows]) for i in range(len(header))]
    line = lambda cells: "  ".join(str(c).rjust(w) if i else str(c).ljust(w)
                                   for i, (c, w) in enumerate(zip(cells, widths)))
    return "\n".join([line(header), line(["-" * w for w in widths]), *map(line, rows)])


def demonstration(path: Path) -> None:
    rng = np.random.default_rng(0)
    t = np.arange(0.0, 10.0, 1 / 30)
    phase = 2 * np.pi * 1.0 * t
    xy = np.column_stack([1.3 + 0.1 * np.cos(phase), 0.4 + 0.1 * np.sin(phase)])
    xy += rng.normal(scale=0.002, size=xy.shape)
    rows = "\n".join(f"{a:.4f},{b:.5f},{c:.5f}" for a, (b, c) in zip(t, xy))
    path.write_text("t,x,y\n" + rows + "\n")


def learn_model(work: Path) -> Path:
    """The learn stage's model of the synthetic demonstration (``wipelab learn``)."""
    csv = work / "demo.csv"
    demonstration(csv)
    wipelab("learn", str(csv), "-o", str(work / "learn"), "--mode", "offline")
    return work / "learn" / "model.json"


def loop_speed(model_path: Path, seconds: float = 30.0) -> float:
    """Sim s per wall s of the control loop alone: compliance + learning on the flat table."""
    from wipelab.control import ForceProfileLearner
    from wipelab.sim.model_file import read_model
    from wipelab.sim.path import PathGenerator, place_model
    from wipelab.sim.surfaces import load_surface
    from wipelab.sim.task import CALIBRATION_LIFT, TaskOptions, build_task

    surface = load_surface("flat")
    model = place_model(read_model(model_path), surface.wipe_center)
    task = build_task(model, surface, TaskOptions())
    try:
        session, path = task.session, PathGenerator(model, ("x", "y"))
        start = np.array([*path.position, task.start_height])
        session.move_to(start + [0, 0, CALIBRATION_LIFT], 1.0)
        session.calibrate()
        learner = ForceProfileLearner(model.kernels, model.width, model.alpha_s, model.beta_s,
                                      task.start_height, 1.0, session.dt)
        omega = model.omega / 4
        begin, wall = session.time, time.perf_counter()
        while session.time - begin < seconds:
            xy, acceleration = path.step(omega, session.dt)
            session.tick(xy, task.start_height, True, path.phase, np.append(acceleration, 0))
            learner.update(session.trace.last("tcp_cmd")[2], path.phase, omega)
        return seconds / (time.perf_counter() - wall)
    finally:
        task.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--surfaces", nargs="+", default=["flat", "bowl", "sink"])
    parser.add_argument("--periods", type=int, default=3, help="scored replay periods per run")
    parser.add_argument("--keep", type=Path, default=None, help="keep the outputs here")
    args = parser.parse_args()
    work = args.keep or Path(tempfile.mkdtemp(prefix="bench_adapt-"))
    work.mkdir(parents=True, exist_ok=True)
    model_path = learn_model(work)

    learning_rows, replay_rows, speed_rows = [], [], []
    for surface in args.surfaces:
        out = work / f"adapt_{surface}"
        wall = wipelab("adapt", str(model_path), "-o", str(out), "--surface", surface, "-q")
        m = json.loads((out / "metrics.json").read_text())
        profile, hold = m["profile_last_learning_period"], m["force_hold"] or {}
        learning_rows.append([
            surface, m["feedback"], m["learning"]["periods"],
            "yes" if m["learning"]["converged"] else "NO",
            f"{100 * profile['true_height_range_m']:.1f}",
            f"{1000 * profile['rms_height_error_m']:.2f}",
            f"{1000 * profile['max_height_error_m']:.1f}",
            f"{hold.get('rms_force_error_n', float('nan')):.2f}",
            f"{100 * hold.get('contact_fraction', 0):.1f}",
            f"{100 * hold.get('coverage', 0):.0f}", m["safety_stop"] or "-"])
        speed_rows.append([f"adapt {surface} (end to end)", f"{m['sim_time_s']:.1f}",
                           f"{wall:.1f}", f"{m['sim_time_s'] / wall:.1f}"])

        out_replay = work / f"replay_{surface}"
        wall = wipelab("replay", str(out / "adapted_model.json"), "-o", str(out_replay),
                       "--frequency-scale", "1", "2", "3", "--periods", str(args.periods), "-q")
        r = json.loads((out_replay / "metrics.json").read_text())
        for scale, runs in r["scales"].items():
            for mode, run in runs.items():
                replay_rows.append([
                    surface, f"{scale}x", mode,
                    f"{run.get('rms_force_error_n', float('nan')):.2f}",
                    f"{100 * run['contact_fraction']:.1f}",
                    f"{run.get('peak_force_n', float('nan')):.1f}",
                    f"{100 * run.get('coverage', 0):.0f}",
                    "stop" if run["safety_stop"] else "-"])
        speed_rows.append([f"replay {surface} (end to end)", f"{r['sim_time_s']:.1f}",
                           f"{wall:.1f}", f"{r['sim_time_s'] / wall:.1f}"])

    print("Force-profile learning (adapt; RMS/max: learned height vs true contact height over "
          "the last learning period)")
    print(table(["surface", "feedback", "periods", "converged", "true dz/period cm [>=3 flat]",
                 "RMS mm [<=3]", "max mm", "|F|-F0 RMS N", "contact %", "coverage %",
                 "safety stop"], learning_rows))
    print(f"\nReplay (F0 = {F0:g} N; targets for the learned profile: RMS <= 2 N at 1x, <= 3 N at "
          f"3x, contact >= 99 %, peak <= {3 * F0:g} N)")
    print(table(["surface", "scale", "mode", "RMS(|F|-F0) N", "contact %", "peak N",
                 "coverage %", "safety"], replay_rows))
    speed = loop_speed(model_path)
    speed_rows.insert(0, ["control loop alone (headless, no logging)", "30.0",
                          f"{30.0 / speed:.1f}", f"{speed:.1f}"])
    print("\nSpeed (simulated s per wall-clock s) [>= 10, aim 50]")
    print(table(["run", "sim s", "wall s", "sim/wall"], speed_rows))
    if args.keep is None:
        shutil.rmtree(work)


if __name__ == "__main__":
    main()
