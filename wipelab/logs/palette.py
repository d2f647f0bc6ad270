"""The colours of every plot: the same in the Rerun layouts and the report's figures.

One colour per replay mode, per replay speed, per axis of a position, for demonstrated vs
learned. RGB uint8 tuples; :func:`hex_colour` gives matplotlib's form.
"""

from __future__ import annotations

from collections.abc import Sequence

#: x, y, z of a position (red, green, blue, as the axes drawn in 3D).
XYZ_COLOURS = {"x": (230, 75, 60), "y": (70, 180, 70), "z": (70, 130, 230)}
#: Demonstrated / measured input and the learned output.
INPUT_COLOUR, LEARNED_COLOUR = (70, 150, 230), (235, 90, 60)
#: The oscillators' frequencies (learn; the chosen fundamental is drawn as a reference).
OSCILLATOR_COLOURS = ((70, 150, 230), (240, 150, 40), (200, 70, 160))
#: A reference value (F0, a true value): mid grey, seen on the viewer's dark and light themes.
REFERENCE_COLOUR = (150, 150, 150)
#: Replay modes.
MODE_COLOURS = {"learned": (60, 130, 230), "learned+compliance": (40, 175, 120),
                "compliance": (240, 150, 40), "planar": (200, 70, 160)}
#: Replay speeds in increasing order (amber = slowest, then red, purple, blue, ...).
SPEED_RAMP = ((235, 170, 20), (230, 80, 60), (150, 60, 190), (60, 120, 230), (40, 190, 200),
              (120, 200, 90))
#: The parts of an adapt or replay run that are not a wiping run.
PHASE_COLOURS = {"approach": (120, 120, 120), "F/T calibration": (230, 190, 60),
                 "learning": (70, 150, 230), "learned profile": (40, 175, 120),
                 "move": (90, 90, 90), "end": (60, 60, 60), "refining": (150, 110, 210)}


def segment_colour(name: str) -> tuple[int, int, int]:
    """Colour of a part of a run by its name: :data:`PHASE_COLOURS` (adapt's "refining at
    <f> Hz" by its first word), or for a replay run ("<scale>x (<f> Hz) <mode>") the colour
    of its mode."""
    return (PHASE_COLOURS.get(name) or PHASE_COLOURS.get(name.split(" ", 1)[0])
            or MODE_COLOURS.get(name.rsplit(" ", 1)[-1], (120, 120, 120)))


def speed_colours(scales: Sequence[float]) -> dict[float, tuple[int, int, int]]:
    """A colour per frequency scale, by rank: the slowest gets the first colour of
    :data:`SPEED_RAMP`, and so on."""
    ordered = sorted(set(float(s) for s in scales))
    return {s: SPEED_RAMP[min(i, len(SPEED_RAMP) - 1)] for i, s in enumerate(ordered)}


def hex_colour(rgb: Sequence[int]) -> str:
    """``(r, g, b)`` uint8 -> ``"#rrggbb"`` (matplotlib)."""
    return "#" + "".join(f"{int(c):02x}" for c in rgb[:3])
