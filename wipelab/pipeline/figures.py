"""Figures of a run in the spirit of the paper's Figs. 4-7 (matplotlib, no I/O but savefig).

Every function takes plain arrays and returns a ``matplotlib.figure.Figure``; the report
reads the arrays from the stages' files. Figures are built with the object API on the Agg
canvas, so no display and no global pyplot state are involved.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib.figure import Figure

#: Colours: measured/input (blue), learned/commanded (red), reference (grey), as in the paper.
INPUT_COLOUR, LEARNED_COLOUR, REFERENCE_COLOUR = "tab:blue", "tab:red", "0.45"
SEGMENT_COLOURS = ("0.97", "#e8f1fb", "#fdf0e6", "#eaf6ea", "#f4ecf7", "#fbf7e3")


def _figure(rows: int, height_per_row: float = 2.4, width: float = 8.0) -> tuple[Figure, list]:
    figure = Figure(figsize=(width, 0.6 + height_per_row * rows), dpi=110,
                    layout="constrained")
    axes = figure.subplots(rows, 1, sharex=True, squeeze=False)[:, 0]
    for ax in axes:
        ax.grid(True, linewidth=0.5, alpha=0.5)
    return figure, list(axes)


def frequency_figure(t: np.ndarray, oscillators_hz: np.ndarray, names: Sequence[str],
                     chosen_hz: np.ndarray | None = None,
                     true_hz: float | None = None,
                     observed: np.ndarray | None = None) -> Figure:
    """Frequency adaptation (paper Fig. 4): every oscillator's frequency and the chosen Omega.

    Parameters
    ----------
    t : ndarray, shape (n,)
        Time, s.
    oscillators_hz : ndarray, shape (n, k)
        Frequencies of the k oscillators (or the learned Omega when k = 1), Hz.
    names : sequence of str, length k
    chosen_hz : ndarray, shape (n,), optional
        The fundamental frequency picked from them, Hz.
    true_hz : float, optional
        The demonstration's true frequency (synthetic demos), Hz.
    observed : ndarray of bool, shape (n,), optional
        Samples the learner saw; the gaps (the sponge lost) are shaded.
    """
    figure, (ax,) = _figure(1, 3.2)
    _shade_gaps(ax, t, observed)
    for j, name in enumerate(names):
        ax.plot(t, oscillators_hz[:, j], linewidth=1.0, label=name)
    if chosen_hz is not None:
        ax.plot(t, chosen_hz, color="black", linewidth=2.0, alpha=0.7, label="chosen Ω")
    if true_hz is not None:
        ax.axhline(true_hz, color=REFERENCE_COLOUR, linestyle="--", linewidth=1.0,
                   label=f"true {true_hz:g} Hz")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("frequency (Hz)")
    ax.set_title("Frequency adaptation of the canonical system")
    ax.legend(loc="best", fontsize="small")
    return figure


def waveform_figure(t: np.ndarray, demonstrated: np.ndarray, learned: np.ndarray,
                    dofs: Sequence[str], period_s: float,
                    observed: np.ndarray | None = None) -> Figure:
    """Demonstrated input vs learned waveform per DOF (paper Fig. 5), with the last periods
    enlarged on the right.

    Parameters
    ----------
    t : ndarray, shape (n,)
        Time, s.
    demonstrated : ndarray, shape (n, d)
        Input signal per DOF (blue).
    learned : ndarray, shape (n, d)
        Output of the learned DMP per DOF (red).
    dofs : sequence of str, length d
    period_s : float
        Period of the learned movement, s: the enlargement shows the last three.
    observed : ndarray of bool, shape (n,), optional
        Samples the learner saw: the demonstration is drawn there only, the gaps shaded.
    """
    if observed is not None:
        demonstrated = np.where(observed[:, None], demonstrated, np.nan)
    figure = Figure(figsize=(10.0, 0.6 + 2.4 * len(dofs)), dpi=110, layout="constrained")
    axes = figure.subplots(len(dofs), 2, sharex="col", squeeze=False,
                           gridspec_kw={"width_ratios": [3, 1]})
    last = t >= t[-1] - 3.0 * period_s
    for j, dof in enumerate(dofs):
        _shade_gaps(axes[j, 0], t, observed)
        for ax, window in ((axes[j, 0], slice(None)), (axes[j, 1], last)):
            ax.plot(t[window], demonstrated[window, j], color=INPUT_COLOUR, linewidth=1.0,
                    label="demonstrated")
            ax.plot(t[window], learned[window, j], color=LEARNED_COLOUR, linewidth=1.0,
                    label="learned")
            ax.grid(True, linewidth=0.5, alpha=0.5)
        axes[j, 0].set_ylabel(f"{dof} (m)")
    axes[0, 0].set_title("Demonstrated movement and learned waveform")
    axes[0, 1].set_title("last three periods")
    axes[0, 1].legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize="small")
    axes[-1, 0].set_xlabel("time (s)")
    axes[-1, 1].set_xlabel("time (s)")
    return figure


def force_profile_figure(t: np.ndarray, heights: np.ndarray, height_names: Sequence[str],
                         force_norm: np.ndarray, target_force: float,
                         segments: Sequence[tuple[float, str]], title: str,
                         end_of_learning: float | None = None) -> Figure:
    """Height and |F| over time with the segments and the end of learning (paper Figs. 6-7).

    Parameters
    ----------
    t : ndarray, shape (n,)
        Simulation time, s.
    heights : ndarray, shape (n, k)
        Tool heights (commanded, actual, ...), m, world z.
    height_names : sequence of str, length k
    force_norm : ndarray, shape (n,)
        Measured |F|, N.
    target_force : float
        F_0, N.
    segments : sequence of (start time s, label)
        Phases of the run (approach, learning, ...), shaded and labelled.
    title : str
    end_of_learning : float, optional
        Time of the dashed vertical line, s.
    """
    figure, (ax_z, ax_f) = _figure(2, 2.6, width=9.0)
    _shade_segments([ax_z, ax_f], segments, float(t[-1]))
    styles = {"commanded": (LEARNED_COLOUR, "--"), "actual": (INPUT_COLOUR, "-")}
    for j, name in enumerate(height_names):
        colour, style = styles.get(name, (REFERENCE_COLOUR, ":"))
        ax_z.plot(t, heights[:, j], color=colour, linestyle=style, linewidth=1.0, label=name)
    ax_f.plot(t, force_norm, color=INPUT_COLOUR, linewidth=0.8, label="measured |F|")
    ax_f.axhline(target_force, color="black", linestyle="--", linewidth=0.8,
                 label=f"F0 = {target_force:g} N")
    for ax in (ax_z, ax_f):
        if end_of_learning is not None:
            ax.axvline(end_of_learning, color="black", linestyle="--", linewidth=1.2)
    if end_of_learning is not None:
        ax_f.annotate("end of learning", (end_of_learning, 1.0), xycoords=("data", "axes fraction"),
                      xytext=(3, -12), textcoords="offset points", fontsize="small")
    ax_z.set_ylabel("height z (m)")
    ax_f.set_ylabel("|F| (N)")
    ax_f.set_ylim(0.0, max(3.0 * target_force, float(np.nanpercentile(force_norm, 99.5)) * 1.1))
    ax_f.set_xlabel("time (s)")
    figure.suptitle(title)
    for ax in (ax_z, ax_f):
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize="small")
    return figure


def force_error_bars_figure(rms_error: dict[str, dict[str, float]], title: str) -> Figure:
    """RMS(|F| - F0) per frequency scale (groups) and mode (bars).

    Parameters
    ----------
    rms_error : dict tempo label (scale and Hz) -> {mode: RMS error in N}
    title : str
    """
    scales = list(rms_error)
    modes = sorted({mode for values in rms_error.values() for mode in values})
    figure = Figure(figsize=(8.0, 3.4), dpi=110, layout="constrained")
    ax = figure.subplots()
    width = 0.8 / max(len(modes), 1)
    x = np.arange(len(scales))
    for i, mode in enumerate(modes):
        values = [rms_error[s].get(mode, np.nan) for s in scales]
        bars = ax.bar(x + (i - (len(modes) - 1) / 2) * width, values, width, label=mode)
        ax.bar_label(bars, fmt="%.2f", fontsize="x-small", padding=1)
    ax.set_xticks(x, scales)
    ax.set_xlabel("tempo (x demonstrated, and in Hz)")
    ax.set_ylabel("RMS(|F| - F0) (N)")
    ax.set_title(title)
    ax.grid(True, axis="y", linewidth=0.5, alpha=0.5)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize="small", title="mode")
    return figure


def _shade_gaps(ax, t: np.ndarray, observed: np.ndarray | None) -> None:
    """Shade the stretches of ``t`` where ``observed`` is False, labelled once."""
    if observed is None or observed.all():
        return
    edges = np.diff(np.concatenate([[0], (~observed).astype(int), [0]]))
    for n, (start, stop) in enumerate(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1))):
        ax.axvspan(t[start], t[stop - 1], color=REFERENCE_COLOUR, alpha=0.2, linewidth=0,
                   label="not observed" if n == 0 else None)


def _shade_segments(axes: list, segments: Sequence[tuple[float, str]], t_end: float) -> None:
    """Shade each segment and name it on a top axis above the first plot."""
    bounds = [start for start, _ in segments[1:]] + [t_end]
    for k, ((start, _), end) in enumerate(zip(segments, bounds)):
        for ax in axes:
            ax.axvspan(start, end, color=SEGMENT_COLOURS[k % len(SEGMENT_COLOURS)], zorder=0,
                       linewidth=0)
    top = axes[0].secondary_xaxis("top")
    top.set_xticks([(start + end) / 2 for (start, _), end in zip(segments, bounds)],
                   [label for _, label in segments], rotation=25, ha="left",
                   fontsize="x-small", color="0.25")
    top.tick_params(length=0)
