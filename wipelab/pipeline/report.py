"""``wipelab report``: figures and a markdown summary of a run directory.

Reads what the stages wrote: the MCAP logs through :mod:`wipelab.logs.reader`, plus their
``metrics.json`` and the run's cache records. Each finished stage contributes by its
command (learn: Figs. 4-5; adapt: Figs. 6-7, one per surface; replay: the adapted movement
at several frequencies), so a run with several adapt stages gets one figure per surface.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wipelab.errors import InputError
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

    t, values, names = read_mcap_scalars(mcap, topic)
    return t, {name: values[:, j] for j, name in enumerate(names)}


def _events(mcap: Path, topic: str) -> list[tuple[float, str]]:
    from wipelab.logs.reader import read_mcap_topic

    return [(ns / 1e9, message["event"]) for ns, message in read_mcap_topic(mcap, topic)]


def _contact_figure(stage_dir: Path, command: str) -> tuple[dict, object]:
    """Height and |F| over the run of an adapt or replay stage."""
    from wipelab.pipeline.figures import force_profile_figure

    mcap = stage_dir / f"{command}.mcap"
    metrics = json.loads((stage_dir / "metrics.json").read_text())
    t, height = _scalars(mcap, f"/{command}/height")
    _, force = _scalars(mcap, f"/{command}/force_norm")
    events = [(start, label) for start, label in _events(mcap, f"/{command}/events")
              if label != "end"]
    names = [name for name in ("actual", "commanded") if name in height]
    target = float(metrics.get("target_force_n", np.nanmedian(force["F0"])))
    end = metrics.get("learning", {}).get("end_time_s")
    surface = metrics.get("surface", {}).get("name", "?")
    title = (f"{stage_dir.name}: force-profile learning on '{surface}'" if command == "adapt"
             else f"{stage_dir.name}: replay on '{surface}' at several frequencies")
    figure = force_profile_figure(t, np.column_stack([height[n] for n in names]), names,
                                  force["measured |F|"], target, events, title,
                                  end_of_learning=end)
    return metrics, figure


def _learn_figures(stage_dir: Path, out: Path) -> list[ReportFigure]:
    from wipelab.pipeline.figures import frequency_figure, waveform_figure

    mcap = stage_dir / "learn.mcap"
    model = json.loads((stage_dir / "model.json").read_text())
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
    try:
        return _scalars(mcap, "/input/valid")[1]["valid"] > 0.5
    except KeyError:
        return np.ones(t.size, dtype=bool)


def _demo_frequency_hz(run_dir: Path) -> float | None:
    """The true frequency of a synthetic demo a track stage of this run read, if any."""
    from wipelab.pipeline.metrics import synthetic_frequency_hz

    for stage_dir, record in stage_records(run_dir):
        if record.command == "track" and record.input is not None:
            frequency_hz = synthetic_frequency_hz(stage_dir.parent / record.input)
            if frequency_hz is not None:
                return frequency_hz
    return None


def _adapt_figures(stage_dir: Path, out: Path) -> list[ReportFigure]:
    metrics, figure = _contact_figure(stage_dir, "adapt")
    name = f"{stage_dir.name}_height_force.png"
    _save(figure, out / name)
    surface = metrics.get("surface", {}).get("name", "?")
    return [ReportFigure(name, f"{stage_dir.name}: tool height and |F| while learning the "
                               f"force profile of '{surface}'; dashed line: end of learning "
                               f"(cf. paper Figs. 6-7)")]


def _replay_figures(stage_dir: Path, out: Path) -> list[ReportFigure]:
    from wipelab.pipeline.figures import force_error_bars_figure

    metrics, figure = _contact_figure(stage_dir, "replay")
    names = [f"{stage_dir.name}_height_force.png", f"{stage_dir.name}_force_error.png"]
    _save(figure, out / names[0])
    rms = {f"{scale}x\n{next(iter(modes.values())).get('frequency_hz', np.nan):.2f} Hz":
           {mode: values.get("rms_force_error_n", np.nan) for mode, values in modes.items()}
           for scale, modes in metrics["scales"].items()}
    surface = metrics.get("surface", {}).get("name", "?")
    _save(force_error_bars_figure(rms, f"{stage_dir.name}: force error on '{surface}' as the "
                                       f"frequency rises"), out / names[1])
    return [ReportFigure(names[0], f"{stage_dir.name}: the adapted movement replayed at "
                                   f"higher frequencies, per mode (shaded)"),
            ReportFigure(names[1], f"{stage_dir.name}: RMS(|F| - F0) per frequency scale and "
                                   f"mode, as the speed rises")]


#: command -> function drawing that stage's figures into the report folder.
STAGE_FIGURES: dict[str, Callable[[Path, Path], list[ReportFigure]]] = {
    "learn": _learn_figures,
    "adapt": _adapt_figures,
    "replay": _replay_figures,
}
