"""``wipelab learn`` and ``wipelab rollout``: wiring only; the work is in wipelab.stages.learn."""

from __future__ import annotations

from pathlib import Path

import click

from wipelab.cli.options import OUTPUT_DIR, OUTPUT_FILE, PATH, comma_separated



@click.command("learn")
@click.argument("trajectory", type=PATH)
@click.option("-o", "--output", "out_dir", type=OUTPUT_DIR, required=True,
              help="Output directory: model.json, learn.mcap, learn.rrd, manifest.json.")
@click.option("--mode", type=click.Choice(["online", "offline"]), default="online",
              show_default=True,
              help="online: sample by sample, as the robot watching; offline: whole recording.")
@click.option("--dofs", default="x,y", show_default=True,
              help="Comma-separated columns to learn (metres, world frame).")
@click.option("--kernels", type=int, default=25, show_default=True, help="Kernels N per DOF.")
@click.option("--width", type=float, default=None, help="Kernel width h [default: 2.5 N].")
@click.option("--canonical", type=click.Choice(["afs", "afo"]), default="afs", show_default=True,
              help="Online canonical system: adaptive Fourier series or the paper's "
                   "oscillator pool (eqs. 1-5).")
@click.option("--seed", type=int, default=0, show_default=True,
              help="Recorded in the manifest (learning draws no random numbers).")
@click.option("-q", "--quiet", is_flag=True, help="No progress bar, no summary.")
def learn(trajectory: Path, out_dir: Path, mode: str, dofs: str, kernels: int,
          width: float | None, canonical: str, seed: int, quiet: bool) -> None:
    """Learn a periodic movement (frequency + periodic DMP) from TRAJECTORY (a Trajectory CSV
    or a track.mcap).

    Refuses (exit code 2) a file it cannot use or a movement that is not periodic.
    """
    from wipelab.stages.learn import LearnParams, learn as learn_stage

    params = LearnParams(mode=mode, dofs=tuple(name.strip() for name in dofs.split(",")),
                         kernels=kernels, width=width, canonical=canonical, seed=seed)
    model = learn_stage(trajectory, out_dir, params, quiet=quiet)
    if not quiet:
        click.echo(f"learned {model.frequency_hz:.4f} Hz, DOFs {','.join(model.dofs)}, "
                   f"{model.kernels} kernels -> {out_dir / 'model.json'}")


@click.command("rollout")
@click.argument("model", type=PATH)
@click.option("-o", "--output", "out_csv", type=OUTPUT_FILE, required=True,
              help="Output Trajectory CSV: t and one column per DOF.")
@click.option("--periods", type=float, default=10.0, show_default=True,
              help="Length in periods.")
@click.option("--frequency", "frequency_hz", type=float, default=None,
              help="Frequency in Hz [default: the learned one].")
@click.option("--rate", "rate_hz", type=float, default=100.0, show_default=True,
              help="Sample rate in Hz.")
@click.option("--amplitude-scale", type=float, default=1.0, show_default=True,
              help="Factor on the amplitude r of every DOF.")
@click.option("--goal", default=None,
              help="New anchor g per DOF in metres, comma-separated in the model's DOF order.")
def rollout(model: Path, out_csv: Path, periods: float, frequency_hz: float | None,
            rate_hz: float, amplitude_scale: float, goal: str | None) -> None:
    """Integrate MODEL (model.json) into a trajectory at any frequency, amplitude and anchor."""
    from wipelab.stages.learn import rollout as rollout_stage

    t, _ = rollout_stage(model, out_csv, periods=periods, frequency_hz=frequency_hz,
                         rate_hz=rate_hz, amplitude_scale=amplitude_scale,
                         goal=comma_separated("--goal", goal))
    click.echo(f"{t.size} samples at {rate_hz:g} Hz ({t[-1]:.2f} s) -> {out_csv}")
