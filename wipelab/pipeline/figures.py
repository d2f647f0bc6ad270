"""Figures of a run in the spirit of the paper's Figs. 4-7 (matplotlib, no I/O but savefig).

Every function takes plain arrays and returns a ``matplotlib.figure.Figure``; the report
reads the arrays from the stages' files. Figures are built with the object API on the Agg
canvas, so no display and no global pyplot state are involved. Colours are those of the
Rerun layouts (:mod:`wipelab.logs.palette`): one per axis, per replay mode, per speed.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from matplotlib.figure import Figure

from wipelab.logs.palette import (INPUT_COLOUR, LEARNED_COLOUR, MODE_COLOURS, OSCILLATOR_COLOURS,
                                  XYZ_COLOURS, hex_colour, segment_colour)
from wipelab.mask_runs import true_runs

INPUT, LEARNED = hex_colour(INPUT_COLOUR), hex_colour(LEARNED_COLOUR)
#: Reference lines (F0, a true value) and truth: black on the white figures.
REFERENCE = "0.15"
#: Shading of what was not observed (a tracking gap), of a frame measured by the colour
#: region where the box fit failed, and of one measured by one camera alone.
GAP_SHADE, CENTROID_SHADE, MONO_SHADE = "0.55", "#f0a030", "#be78dc"
PHASE_TICKS = ([0.0, 0.5 * math.pi, math.pi, 1.5 * math.pi, 2.0 * math.pi],
               ["0", "π/2", "π", "3π/2", "2π"])


def _figure(rows: int, height_per_row: float = 2.4, width: float = 8.0) -> tuple[Figure, list]:
    figure = Figure(figsize=(width, 0.6 + height_per_row * rows), dpi=110,
                    layout="constrained")
    axes = figure.subplots(rows, 1, sharex=True, squeeze=False)[:, 0]
    for ax in axes:
        ax.grid(True, linewidth=0.5, alpha=0.5)
    return figure, list(axes)


def _legend_right(ax) -> None:
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize="small")


def track_figure(t: np.ndarray, position: np.ndarray, valid: np.ndarray,
                 truth: np.ndarray | None = None, quality: Sequence[str] | None = None,
                 frame: str = "world") -> Figure:
    """The tracked sponge: x, y, z over time on separate axes, against the truth when known,
    with the frames where it was lost (and, per the quality column, where only colour-region
    centres were triangulated) shaded; the 3D error when the truth is known.

    Parameters
    ----------
    t : ndarray, shape (n,)
        Frame times, s.
    position : ndarray, shape (n, 3)
        Tracked x, y, z (m) in ``frame``; NaN where lost.
    valid : ndarray of bool, shape (n,)
    truth : ndarray, shape (n, 3), optional
        True x, y, z (m) at the same times (synthetic demos).
    quality : sequence of str, length n, optional
        Per frame ``box``, ``centroid``, ``mono`` or empty (lost). Frames measured by one
        camera are shaded; colour-region frames only where the box fitted elsewhere (without
        a known sponge size every frame is a colour-region frame).
    """
    rows = 4 if truth is not None else 3
    figure, axes = _figure(rows, 1.9, width=9.0)
    quality = None if quality is None else np.asarray(quality)
    for ax in axes:
        _shade(ax, t, ~valid, GAP_SHADE, "lost")
        if quality is not None:
            if np.any(quality == "box"):
                _shade(ax, t, quality == "centroid", CENTROID_SHADE, "box fit failed: centroid")
            _shade(ax, t, quality == "mono", MONO_SHADE, "one camera")
    for j, axis in enumerate("xyz"):
        ax = axes[j]
        ax.plot(t, np.where(valid, position[:, j], np.nan), color=hex_colour(XYZ_COLOURS[axis]),
                linewidth=1.2, label=f"tracked {axis}")
        if truth is not None:
            ax.plot(t, truth[:, j], color=REFERENCE, linewidth=0.7, linestyle="--", label="truth")
        ax.set_ylabel(f"{axis} (m)")
        _legend_right(ax)
    if truth is not None:
        error = 1000.0 * np.linalg.norm(position - truth, axis=1)
        axes[3].plot(t, np.where(valid, error, np.nan), color="0.3", linewidth=0.8,
                     label=f"3D error, RMS {np.sqrt(np.nanmean(error[valid] ** 2)):.1f} mm")
        axes[3].set_ylabel("error (mm)")
        axes[3].set_ylim(bottom=0.0)
        _legend_right(axes[3])
    axes[-1].set_xlabel("time (s)")
    axes[0].set_xlim(t[0], t[-1])
    figure.suptitle(f"Tracked sponge centre ({frame} frame)")
    return figure


def frequency_figure(t: np.ndarray, oscillators_hz: np.ndarray, names: Sequence[str],
                     chosen_hz: np.ndarray | None = None,
                     true_hz: float | None = None,
                     observed: np.ndarray | None = None) -> Figure:
    """Frequency adaptation (paper Fig. 4): every oscillator's frequency and the chosen Omega,
    from t = 0, the legend beside the plot (the transient stays in view).

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
        The frequency a synthetic demonstration was rendered at, Hz (drawn only when known).
    observed : ndarray of bool, shape (n,), optional
        Samples the learner saw; the gaps (the sponge lost) are shaded.
    """
    figure, (ax,) = _figure(1, 3.2, width=9.0)
    if observed is not None:
        _shade(ax, t, ~observed, GAP_SHADE, "not observed")
    for j, name in enumerate(names):
        ax.plot(t, oscillators_hz[:, j], linewidth=1.0, label=name,
                color=hex_colour(OSCILLATOR_COLOURS[j % len(OSCILLATOR_COLOURS)]))
    if chosen_hz is not None:
        ax.plot(t, chosen_hz, color="black", linewidth=2.0, alpha=0.7, label="chosen Ω / 2π")
    if true_hz is not None:
        ax.axhline(true_hz, color=REFERENCE, linestyle="--", linewidth=1.0,
                   label=f"rendered at {true_hz:g} Hz")
    ax.set_xlim(0.0, t[-1])
    ax.set_xlabel("time (s)")
    ax.set_ylabel("frequency (Hz)")
    ax.set_title("Frequency adaptation of the canonical system")
    _legend_right(ax)
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
        if observed is not None:
            _shade(axes[j, 0], t, ~observed, GAP_SHADE, "not observed")
        for ax, window in ((axes[j, 0], slice(None)), (axes[j, 1], last)):
            ax.plot(t[window], demonstrated[window, j], color=INPUT, linewidth=1.0,
                    label="demonstrated")
            ax.plot(t[window], learned[window, j], color=LEARNED, linewidth=1.0,
                    label="learned")
            ax.grid(True, linewidth=0.5, alpha=0.5)
        axes[j, 0].set_ylabel(f"{dof} (m)")
    axes[0, 0].set_title("Demonstrated movement and learned waveform")
    axes[0, 1].set_title("last three periods")
    axes[0, 1].legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize="small")
    axes[-1, 0].set_xlabel("time (s)")
    axes[-1, 1].set_xlabel("time (s)")
    return figure


def height_force_figure(t: np.ndarray, tcp: dict[str, np.ndarray],
                        contact: dict[str, np.ndarray] | None, force_norm: np.ndarray,
                        target_force: float, segments: Sequence[tuple[float, str]], title: str,
                        end_of_learning: float | None = None) -> Figure:
    """Heights and |F| over time with the parts of the run shaded and named (paper Figs. 6-7).

    Parameters
    ----------
    t : ndarray, shape (n,)
        Simulation time, s (NaN rows break the lines: the F/T calibration records nothing).
    tcp : dict name -> ndarray (n,)
        World z (m) of the tool centre point: ``actual``, ``commanded``, ``reference``.
    contact : dict name -> ndarray (n,), optional
        World z (m) of the ``contact_point`` (the sponge's lowest point) and the ``surface``
        under it.
    force_norm : ndarray, shape (n,)
        Measured |F|, N.
    target_force : float
        F_0, N.
    segments : sequence of (start time s, name)
        Parts of the run (approach, F/T calibration, learning, ...), shaded and named.
    title : str
    end_of_learning : float, optional
        Time of the dashed vertical line, s.
    """
    figure, axes = _figure(3 if contact is not None else 2, 2.3, width=10.0)
    _shade_segments(axes, segments, float(np.nanmax(t)))
    styles = {"actual": (INPUT, "-", 1.2), "commanded": ("0.5", ":", 1.0),
              "reference": (LEARNED, "--", 1.0)}
    for name, values in tcp.items():
        colour, style, width = styles.get(name, ("0.3", "-.", 1.0))
        axes[0].plot(t, values, color=colour, linestyle=style, linewidth=width, label=f"TCP {name}")
    axes[0].set_ylabel("tool centre point\n(TCP) z (m)")
    if contact is not None:
        axes[1].plot(t, contact["surface"], color=REFERENCE, linewidth=1.0, label="surface")
        axes[1].plot(t, contact["contact_point"], color=hex_colour((240, 180, 20)), linewidth=1.0,
                     label="contact point")
        axes[1].set_ylabel("contact point\nand surface z (m)")
        axes[1].set_title("contact point: the sponge's lowest point; surface: under it",
                          fontsize="small", loc="left")
    ax_f = axes[-1]
    ax_f.plot(t, force_norm, color=INPUT, linewidth=0.8, label="measured |F|")
    ax_f.axhline(target_force, color=REFERENCE, linestyle="--", linewidth=0.8,
                 label=f"F0 = {target_force:g} N")
    ax_f.set_ylabel("|F| (N)")
    ax_f.set_xlabel("time (s)")
    for ax in axes:
        if end_of_learning is not None:
            ax.axvline(end_of_learning, color="black", linestyle="--", linewidth=1.2)
        _legend_right(ax)
    if end_of_learning is not None:
        ax_f.annotate("end of learning", (end_of_learning, 1.0),
                      xycoords=("data", "axes fraction"), xytext=(3, -12),
                      textcoords="offset points", fontsize="small")
    figure.suptitle(title)
    return figure


def profile_figure(phase: np.ndarray, surface_mm: np.ndarray,
                   learned_mm: Sequence[np.ndarray], title: str) -> Figure:
    """The learned height profile after each period against the true surface, over the phase
    of the movement (how the profile converges, cf. paper Figs. 6-7).

    Parameters
    ----------
    phase : ndarray, shape (m,)
        Phase, rad, in [0, 2 pi).
    surface_mm : ndarray, shape (m,)
        The true surface as the TCP height at which the sponge presses with F_0, mm from its
        mean.
    learned_mm : sequence of ndarray (m,)
        The learned profile after period 1, 2, ..., mm from the same mean.
    """
    figure, (ax,) = _figure(1, 3.4, width=9.0)
    ramp = np.linspace(0.25, 1.0, len(learned_mm)) if len(learned_mm) > 1 else [1.0]
    for period, (values, strength) in enumerate(zip(learned_mm, ramp), start=1):
        ax.plot(phase, values, color=LEARNED, alpha=float(strength), linewidth=1.0 + strength,
                label=f"learned, period {period}")
    ax.plot(phase, surface_mm, color=REFERENCE, linestyle="--", linewidth=1.5,
            label="true surface (TCP z at F0)")
    ax.set_xticks(*PHASE_TICKS)
    ax.set_xlim(0.0, 2.0 * math.pi)
    ax.set_xlabel("phase of the movement (rad)")
    ax.set_ylabel("height - mean (mm)")
    ax.set_title(title)
    _legend_right(ax)
    return figure


def force_over_phase_figure(curves: dict[str, list[tuple[str, tuple, np.ndarray, np.ndarray]]],
                            target_force: float, title: str) -> Figure:
    """|F| over the phase, one panel per replay mode, every speed overlaid.

    Parameters
    ----------
    curves : dict mode -> [(speed label e.g. "2x (0.50 Hz)", (3,) uint8 colour, phase (m,)
        rad, mean |F| (m,) N), ...]
    target_force : float
        F_0, N.
    """
    modes = list(curves)
    columns = 2 if len(modes) > 1 else 1
    rows = math.ceil(len(modes) / columns)
    figure = Figure(figsize=(5.0 * columns + 1.6, 0.8 + 2.8 * rows), dpi=110,
                    layout="constrained")
    axes = figure.subplots(rows, columns, squeeze=False, sharex=True)
    for ax, mode in zip(axes.ravel(), modes):
        for label, colour, phase, force in curves[mode]:
            ax.plot(phase, force, color=hex_colour(colour), linewidth=1.5, label=label)
        ax.axhline(target_force, color=REFERENCE, linestyle="--", linewidth=0.8,
                   label=f"F0 = {target_force:g} N")
        ax.set_title(mode, color=hex_colour(MODE_COLOURS.get(mode, (0, 0, 0))), loc="left")
        ax.set_xticks(*PHASE_TICKS)
        ax.set_xlim(0.0, 2.0 * math.pi)
        ax.set_ylim(bottom=0.0)
        ax.set_ylabel("|F| (N)")
        ax.grid(True, linewidth=0.5, alpha=0.5)
    for ax in axes.ravel()[len(modes):]:
        ax.set_visible(False)
    for ax in axes[-1]:
        ax.set_xlabel("phase of the movement (rad)")
    axes[0, -1].legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize="small",
                       title="speed")
    figure.suptitle(title)
    return figure


def force_error_bars_figure(rms_error: dict[str, dict[str, float]], title: str) -> Figure:
    """RMS(|F| - F0) per speed (groups, labelled with their frequency) and mode (bars, one
    colour per mode).

    Parameters
    ----------
    rms_error : dict tempo label (e.g. "1.5x (0.45 Hz)": x the demonstrated tempo, and the
        Hz it ran at) -> {mode: RMS error in N}
    title : str
    """
    speeds = list(rms_error)
    modes = [m for m in MODE_COLOURS if any(m in values for values in rms_error.values())]
    modes += sorted({m for values in rms_error.values() for m in values} - set(modes))
    figure = Figure(figsize=(8.5, 3.4), dpi=110, layout="constrained")
    ax = figure.subplots()
    width = 0.8 / max(len(modes), 1)
    x = np.arange(len(speeds))
    for i, mode in enumerate(modes):
        values = [rms_error[s].get(mode, np.nan) for s in speeds]
        bars = ax.bar(x + (i - (len(modes) - 1) / 2) * width, values, width, label=mode,
                      color=hex_colour(MODE_COLOURS.get(mode, (128, 128, 128))))
        ax.bar_label(bars, fmt="%.2f", fontsize="x-small", padding=1)
    ax.set_xticks(x, speeds)
    ax.set_xlabel("tempo: x the demonstrated one (Hz it ran at)")
    ax.set_ylabel("RMS(|F| - F0) (N)")
    ax.set_title(title)
    ax.grid(True, axis="y", linewidth=0.5, alpha=0.5)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize="small", title="mode")
    return figure


def _shade(ax, t: np.ndarray, mask: np.ndarray, colour: str, label: str) -> None:
    """Shade the stretches of ``t`` where ``mask`` holds, labelled once; each sample covers
    its own period (half of it either side), so that a single frame shows too."""
    if not mask.any():
        return
    half = 0.5 * float(np.median(np.diff(t))) if len(t) > 1 else 0.0
    for n, (start, stop) in enumerate(true_runs(mask)):
        ax.axvspan(t[start] - half, t[stop - 1] + half, color=colour, alpha=0.25, linewidth=0,
                   label=label if n == 0 else None)


def _shade_segments(axes: list, segments: Sequence[tuple[float, str]], t_end: float) -> None:
    """Shade each part of the run in its colour and name it on a top axis."""
    bounds = [start for start, _ in segments[1:]] + [t_end]
    for (start, name), end in zip(segments, bounds):
        for ax in axes:
            ax.axvspan(start, end, color=hex_colour(segment_colour(name)), alpha=0.12,
                       zorder=0, linewidth=0)
    top = axes[0].secondary_xaxis("top")
    top.set_xticks([(start + end) / 2 for (start, _), end in zip(segments, bounds)],
                   [name for _, name in segments], rotation=25, ha="left",
                   fontsize="x-small", color="0.25")
    top.tick_params(length=0)
