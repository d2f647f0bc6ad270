"""``wipelab report``: figures and a markdown summary of a run directory.

Reads what the stages wrote: the MCAP logs through :mod:`wipelab.logs.reader`, plus their
``metrics.json`` and the run's cache records. Each finished stage contributes by its
command (learn: Figs. 4-5; adapt: Figs. 6-7, one per surface; replay: the adapted movement
at several frequencies), so a run with several adapt stages gets one figure per surface.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wipelab.errors import InputError
from wipelab.input_files import read_input_json, reading
from wipelab.pipeline.cache import StageRecord, read_record
from wipelab.pipeline.metrics import is_key_metric, run_metrics
from wipelab.pipeline.spec import REPORT_DIR
from wipelab.stage_output import staged_output


@dataclass(frozen=True)
class ReportFigure:
    """One figure of the report: file name and caption."""

    file: str
    caption: str


def stage_records(run_dir: Path) -> list[tuple[Path, StageRecord]]:
    """The finished stages of a run, in the order they ran (the order of their records)."""
    found = [(d, read_record(d)) for d in sorted(run_dir.iterdir()) if d.is_dir()]
    stages = [(d, r) for d, r in found if r is not None]
    return sorted(stages, key=lambda item: (item[0] / ".wipelab-stage.json").stat().st_mtime_ns)


def write_report(run_dir: str | os.PathLike, out_dir: str | os.PathLike | None = None) -> Path:
    """Draw the figures of every finished stage and write ``summary.md``; returns out_dir.

    Parameters
    ----------
    run_dir : path-like
        A run directory of ``wipelab run``.
    out_dir : path-like, optional
        Where to write (default ``run_dir/report``); files appear only when all are written.

    Raises
    ------
    InputError
        ``run_dir`` holds no finished stage.
    """
    run_dir = Path(run_dir)
    if not run_dir.is_dir():
        raise InputError(f"{run_dir}: not a directory")
    stages = stage_records(run_dir)
    if not stages:
        raise InputError(f"{run_dir}: no finished stage (a run directory of `wipelab run`)")
    out_dir = Path(out_dir) if out_dir is not None else run_dir / REPORT_DIR
    with staged_output(out_dir) as tmp:
        figures: list[ReportFigure] = []
        for stage_dir, record in stages:
            draw = STAGE_FIGURES.get(record.command)
            if draw is not None:
                with reading(stage_dir, f"does not hold what {record.command} writes"):
                    figures += draw(stage_dir, tmp)
        (tmp / "summary.md").write_text(summary_markdown(run_dir, stages, figures))
    return out_dir


def summary_markdown(run_dir: Path, stages: list[tuple[Path, StageRecord]],
                     figures: list[ReportFigure]) -> str:
    """The report's text: stages with their times, the metrics, the figures."""
    lines = [f"# Run {run_dir.name}", "", "| stage | command | wall time (s) |", "|---|---|---|"]
    lines += [f"| {d.name} | {r.command} | {r.seconds:.1f} |" for d, r in stages]
    metrics = run_metrics(run_dir)
    key = {name: value for name, value in metrics.items() if is_key_metric(name)}
    if key:
        lines += ["", "## Key metrics", "", "| metric | value |", "|---|---|"]
        lines += [f"| {name} | {value:.4g} |" for name, value in key.items()]
    if metrics:
        lines += ["", f"<details><summary>All {len(metrics)} metrics</summary>", "",
                  "| metric | value |", "|---|---|"]
        lines += [f"| {name} | {value:.4g} |" for name, value in metrics.items()]
        lines += ["", "</details>"]
    if figures:
        lines += ["", "## Figures"]
        for figure in figures:
            lines += ["", f"![{figure.caption}]({figure.file})", "", f"*{figure.caption}*"]
    return "\n".join(lines) + "\n"


def _save(figure, path: Path) -> None:
    figure.savefig(path, metadata={"Software": None})


def _scalars(mcap: Path, topic: str) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    from wipelab.logs.reader import read_mcap_scalars

    with reading(mcap, "not a readable log of wipelab"):
        t, values, names = read_mcap_scalars(mcap, topic)
    return t, {name: values[:, j] for j, name in enumerate(names)}


def _messages(mcap: Path, topic: str) -> list[tuple[float, dict]]:
    """(time s, message) of every message on ``topic``."""
    from wipelab.logs.reader import read_mcap_topic

    with reading(mcap, "not a readable log of wipelab"):
        return [(ns / 1e9, message) for ns, message in read_mcap_topic(mcap, topic)]


def _segments(mcap: Path, command: str) -> list[tuple[float, str]]:
    """The parts of an adapt or replay run (start time s, name), the end left out."""
    return [(time, message["state"]) for time, message in _messages(mcap, f"/{command}/segment")
            if message["state"] != "end"]


def _metrics(stage_dir: Path) -> dict:
    return read_input_json(stage_dir / "metrics.json")


