"""Frame-by-frame tracking of the sponge's colour region in a calibrated stereo pair.

Per frame pair (paper, Sec. III-A2: colour segmentation in both cameras, 30 Hz):

1. find the sponge: until it is identified, low-resolution colour blobs of both images are
   paired into 3D candidates and followed; the one that moves like a wiping sponge is the
   sponge (:mod:`wipelab.vision.acquisition`). Its colour is then learnt from its pixels
   against its surroundings, and the table top's plane is measured by dense stereo around it
   (:mod:`wipelab.vision.table_stereo`);
2. measure: inside a window around the predicted position, each undistorted image is
   back-projected through the colour model; the colour region nearest the prediction gives
   a sub-pixel centroid, hence a viewing ray per camera;
3. locate: the sponge slides on the table, so its point is where both rays best meet a plane
   parallel to the table (:func:`~wipelab.vision.table_plane.points_on_plane`), at the
   height its stereo points keep above the table. Stereo alone is poor along the line of
   sight; the plane makes every camera's lateral precision count;
4. check: a frame is valid only when both regions have their usual size (a hand passing in
   front shrinks them), both rays agree on the plane as they usually do, and the point
   continues the track; otherwise the sponge is lost and found again by the rules of step 1,
   with what is now known about it (colour, size, static objects of its colour).
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field

import cv2
import numpy as np

from wipelab.vision.acquisition import (AcquisitionParams, CandidateTrack, CandidateTracks,
                                        StereoCandidate, stereo_candidates, triangulate_rays)
from wipelab.vision.calibration import StereoCalibration
from wipelab.vision.colour_model import ColourModel, ColourSource
from wipelab.vision.colour_regions import blob_mask, find_blobs, prior_model, region_moments
from wipelab.vision.projection import invert_transform
from wipelab.vision.static_background import StaticBackground
from wipelab.vision.table_plane import Plane, fit_plane, points_on_plane
from wipelab.vision.table_stereo import TableStereo
from wipelab.vision.undistortion import Undistorter

QUALITY_NONE, QUALITY_CENTROID, QUALITY_BOX = "", "centroid", "box"


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
        nearer or farther does not change it), relative to its median over the last valid
        frames: a hand passing in front shrinks it, a thing of the same colour joining it
        grows it.
    max_ray_disagreement : float
        Largest change, in multiples of the sponge size, of the offset between the two
        cameras' rays on the plane from its running median.
    coast_frames : int
        Frames the window keeps following the prediction after a failed measurement before
        the search covers the whole image again.
    acquisition : AcquisitionParams
    colour_refresh : int
        Valid frames between refreshes of the colour model (follows the lighting).
    background_every : int
        Frames between updates of the static background (:mod:`.static_background`).
    """

    search_width: int = 320
    sponge_pixels: float = 60.0
    window_size: float = 1.0
    min_area_ratio: float = 0.8
    max_area_ratio: float = 1.25
    max_ray_disagreement: float = 0.12
    coast_frames: int = 6
    acquisition: AcquisitionParams = AcquisitionParams()
    colour_refresh: int = 60
    background_every: int = 3


