"""Adapt/replay benchmark: force-profile learning on flat, bowl and sink; replay at 1x/2x/3x
beside two baselines; simulation speed.

    python benchmarks/bench_adapt.py [--surfaces flat bowl sink] [--periods 3] [--keep DIR]

1. A movement model is learned from a synthetic demonstration (a circular wipe of 10 cm radius
   at 1 Hz, tracked at 30 Hz with 2 mm noise, somewhere in a camera's world frame) with
   ``wipelab learn --mode offline``.
2. The adapt stage on each surface (defaults: F0 = 10 N, |F| feedback, Omega / 4, the unknown
   grasp of the simulator, Y_r = the profile learned so far): periods to convergence, learned
   height against the true contact height (sponge compression at F0 accounted for), force,
   contact, coverage. Beside it, the same with the paper's constant Y_r (``reference =
   "start"``).
3. The replay stage at frequency scales 1, 2 and 3 of each adapted model, all four modes: the
   learned profile alone, with compliance on top, and the baselines compliance alone and the
   planar (unadapted) path; and at 1x and 3x the profiles learned with the paper's Y_r.
4. Speed: simulated seconds per wall-clock second (and per CPU second of the process, which
   the other jobs of a shared machine do not inflate) of the control loop alone (headless, no
   logging; median of three runs) and of each stage with its MCAP/Rerun logging, run in this
   process; and of one whole ``wipelab adapt`` and one whole ``wipelab replay`` command
   (Python start-up, imports and loading the compiled kernels from numba's cache included,
   about 1.7 s whatever the length of the run; CPU of the child process). The loop runs
   first, so the stage rows do not include the one-time kernel loading (the first stage still
   includes Rerun's start-up). The load average is printed with it.

Prints the tables; targets in brackets.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

WIPELAB = [sys.executable, "-c", "from wipelab.cli import main; main()"]
F0 = 10.0


def wipelab(*args: str) -> tuple[float, float]:
    """Run ``wipelab ARGS`` in a new process; returns its wall and CPU time (s)."""
    start, children = time.perf_counter(), resource.getrusage(resource.RUSAGE_CHILDREN)
    done = subprocess.run([*WIPELAB, *args], capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit(f"wipelab {' '.join(args)} failed ({done.returncode}):\n{done.stderr}")
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime + after.ru_stime) - (children.ru_utime + children.ru_stime)
    return time.perf_counter() - start, cpu


def timed(function, *args, **kwargs):
    """(result, wall s, CPU s) of a call."""
    wall, cpu = time.perf_counter(), time.process_time()
    result = function(*args, **kwargs)
    return result, time.perf_counter() - wall, time.process_time() - cpu


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


def loop_speed(model_path: Path, seconds: float = 20.0) -> tuple[float, float]:
    """Sim s per wall s and per CPU s of the control loop alone: compliance + learning on the
    flat table (the learned waveform read at the end of every period, as adapt does), no
    logging."""
    from wipelab.control import COMPARISON_PHASES, ForceProfileLearner
    from wipelab.model_file import read_model
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
        session.move_to(start, 0.8)
        learner = ForceProfileLearner(model.kernels, model.width, model.alpha_s, model.beta_s,
                                      task.start_height, 1.0, session.dt)
        omega = model.omega / 4
        task.world.set_tool_speed(path.max_speed(omega))
        period_end = 2.0 * np.pi
        begin, wall, cpu = session.time, time.perf_counter(), time.process_time()
        while session.time - begin < seconds:
            xy, velocity = path.step(omega, session.dt)
            session.tick(xy, task.start_height, True, path.phase, velocity=np.append(velocity, 0))
            learner.update(session.trace.last("tcp_cmd")[2], path.phase, omega)
            if path.phase >= period_end:
                period_end += 2.0 * np.pi
                learner.waveform(COMPARISON_PHASES)
        return (seconds / (time.perf_counter() - wall), seconds / (time.process_time() - cpu))
    finally:
        task.close()


def speed_row(name: str, sim: float, wall: float, cpu: float) -> list:
    return [name, f"{sim:.1f}", f"{wall:.2f}", f"{sim / wall:.1f}", f"{sim / cpu:.1f}",
            f"{os.getloadavg()[0]:.1f}"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--surfaces", nargs="+", default=["flat", "bowl", "sink"])
    parser.add_argument("--periods", type=int, default=3, help="scored replay periods per run")
    parser.add_argument("--keep", type=Path, default=None, help="keep the outputs here")
    args = parser.parse_args()
    from wipelab.control import ProfileLearningParams
    from wipelab.stages.adapt import AdaptParams, run_adapt
    from wipelab.stages.replay import ReplayParams, run_replay

    work = args.keep or Path(tempfile.mkdtemp(prefix="bench_adapt-"))
    work.mkdir(parents=True, exist_ok=True)
    model_path = learn_model(work)

    loops = [loop_speed(model_path) for _ in range(3)]
    wall_speed = statistics.median(s for s, _ in loops)
    cpu_speed = statistics.median(c for _, c in loops)
    speed_rows = [["control loop alone (headless, no logging; median of 3)", "20.0",
                   f"{20.0 / wall_speed:.2f}", f"{wall_speed:.1f}", f"{cpu_speed:.1f}",
                   f"{os.getloadavg()[0]:.1f}"]]
    learning_rows, replay_rows, paper_rows = [], [], []
    for surface in args.surfaces:
        for reference in ("learned", "start"):
            out = work / f"adapt_{surface}" if reference == "learned" else \
                work / f"adapt_{surface}_paper"
            params = AdaptParams(surface=surface,
                                 learning=ProfileLearningParams(reference=reference))
            m, wall, cpu = timed(run_adapt, model_path, out, params, quiet=True)
            profile, hold = m["profile_last_learning_period"], m["force_hold"] or {}
            learning_rows.append([
                surface, reference, m["learning"]["periods"],
                "yes" if m["learning"]["converged"] else "NO",
                f"{100 * profile['true_height_range_m']:.1f}",
                f"{1000 * profile['rms_height_error_m']:.2f}",
                f"{1000 * profile['mean_height_error_m']:+.2f}",
                f"{1000 * profile['max_height_error_m']:.1f}",
                f"{m['force_last_learning_period']['rms_force_error_n']:.2f}",
                f"{hold.get('rms_force_error_n', float('nan')):.2f}",
                f"{100 * hold.get('contact_fraction', 0):.1f}",
                f"{100 * hold.get('coverage', 0):.0f}", m["safety_stop"] or "-"])
            if reference == "learned":
                speed_rows.append(speed_row(f"adapt {surface} (stage, with logging)",
                                            m["sim_time_s"], wall, cpu))

        paper = run_replay(work / f"adapt_{surface}_paper" / "adapted_model.json",
                           work / f"replay_{surface}_paper",
                           ReplayParams(frequency_scales=(1.0, 3.0),
                                        modes=("learned", "learned+compliance"),
                                        periods=args.periods), quiet=True)
        for scale, runs in paper["scales"].items():
            for mode, run in runs.items():
                paper_rows.append([surface, f"{scale}x", mode,
                                   f"{run.get('rms_force_error_n', float('nan')):.2f}",
                                   f"{100 * run['contact_fraction']:.1f}",
                                   f"{run.get('peak_force_n', float('nan')):.1f}"])

        out_replay = work / f"replay_{surface}"
        r, wall, cpu = timed(run_replay, work / f"adapt_{surface}" / "adapted_model.json",
                             out_replay, ReplayParams(frequency_scales=(1.0, 2.0, 3.0),
                                                      periods=args.periods), quiet=True)
        for scale, runs in r["scales"].items():
            for mode, run in runs.items():
                replay_rows.append([
                    surface, f"{scale}x", mode,
                    f"{run.get('rms_force_error_n', float('nan')):.2f}",
                    f"{100 * run['contact_fraction']:.1f}",
                    f"{run.get('peak_force_n', float('nan')):.1f}",
                    f"{100 * run.get('coverage', 0):.0f}",
                    "stop" if run["safety_stop"] else "-"])
        speed_rows.append(speed_row(f"replay {surface} (stage, with logging)", r["sim_time_s"],
                                    wall, cpu))

    print("Force-profile learning (adapt; RMS/mean/max: learned height vs true contact height "
          "over the last learning period; reference: Y_r while learning, 'start' = the paper's)")
    print(table(["surface", "reference", "periods [<=5]", "converged",
                 "true dz/period cm [>=3 flat]", "RMS mm [<=3]", "mean mm", "max mm",
                 "|F|-F0 RMS learning N", "|F|-F0 RMS hold N", "contact %", "coverage %",
                 "safety stop"], learning_rows))
    print(f"\nReplay (F0 = {F0:g} N; targets for the learned profile: RMS <= 2 N at 1x, <= 3 N at "
          f"3x, contact >= 99 %, peak <= {3 * F0:g} N)")
    print(table(["surface", "scale", "mode", "RMS(|F|-F0) N", "contact %", "peak N",
                 "coverage %", "safety"], replay_rows))

    print("\nReplay of the profiles learned with the paper's constant Y_r (reference 'start')")
    print(table(["surface", "scale", "mode", "RMS(|F|-F0) N", "contact %", "peak N"],
                paper_rows))

    out = work / "adapt_cli"
    wall, cpu = wipelab("adapt", str(model_path), "-o", str(out), "--surface", "flat", "-q")
    sim = json.loads((out / "metrics.json").read_text())["sim_time_s"]
    speed_rows.append(speed_row(f"wipelab adapt flat (whole command, {os.cpu_count()} CPUs)",
                                sim, wall, cpu))
    replayed = work / "replay_cli"
    wall, cpu = wipelab("replay", str(out / "adapted_model.json"), "-o", str(replayed),
                        "--surface", "flat", "-q")
    sim = json.loads((replayed / "metrics.json").read_text())["sim_time_s"]
    speed_rows.append(speed_row(f"wipelab replay flat 1x 2x 3x (whole command, "
                                f"{os.cpu_count()} CPUs)", sim, wall, cpu))
    print("\nSpeed (simulated s per wall-clock s [>= 10, aim 50]; per CPU s of the process "
          "that ran it)")
    print(table(["run", "sim s", "wall s", "sim/wall", "sim/CPU", "load avg"], speed_rows))
    if args.keep is None:
        shutil.rmtree(work)


if __name__ == "__main__":
    main()
