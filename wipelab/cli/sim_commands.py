"""``wipelab adapt`` and ``wipelab replay``: the simulated ARMAR-IIIb (wiring only).

The work is in :mod:`wipelab.stages.adapt` and :mod:`wipelab.stages.replay`; PyBullet is
imported when a command runs.
"""

from __future__ import annotations

from pathlib import Path

import click

from wipelab.blas_threads import start_with_one_blas_thread
from wipelab.cli.options import OUTPUT_DIR, PATH, comma_separated



def _common(function):
    options = [
        click.option("-o", "--output", "out_dir", type=OUTPUT_DIR, required=True,
                     help="Output directory."),
        click.option("--surface", default=None, metavar="NAME|FILE.toml",
                     help="flat, bowl, sink or a surface TOML file."),
        click.option("--force", type=float, default=None,
                     help="Contact force F0 (N) [adapt default: 10]."),
        click.option("--feedback", type=click.Choice(["fz", "norm"]), default=None,
                     help="Force feedback: F_z or |F| (lets the hand climb edges) "
                          "[adapt default: norm]."),
        click.option("--base", default=None, metavar="X,Y,YAW",
                     help="Robot platform pose in the world (m, m, rad) [default: chosen with "
                          "the path's place; replay: where the model was adapted]."),
        click.option("--sponge-stiffness", type=float, default=1000.0, show_default=True,
                     help="Sponge stiffness (N/m, 500-2000)."),
        click.option("--seed", type=int, default=0, show_default=True,
                     help="Seed of the F/T sensor noise and bias."),
        click.option("-q", "--quiet", is_flag=True,
                     help="No progress bar, no summary (warnings still go to stderr)."),
    ]
    for option in reversed(options):
        function = option(function)
    return function


@click.command("adapt")
@click.argument("model", type=PATH)
@_common
@click.option("--periods", type=click.IntRange(min=1), default=8, show_default=True,
              help="Most learning periods (learning stops earlier when converged).")
@click.option("--center", default=None, metavar="X,Y",
              help="Where the centre of the path's bounding box goes (m, world) [default: "
                   "chosen on the surface, as near its wiping centre as the robot does well].")
@click.option("--amplitude-scale", type=float, default=1.0, show_default=True,
              help="Scale of the x-y oscillation.")
@click.option("--slowdown", type=float, default=4.0, show_default=True,
              help="Omega is divided by this for online learning (the paper's stage).")
@click.option("--tempos", default="1", show_default=True, metavar="S,S,...|none",
              help="Refine the profile by iterative learning at the learning tempo, then at "
                   "these multiples of the demonstrated tempo; none: keep the paper's "
                   "profile as learned online.")
@click.option("--hold-periods", type=click.IntRange(min=0), default=1, show_default=True,
              help="Periods with the learned profile after learning.")
@click.option("--tolerance", type=float, default=0.002, show_default=True,
              help="Convergence: largest change of the learned profile over a period (m).")
@click.option("--kernels", type=int, default=50, show_default=True,
              help="Kernels of the adapted model (the x-y path is refitted onto them).")
@click.option("--reference", type=click.Choice(["learned", "start"]), default="learned",
              show_default=True,
              help="Y_r while learning: the profile learned so far, or the start height "
                   "(the paper's).")
