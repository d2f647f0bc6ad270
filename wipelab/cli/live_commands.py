"""``wipelab live``: the on-line chain frame by frame (wiring only; the work is in
:mod:`wipelab.stages.live`)."""

from __future__ import annotations

from pathlib import Path

import click

from wipelab.blas_threads import start_with_one_blas_thread
from wipelab.cli.options import OUTPUT_DIR, PATH, comma_separated


@click.command("live")
@click.argument("source", type=PATH, required=False)
@click.option("-o", "--output", "out_dir", type=OUTPUT_DIR, required=True,
              help="Output directory: track.csv, model.json, adapted_model.json, "
                   "metrics.json, live.mcap, live.rrd, manifest.json.")
@click.option("--camera", "cameras", default=None, metavar="LEFT,RIGHT",
              help="Two cameras instead of SOURCE: OpenCV device indices, stream URLs or "
                   "video files (needs --calibration).")
@click.option("--calibration", type=PATH, default=None,
              help="Stereo calibration of --camera (OpenCV FileStorage, as a demo "
                   "directory's calibration.yaml).")
@click.option("--fps", type=click.FloatRange(min=1.0, max=240.0), default=None,
              help="Frame rate of cameras that do not report it (Hz).")
@click.option("--speed", type=click.Choice(["1", "max"]), default="1", show_default=True,
              help="1: at the source's frame rate (real time); max: as fast as it goes "
                   "(a demo directory or video files; the same files on every run).")
@click.option("--viewer", default="none", show_default=True,
              metavar="none|spawn|serve[=PORT]|connect=ADDR",
              help="Stream to a Rerun viewer while it runs: spawn one, serve the stream "
                   "(open it with the printed rerun command), or connect to one listening "
                   "at ADDR (rerun+http://HOST:PORT/proxy or a port).")
@click.option("--surface", default="flat", show_default=True, metavar="NAME|FILE.toml",
              help="What the robot wipes: flat, bowl, sink or a surface TOML file.")
@click.option("--color", "colour", default=None,
              help="Named sponge colour [default: demo.toml's sponge_colour, else yellow].")
@click.option("--hsv", default=None, metavar="H,S,V,H,S,V",
              help="Sponge colour as an HSV range, low then high, OpenCV units.")
@click.option("--sponge-size", default=None, metavar="L,W,H",
              help="Sponge length, width, height in metres, if known [default: demo.toml's].")
@click.option("--learn-periods", type=click.FloatRange(min=1.0), default=None,
              help="End imitation learning after this many periods of the movement (counted "
                   "from when the robot starts to imitate).")
@click.option("--stop-on-convergence/--no-stop-on-convergence", default=True,
              show_default=True,
              help="End imitation learning when the learned waveform stopped changing.")
@click.option("--replay-scale", type=click.FloatRange(min=0.1, max=3.0), default=1.0,
              show_default=True,
              help="After learning the surface, wipe at this many times the demonstrated tempo.")
@click.option("--replay-periods", type=click.IntRange(min=1, max=50), default=3,
              show_default=True, help="Periods of that wiping.")
@click.option("--slowdown", type=click.FloatRange(min=1.0, max=10.0), default=4.0,
              show_default=True, help="Omega is divided by this while the surface is learned.")
@click.option("--force", type=click.FloatRange(min=1.0, max=40.0), default=10.0,
              show_default=True, help="Contact force F0 (N).")
@click.option("--particles", type=click.IntRange(min=10, max=5000), default=100,
              show_default=True, help="Particles of the sponge box refinement.")
@click.option("--seed", type=int, default=0, show_default=True,
              help="Seed of the particle filter and the F/T sensor noise.")
@click.option("-q", "--quiet", is_flag=True, help="No progress bar, no summary.")
def live(source: Path | None, out_dir: Path, cameras: str | None, calibration: Path | None,
         fps: float | None, speed: str, viewer: str, surface: str, colour: str | None,
         hsv: str | None, sponge_size: str | None, learn_periods: float | None,
         stop_on_convergence: bool, replay_scale: float, replay_periods: int, slowdown: float,
         force: float, particles: int, seed: int, quiet: bool) -> None:
    """The robot mimics while the person demonstrates, then learns the surface (the paper's
    on-line scenario), one frame at a time.

    SOURCE is a demo directory (as for track), played at its frame rate (--speed 1) or as
    fast as the machine goes (--speed max); or give two cameras with --camera and
    --calibration. Imitation learning ends at the end of the demonstration (sponge gone or
    still, end of the video), on Enter or SIGUSR1, after --learn-periods, or when the learned
    waveform stopped changing; then the robot slows down, moves down until contact, learns
    the force profile and wipes at --replay-scale times the demonstrated tempo.
    """
    start_with_one_blas_thread()
    from wipelab.errors import InputError
    from wipelab.live.imitation import ImitationParams
    from wipelab.live.robot import RobotParams
    from wipelab.stages.adapt import AdaptParams
    from wipelab.live.sources import LiveSource
    from wipelab.stages.live import LiveParams, run_live
    from wipelab.stages.track import TrackParams

    if cameras is None and source is None:
        raise click.UsageError("missing argument 'SOURCE' (or give --camera LEFT,RIGHT)")
    if cameras is not None and source is not None:
        raise InputError(f"--camera: give either SOURCE ({source}) or --camera, not both")
    if cameras is not None and calibration is None:
        raise InputError("--camera: needs --calibration FILE (the cameras' stereo calibration)")
    if calibration is not None and cameras is None:
        raise InputError("--calibration: only with --camera (a demo directory has its own)")
    pair = None
    if cameras is not None:
        pair = tuple(part.strip() for part in cameras.split(","))
        if len(pair) != 2 or not all(pair):
            raise InputError(f"--camera: expected LEFT,RIGHT, got {cameras!r}")
    params = LiveParams(
        speed=speed, viewer=viewer, fps=fps,
        track=TrackParams(colour=colour, hsv=hsv, particles=particles, seed=seed,
                          sponge_size=comma_separated("--sponge-size", sponge_size, 3)),
        imitation=ImitationParams(learn_periods=learn_periods,
                                  stop_on_convergence=stop_on_convergence),
        robot=RobotParams(adapt=AdaptParams(surface=surface, force=force, slowdown=slowdown,
                                            seed=seed),
                          replay_scale=replay_scale, replay_periods=replay_periods))
    live_source = LiveSource(demo=source, cameras=pair, calibration=calibration)
    metrics = run_live(live_source, out_dir, params, quiet=quiet)
    if metrics["safety_stop"]:
        click.echo(f"warning: safety stop: {metrics['safety_stop']}", err=True)
    if quiet:
        return
    timing, imitation = metrics["timing"], metrics["imitation"]
    latency = timing["latency_ms"]
    click.echo(f"imitated {imitation['frequency_hz']:.3f} Hz for "
               f"{imitation['periods_since_lock']:.1f} periods (ended: "
               f"{imitation['stop_reason']}); frames {timing['frames']} processed, "
               f"{timing['dropped_frames']} dropped, {timing['late_frames']} late; latency "
               f"p50 {latency['p50']:.1f} ms, p99 {latency['p99']:.1f} ms; "
               f"{timing['frames_per_second']:.0f} frames/s")
    replay = metrics.get("replay")
    if replay is not None:
        click.echo(f"wiped at {replay['scale']:g}x: RMS(|F|-F0) "
                   f"{replay.get('rms_force_error_n', float('nan')):.2f} N -> {out_dir}")
