"""The demonstration area of the paper's Fig. 3 and the normalised offsets from its centre.

"For learning of movements we first define the area of demonstration by measuring the
lower-left and the upper-right position within a given time-frame [...]. All tracked
sponge-movement is then normalized and given as offset to the central position of this
area." (Sec. III-A2). Here the area is the axis-aligned rectangle spanned by the smallest
and largest x and y of the tracked sponge centre within the time window; the normalised
offset of a position is its offset from the rectangle's centre divided by the rectangle's
half-size, per axis, so positions inside the area map to [-1, 1].
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Smallest half-size used for normalising, metres (a straight stroke has no width).
MIN_HALF_SIZE = 0.005


@dataclass(frozen=True)
class DemonstrationArea:
    """Rectangle of the demonstration in the horizontal plane.

    Attributes
    ----------
    lower_left : ndarray, shape (2,)
        (min x, min y), metres.
    upper_right : ndarray, shape (2,)
        (max x, max y), metres.
    window : tuple of float
        Time window (start, end) it was measured in, seconds.
    """

    lower_left: np.ndarray
    upper_right: np.ndarray
    window: tuple[float, float]

    @property
    def centre(self) -> np.ndarray:
        """Centre of the rectangle, (x, y), metres."""
        return 0.5 * (self.lower_left + self.upper_right)

    @property
    def half_size(self) -> np.ndarray:
        """Half width along x and y, metres, at least :data:`MIN_HALF_SIZE`."""
        return np.maximum(0.5 * (self.upper_right - self.lower_left), MIN_HALF_SIZE)

    def normalise(self, xy: np.ndarray) -> np.ndarray:
        """Normalised offsets (n, 2) of positions (n, 2): (p - centre) / half_size."""
        return (np.asarray(xy, dtype=np.float64) - self.centre) / self.half_size


def measure_demonstration_area(t: np.ndarray, xy: np.ndarray, valid: np.ndarray,
                               window: tuple[float, float]) -> DemonstrationArea:
    """Lower-left and upper-right corners of the valid positions inside a time window.

    Parameters
    ----------
    t : ndarray, shape (n,)
        Seconds.
    xy : ndarray, shape (n, 2)
        Positions, metres (NaN where invalid).
    valid : ndarray of bool, shape (n,)
    window : tuple of float
        (start, end), seconds. If fewer than two valid positions fall inside it, the whole
        recording is used (and ``window`` of the result says so).

    Raises
    ------
    ValueError
        If there are fewer than two valid positions at all.
    """
    valid = np.asarray(valid, dtype=bool)
    inside = valid & (t >= window[0]) & (t <= window[1])
    if inside.sum() < 2:
        inside = valid
        window = (float(t[0]), float(t[-1])) if len(t) else window
    if inside.sum() < 2:
        raise ValueError("need at least two valid positions to measure the demonstration area")
    points = xy[inside]
    return DemonstrationArea(points.min(axis=0), points.max(axis=0),
                             (float(window[0]), float(window[1])))


class AreaMeter:
    """The demonstration area measured online, as a robot watching would (Fig. 3): the
    rectangle of the valid positions from the first one added until :meth:`freeze`; later
    positions are normalised by it.

    Attributes
    ----------
    area : DemonstrationArea or None
        The rectangle so far (None before two positions); ``window`` spans the times of the
        first and the last position it holds.
    frozen : bool
    """

    def __init__(self):
        self.area: DemonstrationArea | None = None
        self.frozen = False
        self._first: tuple[float, np.ndarray] | None = None

    def add(self, t: float, xy: np.ndarray) -> None:
        """Take the valid position ``xy`` (2,) (m) at time ``t`` (s), unless frozen."""
        if self.frozen:
            return
        xy = np.asarray(xy, dtype=np.float64)
        if self._first is None:
            self._first = (float(t), xy)
            return
        lower = xy if self.area is None else np.minimum(self.area.lower_left, xy)
        upper = xy if self.area is None else np.maximum(self.area.upper_right, xy)
        if self.area is None:
            lower, upper = np.minimum(lower, self._first[1]), np.maximum(upper, self._first[1])
        self.area = DemonstrationArea(lower, upper, (self._first[0], float(t)))

    def freeze(self) -> None:
        """Stop measuring: the area is what it is now."""
        self.frozen = True
