"""Frame-by-frame tracking of the sponge's colour region in a calibrated stereo pair.

Per frame pair (paper, Sec. III-A2: colour segmentation in both cameras, 30 Hz):

1. find the sponge: until it is identified, low-resolution colour blobs of both images,
   without the still things of the colour (a background of the recent frames tells them),
   are paired into 3D candidates and followed; the one that moves like a wiping sponge is
   the sponge (:mod:`wipelab.vision.acquisition`). Its colour is then learnt from the vivid
   part of its pixels (not a duller hand or table of a near hue) against its surroundings,
   and the table top's plane is measured by dense stereo around it
   (:mod:`wipelab.vision.table_stereo`);
2. measure: inside a window around the predicted position, each undistorted image is
   back-projected through the colour model; the colour region nearest the prediction gives
   a sub-pixel centroid, hence a viewing ray per camera;
3. locate: the sponge slides on the table, so its point is where both rays best meet a plane
   parallel to the table (:func:`~wipelab.vision.table_plane.points_on_plane`), at the
   height its stereo points keep above the table. Stereo alone is poor along the line of
   sight; the plane makes every camera's lateral precision count;
4. check: a frame is valid only when both regions have their usual size (a hand passing in
   front shrinks them; until the usual sizes are known, the two cameras' regions must agree
   in size), both rays agree on the plane as they usually do, and the point continues the
   track; otherwise the sponge is lost and found again by the rules of step 1, with what is
   now known about it (colour, size, static objects of its colour).
"""

from __future__ import annotations

import math
from collections import deque
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, field, replace
from typing import Callable, TypeVar

import cv2
import numpy as np

from wipelab.thread_priority import run_as_helper
from wipelab.vision.acquisition import (AcquisitionParams, CandidateTrack, CandidateTracks,
                                        StereoCandidate, stereo_candidates, triangulate_rays)
from wipelab.vision.calibration import StereoCalibration
from wipelab.vision.colour_model import ColourModel, ColourSource, vivid_part
from wipelab.vision.colour_regions import (blob_mask, find_blobs, hue_centre, hue_range,
                                           prior_model, region_moments, spanning_hues,
                                           vivid_area, widened_hues)
from wipelab.vision.projection import invert_transform
from wipelab.vision.static_background import StaticBackground
from wipelab.vision.table_plane import Plane, fit_plane, points_on_plane
from wipelab.vision.table_stereo import TableStereo
from wipelab.vision.undistortion import Undistorter

T = TypeVar("T")

QUALITY_NONE, QUALITY_CENTROID, QUALITY_MONO, QUALITY_BOX = "", "centroid", "mono", "box"
#: Length of the largest kitchen sponge (its visible area is under this squared), metres.
LARGEST_SPONGE = 0.16
#: While searching for the sponge, the backgrounds are learnt again every this many frames.
BACKGROUND_REFRESH_FRAMES = 15
#: ... from this many of the recent frames.
BACKGROUND_FRAMES = 12
#: ... and from this many when a moving candidate is checked (both cameras at once).
IDENTIFY_BACKGROUND_FRAMES = 24
#: A camera's usual region area is known once this many regions were measured.
USUAL_AREA_FRAMES = 5
#: Until the usual region areas are known, a frame is valid only when the two cameras'
#: regions (square metres at the sponge's distance) agree within this factor.
FIRST_AREAS_AGREEMENT = 1.6
#: Once found, the hues of the sponge's vivid pixels (5th to 95th percentile) are of its
#: colour, also where they reach beyond the named colour's box: there with this many OpenCV
#: hue units (0-179) more.
SPONGE_HUE_MARGIN = 2.0
#: ... measured at most this many times (each with the sponge's region by the range so far).
SPONGE_HUE_ROUNDS = 3
#: ... but not grown where that would make more than this share of the still scene around the
#: sponge (the backgrounds' median, :data:`SPAN_CHECK_REACH` around it) of its colour: a
#: table whose hue lies next to the sponge's, which the sponge's own pixels reach into.
SPAN_SURROUNDINGS = 0.05
#: Half side of the square around the sponge that :data:`SPAN_SURROUNDINGS` and
#: :data:`SCENE_SHARE` look at, metres.
SPAN_CHECK_REACH = 2 * LARGEST_SPONGE
#: A colour model learnt from an identified candidate that reads more than this share of the
#: still scene around it (the backgrounds' median) as the sponge learnt the scene's colour: the
#: candidate was a piece of a table of the named colour (where the arm has been lying, the
#: background has not yet learnt the table), not a sponge. A sponge's model, learnt against
#: its window, reads at most a quarter of any scene as itself (a cloth of its colour there);
#: such pieces of table read 0.43 to 0.65.
SCENE_SHARE = 0.35
#: A camera whose still scene is of the sponge's colour over more than this share of its view
#: sees a table of a near hue: where the arm lay while the background was learnt, the table
#: is not yet known as still and merges with the sponge's blob, which then grows and shrinks
#: as the arm moves. While the sponge is searched for, a blob's vivid part there
#: (:func:`~wipelab.vision.colour_regions.vivid_area`), the sponge's, tells whether its size
#: stays as a sponge's does (:attr:`~wipelab.vision.acquisition.CandidateTrack.vivid_sizes`);
#: its centre and size stay the whole blob's, which both cameras see alike. A cloth or a
#: plate of the colour covers a few hundredths of the view.
TABLE_OF_THE_COLOUR = 0.1
#: The plane the sponge's point moves in lies at most this far under the table's, metres:
#: the sponge's stereo points and the table's dense stereo each miss by a centimetre or two.
PLANE_BELOW_TABLE = 0.03
#: A search widened beyond the named colour (:meth:`RegionTracker.widen_search`) takes hues
#: this far beyond its box.
SEARCH_HUE_WIDENING = 6.0


