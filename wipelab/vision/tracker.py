"""The sponge tracker of the track stage (paper, Sec. III-A2: colour segmentation and a
particle filter on the stereo pair, 30 Hz).

Two estimators share the work:

* the region tracker (:mod:`wipelab.vision.region_tracker`) always runs: it finds the
  sponge among everything of its colour (the region that moves, is consistent between the
  two views and has a sponge's size), learns its colour, measures the table by dense stereo,
  and places the centroids of the sponge's colour region in both cameras on a plane parallel
  to the table. It needs nothing about the sponge but its colour (quality ``centroid``);
* when the sponge's dimensions are known (``demo.toml``, ``--sponge-size``), the box
  refinement (:mod:`wipelab.vision.box_tracker`: a particle filter over box poses and a
  Newton fit of the box outline) gives the box centre itself to a fraction of a millimetre
  (quality ``box``). Whenever it cannot fit (a hand over an edge, blur, a box of other
  proportions) the region's estimate stands in, shifted by the offset between the two
  learnt while both held, and the filter is seeded again from it.

A frame is reported valid only when the estimate that stands is backed by both images; a
distractor, a stale estimate or a guess during an occlusion is never valid. Looking back over
a whole video, a valid run too short to be the sponge found again (:func:`fleeting_runs`),
or one that kept still once the sponge had wiped (:func:`still_runs`), is not valid either.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field, replace

import numpy as np

from wipelab.mask_runs import true_runs
from wipelab.vision.calibration import StereoCalibration
from wipelab.vision.colour_model import ColourSource, LinearColourFeature
from wipelab.vision.projection import invert_transform, transform_points
from wipelab.vision.region_tracker import (QUALITY_BOX, QUALITY_CENTROID, QUALITY_MONO,
                                           QUALITY_NONE, RegionTracker, RegionTrackerParams,
                                           keeps_still)
from wipelab.vision.particle_filter import wrap_half_turn
from wipelab.vision.sponge_box import SpongeBox
from wipelab.vision.table_plane import table_axes

__all__ = ["TrackerParams", "FrameEstimate", "SpongeTracker", "fleeting_runs", "still_runs",
           "commonest_failure",
           "QUALITY_BOX", "QUALITY_CENTROID", "QUALITY_MONO", "QUALITY_NONE"]

#: A run of valid frames between losses that lasts at most this long (seconds) is a fleeting
#: blob of the sponge's colour, not the sponge found again: while the sponge is hidden, a
#: cloth's edge between the occluder and the arm, or a hand of a near hue, passes the checks
#: for a few frames; a sponge that shows again stays in view.
FLEETING_RUN_S = 0.2


def fleeting_runs(valid: np.ndarray, fps: float, longest_s: float = FLEETING_RUN_S
                  ) -> np.ndarray:
    """The frames (bool mask, shape of ``valid``) of the runs of valid frames that last at
    most ``longest_s`` seconds at ``fps`` frames per second, except a run that the video's
    end cuts off (it may have gone on)."""
    longest = int(np.floor(longest_s * fps + 1e-9))
    fleeting = np.zeros(len(valid), bool)
    for start, end in true_runs(valid):
        if end - start <= longest and end < len(valid):
            fleeting[start:end] = True
    return fleeting


def still_runs(valid: np.ndarray, points: np.ndarray, size: float,
               params: RegionTrackerParams) -> np.ndarray:
    """The frames (bool mask, shape of ``valid``) of the runs of valid frames after the
    first one that moved whose ``points`` (n, 3), metres, kept still
    (:func:`~wipelab.vision.region_tracker.keeps_still` for a thing of ``size``): a
    sponge-sized patch of a cloth, a cup or a plate found where the sponge was lost,
    whatever the run's length (the tracker forgets one only after ``params.still_seconds``);
    once it wipes, the sponge moves. Still runs before the first that moved are the sponge
    resting where the demonstration starts. A run goes on over gaps of up to
    ``params.coast_frames`` frames (the tracker loses the sponge only after longer ones)."""
    still = np.zeros(len(valid), bool)
    runs: list[list[int]] = []
    for start, end in true_runs(valid):
        if runs and start - runs[-1][1] <= params.coast_frames:
            runs[-1][1] = end
        else:
            runs.append([start, end])
    moved = False
    for start, end in runs:
        inside = np.flatnonzero(valid[start:end]) + start
        if not keeps_still(points[inside], size, params):
            moved = True
        elif moved:
            still[inside] = True
    return still


#: Why frames were not valid, by words of the region tracker's reasons, in the terms a user
#: can act on (the first that matches a reason names it).
FAILURE_KINDS = (
    ("usual area", "the sponge's colour region kept changing size (a thing of its colour "
                   "joining it, or the hand hiding it)"),
    ("another size", "the sponge's colour region was of another size in each camera"),
    ("disagree", "the two cameras' regions of its colour did not show one thing"),
    ("has not moved", "what was followed stood still"),
    ("search", "it was lost and not found again"),
    ("not seen", "it was lost and not found again"),
)


def commonest_failure(reasons) -> tuple[str, float]:
    """The commonest kind of failure among the reasons of frames that were not valid (any
    iterable of strings; :data:`FAILURE_KINDS`, else "its colour region failed the tracker's
    checks") and its share of them (0 to 1; ("", 0.0) for none)."""
    counts: dict[str, int] = {}
    for reason in reasons:
        kind = next((text for words, text in FAILURE_KINDS if words in reason),
                    "its colour region failed the tracker's checks")
        counts[kind] = counts.get(kind, 0) + 1
    if not counts:
        return "", 0.0
    kind = max(counts, key=lambda key: (counts[key], key))
    return kind, counts[kind] / sum(counts.values())


@dataclass(frozen=True)
class TrackerParams:
    """Tracker settings.

    Attributes
    ----------
    particles : int
        Particles of the box refinement's filter.
    seed : int
        Seed of the filter's random numbers.
    sponge : SpongeBox or None
        The sponge's dimensions when known: enables the box refinement. None: the sponge
        is tracked by its colour region alone.
    region : RegionTrackerParams
    region_every : int
        While the box fits, the region is measured on every n-th frame only (to keep the
        offset between the two up to date).
    fps : float
        Frame rate of the video (the sponge is told by its periodic motion).
    """

    particles: int = 100
    seed: int = 0
    sponge: SpongeBox | None = None
    region: RegionTrackerParams = field(default_factory=RegionTrackerParams)
    region_every: int = 5
    fps: float = 30.0

    def __post_init__(self):
        if self.particles < 10:
            raise ValueError("particles must be at least 10")


@dataclass(frozen=True)
class FrameEstimate:
    """The tracker's answer for one frame pair.

    Attributes
    ----------
    pose : ndarray, shape (4,)
        Sponge centre (x, y, z) in the tracking frame, metres, and yaw (rad: of the box, or
        of the colour region's longer axis); NaN when not valid.
    valid : bool
    quality : str
        ``box``, ``centroid``, ``mono`` or ``""`` (not valid); see
        :class:`~wipelab.vision.region_tracker.RegionEstimate`.
    areas : ndarray, shape (2,)
        Pixels of the sponge's colour region in the left and right image (0 when not
        measured this frame).
    particles : ndarray, shape (n, 4)
        The box refinement's particles (empty without it).
    reason : str
        Why a frame is not valid.
    """

    pose: np.ndarray
    valid: bool
    quality: str
    areas: np.ndarray
    particles: np.ndarray
    reason: str = ""


class SpongeTracker:
    """Track the sponge in 3D through a calibrated stereo video, frame by frame.

    Parameters
    ----------
    calibration : StereoCalibration
        Poses are reported in ``calibration.track_frame`` (world if it has T_world_left).
    colour : ColourSource
        The sponge body's colour (a named colour, an HSV range or a region of the first left
        frame).
    params : TrackerParams
    """

    def __init__(self, calibration: StereoCalibration, colour: ColourSource,
                 params: TrackerParams = TrackerParams()):
        self.calibration = calibration
        self.params = params
        region = replace(params.region, acquisition=replace(params.region.acquisition,
                                                              fps=params.fps))
        self.region = RegionTracker(calibration, colour, region)
        self.box = None
        if params.sponge is not None:
            # imported here: its compiled kernels (numba, 0.2 s to import) serve a known box only
            from wipelab.vision.box_tracker import BoxParams, BoxTracker
            self.box = BoxTracker(calibration, BoxParams(particles=params.particles,
                                                         seed=params.seed,
                                                         sponge=params.sponge))
        self.T_track_left = calibration.T_track_left
        self.T_left_track = invert_transform(self.T_track_left)
        self.feature: LinearColourFeature | None = None
        self.offsets: deque[np.ndarray] = deque(maxlen=30)  # box centre - region point, left
        self._median_offset: np.ndarray | None = None
        self._table_axes: tuple[bytes, np.ndarray] | None = None  # (plane normal, axes)
        self.frame = -1

    @property
    def identified(self) -> bool:
        """Whether the sponge has been found."""
        return self.region.identified

    @property
    def ready(self) -> bool:
        """Whether everything a second pass needs is known (sponge, plane of motion)."""
        return self.region.identified and self.region.sponge_plane() is not None

    def accept_any_motion(self) -> None:
        """Let a thing of the colour that moves, but not yet periodically, be the sponge:
        for a video too short for periodic motion to show (the track stage asks after a
        whole pass found nothing)."""
        region = self.region
        region.params = replace(region.params, acquisition=replace(
            region.params.acquisition, min_periodicity=0.0))
        region.candidates.params = region.params.acquisition

    def widen_colour(self, side: int) -> None:
        """Search for a sponge whose colour lies a little above (``side`` +1) or below (-1)
        the named one too, between two names (0: the named colour again;
        :meth:`RegionTracker.widen_search`)."""
        self.region.widen_search(side)

    def restart(self) -> None:
        """Forget the track, keep what was learnt (for a second pass from the video's start)."""
        self.region.restart()
        if self.box is not None:
            self.box.tracking = False
        self.frame = -1

    def step(self, left: np.ndarray, right: np.ndarray) -> FrameEstimate:
        """Process the next synchronised frame pair (BGR uint8)."""
        self.frame += 1
        if self.box is not None and self.box.tracking:
            estimate = self._box_step(left, right)
            if estimate is not None:
                return estimate
        region = self.region.step(left, right)
        if not region.valid:
            return FrameEstimate(np.full(4, np.nan), False, QUALITY_NONE, region.areas,
                                 self._particles(), region.reason)
        point = region.point + self._offset()
        if self.box is not None:
            self._start_box(left, right, point)
        pose = np.append(transform_points(self.T_track_left, point),
                         self._yaw(region.direction))
        return FrameEstimate(pose, True, region.quality, region.areas, self._particles())

    def table_axes_in_track(self) -> np.ndarray:
        """Axes (3, 3) of the table in the tracking frame, as yaw is measured about them
        (:func:`table_axes` of the plane the sponge moves in; identity before it is known);
        not to be changed."""
        plane = self.region.sponge_plane()
        if plane is None:
            return np.eye(3)
        normal = plane.normal.tobytes()  # refitted often, the plane keeps its normal mostly
        if self._table_axes is None or self._table_axes[0] != normal:
            self._table_axes = (normal, table_axes(self.T_track_left[:3, :3] @ plane.normal))
        return self._table_axes[1]

    def _yaw(self, direction_left: np.ndarray) -> float:
        """Yaw (rad, half turn) of the region's long axis (3,), left frame, about the table
        normal (:meth:`table_axes_in_track`), measured like the box's."""
        d = self.table_axes_in_track().T @ (self.T_track_left[:3, :3] @ direction_left)
        return float(wrap_half_turn(np.arctan2(d[1], d[0])))

    # -------------------------------------------------------------- the box
    def _box_step(self, left, right) -> FrameEstimate | None:
        """The box fit of this frame, or None when it failed (the region takes over)."""
        box = self.box.step(left, right)
        if not box.valid:
            return None
        centre_left = transform_points(self.T_left_track, box.pose[:3])
        areas = np.zeros(2)
        if not self.offsets or self.frame % self.params.region_every == 0:
            region = self.region.step(left, right)
            areas = region.areas
            if region.valid:
                self.offsets.append(centre_left - region.point)
                self._median_offset = None
        else:
            self.region.observe(centre_left - self._offset())
        return FrameEstimate(box.pose, True, QUALITY_BOX, areas, box.particles)

    def _offset(self) -> np.ndarray:
        """Box centre minus region point (3,), left frame: median over recent frames, 0
        before the box ever fitted (computed again only when a new offset came in)."""
        if self._median_offset is None:
            self._median_offset = np.median(np.array(self.offsets), axis=0) if self.offsets \
                else np.zeros(3)
        return self._median_offset

    def _start_box(self, left, right, centre_left: np.ndarray) -> None:
        """Seed the box refinement at the region's estimate (and learn the colour feature the
        refinement reads on the first occasion)."""
        region = self.region
        if region.table is None:
            return
        if self.feature is None:
            try:
                self.feature = LinearColourFeature.fit(region.seed_windows, region.seed_masks)
            except ValueError:  # too few of the sponge's pixels to learn it from yet
                return
        R_track_table = table_axes(self.T_track_left[:3, :3] @ region.table.normal)
        if self.box.R_track_table is not None and np.allclose(self.box.R_track_table,
                                                              R_track_table):
            R_track_table = self.box.R_track_table
        if not self.offsets:
            # before the first fit: the box centre half the sponge's height above the table
            height = self.params.sponge.height / 2 - float(region.table.distance(centre_left))
            centre_left = centre_left + height * region.table.normal
        self.box.start(region.body_model, self.feature, R_track_table,
                       transform_points(self.T_track_left, centre_left))

    def _particles(self) -> np.ndarray:
        if self.box is None or self.box.particles is None:
            return np.zeros((0, 4))
        return self.box.particles.copy()
