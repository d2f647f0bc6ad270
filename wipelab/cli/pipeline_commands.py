"""``wipelab run``, ``dataset``, ``synth-dataset``, ``report`` and ``view``: stages composed.

Only wiring: the work is in :mod:`wipelab.pipeline`. Heavy libraries (matplotlib, Dask,
Rerun) are imported inside the commands that need them, so that ``wipelab run`` on a fully
cached pipeline starts fast.
"""

from __future__ import annotations

import sys
from pathlib import Path

import click

from wipelab.cli.options import (FRAME_RATE, JOBS, OUTPUT_DIR, OUTPUT_FILE, PATH,
                                  SYNTH_DURATION_S, SYNTH_FREQUENCY_HZ)



@click.command("run")
@click.argument("pipeline_file", type=PATH)
@click.option("-o", "--output", "run_dir", type=OUTPUT_DIR, default=None,
              help="Run directory [default: runs/<pipeline name>].")
@click.option("--set", "sets", multiple=True, metavar="STAGE.KEY=VALUE",
              help="Override a stage parameter, e.g. --set learn.kernels=30 (repeatable).")
@click.option("--input", "inputs", multiple=True, metavar="[NAME=]PATH",
              help="Replace a named input of the pipeline, e.g. --input demo=my_demo.")
@click.option("--force", is_flag=True, help="Run every stage even when its cache holds.")
@click.option("-q", "--quiet", is_flag=True, help="Print nothing but errors.")
@click.pass_context
def run(ctx: click.Context, pipeline_file: Path, run_dir: Path | None, sets: tuple[str, ...],
        inputs: tuple[str, ...], force: bool, quiet: bool) -> None:
    """Run the stages of PIPELINE_FILE (TOML), reusing those whose inputs, parameters and
    code are unchanged.

    Each stage writes into RUN_DIR/<stage>/. An interrupted run keeps the stages it
    finished; run the same command again to resume.
    """
    from wipelab.pipeline.runner import run_pipeline
    from wipelab.pipeline.spec import load_pipeline

    pipeline = load_pipeline(pipeline_file).with_overrides(sets=sets, inputs=inputs)
    run_dir = run_dir if run_dir is not None else Path("runs") / pipeline.name
    try:
        run_pipeline(pipeline, run_dir, quiet=quiet, force=force,
                     echo=lambda line: click.echo(line, err=True))
    except KeyboardInterrupt:
        click.echo(f"interrupted: finished stages are kept in {run_dir}; run the same "
                   f"command again to resume", err=True)
        ctx.exit(130)


@click.command("dataset")
@click.argument("data_dir", type=PATH)
@click.option("--pipeline", "pipeline_file", type=PATH, required=True,
              help="Pipeline TOML with one [inputs] entry, replaced by each demo directory.")
@click.option("-j", "--jobs", type=JOBS, default=1, show_default=True,
              help="Demos processed in parallel on this machine.")
@click.option("--scheduler", metavar="ADDRESS", default=None,
              help="Dask distributed scheduler, e.g. tcp://127.0.0.1:8786 (instead of -j).")
@click.option("-o", "--output", "out_dir", type=OUTPUT_DIR, default=None,
              help="Output directory: summary.csv and runs/<demo>/ [default: runs/dataset-<name>].")
@click.option("--set", "sets", multiple=True, metavar="STAGE.KEY=VALUE",
              help="Override a stage parameter for every demo (repeatable).")
@click.option("-q", "--quiet", is_flag=True, help="Print only the summary table.")
@click.pass_context
def dataset(ctx: click.Context, data_dir: Path, pipeline_file: Path, jobs: int,
            scheduler: str | None, out_dir: Path | None, sets: tuple[str, ...],
            quiet: bool) -> None:
    """Run a pipeline over every demo directory under DATA_DIR and tabulate the metrics.

    Writes OUT/summary.csv (one row per demo). A failing demo is reported and the others go
    on; the exit code is 1 when any demo failed.
    """
    from tqdm import tqdm

    from wipelab.pipeline.dataset import (dataset_tasks, format_summary, run_dataset,
                                          write_summary_csv)
    from wipelab.output_location import check_output_dir
    from wipelab.pipeline.spec import load_pipeline

    pipeline = load_pipeline(pipeline_file).with_overrides(sets=sets)
    out_dir = check_output_dir(out_dir if out_dir is not None
                               else Path("runs") / f"dataset-{pipeline.name}")
    tasks = dataset_tasks(pipeline, data_dir, out_dir)
    with tqdm(total=len(tasks), unit="demo", desc="dataset", disable=quiet) as bar:
        def on_result(result) -> None:
            bar.update(1)
            if not result.ok and not quiet:
                bar.write(f"failed {result.demo}: {result.error}", file=sys.stderr)

        results = run_dataset(tasks, jobs=jobs, scheduler=scheduler, on_result=on_result)
    summary = out_dir / "summary.csv"
    write_summary_csv(summary, results)
    click.echo(format_summary(results))
    failed = [result.demo for result in results if not result.ok]
    if not quiet:
        click.echo(f"{len(results) - len(failed)} of {len(results)} demos ok; summary: "
                   f"{summary}", err=True)
    if failed:
        ctx.exit(1)