def adapt(model: Path, out_dir: Path, surface: str | None, force: float | None,
          feedback: str | None, base: str | None, sponge_stiffness: float, seed: int,
          quiet: bool, periods: int, center: str | None, amplitude_scale: float, slowdown: float,
          tempos: str, hold_periods: int, tolerance: float, kernels: int,
          reference: str) -> None:
    """Learn the force profile of a surface for MODEL (model.json) on the simulated robot.

    The x-y path is centred at --center, slowed down, and executed with active compliance in
    z; the z that keeps F0 is learned online. Writes OUT/adapted_model.json, metrics.json,
    adapt.mcap, adapt.rrd and manifest.json.
    """
    start_with_one_blas_thread()
    from wipelab.control.force_profile import ProfileLearningParams
    from wipelab.stages.adapt import AdaptParams, run_adapt

    params = AdaptParams(
        surface=surface or "flat", center=comma_separated("--center", center, 2),
        amplitude_scale=amplitude_scale, slowdown=slowdown, periods=periods,
        tempos=() if tempos == "none" else comma_separated("--tempos", tempos),
        hold_periods=hold_periods, force=10.0 if force is None else force,
        feedback=feedback or "norm", base=comma_separated("--base", base, 3),
        sponge_stiffness=sponge_stiffness, seed=seed, kernels=kernels,
        learning=ProfileLearningParams(tolerance=tolerance, reference=reference))
    metrics = run_adapt(model, out_dir, params, quiet=quiet)
    learning, profile = metrics["learning"], metrics["profile_last_learning_period"]
    state = "converged" if learning["converged"] else "not converged"
    if not quiet:
        place = metrics["placement"]
        (cx, cy), (bx, by, yaw) = place["center"], place["base"]
        click.echo(f"adapt: path centred at ({cx:.2f}, {cy:.2f}) m, platform at ({bx:.2f}, "
                   f"{by:.2f}) m, yaw {yaw:.2f} rad; the arm follows up to "
                   f"{place['max_frequency_hz']:.2f} Hz")
        for stage in metrics["tempos"]:
            limited = " (the arm's fastest)" if stage["arm_limited"] else ""
            click.echo(f"adapt: refined at {stage['frequency_hz']:.2f} Hz{limited}: RMS(|F|-F0) "
                       f"{stage['rms_force_error_n'][0]:.2f} -> "
                       f"{min(stage['rms_force_error_n']):.2f} N in {stage['periods']} periods")
        click.echo(f"adapt: online learning {state} after {learning['periods']} periods; "
                   f"learned height RMS error {1000 * profile['rms_height_error_m']:.1f} mm "
                   f"-> {out_dir}")
    if metrics["safety_stop"]:
        click.echo(f"warning: safety stop: {metrics['safety_stop']}", err=True)


@click.command("replay")
@click.argument("model", type=PATH)
@click.argument("more_scales", nargs=-1, type=float, metavar="")
@_common
@click.option("--frequency-scale", "scales", type=float, multiple=True,
              help="Tempo(s) as multiples of the demonstrated one (the model's frequency_hz; "
                   "1 = as fast as the person wiped): --frequency-scale 0.25 1 1.5 "
                   "[default: 1 1.5].")
@click.option("--mode", "modes", multiple=True,
              type=click.Choice(["learned", "learned+compliance", "compliance", "planar"]),
              help="Run only these modes (repeatable) [default: all four].")
@click.option("--periods", type=click.IntRange(min=1), default=3, show_default=True,
              help="Scored periods per scale and mode.")
@click.option("--warmup-periods", type=click.IntRange(min=0), default=1, show_default=True,
              help="Unscored periods first.")
@click.option("--center", default=None, metavar="X,Y",
              help="Placement of a model without z (as in adapt).")
def replay(model: Path, more_scales: tuple[float, ...], out_dir: Path, surface: str | None,
           force: float | None, feedback: str | None, base: str, sponge_stiffness: float,
           seed: int, quiet: bool, scales: tuple[float, ...], modes: tuple[str, ...],
           periods: int, warmup_periods: int, center: str | None) -> None:
    """Execute MODEL (an adapted_model.json) at several speeds, with the learned profile
    alone, with compliance on top, and the two baselines (compliance alone, planar path).

    Usage: wipelab replay MODEL -o OUT --frequency-scale 1 2 3. Writes OUT/metrics.json (per
    scale and mode), replay.mcap, replay.rrd and manifest.json.
    """
    start_with_one_blas_thread()
    from wipelab.stages.replay import MODES, ReplayParams, run_replay

    if more_scales and not scales:
        raise click.UsageError(f"unexpected extra arguments {list(more_scales)}")
    all_scales = tuple(scales) + tuple(more_scales) or ReplayParams.frequency_scales
    params = ReplayParams(surface=surface, frequency_scales=all_scales,
                          modes=tuple(modes) or MODES, periods=periods,
                          warmup_periods=warmup_periods, force=force, feedback=feedback,
                          center=comma_separated("--center", center, 2),
                          base=comma_separated("--base", base, 3),
                          sponge_stiffness=sponge_stiffness, seed=seed)
    metrics = run_replay(model, out_dir, params, quiet=quiet)
    if quiet:
        return
    for scale, runs in metrics["scales"].items():
        summary = ", ".join(f"{mode} {run.get('rms_force_error_n', float('nan')):.2f} N"
                            for mode, run in runs.items())
        first = next(iter(runs.values()))
        limited = (f" (the arm cannot follow {first['requested_frequency_hz']:.2f} Hz)"
                   if first["arm_limited"] else "")
        click.echo(f"replay {scale}x = {first['frequency_hz']:.2f} Hz{limited}: "
                   f"RMS(|F|-F0) {summary}")
    click.echo(f"-> {out_dir}")