def _height_force_figure(stage_dir: Path, command: str, metrics: dict, title: str):
    """TCP and contact heights and |F| over the run of an adapt or replay stage."""
    from wipelab.pipeline.figures import height_force_figure

    mcap = stage_dir / f"{command}.mcap"
    t, tcp = _scalars(mcap, f"/{command}/tcp_height")
    _, contact = _scalars(mcap, f"/{command}/contact_height")
    _, force = _scalars(mcap, f"/{command}/force_norm")
    target = float(metrics.get("target_force_n", np.nanmedian(force["F0"])))
    shown = {name: tcp[name] for name in ("actual", "reference") if name in tcp}
    return height_force_figure(t, shown, contact, force["measured"], target,
                               _segments(mcap, command), title,
                               end_of_learning=metrics.get("learning", {}).get("end_time_s"))


def _track_figures(stage_dir: Path, out: Path) -> list[ReportFigure]:
    """x, y, z of the tracked sponge over time, against truth.csv when the demo has one."""
    from wipelab.pipeline.figures import track_figure
    from wipelab.trajectory_csv import read_trajectory

    mcap = stage_dir / "track.mcap"
    t_all, valid = _scalars(mcap, "/track/valid")
    t_valid, xyz = _scalars(mcap, "/track/position")
    valid = valid["value"] > 0.5
    position = np.full((t_all.size, 3), np.nan)
    position[np.searchsorted(t_all, t_valid)] = np.column_stack([xyz[a] for a in "xyz"])
    (_, area), = _messages(mcap, "/track/demonstration_area")
    frame = area.get("frame", "world")
    truth = None
    demo = _demo_dir(stage_dir.parent)
    if demo is not None and frame == "world" and (demo / "truth.csv").is_file():
        true = read_trajectory(demo / "truth.csv", required=("t", "x", "y", "z"))
        truth = np.column_stack([np.interp(t_all, true.t, true.columns[a]) for a in "xyz"])
    name = f"{stage_dir.name}_trajectory.png"
    _save(track_figure(t_all, position, valid, truth, _quality(stage_dir / "track.csv"), frame),
          out / name)
    against = " against the demo's truth.csv (dashed) and the 3D error" if truth is not None else ""
    return [ReportFigure(name, f"{stage_dir.name}: the tracked sponge centre, x, y and z over "
                               f"time{against}; shaded: frames where the sponge was lost")]


def _quality(track_csv: Path) -> list[str] | None:
    """The per-frame ``quality`` column of a track.csv (box, centroid, empty when lost), or
    None when the file has none."""
    import csv
    import io

    from wipelab.input_files import read_input_text

    rows = list(csv.DictReader(io.StringIO(read_input_text(track_csv))))
    if not rows or "quality" not in rows[0]:
        return None
    return [row["quality"] or "" for row in rows]


def _learn_figures(stage_dir: Path, out: Path) -> list[ReportFigure]:
    from wipelab.pipeline.figures import frequency_figure, waveform_figure

    mcap = stage_dir / "learn.mcap"
    model = read_input_json(stage_dir / "model.json")
    dofs = model["dofs"]
    t, oscillators = _scalars(mcap, "/oscillators/frequency_hz")
    _, fundamental = _scalars(mcap, "/oscillators/fundamental_hz")
    names = list(oscillators)
    observed = _observed(mcap, t)
    figure = frequency_figure(t, np.column_stack([oscillators[n] for n in names]), names,
                              fundamental["fundamental"], _demo_frequency_hz(stage_dir.parent),
                              observed)
    files = [f"{stage_dir.name}_frequency.png", f"{stage_dir.name}_waveform.png"]
    _save(figure, out / files[0])
    waveforms = [_scalars(mcap, f"/dmp/{dof}/waveform")[1] for dof in dofs]
    _save(waveform_figure(t, np.column_stack([w["input"] for w in waveforms]),
                          np.column_stack([w["learned"] for w in waveforms]), dofs,
                          1.0 / model["frequency_hz"], observed),
          out / files[1])
    return [ReportFigure(files[0], f"{stage_dir.name}: frequency adaptation of the canonical "
                                   f"system and the chosen fundamental (cf. paper Fig. 4)"),
            ReportFigure(files[1], f"{stage_dir.name}: demonstrated movement (blue) and the "
                                   f"learned waveform (red) per DOF (cf. paper Fig. 5)")]


def _observed(mcap: Path, t: np.ndarray) -> np.ndarray:
    """The samples the learner saw (/input/valid; every one in recordings from before it)."""
    from wipelab.logs.reader import mcap_topics

    if "/input/valid" not in mcap_topics(mcap):
        return np.ones(t.size, dtype=bool)
    return _scalars(mcap, "/input/valid")[1]["valid"] > 0.5