@dataclass
class RegionEstimate:
    """The tracker's answer for one frame pair.

    Attributes
    ----------
    point : ndarray, shape (3,)
        Sponge point, left optical frame, metres (NaN when not valid).
    valid : bool
    quality : str
        ``centroid`` for a valid frame, ``""`` otherwise.
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
        self.search_scale = min(1.0, params.search_width / max(size))
        self.backgrounds = [StaticBackground(view.undistorter, self.search_scale)
                            for view in self.views]
        self.prior = prior_model(colour.hsv_range) if colour.hsv_range is not None else None
        self.model: ColourModel | None = None
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
        self.plane_heights: deque[float] = deque(maxlen=900)
        self.ray_offsets: deque[np.ndarray] = deque(maxlen=90)
        self.areas = [deque(maxlen=45), deque(maxlen=45)]  # metric areas of valid frames
        self.history: deque[tuple[int, np.ndarray]] = deque(maxlen=3)
        self.failures = 0
        self.valid_count = 0
        self.frames_with_candidates = 0  # before identification: frames showing the colour
        self._stereo_points: list[np.ndarray] = []
        self._fitted: Plane | None = None
        # the sponge's pixels in both cameras when it was identified (window images, 0/255
        # masks): what colour models are learnt from
        self.seed_windows: list[np.ndarray] = []
        self.seed_masks: list[np.ndarray] = []

    # ----------------------------------------------------------------- public
    @property
    def identified(self) -> bool:
        """Whether the sponge has been found (its colour, size and plane are known)."""
        return self.size is not None

    def restart(self) -> None:
        """Forget the track but keep what was learnt about the sponge and the scene (for a
        second pass over the same video from its start)."""
        self.frame = -1
        self.history.clear()
        self.failures = self.params.coast_frames + 1
        self.candidates.tracks.clear()

    def observe(self, point: np.ndarray) -> None:
        """Take this frame's sponge point (3,), left optical frame, from elsewhere (the box
        refinement) instead of measuring it: keeps the prediction going."""
        self.frame += 1
        self.history.append((self.frame, np.asarray(point, dtype=np.float64).copy()))
        self.failures = 0

    def step(self, left: np.ndarray, right: np.ndarray) -> RegionEstimate:
        """Process the next synchronised frame pair (BGR uint8)."""
        self.frame += 1
        frames = (left, right)
        if not self.identified:
            if self.model is None and not self._seed_colour(frames):
                return self._invalid("the colour does not show")
            track = self._follow_candidates(frames, self.prior if self.model is None
                                            else self.model)
            if track is None:
                return self._invalid("searching for the moving sponge")
            self._identify(frames, track)
        elif not self.history and self.failures > self.params.coast_frames:
            candidate = self._reacquire(frames)
            if candidate is None:
                return self._invalid("searching")
            self.history.append((self.frame - 1, candidate.point.copy()))
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

    def _search_candidates(self, frames, model: ColourModel) -> list[StereoCandidate]:
        """Stereo candidates of the sponge's colour anywhere in both (scaled) images."""
        s = self.search_scale
        blobs, rays = [], []
        for view, frame in zip(self.views, frames):
            small = cv2.resize(frame, None, fx=s, fy=s, interpolation=cv2.INTER_LINEAR) \
                if s < 1.0 else frame
            found = find_blobs(model.back_project(small), min_area=max(6.0, 15.0 * s * s))
            found = found[:12]
            blobs.append(found)
            centres = np.array([(b.centroid + 0.5) / s - 0.5 for b in found]).reshape(-1, 2)
            rays.append(view.rays_of_distorted(centres))
        c = self.calibration
        return stereo_candidates(blobs[0], blobs[1], rays[0], rays[1], c.R, c.T,
                                 (self.views[0].focal, self.views[1].focal), s,
                                 self.views[0].K, self.views[1].K)

    def _follow_candidates(self, frames, model: ColourModel) -> CandidateTrack | None:
        candidates = self._search_candidates(frames, model)
        self.frames_with_candidates += bool(candidates)
        self.candidates.update(self.frame, candidates)
        return self.candidates.moving(self.frame)

    def _identify(self, frames, track: CandidateTrack) -> None:
        """The moving candidate is the sponge: learn its size, colour and the table."""
        self.candidates.static.pop(track.ident, None)  # it may have rested before it moved
        self.size = track.size
        point = track.last_point
        self.history.append((self.frame - 1, point.copy()))
        masks, windows = [], []
        for view, frame in zip(self.views, frames):
            window, origin = self._window(view, frame, point, 2.0 * self.size)
            probability = self.prior.back_project(window)
            blobs = find_blobs(probability, min_area=4)
            centre = view.pixel(point) - origin
            mask = np.zeros(window.shape[:2], np.uint8)
            if blobs:
                nearest = min(blobs, key=lambda b: np.linalg.norm(b.centroid - centre))
                mask[blob_mask(mask.shape, [nearest], grow=0)] = 255
            masks.append(mask)
            windows.append(window)
        if all(mask.any() for mask in masks):
            self.model = ColourModel.fit(windows, masks)
        else:
            self.model = self.prior
        self.seed_windows, self.seed_masks = windows, masks
        radius = max(0.3, 4.0 * self.size)
        self.table = self.table_stereo.plane_near([frames], point, radius)

    def _reacquire(self, frames) -> StereoCandidate | None:
        """After a loss: a candidate of the sponge's size that is not a static object and
        lies near where the sponge was."""
        candidates = self._search_candidates(frames, self.model)
        self.candidates.update(self.frame, candidates)
        plausible = [c for c in candidates
                     if 0.6 < c.size / self.size < 1.6
                     and not self.candidates.is_static(c.point, c.size)]
        if not plausible:
            return None
        if self.last_valid is not None:
            plausible.sort(key=lambda c: np.linalg.norm(c.point - self.last_valid))
        return plausible[0]

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
                np.array([x0, y0], float))

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

    def _update_backgrounds(self, frames, keep_out: list) -> None:
        """Blend the frames into the static backgrounds, except where the sponge's regions
        are (per camera: (mask, origin, step))."""
        for background, frame, region in zip(self.backgrounds, frames, keep_out):
            background.update(frame, self.model, [region])

    def _region(self, view: _View, frame: np.ndarray, point: np.ndarray, slack: float,
                background: StaticBackground | None = None):
        """The sponge's region near ``point`` in one camera: (ray (3,), area in canvas
        pixels, ray (3,) of a point 10 pixels along the region's longer axis, (mask, origin,
        step) of the region in the window) or None."""
        p = self.params
        pixels_per_metre = view.focal / max(view.depth(point), 1e-3)
        # a sponge much larger than needed for sub-pixel centroids is read at a coarser step
        step = max(1, int(self.size * pixels_per_metre / p.sponge_pixels))
        window, origin = self._window(view, frame, point, p.window_size * self.size + slack,
                                      step)
        probability = self.model.back_project(window)
        if background is not None:
            # the sponge's colour where the scene showed it while the sponge was elsewhere,
            # unchanged: a still thing of its colour (a cloth, a stain), not the sponge
            still = background.still_colour(window, origin, step)
            if still is not None:
                probability[still] = 0.0
        scale = pixels_per_metre / step  # window pixels per metre
        blobs = find_blobs(probability, min_area=max(4.0, 0.05 * (self.size * scale) ** 2))
        centre = (view.pixel(point) - origin) / step
        reach = (0.8 * self.size + slack) * scale
        chosen = [b for b in blobs if np.linalg.norm(b.centroid - centre) < reach + b.radius]
        if not chosen:
            return None
        inside = blob_mask(probability.shape, chosen)
        centroid, _, mass, axis, _ = region_moments(probability, inside, tuple(origin), step)
        area = mass * step * step  # sponge pixels (soft), canvas units
        rays = view.rays_of_pixels(np.stack([centroid, centroid + 10.0 * axis]))
        return rays[0], area, rays[1], (inside, origin, step)

    def _measure(self, frames) -> RegionEstimate:
        p = self.params
        predicted, slack = self._predict() if self.history else (None, 0.0)
        if predicted is None:
            return self._invalid("no prediction")
        rays = np.full((2, 3), np.nan)
        axis_ray = np.full(3, np.nan)
        areas = np.zeros(2)
        masks = [None, None]
        for k, (view, frame) in enumerate(zip(self.views, frames)):
            region = self._region(view, frame, predicted, slack + 0.02, self.backgrounds[k])
            if region is not None:
                rays[k], areas[k], along, masks[k] = region
                if k == 0:
                    axis_ray = along

        stereo = np.full(3, np.nan)
        if np.all(np.isfinite(rays)):
            stereo = triangulate_rays(rays[:1], rays[1:], self.calibration.R,
                                      self.calibration.T)[0][0]
        metric_areas = np.array([area * (view.depth(predicted) / view.focal) ** 2
                                 for area, view in zip(areas, self.views)])
        reason = self._check(rays, metric_areas, stereo, predicted, slack)
        if reason:
            return self._fail(rays, areas, stereo, reason)
        point = self._locate(rays, stereo)
        self._accept(frames, point, rays, metric_areas, stereo)
        if self.frame % p.background_every == 0:
            self._update_backgrounds(frames, masks)
        return RegionEstimate(point, True, QUALITY_CENTROID, rays, areas, stereo,
                              self._direction(rays[0], axis_ray))

    def _direction(self, ray: np.ndarray, axis_ray: np.ndarray) -> np.ndarray:
        """Unit direction (3,) on the plane from where ``ray`` meets it to where
        ``axis_ray`` does (left camera rays)."""
        plane = self.sponge_plane()
        if plane is None:
            return np.full(3, np.nan)
        ends = plane.intersect(np.zeros((2, 3)), np.stack([ray, axis_ray]))
        direction = ends[1] - ends[0]
        return direction / np.linalg.norm(direction)

    def sponge_plane(self) -> Plane | None:
        """The plane the tracked point moves in: the table's, at the median height of the
        stereo points so far (None before the first measurement)."""
        if self.table is not None:
            if not self.plane_heights:
                return None
            return self.table.shifted(float(np.median(self.plane_heights)))
        # no table plane (a plain, untextured table): the plane of the sponge's own stereo
        # points, pulled towards the world's up axis when the calibration has a world frame
        if len(self._stereo_points) < 30:
            return None
        if self._fitted is None or len(self._stereo_points) % 30 == 0:
            self._fitted = fit_plane(np.array(self._stereo_points[-900:]), towards=np.zeros(3),
                                     prior_normal=self.world_up)
        return self._fitted

    def _locate(self, rays: np.ndarray, stereo: np.ndarray) -> np.ndarray:
        plane = self.sponge_plane()
        if plane is None:
            return stereo
        cameras = [(view.R, view.t, view.focal) for view in self.views]
        return points_on_plane(plane, [rays[:1], rays[1:]], cameras)[0]

    def _check(self, rays, areas, stereo, predicted, slack) -> str:
        p = self.params
        if not np.all(np.isfinite(rays)):
            return "not seen by both cameras"
        for k in range(2):
            if len(self.areas[k]) >= 5:
                ratio = areas[k] / np.median(self.areas[k])
                if not p.min_area_ratio <= ratio <= p.max_area_ratio:
                    return f"region {'left' if k == 0 else 'right'} {ratio:.2f}x its usual area"
        plane = self.sponge_plane()
        if plane is not None and len(self.ray_offsets) >= 5:
            offset = self._ray_offset(plane, rays)
            typical = np.median(np.array(self.ray_offsets), axis=0)
            if np.linalg.norm(offset - typical) > p.max_ray_disagreement * self.size:
                return "the cameras' regions disagree"
        return ""

    def _ray_offset(self, plane: Plane, rays: np.ndarray) -> np.ndarray:
        """Where the right ray meets the plane minus where the left one does (3,)."""
        points = [plane.intersect(view.eye[None], (view.R.T @ ray)[None])[0]
                  for view, ray in zip(self.views, rays)]
        return points[1] - points[0]

    def _accept(self, frames, point, rays, areas, stereo) -> None:
        self.history.append((self.frame, point.copy()))
        self.failures = 0
        self.valid_count += 1
        for k in range(2):
            self.areas[k].append(areas[k])
        if np.all(np.isfinite(stereo)):
            if self.table is not None:
                self.plane_heights.append(float(self.table.distance(stereo)))
            else:
                self._stereo_points.append(stereo)
        plane = self.sponge_plane()
        if plane is not None:
            self.ray_offsets.append(self._ray_offset(plane, rays))

    def _fail(self, rays, areas, stereo, reason: str) -> RegionEstimate:
        self.failures += 1
        if self.failures > self.params.coast_frames:
            self.history.clear()
        return RegionEstimate(np.full(3, np.nan), False, QUALITY_NONE, rays, areas, stereo,
                              reason=reason)

    def _invalid(self, reason: str) -> RegionEstimate:
        return RegionEstimate(np.full(3, np.nan), False, QUALITY_NONE, np.full((2, 3), np.nan),
                              np.zeros(2), np.full(3, np.nan), reason=reason)