@dataclass(frozen=True)
class RegionTrackerParams:
    """Settings of the region tracker.

    Attributes
    ----------
    search_width : int
        Width, pixels, images are scaled to for the search (acquisition, after a loss).
    sponge_pixels : float
        A sponge that spans more pixels than twice this is measured on every second (third,
        ...) pixel of the window: enough for sub-pixel centroids, and fast on big images.
    window_size : float
        Half-size of the measurement window in multiples of the sponge's size (plus the
        distance it may move in a frame).
    min_area_ratio, max_area_ratio : float
        A valid region's area, in square metres at the sponge's distance (so that moving
        nearer or farther does not change it), must lie within these factors of its median
        over the last valid frames, or within ``area_margin`` of the range it has spanned
        (the 2nd to 98th percentile; the sponge turning, the holding hand moving on it):
        a hand passing in front shrinks it, a thing of the same colour joining it grows it.
    area_margin : float
    area_floor, area_ceiling : float
        Whatever the range spanned, a valid region's area stays within these factors of the
        median.
    max_ray_disagreement : float
        Largest change, in multiples of the sponge size, of the offset between the two
        cameras' rays on the plane from its running median; once 30 frames are known, up to
        1.5 times the 98th percentile of the changes seen (views far apart see the sponge's
        faces differently as it moves), at most ``ray_disagreement_ceiling``.
    ray_disagreement_ceiling : float
    coast_frames : int
        Frames the window keeps following the prediction after a failed measurement before
        the search covers the whole image again.
    acquisition : AcquisitionParams
    background_every : int
        Frames between updates of the static background (:mod:`.static_background`).
    table_pairs : int
        Frame pairs whose dense stereo measures the table (one when the sponge is found, the
        others every ``table_every`` valid frames after it): more pairs, a steadier plane.
    table_every : int
    table_radius : float
        The table is measured within this distance of the sponge, metres.
    max_height : float
        A moving thing of the sponge's colour whose centre keeps higher than this above the
        table is not the sponge (a hand or sleeve of a near colour), metres.
    still_seconds, still_travel, still_share : float
        A tracked thing that moves less than ``still_travel`` metres or ``still_share`` of
        its own size, whichever is more (90th percentile of its distances from their median),
        over ``still_seconds`` is a still thing the tracker went to, not a wiping sponge: it
        is remembered as still and the sponge searched again. A wiping stroke is longer than
        the sponge; the region of a cloth that the wiping arm covers here and there moves by
        a small share of the cloth's size.
    """

    search_width: int = 320
    sponge_pixels: float = 60.0
    window_size: float = 1.0
    min_area_ratio: float = 0.8
    max_area_ratio: float = 1.25
    area_margin: float = 0.1
    area_floor: float = 0.5
    area_ceiling: float = 2.0
    max_ray_disagreement: float = 0.12
    ray_disagreement_ceiling: float = 0.4
    coast_frames: int = 6
    acquisition: AcquisitionParams = AcquisitionParams()
    background_every: int = 6
    table_pairs: int = 6
    table_every: int = 15
    table_radius: float = 0.5
    max_height: float = 0.08
    still_seconds: float = 3.0
    still_travel: float = 0.01
    still_share: float = 0.25


def keeps_still(points: np.ndarray, size: float, params: RegionTrackerParams) -> bool:
    """Whether a thing tracked at ``points`` (n, 3), metres, of ``size`` metres stood still:
    nine in ten of its points lie within ``params.still_travel`` metres or
    ``params.still_share`` of its size of their median."""
    spread = np.linalg.norm(points - np.median(points, axis=0), axis=1)
    return float(np.percentile(spread, 90)) < max(params.still_travel,
                                                   params.still_share * size)


@dataclass
class RegionEstimate:
    """The tracker's answer for one frame pair.

    Attributes
    ----------
    point : ndarray, shape (3,)
        Sponge point, left optical frame, metres (NaN when not valid).
    valid : bool
    quality : str
        ``centroid`` (both cameras' regions on the plane), ``mono`` (one camera's, the other
        hidden or cut by the image's edge) or ``""`` (not valid).
    rays : ndarray, shape (2, 3)
        The two cameras' measured viewing rays (NaN where a camera saw no region).
    areas : ndarray, shape (2,)
        Region areas, pixels (0 where none).
    stereo_point : ndarray, shape (3,)
        Triangulated point of the two rays, left optical frame (NaN if not both).
    direction : ndarray, shape (3,)
        The left region's longer axis on the plane (unit, left optical frame; NaN when not
        valid).
    reason : str
        Why a frame is not valid (for logs and tests).
    """

    point: np.ndarray
    valid: bool
    quality: str
    rays: np.ndarray
    areas: np.ndarray
    stereo_point: np.ndarray
    direction: np.ndarray = field(default_factory=lambda: np.full(3, np.nan))
    reason: str = ""


class _View:
    """One camera: undistortion into a pinhole canvas, pose in the left optical frame."""

    def __init__(self, K, D, T_cam_left, size):
        self.undistorter = Undistorter(K, D, size)
        self.K = self.undistorter.K
        self.K_inverse = np.linalg.inv(self.K)
        self.focal = float(self.K[0, 0])
        self.R = np.ascontiguousarray(T_cam_left[:3, :3])
        self.t = np.ascontiguousarray(T_cam_left[:3, 3])
        self.eye = invert_transform(T_cam_left)[:3, 3]
        self.K_distorted, self.D = K, D
        self.size = size
        # canvas pixels that show the frame (not its surroundings), a pixel in from the edge
        u, v = cv2.convertMaps(self.undistorter.map_xy, self.undistorter.map_fraction,
                               cv2.CV_32FC1)
        width, height = size
        inside = ((u >= 1) & (v >= 1) & (u <= width - 2) & (v <= height - 2)).astype(np.uint8)
        self.in_frame = cv2.erode(inside, np.ones((3, 3), np.uint8)) > 0

    def pixel(self, point_left: np.ndarray) -> np.ndarray:
        """Undistorted-canvas pixel (2,) of a left-frame point (3,)."""
        camera = self.R @ point_left + self.t
        return self.K[:2, :2] @ (camera[:2] / camera[2]) + self.K[:2, 2]

    def depth(self, point_left: np.ndarray) -> float:
        return float((self.R @ point_left + self.t)[2])

    def rays_of_pixels(self, pixels: np.ndarray) -> np.ndarray:
        """Viewing rays (n, 3) of undistorted-canvas pixels (n, 2)."""
        return np.column_stack([pixels, np.ones(len(pixels))]) @ self.K_inverse.T

    def rays_of_distorted(self, pixels: np.ndarray) -> np.ndarray:
        """Viewing rays (n, 3) of distorted image pixels (n, 2)."""
        if len(pixels) == 0:
            return np.zeros((0, 3))
        xy = cv2.undistortPoints(np.asarray(pixels, np.float64).reshape(-1, 1, 2),
                                 self.K_distorted, self.D).reshape(-1, 2)
        return np.column_stack([xy, np.ones(len(xy))])


#: Frames after which a table measurement of a tracked frame (run on a worker thread) is
#: taken up.
TABLE_DELAY_FRAMES = 30