def _demo_dir(run_dir: Path) -> Path | None:
    """The demo directory a track stage of this run read, if any."""
    for stage_dir, record in stage_records(run_dir):
        if record.command == "track" and record.input is not None:
            return stage_dir.parent / record.input
    return None


def _demo_frequency_hz(run_dir: Path) -> float | None:
    """The frequency a synthetic demo a track stage of this run read was rendered at, if any."""
    from wipelab.pipeline.metrics import synthetic_frequency_hz

    demo = _demo_dir(run_dir)
    return None if demo is None else synthetic_frequency_hz(demo)


def _adapt_figures(stage_dir: Path, out: Path) -> list[ReportFigure]:
    from wipelab.pipeline.figures import profile_figure

    metrics = _metrics(stage_dir)
    surface = metrics.get("surface", {}).get("name", "?")
    names = [f"{stage_dir.name}_height_force.png", f"{stage_dir.name}_profile.png"]
    _save(_height_force_figure(stage_dir, "adapt", metrics,
                               f"{stage_dir.name}: force-profile learning on '{surface}'"),
          out / names[0])
    profiles = [message for _, message in _messages(stage_dir / "adapt.mcap", "/adapt/profile")]
    figures = [ReportFigure(names[0], f"{stage_dir.name}: TCP height, contact point and |F| "
                                      f"while learning the force profile of '{surface}'; "
                                      f"dashed line: end of learning (cf. paper Figs. 6-7)")]
    if profiles:
        _save(profile_figure(np.array(profiles[0]["phase_rad"]),
                             np.array(profiles[-1]["surface_mm"], dtype=float),
                             [np.array(p["learned_mm"], dtype=float) for p in profiles],
                             f"{stage_dir.name}: learned height profile per period vs the "
                             f"true surface ('{surface}')"), out / names[1])
        figures.append(ReportFigure(names[1], f"{stage_dir.name}: the learned profile after "
                                              f"each period (light to dark) against the true "
                                              f"surface, over the phase of the movement"))
    return figures


def _replay_figures(stage_dir: Path, out: Path) -> list[ReportFigure]:
    from wipelab.logs.palette import speed_colours
    from wipelab.pipeline.figures import force_error_bars_figure, force_over_phase_figure
    from wipelab.sim.recording import mode_entity, speed_label

    metrics = _metrics(stage_dir)
    surface = metrics.get("surface", {}).get("name", "?")
    target = float(metrics.get("target_force_n", 10.0))
    names = [f"{stage_dir.name}_force_over_phase.png", f"{stage_dir.name}_height_force.png",
             f"{stage_dir.name}_force_error.png"]
    runs = {scale: {mode: values for mode, values in modes.items()}
            for scale, modes in metrics["scales"].items()}
    colours = speed_colours([float(scale) for scale in runs])
    mcap = stage_dir / "replay.mcap"
    curves = {}
    for mode in dict.fromkeys(mode for modes in runs.values() for mode in modes):
        for _, message in _messages(mcap, f"/replay/force_by_phase/{mode_entity(mode)}"):
            curves.setdefault(mode, []).append((
                speed_label(message["scale"], message["frequency_hz"]), colours[message["scale"]],
                np.array(message["phase_rad"]),
                np.array([np.nan if v is None else v for v in message["force_n"]])))
    _save(force_over_phase_figure(curves, target, f"{stage_dir.name}: |F| over the phase at "
                                                  f"every speed, per mode, on '{surface}'"),
          out / names[0])
    _save(_height_force_figure(stage_dir, "replay", metrics,
                               f"{stage_dir.name}: replay on '{surface}', every speed and mode"),
          out / names[1])
    rms = {}
    for scale, modes in runs.items():
        frequency = next((values["frequency_hz"] for values in modes.values()
                          if "frequency_hz" in values),
                         metrics.get("base_frequency_hz", math.nan) * float(scale))
        rms[speed_label(float(scale), frequency)] = {
            mode: values.get("rms_force_error_n", np.nan) for mode, values in modes.items()}
    _save(force_error_bars_figure(rms, f"{stage_dir.name}: force error on '{surface}' as the "
                                       f"speed rises"), out / names[2])
    return [ReportFigure(names[0], f"{stage_dir.name}: |F| over the phase of the movement, the "
                                   f"mean over the scored periods, every speed overlaid, one "
                                   f"panel per mode; dashed: F0"),
            ReportFigure(names[1], f"{stage_dir.name}: TCP height, contact point and |F| over "
                                   f"the whole replay, each run shaded in its mode's colour"),
            ReportFigure(names[2], f"{stage_dir.name}: RMS(|F| - F0) per speed and mode")]


#: command -> function drawing that stage's figures into the report folder.
STAGE_FIGURES: dict[str, Callable[[Path, Path], list[ReportFigure]]] = {
    "track": _track_figures,
    "learn": _learn_figures,
    "adapt": _adapt_figures,
    "replay": _replay_figures,
}
