"""Pipeline benchmark: the quickstart per stage, a cached rerun, and a data set at -j 1 vs -j 2.

    python benchmarks/bench_pipeline.py [--demos 10] [--duration 12] [--keep DIR]

1. ``wipelab run pipelines/quickstart.toml`` from scratch: wall time per stage, then the
   same command again (fully cached) timed as a user sees it (a new process).
2. ``wipelab synth-dataset`` renders N short demos (circle and line at 0.6, 0.8, ... Hz),
   then ``wipelab dataset`` processes them with ``pipelines/dataset.toml`` at -j 1 and at
   -j 2, each from scratch: wall time and speed-up.

Prints two tables. Everything runs through the ``wipelab`` command, as a user would.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
WIPELAB = [sys.executable, "-c", "from wipelab.cli import main; main()"]


def wipelab(*args: str, check: bool = True) -> tuple[float, subprocess.CompletedProcess]:
    """Run ``wipelab ARGS`` in a new process; returns (wall seconds, completed process)."""
    start = time.perf_counter()
    done = subprocess.run([*WIPELAB, *args], capture_output=True, text=True)
    seconds = time.perf_counter() - start
    if check and done.returncode != 0:
        sys.exit(f"wipelab {' '.join(args)} failed ({done.returncode}):\n{done.stderr}")
    return seconds, done


def table(header: list[str], rows: list[list[str]]) -> str:
    widths = [max(len(str(r[i])) for r in [header, *rows]) for i in range(len(header))]
    line = lambda cells: "  ".join(str(c).rjust(w) if i else str(c).ljust(w)
                                   for i, (c, w) in enumerate(zip(cells, widths)))
    return "\n".join([line(header), line(["-" * w for w in widths]), *map(line, rows)])


def bench_quickstart(work: Path) -> str:
    run_dir = work / "quickstart"
    total, _ = wipelab("run", str(ROOT / "pipelines" / "quickstart.toml"), "-o", str(run_dir),
                       "-q")
    rows = []
    for stage_dir in sorted(run_dir.iterdir(), key=lambda d: d.stat().st_mtime_ns):
        record = stage_dir / ".wipelab-stage.json"
        if record.is_file():
            data = json.loads(record.read_text())
            rows.append([data["stage"], data["command"], f"{data['seconds']:.1f}"])
    cached, done = wipelab("run", str(ROOT / "pipelines" / "quickstart.toml"), "-o",
                           str(run_dir))
    reused = sum("(cache hit)" in line for line in done.stderr.splitlines())
    rows += [["(all, fresh)", "wipelab run", f"{total:.1f}"],
             [f"(all, rerun: {reused} of {len(rows)} reused)", "wipelab run", f"{cached:.2f}"]]
    return table(["stage", "command", "wall s"], rows)


def bench_dataset(work: Path, demos: int, duration: float) -> str:
    data = work / "synthetic"
    frequencies = [f"{0.6 + 0.2 * k:g}" for k in range((demos + 1) // 2)]
    wipelab("synth-dataset", str(data), "--pattern", "circle", "--pattern", "line",
            *[arg for f in frequencies for arg in ("--frequency", f)],
            "--duration", str(duration), "-j", "2", "-q")
    for extra in sorted(d for d in data.iterdir() if not d.name.startswith("."))[demos:]:
        shutil.rmtree(extra)
    rows, base = [], None
    for jobs in (1, 2):
        out = work / f"dataset-j{jobs}"
        seconds, _ = wipelab("dataset", str(data), "--pipeline",
                             str(ROOT / "pipelines" / "dataset.toml"), "-j", str(jobs),
                             "-o", str(out), "-q", check=False)
        with open(out / "summary.csv") as f:
            statuses = [row["status"] for row in csv.DictReader(f)]
        base = base or seconds
        rows.append([f"-j {jobs}", str(len(statuses)), str(statuses.count("ok")),
                     f"{seconds:.1f}", f"{base / seconds:.2f}"])
    return table(["jobs", "demos", "ok", "wall s", "speed-up"], rows)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--demos", type=int, default=10)
    parser.add_argument("--duration", type=float, default=12.0, help="seconds per demo")
    parser.add_argument("--keep", type=Path, default=None, help="work here and keep the files")
    args = parser.parse_args()
    work = args.keep or Path(tempfile.mkdtemp(prefix="wipelab-bench-"))
    work.mkdir(parents=True, exist_ok=True)
    try:
        print(f"machine: {os.cpu_count()} cores, Python {sys.version.split()[0]}\n")
        print("Quickstart pipeline (pipelines/quickstart.toml), wall time per stage")
        print(bench_quickstart(work), "\n")
        print(f"Data set of {args.demos} synthetic demos ({args.duration:g} s each), "
              f"pipelines/dataset.toml")
        print(bench_dataset(work, args.demos, args.duration))
    finally:
        if args.keep is None:
            shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