class RegionTracker:
    """Tracks the sponge's colour region in both cameras and places it on the table plane.

    Parameters
    ----------
    calibration : StereoCalibration
    colour : ColourSource
        The sponge body's colour: a named colour or an HSV range (a soft prior until the
        sponge is found), or a region of the first left frame.
    params : RegionTrackerParams
    """

    def __init__(self, calibration: StereoCalibration, colour: ColourSource,
                 params: RegionTrackerParams = RegionTrackerParams()):
        self.calibration = calibration
        self.colour = colour
        self.params = params
        size = calibration.image_size
        self.views = [_View(calibration.K1, calibration.D1, np.eye(4), size),
                      _View(calibration.K2, calibration.D2, calibration.right.T_cam_ref, size)]
        search_scale = min(1.0, params.search_width / max(size))
        self.backgrounds = [StaticBackground(view.undistorter, search_scale)
                            for view in self.views]
        #: the colour the user named (or the range given), None for a region (``--roi``)
        self.named = colour.hsv_range
        #: the colour searched for, then (once the sponge is found) the named colour as the
        #: sponge shows it: what the learnt colour is bounded by
        self.prior = prior_model(self.named) if self.named is not None else None
        self.spanned = self.named  # the box of the prior
        self.model: ColourModel | None = None  # the sponge's vivid body: what is tracked
        #: the colour of all the sponge's faces, lit and shaded (what a box model's outline
        #: is scored on)
        self.body_model: ColourModel | None = None
        self.candidates = CandidateTracks(params.acquisition)
        self.table_stereo = TableStereo(calibration)
        world_up = None
        if calibration.T_world_left is not None:
            world_up = calibration.T_world_left[:3, :3].T @ np.array([0.0, 0.0, 1.0])
        self.world_up = world_up
        self.frame = -1
        # what is known about the sponge once found
        self.size: float | None = None
        self.table: Plane | None = None
        self._table_points: list[np.ndarray] = []  # dense stereo points of the table pairs
        # table measurements running on a worker: (frame at which they are taken up, job)
        self._table_jobs: deque[tuple[int, Future]] = deque()
        self._table_worker: ThreadPoolExecutor | None = None
        self._right_camera_worker: ThreadPoolExecutor | None = None  # see _per_camera
        self._table_centre: np.ndarray | None = None
        self.ray_offsets: deque[np.ndarray] = deque(maxlen=90)
        self.ray_changes: deque[float] = deque(maxlen=120)  # of accepted frames, / size
        self._ray_change: float | None = None
        self._disagreement_of: tuple[int, str] = (-1, "")  # (frame, reason) last computed
        self.areas = [deque(maxlen=120), deque(maxlen=120)]  # metric areas of valid frames
        self.history: deque[tuple[int, np.ndarray]] = deque(maxlen=3)
        self.failures = 0
        self.valid_count = 0
        self.frames_with_candidates = 0  # before identification: frames showing the colour
        self._stereo_points: deque[tuple[int, np.ndarray]] = deque(maxlen=900)  # (frame, point)
        self._statistics: dict[str, tuple] = {}
        self._valid_points: deque[tuple[int, np.ndarray]] = deque(maxlen=600)  # (frame, point)
        self._last_seen: np.ndarray | None = None
        self._plane: Plane | None = None
        self._track_start = 0  # frame at which the sponge was last found
        #: (first frame, end frame) of each track of this pass that turned out to follow a
        #: still thing (:meth:`_kept_still`): none of its frames showed the sponge
        self.still_tracks: list[tuple[int, int]] = []
        # the sponge's pixels in both cameras when it was identified (window images, 0/255
        # masks): what colour models are learnt from
        self.seed_windows: list[np.ndarray] = []
        self.seed_masks: list[np.ndarray] = []
        # before the sponge is known: per camera, the last frames in the background's
        # pixels and where they show the colour (to find still things of the colour)
        acquisition = params.acquisition
        window = max(acquisition.window, int(1.5 * acquisition.periods[1] * acquisition.fps) + 1)
        self._recent = [deque(maxlen=window), deque(maxlen=window)]

    # ----------------------------------------------------------------- public
    @property
    def identified(self) -> bool:
        """Whether the sponge has been found (its colour, size and plane are known)."""
        return self.size is not None

    def widen_search(self, side: int) -> None:
        """Search for a sponge whose colour lies up to :data:`SEARCH_HUE_WIDENING` hue units
        above (``side`` +1) or below (-1) the named colour's box as well, between two names
        (a lemon yellow, a golden orange); 0: the named colour again. The track stage asks
        after a whole pass found nothing of the named colour: one side at a time, so that
        what lies on the other (a wooden table below a lemon yellow) stays out."""
        if self.named is not None and not self.identified:
            self.spanned = widened_hues(self.named, SEARCH_HUE_WIDENING, side) if side \
                else self.named
            self.prior = prior_model(self.spanned)

    def restart(self) -> None:
        """Forget the track but keep what was learnt about the sponge and the scene (for a
        second pass over the same video from its start)."""
        self._take_up_tables(every=True)
        self.frame = -1
        self._disagreement_of = (-1, "")
        self.history.clear()
        self.failures = self.params.coast_frames + 1
        self.candidates.tracks.clear()
        for recent in self._recent:
            recent.clear()
        self._last_seen = None  # the pass starts where the video starts, not where it ended
        self.still_tracks.clear()
        self._release_visited()

    def _release_visited(self) -> None:
        """Forget the still things of a sponge's size that lie where the sponge has been
        (:meth:`StaticBackground.release_visited`): the pass starts where the sponge may
        have rested, as still as a thing of its colour, before it wiped."""
        if not self._valid_points or self.size is None:
            return
        points = np.array([point for _, point in self._valid_points])
        middle = np.median(points, axis=0)
        for view, background in zip(self.views, self.backgrounds):
            pixels = np.array([view.pixel(point) for point in points])
            background.release_visited(pixels, self._largest_ghost(view, middle))

    def _largest_ghost(self, view: _View, point: np.ndarray) -> float:
        """Canvas pixels of camera ``view`` that a ghost of the sponge at ``point`` covers at
        most (twice its area: it may have dwelt a little here and there)."""
        return 2.0 * (self.size * view.focal / max(view.depth(point), 1e-3)) ** 2

    def observe(self, point: np.ndarray) -> None:
        """Take this frame's sponge point (3,), left optical frame, from elsewhere (the box
        refinement) instead of measuring it: keeps the prediction going."""
        self.frame += 1
        self._take_up_tables()
        point = np.asarray(point, dtype=np.float64).copy()
        self.history.append((self.frame, point))
        self._last_seen = point
        self._valid_points.append((self.frame, point))
        self.failures = 0

    def step(self, left: np.ndarray, right: np.ndarray) -> RegionEstimate:
        """Process the next synchronised frame pair (BGR uint8)."""
        self.frame += 1
        self._take_up_tables()
        frames = (left, right)
        if not self.identified:
            if self.model is None and not self._seed_colour(frames):
                return self._invalid("the colour does not show")
            track = self._follow_candidates(frames, self.prior if self.model is None
                                            else self.model)
            if track is None or not self._identify(frames, track):
                return self._invalid("searching for the moving sponge")
        elif not self.history and self.failures > self.params.coast_frames:
            candidate = self._reacquire(frames)
            if candidate is None:
                return self._invalid("searching")
            self.history.append((self.frame - 1, candidate.point.copy()))
            self._track_start = self.frame
        return self._measure(frames)

    # ------------------------------------------------------------ acquisition
    def _seed_colour(self, frames) -> bool:
        """A region seed (``--roi``) teaches a colour model from that region of the first
        frame; a named colour or range already has its prior."""
        if self.prior is not None:
            return True
        x, y, w, h = self.colour.roi
        roi = np.zeros(frames[0].shape[:2], np.uint8)
        roi[y:y + h, x:x + w] = 255
        self.prior = ColourModel.fit([frames[0]], [roi])
        return True

    def _search_candidates(self, frames, model: ColourModel, images=None, probabilities=None,
                           vivid: bool = False) -> list[StereoCandidate]:
        """Stereo candidates of the sponge's colour anywhere in both images, found in the
        backgrounds' low-resolution undistorted canvases (``images``, or resampled from
        ``frames``; ``probabilities``: their back-projections, when already made), without
        the still things of its colour the backgrounds know. ``vivid``: in a camera whose
        still scene is of the colour widely (:data:`TABLE_OF_THE_COLOUR`), the blobs' vivid
        parts are measured too."""
        if images is None:
            images = [background.canvas_image(frame)
                      for background, frame in zip(self.backgrounds, frames)]
        if probabilities is None:
            probabilities = [model.back_project(image) for image in images]
        blobs, rays = [], []
        for view, background, image, probability in zip(self.views, self.backgrounds, images,
                                                         probabilities):
            still = background.still_in_canvas_image(image)
            if still is not None:
                probability[still] = 0.0
            scale = background.scale
            found = find_blobs(probability, min_area=max(6.0, 15.0 * scale * scale))[:12]
            if vivid and background.coloured_share > TABLE_OF_THE_COLOUR:
                found = [replace(blob, vivid_pixels=vivid_area(image, probability, blob))
                         for blob in found]
            blobs.append(found)
            centres = background.canvas_pixels([b.centroid for b in found]).reshape(-1, 2)
            rays.append(view.rays_of_pixels(centres))
        c = self.calibration
        return stereo_candidates(blobs[0], blobs[1], rays[0], rays[1], c.R, c.T,
                                 (self.views[0].focal, self.views[1].focal),
                                 self.backgrounds[0].scale, self.views[0].K, self.views[1].K)

    def _follow_candidates(self, frames, model: ColourModel) -> CandidateTrack | None:
        images = [background.canvas_image(frame)
                  for background, frame in zip(self.backgrounds, frames)]
        probabilities = [model.back_project(image) for image in images]
        for image, probability, recent in zip(images, probabilities, self._recent):
            recent.append((self.frame, image, probability > 0.5))
        if len(self._recent[0]) >= self.params.acquisition.window // 2 and \
                self.frame % BACKGROUND_REFRESH_FRAMES == 0:
            # one camera at a time, from a dozen of the recent frames: a few milliseconds,
            # not a stall of a live session
            camera = (self.frame // BACKGROUND_REFRESH_FRAMES) % 2
            self._learn_backgrounds(cameras=(camera,), frames=BACKGROUND_FRAMES)
        candidates = self._search_candidates(frames, model, images, probabilities, vivid=True)
        self.frames_with_candidates += bool(candidates)
        self.candidates.update(self.frame, candidates)
        return self.candidates.moving(self.frame)

    def _learn_backgrounds(self, cameras: tuple[int, ...] = (0, 1),
                           frames: int | None = None) -> None:
        """Start the ``cameras``' backgrounds from their recent frames (all of them, or
        ``frames`` spread evenly over them): the search then sees only what of the sponge's
        colour is not a still thing (a wooden table of a near hue, a cloth, a cup), so that
        the moving sponge is a blob of its own."""
        for camera in cameras:
            background, recent = self.backgrounds[camera], list(self._recent[camera])
            if frames is not None and len(recent) > frames:
                recent = [recent[i] for i in np.linspace(0, len(recent) - 1, frames).astype(int)]
            background.initialise(np.stack([image for _, image, _ in recent]),
                                  np.stack([positive for _, _, positive in recent]))

    def _identify(self, frames, track: CandidateTrack) -> bool:
        """The moving candidate is the sponge if something of its colour is left where it
        is once the still things of its colour are taken away (they stayed in place over
        the last frames; a cloth the sponge touches moves with it in the colour mask only):
        learn its size, colour and position from its pixels alone, and measure the table.
        False when nothing is left (the candidate was a still thing and is remembered as
        one)."""
        self.candidates.static.pop(track.ident, None)  # it may have rested before it moved
        if len(self._recent[0]) < self.params.acquisition.window // 2:
            return False  # too few frames yet to tell still from moving
        path = track.recent(self.frame, self.params.acquisition.window)
        self._learn_backgrounds(frames=IDENTIFY_BACKGROUND_FRAMES)
        for view, background in zip(self.views, self.backgrounds):
            # a sponge wiping a path smaller than itself, or that rested where its path goes
            # (it was no candidate then: still, it was taken away), is not a still thing of
            # its colour
            pixels = np.array([view.pixel(point) for point in path])
            per_metre = view.focal / float(np.median([view.depth(point) for point in path]))
            largest = (LARGEST_SPONGE * per_metre) ** 2
            background.release(pixels, largest, 0.25 * LARGEST_SPONGE * per_metre)
            background.release_visited(pixels, largest)
        if self._above_the_table(frames, track):
            self.candidates.rejected.add(track.ident)
            return False
        # the candidate's region again, without what stayed still: nothing left means it
        # was a still thing that the sponge (or an arm) touched
        self.size = track.size
        searched = (self.spanned, self.prior)
        if self.named is not None:
            self._span_the_named_colour(frames, track.last_point)
        self.model = self.prior
        rays, areas = [], []
        for view, frame, background in zip(self.views, frames, self.backgrounds):
            region = self._region(view, frame, track.last_point, 0.02, background)
            if region is None:
                break
            rays.append(region[0])
            areas.append(region[1] * (view.depth(track.last_point) / view.focal) ** 2)
        if len(rays) < 2:
            self.candidates.static[track.ident] = (track.last_point.copy(), track.size)
            self.candidates.tracks = [t for t in self.candidates.tracks if t is not track]
            return self._not_identified(searched)
        point = triangulate_rays(rays[0][None], rays[1][None], self.calibration.R,
                                 self.calibration.T)[0][0]
        self.size = float(np.sqrt(np.mean(areas)))
        windows, masks, cores = self._seed_regions(frames, point)
        self.body_model = self._colour(windows, cores, masks)
        # the region's centre is measured on its vivid part: what else the region holds (a
        # duller hand, the sponge's shaded sides) is neither sponge nor background
        self.model = self._colour(windows, [vivid_part(window, core) for window, core
                                            in zip(windows, cores)], masks, unsure=masks)
        if self._scene_share(self.model, point) > SCENE_SHARE:
            self.candidates.rejected.add(track.ident)
            return self._not_identified(searched)
        for recent in self._recent:
            recent.clear()
        self.history.append((self.frame - 1, point.copy()))
        self.seed_windows, self.seed_masks = windows, masks
        self._track_start = self.frame
        self._table_centre = point.copy()
        self._measure_table(None if self._table_points else frames)
        return True

    def _not_identified(self, searched) -> bool:
        """Undo what an identification learnt: no size or model, and the colour range and
        prior it searched with (``searched``); False."""
        self.size = self.model = self.body_model = None
        self.spanned, self.prior = searched
        return False

    def _span_the_named_colour(self, frames, point: np.ndarray) -> None:
        """The prior becomes the named colour as the sponge at ``point`` shows it: a sponge
        whose hue lies at the edge of its name, or between two names, is whole in it. Its
        pixels beyond the prior are not in its region at first: measured again (at most
        :data:`SPONGE_HUE_ROUNDS` times) until the range stays; a range that would make the
        still scene round the sponge (a table of a near hue) its colour is not taken."""
        for _ in range(SPONGE_HUE_ROUNDS):
            windows, masks, _ = self._seed_regions(frames, point)
            hues = hue_range(windows, [vivid_part(window, mask) for window, mask
                                       in zip(windows, masks)], hue_centre(self.named))
            if hues is None:
                return
            spanned = spanning_hues(self.named, *hues, SPONGE_HUE_MARGIN)
            if spanned == self.spanned:
                return
            prior = prior_model(spanned)
            if self._takes_in_the_scene(prior, point):
                return
            self.spanned, self.prior = spanned, prior

    def _takes_in_the_scene(self, prior: ColourModel, point: np.ndarray) -> bool:
        """Whether ``prior`` reads more of the still scene around ``point`` (the backgrounds'
        median) as the sponge's colour than the prior so far, by :data:`SPAN_SURROUNDINGS`."""
        scene = self._still_scene(point)
        if not len(scene):
            return False
        gained = np.count_nonzero(prior.likely(scene) & ~self.prior.likely(scene))
        return gained > SPAN_SURROUNDINGS * len(scene)

    def _scene_share(self, model: ColourModel, point: np.ndarray) -> float:
        """The share of the still scene around ``point`` that ``model`` reads as the sponge."""
        scene = self._still_scene(point)
        return float(np.count_nonzero(model.likely(scene))) / len(scene) if len(scene) else 0.0

    def _still_scene(self, point: np.ndarray) -> np.ndarray:
        """Both backgrounds' median within :data:`SPAN_CHECK_REACH` of ``point``: HSV uint8,
        (k, 1, 3), an image one pixel wide (k may be 0: the point out of both views)."""
        scenes = []
        for view, background in zip(self.views, self.backgrounds):
            reach = SPAN_CHECK_REACH * view.focal / max(view.depth(point), 1e-3)
            scenes.append(background.median_near(view.pixel(point), reach))
        scene = np.concatenate(scenes)
        return cv2.cvtColor(scene, cv2.COLOR_BGR2HSV) if len(scene) else scene

    def _seed_regions(self, frames, point: np.ndarray):
        """The sponge's pixels at ``point`` in both cameras, by the prior: (windows (BGR),
        region masks, core masks (0/255): the region's pixels well inside the prior's box)."""
        windows, masks, cores = [], [], []
        for view, frame, background in zip(self.views, frames, self.backgrounds):
            window, origin, _ = self._window(view, frame, point, 1.5 * self.size)
            probability = self.prior.back_project(window)
            # a table or cloth of the named colour that the sponge lies on is a still thing:
            # its colour is learnt as what the sponge is not
            background.clear_still(probability, window, origin, 1)
            centre = view.pixel(point) - origin
            reach = 0.8 * self.size * view.focal / view.depth(point)
            blobs = [b for b in find_blobs(probability, min_area=4)
                     if np.linalg.norm(b.centroid - centre) < reach + b.radius]
            region = blob_mask(probability, blobs, grow=0)
            masks.append(region.astype(np.uint8) * 255)
            # the sponge's colour is learnt from the pixels well inside the named colour only:
            # the soft edge of the prior may take in a hand of a near hue
            cores.append((region & (probability > 0.99)).astype(np.uint8) * 255)
            windows.append(window)
        return windows, masks, cores

    def _colour(self, windows, cores, masks, unsure=None) -> ColourModel:
        """The colour model of the sponge's pixels ``cores`` in both cameras' windows (of its
        whole region ``masks`` when a camera shows no core; the prior when neither). With a
        named colour or range, the model says no more than the prior (a prior learnt from
        a region, ``--roi``, is no bound)."""
        if all(core.any() for core in cores):
            model = ColourModel.fit(windows, cores, unsure=unsure)
        elif all(mask.any() for mask in masks):
            model = ColourModel.fit(windows, masks)
        else:
            return self.prior
        return model if self.colour.roi is not None else model.at_most(self.prior)

    def _above_the_table(self, frames, track: CandidateTrack) -> bool:
        """Whether a moving candidate keeps above the table (by dense stereo around it): a
        wiping sponge lies on the table, a hand or a sleeve of its colour does not. False
        when the table cannot be measured (a plain, untextured one)."""
        point = track.last_point
        if not self._table_points:
            self._table_points.append(self.table_stereo.table_points(*frames, point))
        table = self.table_stereo.plane_of_pairs(self._table_points, point,
                                                 self.params.table_radius,
                                                 prior_normal=self.world_up, remember=False)
        if table is None:
            return False
        height = float(np.median(table.distance(np.array(list(track.points)[-15:]))))
        return height > self.params.max_height

    def _reacquire(self, frames) -> StereoCandidate | None:
        """After a loss: a candidate of the sponge's size that is not a still thing, lies
        where the sponge has been wiping (within the area of its valid points, grown by
        their spread) and, of those, nearest where it was last seen."""
        candidates = self._search_candidates(frames, self.model)
        self.candidates.update(self.frame, candidates)
        home, reach = self._wiping_area()
        plausible = [c for c in candidates
                     if 0.5 < c.size / self.size < 2.0
                     and not self.candidates.is_static(c.point, c.size)
                     and (home is None or np.linalg.norm(c.point - home) < reach)]
        if not plausible:
            return None
        last = self._last_seen if self._last_seen is not None else home
        if last is not None:
            plausible.sort(key=lambda c: np.linalg.norm(c.point - last))
        return plausible[0]

    def _wiping_area(self) -> tuple[np.ndarray | None, float]:
        """Centre (3,) of where the sponge has been (median of its recent valid points) and
        how far from it the sponge may show again: the points' farthest distance plus the
        sponge's size and a margin (None before any valid point)."""
        if not self._valid_points:
            return None, 0.0
        points = np.array([point for _, point in self._valid_points])
        centre = np.median(points, axis=0)
        spread = float(np.percentile(np.linalg.norm(points - centre, axis=1), 98))
        return centre, spread + self.size + 0.05

    # -------------------------------------------------------------- measuring
    def _window(self, view: _View, frame: np.ndarray, point: np.ndarray, radius: float,
                step: int = 1):
        """Undistorted window (image, origin (2,)) around a left-frame point, ``radius``
        metres in the object's distance, sampling every ``step``-th canvas pixel."""
        centre = view.pixel(point)
        half = view.focal * radius / max(view.depth(point), 1e-3)
        width, height = view.undistorter.size
        x0 = int(min(max(math.floor(centre[0] - half), 0), width - 1))
        y0 = int(min(max(math.floor(centre[1] - half), 0), height - 1))
        x1 = int(min(max(math.ceil(centre[0] + half), x0 + 1), width))
        y1 = int(min(max(math.ceil(centre[1] + half), y0 + 1), height))
        return (view.undistorter.window(frame, x0, y0, x1, y1, step),
                np.array([x0, y0], float), (x0, y0, x1, y1))

    def _predict(self) -> tuple[np.ndarray, float]:
        """Predicted point (3,) and how far it may be off, metres."""
        (f1, p1) = self.history[-1]
        if len(self.history) >= 2:
            f0, p0 = self.history[-2]
            velocity = (p1 - p0) / max(1, f1 - f0)
        else:
            velocity = np.zeros(3)
        steps = self.frame - f1
        return p1 + velocity * steps, float(np.linalg.norm(velocity)) * steps

    @property
    def last_valid(self) -> np.ndarray | None:
        return self.history[-1][1] if self.history else None

    def _update_backgrounds(self, frames, regions: list) -> None:
        """Learn the frames into the static backgrounds, with the sponge's regions (per
        camera: (mask, origin, step); None: that camera is not learnt) under which still
        things are ghosts."""
        def update(k: int) -> None:
            if regions[k] is not None:
                self.backgrounds[k].update(frames[k], (self.model, self.prior), [regions[k]],
                                           self._largest_ghost(self.views[k],
                                                               self.history[-1][1]))

        self._per_camera(update)

    def _per_camera(self, work: Callable[[int], T]) -> list[T]:
        """``[work(0), work(1)]``: the left camera's part on the calling thread, the right
        camera's at once on a worker (OpenCV and numpy's array loops release the
        interpreter's lock, so the two run on two cores). ``work`` must touch only its own
        camera's state."""
        if self._right_camera_worker is None:
            self._right_camera_worker = ThreadPoolExecutor(1, thread_name_prefix="wipelab-right")
        right = self._right_camera_worker.submit(work, 1)
        return [work(0), right.result()]

    def _region(self, view: _View, frame: np.ndarray, point: np.ndarray, slack: float,
                background: StaticBackground | None = None):
        """The sponge's region near ``point`` in one camera: (ray (3,), area in canvas
        pixels, ray (3,) of a point 10 pixels along the region's longer axis, (mask, origin,
        step) of the region in the window, whether it reaches the frame's edge) or None."""
        p = self.params
        pixels_per_metre = view.focal / max(view.depth(point), 1e-3)
        # a sponge much larger than needed for sub-pixel centroids is read at a coarser step
        step = max(1, int(self.size * pixels_per_metre / p.sponge_pixels))
        window, origin, (x0, y0, x1, y1) = self._window(
            view, frame, point, p.window_size * self.size + slack, step)
        probability = self.model.back_project(window)
        if background is not None:
            # the sponge's colour where the scene showed it while the sponge was elsewhere,
            # unchanged: a still thing of its colour (a cloth, a stain), not the sponge
            background.clear_still(probability, window, origin, step)
        scale = pixels_per_metre / step  # window pixels per metre
        blobs = find_blobs(probability, min_area=max(4.0, 0.05 * (self.size * scale) ** 2))
        centre = (view.pixel(point) - origin) / step
        reach = (0.8 * self.size + slack) * scale
        chosen = [b for b in blobs if np.linalg.norm(b.centroid - centre) < reach + b.radius]
        if not chosen:
            return None
        inside = blob_mask(probability, chosen)
        centroid, _, mass, axis, _ = region_moments(probability, inside, tuple(origin), step)
        area = mass * step * step  # sponge pixels (soft), canvas units
        rays = view.rays_of_pixels(np.stack([centroid, centroid + 10.0 * axis]))
        truncated = bool(np.any(inside & ~view.in_frame[y0:y1:step, x0:x1:step]))
        return rays[0], area, rays[1], (inside, origin, step), truncated

    def _measure(self, frames) -> RegionEstimate:
        p = self.params
        predicted, slack = self._predict() if self.history else (None, 0.0)
        if predicted is None:
            return self._invalid("no prediction")
        rays = np.full((2, 3), np.nan)
        axis_rays = np.full((2, 3), np.nan)
        areas = np.zeros(2)
        masks, problems = [None, None], ["not seen", "not seen"]
        regions = self._per_camera(lambda k: self._region(
            self.views[k], frames[k], predicted, slack + 0.02, self.backgrounds[k]))
        for k, region in enumerate(regions):
            if region is None:
                continue
            rays[k], areas[k], axis_rays[k], masks[k], truncated = region
            problems[k] = "at the edge of the image" if truncated else ""
        metric_areas = np.array([area * (view.depth(predicted) / view.focal) ** 2
                                 for area, view in zip(areas, self.views)])
        self._learn_area_range(problems, rays, metric_areas)
        for k in range(2):
            if not problems[k] and self._area_known(k):
                low, median, high = self._area_range(k)
                ratio = metric_areas[k] / median
                lowest = max(p.area_floor, min(p.min_area_ratio, (1 - p.area_margin) * low / median))
                highest = min(p.area_ceiling, max(p.max_area_ratio,
                                                  (1 + p.area_margin) * high / median))
                if not lowest <= ratio <= highest:
                    problems[k] = f"{ratio:.2f}x its usual area"
        stereo = np.full(3, np.nan)
        if np.all(np.isfinite(rays)):
            stereo = triangulate_rays(rays[:1], rays[1:], self.calibration.R,
                                      self.calibration.T)[0][0]
        if not any(problems) and not (self._area_known(0) and self._area_known(1)) and \
                max(metric_areas) > FIRST_AREAS_AGREEMENT * min(metric_areas):
            # the first frames teach what is usual (area, rays' offset): a region that takes
            # in a hand of a near hue in one camera would teach it wrong for good
            problems = ["of another size than the other camera's"] * 2
        good = [k for k in range(2) if not problems[k]]
        reason = "; ".join(f"{side} region {problem}" for side, problem
                           in zip(("left", "right"), problems) if problem)
        point, quality = None, QUALITY_CENTROID
        if len(good) == 2:
            reason = self._disagreement(rays)
            if not reason:
                point = self._locate(rays, stereo)
        elif len(good) == 1 and self._mono_allowed(good[0], metric_areas[good[0]]):
            point = self._locate_mono(good[0], rays[good[0]])
            quality = QUALITY_MONO
            if point is not None and \
                    np.linalg.norm(point - predicted) > 0.3 * self.size + slack:
                point, reason = None, reason + "; the one camera's region jumped"
        if point is None:
            return self._fail(rays, areas, stereo, reason or "no plane yet for one camera")
        if self._kept_still(point):
            self._forget_track(point)
            return self._fail(rays, areas, stereo, "what was tracked has not moved for "
                              f"{p.still_seconds:g} s: a still thing, not the sponge")
        self._accept(frames, point, rays, metric_areas, stereo, good)
        if self.frame % p.background_every == 0:
            self._update_backgrounds(frames, masks)
        k = good[0]
        return RegionEstimate(point, True, quality, rays, areas, stereo,
                              self._direction(k, rays[k], axis_rays[k]))

    def _direction(self, k: int, ray: np.ndarray, axis_ray: np.ndarray) -> np.ndarray:
        """Unit direction (3,) on the plane from where camera k's ``ray`` meets it to where
        its ``axis_ray`` does."""
        plane = self.sponge_plane()
        if plane is None:
            return np.full(3, np.nan)
        view = self.views[k]
        ends = plane.intersect(np.broadcast_to(view.eye, (2, 3)),
                               np.stack([ray, axis_ray]) @ view.R)
        direction = ends[1] - ends[0]
        return direction / np.linalg.norm(direction)

    def _measure_table(self, frames=None) -> None:
        """Add a frame pair's dense stereo points of the table (if given) and fit the table
        again."""
        if frames is not None:
            self._table_points.append(self.table_stereo.table_points(*frames,
                                                                     self._table_centre))
        table = self.table_stereo.plane_of_pairs(self._table_points, self._table_centre,
                                                 self.params.table_radius,
                                                 prior_normal=self.world_up)
        if table is not None:
            self.table = table
            self._refresh_plane(force=True)

    def _measure_table_later(self, frames) -> None:
        """:meth:`_measure_table` on a worker thread (dense stereo and the plane fit take
        0.05-1 s, many frames of a live session), taken up :data:`TABLE_DELAY_FRAMES` frames
        later, waiting for it then: the same frame on every run, however fast the machine."""
        if self._table_worker is None:
            self._table_worker = ThreadPoolExecutor(1, thread_name_prefix="wipelab-table",
                                                    initializer=run_as_helper)
        job = self._table_worker.submit(self._table_fit, frames, list(self._table_points),
                                        self._table_centre.copy())
        self._table_jobs.append((self.frame + TABLE_DELAY_FRAMES, job))

    def _table_fit(self, frames, earlier: list[np.ndarray], centre: np.ndarray
                   ) -> tuple[np.ndarray, Plane | None]:
        points = self.table_stereo.table_points(*frames, centre)
        return points, self.table_stereo.plane_of_pairs(
            earlier + [points], centre, self.params.table_radius, prior_normal=self.world_up)

    def _take_up_tables(self, every: bool = False) -> None:
        """The table measurements that are due (``every``: all of them)."""
        while self._table_jobs and (every or self._table_jobs[0][0] <= self.frame):
            points, table = self._table_jobs.popleft()[1].result()
            self._table_points.append(points)
            if table is not None:
                self.table = table
                self._refresh_plane(force=True)

    def sponge_plane(self) -> Plane | None:
        """The plane the tracked point moves in (None before the first measurement): the
        table's, at the median height of the sponge's stereo points above it."""
        return self._plane

    def _refresh_plane(self, force: bool = False) -> None:
        """Recompute :meth:`sponge_plane` from the sponge's stereo points so far: on each of
        the first 30 valid frames, then on every 10th (and whenever the table changes).
        With a world frame its up axis is the plane's normal (the table is level: a camera
        low over it measures the table's tilt worse than its calibration knows it);
        otherwise the table's normal, as dense stereo measures it."""
        count = len(self._stereo_points)
        if count == 0 or (not force and count > 30 and count % 10):
            return
        points = np.array([point for _, point in self._stereo_points])
        level = self.table if self.world_up is None else Plane(self.world_up, 0.0)
        if level is not None:
            height = float(np.median(level.distance(points)))
            if self.table is not None:
                # the sponge lies on the table: its point is neither under the table nor
                # higher than a hand-held sponge's (the first few stereo points, of regions
                # that a hand hides differently in the two views, can be centimetres off)
                on_table = points - self.table.distance(points)[:, None] * self.table.normal
                floor = float(np.median(level.distance(on_table)))
                height = min(max(height, floor - PLANE_BELOW_TABLE),
                             floor + self.params.max_height)
            self._plane = level.shifted(height)
        elif count >= 30:
            # no table plane (a plain, untextured table): the plane of the sponge's own
            # stereo points
            self._plane = fit_plane(points, towards=np.zeros(3))

    def _locate(self, rays: np.ndarray, stereo: np.ndarray) -> np.ndarray:
        plane = self.sponge_plane()
        if plane is None:
            return stereo
        cameras = [(view.R, view.t, view.focal) for view in self.views]
        return points_on_plane(plane, [rays[:1], rays[1:]], cameras)[0]

    def _learn_area_range(self, problems, rays, metric_areas) -> None:
        """Learn the range the region's area spans from every frame in which both cameras
        show a whole region whose rays agree and whose area is within the floor and ceiling
        of the median (the sponge turning, the holding hand moving on it), whether or not the
        frame is then accepted; a hand passing in front is too rare to widen it much."""
        p = self.params
        if any(problems) or not self._area_known(0) or self._disagreement(rays):
            return
        for k in range(2):
            ratio = metric_areas[k] / self._area_range(k)[1]
            if not p.area_floor <= ratio <= p.area_ceiling:
                return
        for k in range(2):
            self.areas[k].append(metric_areas[k])

    def _cached(self, key: str, count: int, compute):
        """``compute()``, recomputed every frame while its data (``count`` values) are few,
        then on every 10th frame (these statistics change slowly; the percentiles cost more
        than the rest of a frame's checks)."""
        cached = self._statistics.get(key)
        if cached is None or count < 30 or cached[0] != self.frame // 10:
            cached = (self.frame // 10, compute())
            self._statistics[key] = cached
        return cached[1]

    def _area_known(self, k: int) -> bool:
        """Whether camera k's usual region area is known (:data:`USUAL_AREA_FRAMES`)."""
        return len(self.areas[k]) >= USUAL_AREA_FRAMES

    def _area_range(self, k: int) -> np.ndarray:
        """2nd, 50th and 98th percentile (3,) of camera k's recent region areas."""
        return self._cached(f"area{k}", len(self.areas[k]),
                            lambda: np.percentile(self.areas[k], [2, 50, 98]))

    def _ray_statistics(self) -> tuple[np.ndarray, float | None]:
        """The usual offset (3,) between the two cameras' points on the plane and the 98th
        percentile of its changes (None before 30 are known)."""
        return self._cached("rays", len(self.ray_changes), lambda: (
            np.median(np.array(self.ray_offsets), axis=0),
            float(np.percentile(self.ray_changes, 98)) if len(self.ray_changes) >= 30
            else None))

    def _disagreement(self, rays: np.ndarray) -> str:
        """Why the two cameras' regions of this frame (``rays``) cannot show the same sponge
        ("" if they can): where their rays meet the plane must differ as usual (a hand hiding
        part of the sponge in one camera shifts its centroid). Computed once per frame."""
        if self._disagreement_of[0] != self.frame:
            self._disagreement_of = (self.frame, self._ray_disagreement(rays))
        return self._disagreement_of[1]

    def _ray_disagreement(self, rays: np.ndarray) -> str:
        plane = self.sponge_plane()
        if plane is None or len(self.ray_offsets) < 5:
            return ""
        p = self.params
        typical, usual_change = self._ray_statistics()
        change = np.linalg.norm(self._ray_offset(plane, rays) - typical) / self.size
        limit = p.max_ray_disagreement
        if usual_change is not None:
            limit = min(p.ray_disagreement_ceiling, max(limit, 1.5 * usual_change))
        if change > limit:
            return "the cameras' regions disagree"
        self._ray_change = change
        return ""

    def _mono_allowed(self, k: int, metric_area: float) -> bool:
        """Whether camera k alone may stand for both: only to continue a track that was
        valid on the previous frame, with a region of its usual area (a hand hiding the
        sponge in one camera may show something of a near colour in the other)."""
        p = self.params
        if not self.history or self.history[-1][0] != self.frame - 1 or \
                not self._area_known(k):
            return False
        ratio = metric_area / self._area_range(k)[1]
        return p.min_area_ratio <= ratio <= p.max_area_ratio

    def _locate_mono(self, k: int, ray: np.ndarray) -> np.ndarray | None:
        """The sponge point from camera k alone: where its ray meets the plane, moved by half
        the usual offset between the two cameras' points (None before both are known)."""
        plane = self.sponge_plane()
        if plane is None or len(self.ray_offsets) < 5:
            return None
        view = self.views[k]
        point = plane.intersect(view.eye[None], (view.R.T @ ray)[None])[0]
        half = 0.5 * self._ray_statistics()[0]
        return point + half if k == 0 else point - half

    def _ray_offset(self, plane: Plane, rays: np.ndarray) -> np.ndarray:
        """Where the right ray meets the plane minus where the left one does (3,)."""
        points = [plane.intersect(view.eye[None], (view.R.T @ ray)[None])[0]
                  for view, ray in zip(self.views, rays)]
        return points[1] - points[0]

    def _accept(self, frames, point, rays, areas, stereo, good) -> None:
        self.history.append((self.frame, point.copy()))
        self._last_seen = point.copy()
        self._valid_points.append((self.frame, point.copy()))
        # a "still thing" where the sponge is now was the sponge resting before it moved
        for ident, (centre, _) in list(self.candidates.static.items()):
            if ident >= 0 and np.linalg.norm(centre - point) < 0.5 * self.size:
                del self.candidates.static[ident]
        self.failures = 0
        self.valid_count += 1
        for k in good:
            if not self._area_known(k):  # the first ones; then _learn_area_range adds them
                self.areas[k].append(areas[k])
        if self.valid_count % 30 == 0 and self.areas[0] and self.areas[1]:
            # the sponge's size as it is measured now (its first estimate came from a few
            # low-resolution frames)
            self.size = float(np.sqrt(np.median(self.areas[0]) + np.median(self.areas[1])) / np.sqrt(2.0))
        if len(good) == 2 and np.all(np.isfinite(stereo)):
            self._stereo_points.append((self.frame, stereo))
            self._refresh_plane()
        p = self.params
        if len(self._table_points) + len(self._table_jobs) < p.table_pairs and \
                self.valid_count % p.table_every == 0:
            self._measure_table_later(frames)
        plane = self.sponge_plane()
        if plane is not None and len(good) == 2:
            self.ray_offsets.append(self._ray_offset(plane, rays))
            if self._ray_change is not None:
                self.ray_changes.append(self._ray_change)
        self._ray_change = None

    @property
    def _still_window(self) -> int:
        """Frames over which a still thing keeps still (``still_seconds``)."""
        return int(round(self.params.still_seconds * self.params.acquisition.fps))

    def _kept_still(self, point: np.ndarray) -> bool:
        """Whether, with ``point``, the tracked thing has kept still over the last
        ``still_seconds`` (seen in most of those frames)."""
        p = self.params
        window = self._still_window
        recent = [point]
        for f, q in reversed(self._valid_points):  # the newest first
            if self.frame - f >= window:
                break
            recent.append(q)
        if len(recent) < 0.8 * window:
            return False
        return keeps_still(np.array(recent), self.size, p)

    def _forget_track(self, point: np.ndarray) -> None:
        """The tracker followed a still thing: remember it as one. When what was tracked
        before it moved (the sponge, identified right, then lost and "found" as this thing),
        go on searching for that sponge without the still thing's frames; otherwise identify
        the sponge anew among the moving things of its colour (where it has been wiping and
        its size are unknown again: both were learnt from the still thing). The still thing
        was taken for the sponge's ghost in the backgrounds; it is a still thing of them
        again."""
        self.candidates.static[-1 - len(self.candidates.static)] = (point.copy(), self.size)
        # it was followed since it was found, or since the first of the frames that showed it
        # still (a short loss and a find of the same thing again in between)
        since = [f for f, _ in self._valid_points
                 if self.frame - self._still_window < f <= self.frame]
        start = min([self._track_start] + since)
        self.still_tracks.append((start, self.frame))
        before = [(f, q) for f, q in self._valid_points if f < start]
        for background in self.backgrounds:
            background.forget_ghosts()
        self.history.clear()
        self._last_seen = None
        if len(before) >= self._still_window // 2 and \
                not keeps_still(np.array([q for _, q in before]), self.size, self.params):
            self._valid_points = deque(before, maxlen=self._valid_points.maxlen)
            self._stereo_points = deque([(f, q) for f, q in self._stereo_points if f < start],
                                        maxlen=self._stereo_points.maxlen)
            self._refresh_plane(force=True)
            self.failures = self.params.coast_frames + 1  # search again from the next frame
            return
        self.failures = self.params.coast_frames  # the search for a moving sponge takes over
        self.size = None
        for areas in self.areas:
            areas.clear()
        self._stereo_points.clear()  # the plane the sponge moves in, too
        self._plane = None
        self._valid_points.clear()

    def _fail(self, rays, areas, stereo, reason: str) -> RegionEstimate:
        self.failures += 1
        if self.failures > self.params.coast_frames:
            self.history.clear()
        return RegionEstimate(np.full(3, np.nan), False, QUALITY_NONE, rays, areas, stereo,
                              reason=reason)

    def _invalid(self, reason: str) -> RegionEstimate:
        return RegionEstimate(np.full(3, np.nan), False, QUALITY_NONE, np.full((2, 3), np.nan),
                              np.zeros(2), np.full(3, np.nan), reason=reason)

