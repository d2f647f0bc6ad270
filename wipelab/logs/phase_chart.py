"""Curves over one period of the phase, drawn as a chart in a Rerun 2D view.

Rerun plots series over a timeline only. A quantity over the phase of the periodic movement
(the learned height profile period by period, the force at each speed) is drawn here as line
strips in a 2D view with axes, ticks and labels of its own. Chart coordinates: x from 0 to
:attr:`PhaseChart.width` over one period, y downwards (as in an image) from the top of the
value range to its bottom at :attr:`PhaseChart.height`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import rerun as rr
import rerun.blueprint as rrb

from wipelab.logs.palette import REFERENCE_COLOUR
from wipelab.mask_runs import true_runs

#: Phase ticks (rad) and their labels.
PHASE_TICKS = ((0.0, "0"), (0.5 * math.pi, "π/2"), (math.pi, "π"), (1.5 * math.pi, "3π/2"),
               (2.0 * math.pi, "2π"))
#: Mid greys (the grid half transparent): readable on the viewer's dark and light themes.
AXIS_COLOUR, GRID_COLOUR, LABEL_COLOUR = (140, 140, 140), (128, 128, 128, 70), (140, 140, 140)
#: How far (fraction of the chart height) a label's anchor sits above the text it centres.
LABEL_LIFT = 0.06


def nice_ticks(low: float, high: float, count: int = 5) -> np.ndarray:
    """Round tick values covering [low, high], 1, 2, 5 or 10 times a power of ten apart:
    the spacing whose number of ticks is closest to ``count`` (the fewer on a tie)."""
    span = max(high - low, 1e-12)
    power = 10.0 ** math.floor(math.log10(span / max(count - 1, 1)))

    def ticks(step: float) -> np.ndarray:
        return np.arange(math.floor(low / step + 1e-9), math.ceil(high / step - 1e-9) + 1) * step

    options = [ticks(m * power) for m in (1.0, 2.0, 5.0, 10.0)]
    return min(options, key=lambda values: (abs(len(values) - count), len(values)))


@dataclass(frozen=True)
class PhaseChart:
    """A chart of values over one period of the phase (0 to 2 pi rad).

    Attributes
    ----------
    y_ticks : ndarray, shape (m,)
        Tick values on the value axis, increasing; the first and last bound the chart.
    y_label : str
        Name and unit of the value axis, e.g. ``"|F| (N)"``.
    width, height : float
        Size of the plotting area in chart units.
    """

    y_ticks: np.ndarray
    y_label: str
    width: float = 400.0
    height: float = 220.0

    @classmethod
    def fitting(cls, values, y_label: str, ticks: int = 5) -> PhaseChart:
        """A chart whose value axis covers the finite ``values`` (any shape)."""
        values = np.asarray(values, dtype=float)
        finite = values[np.isfinite(values)]
        low, high = (0.0, 1.0) if finite.size == 0 else (float(finite.min()), float(finite.max()))
        if high - low < 1e-9:
            low, high = low - 0.5, high + 0.5
        return cls(nice_ticks(low, high, ticks), y_label)

    def to_chart(self, phase: np.ndarray, values: np.ndarray) -> np.ndarray:
        """Chart coordinates (n, 2) of values (n,) at phases (n,) rad (taken modulo 2 pi
        except for an exact 2 pi, the end of the period)."""
        phase = np.asarray(phase, dtype=float)
        wrapped = np.where(np.isclose(phase, 2.0 * math.pi), 2.0 * math.pi,
                           np.mod(phase, 2.0 * math.pi))
        low, high = float(self.y_ticks[0]), float(self.y_ticks[-1])
        x = wrapped / (2.0 * math.pi) * self.width
        y = (high - np.asarray(values, dtype=float)) / (high - low) * self.height
        return np.column_stack([x, y])

    def strips(self, phase: np.ndarray, values: np.ndarray) -> list[np.ndarray]:
        """The curve as line strips in chart coordinates, split where values are not finite
        (a gap stays a gap)."""
        points = self.to_chart(phase, values)
        finite = np.isfinite(points).all(axis=1)
        return [points[a:b] for a, b in true_runs(finite) if b - a > 1]

    @classmethod
    def bounds(cls) -> rrb.VisualBounds2D:
        """A 2D view's visible area for charts of the default size: the plot with room for
        the tick labels, the legend above it and the reference labels on the right."""
        return rrb.VisualBounds2D(x_range=[-0.16 * cls.width, 1.2 * cls.width],
                                  y_range=[-0.32 * cls.height, 1.14 * cls.height])

    def log_axes(self, stream: rr.RecordingStream, entity: str,
                 references: dict[str, float] | None = None) -> None:
        """The frame, grid, ticks and the value axis's name, static, under ``entity``/axes;
        each reference value (label -> value, e.g. ``{"F0 = 10 N": 10.0}``) as a line
        labelled on the right. (Rerun writes a point's label under the point.)"""
        w, h = self.width, self.height
        ys = self.to_chart(np.zeros(len(self.y_ticks)), self.y_ticks)[:, 1]
        xs = [phase / (2.0 * math.pi) * w for phase, _ in PHASE_TICKS]
        grid = [np.array([[0.0, y], [w, y]]) for y in ys] + \
               [np.array([[x, 0.0], [x, h]]) for x in xs]
        stream.log(f"{entity}/axes/grid", rr.LineStrips2D(grid, colors=GRID_COLOUR, radii=0.4,
                                                          draw_order=1.0), static=True)
        frame = np.array([[0.0, 0.0], [w, 0.0], [w, h], [0.0, h], [0.0, 0.0]])
        stream.log(f"{entity}/axes/frame", rr.LineStrips2D([frame], colors=AXIS_COLOUR,
                                                           radii=0.6, draw_order=2.0),
                   static=True)
        lift = LABEL_LIFT * h
        labels = [f"{v:g}" for v in self.y_ticks] + [text for _, text in PHASE_TICKS]
        anchors = [[-0.07 * w, y - lift] for y in ys] + [[x, 1.02 * h] for x in xs]
        labels.append(self.y_label)
        anchors.append([0.0, -0.1 * h - lift])
        references = references or {}
        if references:
            ry = self.to_chart(np.zeros(len(references)), np.array(list(references.values())))[:, 1]
            stream.log(f"{entity}/axes/references", rr.LineStrips2D(
                [np.array([[0.0, y], [w, y]]) for y in ry], colors=REFERENCE_COLOUR, radii=0.8,
                draw_order=5.0), static=True)
            labels += list(references)
            anchors += [[1.1 * w, y - lift] for y in ry]
        stream.log(f"{entity}/axes/labels", rr.Points2D(anchors, labels=labels, radii=0.01,
                                                         colors=LABEL_COLOUR, show_labels=True),
                   static=True)

    def log_legend(self, stream: rr.RecordingStream, entity: str,
                   entries: dict[str, tuple]) -> None:
        """A legend above the plot, static, under ``entity``/legend: per entry (label ->
        (3,) uint8 colour) a short line in its colour with the label over it, up to three
        entries a row."""
        w, h = self.width, self.height
        columns = min(len(entries), 3)
        strips, colours, anchors = [], [], []
        for k, (label, colour) in enumerate(entries.items()):
            x = (k % columns + 0.5) * w / columns
            y = -0.12 * h - (k // columns) * 0.16 * h
            strips.append(np.array([[x - 0.05 * w, y], [x + 0.05 * w, y]]))
            colours.append(colour)
            anchors.append([x, y - 0.08 * h - LABEL_LIFT * h])
        stream.log(f"{entity}/legend", rr.LineStrips2D(strips, colors=colours, radii=1.5),
                   rr.Points2D(anchors, labels=list(entries), radii=0.01, colors=colours,
                               show_labels=True), static=True)
