"""``wipelab synth`` and ``wipelab track``: wiring only; the work is in wipelab.stages."""

from __future__ import annotations

from pathlib import Path

import click

from wipelab.blas_threads import start_with_one_blas_thread
from wipelab.cli.options import (OUTPUT_DIR, PATH, SYNTH_DURATION_S, SYNTH_FREQUENCY_HZ,
                                  comma_separated)



@click.command("synth")
@click.argument("out_dir", type=OUTPUT_DIR)
@click.option("--pattern", type=click.Choice(["circle", "line", "figure8"]), default="circle",
              show_default=True, help="Wiping pattern on the table.")
@click.option("--frequency", "frequency_hz", type=SYNTH_FREQUENCY_HZ,
              default=1.0, show_default=True, help="Wiping frequency, Hz.")
@click.option("--duration", type=SYNTH_DURATION_S, default=30.0,
              show_default=True, help="Length of the recording, seconds.")
@click.option("--seed", type=int, default=0, show_default=True,
              help="Seeds the motion's variation, textures, occlusions and noise.")
@click.option("--amplitude", type=click.FloatRange(min=0.01, max=0.3), default=None,
              help="Movement size, metres [default: 0.085 circle, 0.14 line, 0.12 figure8].")
@click.option("--sponge-color", "sponge_colour", default="yellow", show_default=True,
              type=click.Choice(["yellow", "green", "blue", "pink", "orange"]),
              help="Colour of the rendered sponge.")
@click.option("-q", "--quiet", is_flag=True, help="No progress bar, no summary.")
def synth(out_dir: Path, pattern: str, frequency_hz: float, duration: float, seed: int,
          amplitude: float | None, sponge_colour: str, quiet: bool) -> None:
    """Render a synthetic stereo demonstration with ground truth into OUT_DIR.

    What ARMAR-IIIb's wide-angle stereo pair sees while a person wipes a table: left.mp4,
    right.mp4 (H.264), calibration.yaml, demo.toml, truth.csv, manifest.json.
    """
    from wipelab.stages.synth import SynthParams, synth as synth_stage

    params = SynthParams(pattern=pattern, frequency_hz=frequency_hz, duration=duration,
                         seed=seed, amplitude=amplitude, sponge_colour=sponge_colour)
    synth_stage(out_dir, params, quiet=quiet)
    if not quiet:
        click.echo(f"rendered {params.duration:g} s of {pattern} wiping at {frequency_hz:g} Hz "
                   f"-> {out_dir}")


@click.command("track")
@click.argument("demo_dir", type=PATH)
@click.option("-o", "--output", "out_dir", type=OUTPUT_DIR, required=True,
              help="Output directory: track.csv, track.mcap, track.rrd, manifest.json.")
@click.option("--color", "colour", default=None,
              help="Named sponge colour (red, orange, yellow, green, cyan, blue, purple, pink) "
                   "[default: demo.toml's sponge_colour, else yellow].")
@click.option("--hsv", default=None, metavar="H,S,V,H,S,V",
              help="Sponge colour as an HSV range, low then high, OpenCV units "
                   "(hue 0-179; a low hue above the high one wraps through red).")
@click.option("--roi", default=None, metavar="X,Y,W,H",
              help="Learn the sponge colour from this region of the first left frame (pixels; "
                   "mostly sponge, not the hand).")
@click.option("--particles", type=click.IntRange(min=10, max=5000), default=100,
              show_default=True, help="Number of particles.")
@click.option("--seed", type=int, default=0, show_default=True, help="Particle filter seed.")
@click.option("--sponge-size", default=None, metavar="L,W,H",
              help="Sponge length, width, height in metres, if known: the box refinement then "
                   "reports the box centre [default: demo.toml's sponge_size, else unknown: the "
                   "sponge is tracked by its colour region].")
@click.option("--area-window", default="0,10", show_default=True, metavar="START,END",
              help="Time window (s) in which the demonstration area is measured (paper Fig. 3).")
@click.option("-q", "--quiet", is_flag=True, help="No progress bar, no summary.")
def track(demo_dir: Path, out_dir: Path, colour: str | None, hsv: str | None, roi: str | None,
          particles: int, seed: int, sponge_size: str | None, area_window: str,
          quiet: bool) -> None:
    """Track the sponge of DEMO_DIR in 3D (colour particle filter on both cameras).

    DEMO_DIR holds left.mp4, right.mp4 (any codec OpenCV reads), calibration.yaml (OpenCV
    FileStorage stereo calibration) and optionally demo.toml. Refuses (exit code 2) bad
    input, writing nothing.
    """
    start_with_one_blas_thread()  # its products are small: threads would only spin
    from wipelab.stages.track import TrackParams, track as track_stage

    params = TrackParams(colour=colour, hsv=hsv, roi=comma_separated("--roi", roi, 4, int),
                         particles=particles, seed=seed,
                         sponge_size=comma_separated("--sponge-size", sponge_size, 3),
                         area_window=comma_separated("--area-window", area_window, 2))
    result = track_stage(demo_dir, out_dir, params, quiet=quiet)
    if not quiet:
        click.echo(f"tracked {result.valid.sum()} of {result.valid.size} frames "
                   f"({result.frame} frame) -> {out_dir / 'track.csv'}")