@click.command("report")
@click.argument("run_dir", type=PATH)
@click.option("-o", "--output", "out_dir", type=OUTPUT_DIR, default=None,
              help="Where to write the figures [default: RUN_DIR/report].")
def report(run_dir: Path, out_dir: Path | None) -> None:
    """Draw PNG figures of a run (cf. the paper's Figs. 4-7) and a markdown summary."""
    from wipelab.pipeline.report import write_report

    out_dir = write_report(run_dir, out_dir)
    for path in sorted(out_dir.iterdir()):
        click.echo(path)


@click.command("synth-dataset")
@click.argument("out_dir", type=OUTPUT_DIR)
@click.option("--pattern", "patterns", multiple=True, default=("circle", "line", "figure8"),
              show_default=True, help="Wiping pattern (repeatable).")
@click.option("--frequency", "frequencies_hz", multiple=True, type=SYNTH_FREQUENCY_HZ,
              default=(1.0,), show_default=True, metavar="HZ",
              help="Wiping frequency in Hz (repeatable).")
@click.option("--seed", "seeds", multiple=True, type=int, default=(0,), show_default=True,
              help="Random seed (repeatable).")
@click.option("--duration", type=SYNTH_DURATION_S, default=20.0, show_default=True,
              metavar="S", help="Length of each demo, seconds.")
@click.option("--fps", type=FRAME_RATE, default=30, show_default=True, help="Frame rate.")
@click.option("-j", "--jobs", type=JOBS, default=1, show_default=True,
              help="Demos rendered in parallel.")
@click.option("-q", "--quiet", is_flag=True, help="No progress bar.")
def synth_dataset(out_dir: Path, patterns: tuple[str, ...], frequencies_hz: tuple[float, ...],
                  seeds: tuple[int, ...], duration: float, fps: int, jobs: int,
                  quiet: bool) -> None:
    """Render a synthetic data set: one demo per pattern x frequency x seed, in OUT_DIR.

    Demos already complete are kept. Process it with `wipelab dataset OUT_DIR --pipeline ...`.
    """
    from tqdm import tqdm

    from wipelab.pipeline.synth_grid import grid_points, missing_points, synth_grid

    points = grid_points(patterns, frequencies_hz, seeds)
    done = len(points) - len(missing_points(out_dir, points))
    with tqdm(total=len(points), initial=done, unit="demo", desc="synth-dataset",
              disable=quiet) as bar:
        demos = synth_grid(out_dir, points, duration, fps, jobs=jobs,
                           on_done=lambda path: bar.update(1))
    click.echo(f"{len(demos)} demos in {out_dir}")


@click.command("view")
@click.argument("path", type=PATH)
@click.option("--save", type=OUTPUT_FILE, default=None,
              help="Write all the recordings (each stage's, with its layout) into this one .rrd "
                   "and exit.")
@click.option("--web", is_flag=True, help="Serve a web viewer instead (works without a display).")
@click.option("--port", type=click.IntRange(1, 65535), default=None,
              help="Port of the viewer's server [default: Rerun's, 9876; a viewer already "
                   "listening there gets the recordings].")
@click.option("--web-port", type=click.IntRange(1, 65535), default=None,
              help="With --web: port of the web page [default: Rerun's, 9090].")
@click.pass_context
def view(ctx: click.Context, path: Path, save: Path | None, web: bool, port: int | None,
         web_port: int | None) -> None:
    """Open the Rerun recordings (.rrd) of a run directory, stage folder or file.

    Every stage opens as a recording of its own, with its own layout and clock, in one
    viewer (its left panel lists them). The native viewer plays the stereo videos with the
    `ffmpeg` program. Without a display it says how to open them instead.
    """
    from wipelab.pipeline.recordings import (find_recordings, has_display, how_to_open,
                                             run_program, save_recordings, terminated_as_exit,
                                             viewer_argv)

    recordings = find_recordings(path)
    with terminated_as_exit():
        if save is not None:
            save_recordings(recordings, save)
            click.echo(f"wrote {save}: {len(recordings)} recording(s)")
            return
        if not web and not has_display():
            click.echo(how_to_open(recordings, path))
            return
        ctx.exit(run_program(viewer_argv(recordings, web=web, port=port, web_port=web_port)))
