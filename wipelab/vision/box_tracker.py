"""The sponge-box refinement: a 3D particle filter over box poses with sub-millimetre pose
refinement, used when the sponge's dimensions are known (paper, Sec. III-A2: "a particle
filter framework provides a robust location estimation of the sponge in 3D").

The region tracker (:mod:`wipelab.vision.region_tracker`) finds the sponge, learns its
colour and measures the table; :meth:`BoxTracker.start` then seeds the filter at its
position. Per frame:

1. predict: every particle (x, y, z, yaw) moves with the sponge's motion extrapolated from
   the last measured poses (constant acceleration, damped) plus random diffusion;
2. weight: inside a window around the prediction, both frames are back-projected through
   the colour histogram (:class:`~wipelab.vision.colour_model.ColourModel`); each
   particle's box is projected into both images, lens distortion included, and scored by
   its silhouette contrast and face coverage (:mod:`wipelab.vision.sponge_likelihood`);
   ``w ~ exp(gain * score)``; the estimate is the weighted mean;
3. refine: Newton ascent of the silhouette contrast of both images read from a *linear*
   colour feature (:class:`~wipelab.vision.colour_model.LinearColourFeature`), whose blurred
   edges stay centred on the true outline, gives the pose to a fraction of a millimetre
   (:mod:`wipelab.vision.pose_refinement`);
4. decide: the refined box must be seen (coverage) with a clear outline (contrast) in
   *both* images; otherwise the fit has failed for this frame (occlusion, blur, a box of
   other proportions than the sponge) and :attr:`BoxTracker.tracking` turns False until it
   is started again. Valid frames resample the particles.

The reported point is the centre of the sponge box (not the visible region's centroid): the
same point as synth's truth.csv.
"""

from __future__ import annotations

import math
import statistics
from collections import deque
from dataclasses import dataclass, field

import cv2
import numpy as np

from wipelab.vision._moments_kernel import threshold_moments
from wipelab.vision.calibration import StereoCalibration
from wipelab.vision.colour_model import ColourModel, LinearColourFeature
from wipelab.vision.particle_filter import (align_yaw, normalised_weights,
                                            systematic_resample, weighted_pose_mean,
                                            wrap_half_turn)
from wipelab.vision.projection import invert_transform
from wipelab.vision.sponge_box import CORNER_SIGNS, SpongeBox, yaw_rotation
from wipelab.vision.sponge_likelihood import (SilhouetteContrast, SpongeTemplate, ViewImage,
                                              ViewSamples, facing_camera, score_view,
                                              view_samples)
from wipelab.vision.stereo_geometry import closest_point_of_rays
from wipelab.vision.undistortion import Undistorter


@dataclass(frozen=True)
class BoxParams:
    """Settings of the box refinement.

    Attributes
    ----------
    particles : int
        Number of particles.
    seed : int
        Seed of the filter's random numbers.
    sponge : SpongeBox
        Sponge dimensions, metres.
    position_noise : float
        Per-frame random walk of a particle's position around the prediction, metres
        (standard deviation per axis).
    yaw_noise : float
        Per-frame random walk of yaw, rad.
    likelihood_gain : float
        Log-likelihood per unit of score (sharpness of the weights).
    search_offsets : tuple of float
        Distances of the inside/outside samples from the outline when weighting particles,
        metres.
    refine_offsets : tuple of float
        The same for the refinement (closer to the outline, so that the optimum is sharp).
    refine_steps : tuple of float
        Typical refinement step: x, y, z (metres), yaw (rad); Newton steps are limited to
        four of them per iteration.
    refine_iterations : int
        Most Newton steps per frame.
    blur_sigma : float
        Gaussian blur of the colour feature the refinement reads, pixels (smooths the score
        below a pixel).
    window_margin : int
        Margin, pixels, around the predicted sponge boxes (grown by the farthest sample
        offset) of the window where frames are scored: room for the blur and the refinement.
    min_contrast : float
        Silhouette contrast (back-projection) each camera needs for a valid frame.
    min_coverage : float
        Fraction of the faces turned to a camera that must look sponge-coloured in it.
    retry_below : float
        Refine again from other starting points when the summed contrast of both cameras is
        below this fraction of its median over the last 30 valid frames.
    retry_distance : float
        Those starting points lie this far nearer and farther along the line of sight,
        metres (plus one at the colour blob).
    min_relative_contrast : float
        A valid frame needs at least this fraction of that median contrast.
    min_blob_area : int
        Fewest pixels of sponge colour a window must hold for the colour-blob particles.
    """

    particles: int = 100
    seed: int = 0
    sponge: SpongeBox = field(default_factory=SpongeBox)
    position_noise: float = 0.005
    yaw_noise: float = 0.03
    likelihood_gain: float = 30.0
    search_offsets: tuple[float, ...] = (0.004, 0.008)
    refine_offsets: tuple[float, ...] = (0.001, 0.0025, 0.0045)
    refine_steps: tuple[float, float, float, float] = (0.001, 0.001, 0.001, 0.015)
    refine_iterations: int = 8
    blur_sigma: float = 0.7
    window_margin: int = 4
    min_contrast: float = 0.35
    min_coverage: float = 0.30
    retry_below: float = 0.9
    retry_distance: float = 0.012
    min_relative_contrast: float = 0.75
    min_blob_area: int = 150

    def __post_init__(self):
        if self.particles < 10:
            raise ValueError("particles must be at least 10")


@dataclass(frozen=True)
class BoxEstimate:
    """The box refinement's answer for one frame.

    Attributes
    ----------
    pose : ndarray, shape (4,)
        Sponge centre (x, y, z) in the tracking frame, metres, and yaw (rad); NaN when the
        fit failed.
    valid : bool
        The box was seen in both images with a clear outline.
    contrast, coverage : ndarray, shape (2,)
        Per camera (left, right) at ``pose``.
    particles : ndarray, shape (n, 4)
        The particle set after this frame.
    """

    pose: np.ndarray
    valid: bool
    contrast: np.ndarray
    coverage: np.ndarray
    particles: np.ndarray


class _View:
    """A camera as the tracker uses it: pose in the tracking frame, undistortion, size."""

    def __init__(self, K: np.ndarray, D: np.ndarray, T_cam_track: np.ndarray,
                 size: tuple[int, int]):
        self.undistorter = Undistorter(K, D, size)
        self.K = self.undistorter.K  # of the undistorted canvas
        self.K_inverse = np.linalg.inv(self.K)
        self.R = np.ascontiguousarray(T_cam_track[:3, :3])
        self.t = np.ascontiguousarray(T_cam_track[:3, 3])
        self.eye = invert_transform(T_cam_track)[:3, 3]

    def window_around(self, points_track: np.ndarray, margin: int) -> tuple[int, int, int, int]:
        """Pixel bounds (x0, y0, x1, y1) of the undistorted canvas that hold the projections
        of points (n, 3) with ``margin`` pixels around them (pinhole projection, as
        :func:`~wipelab.vision.undistortion.pinhole`); the whole canvas if a point lies behind
        the camera."""
        width, height = self.undistorter.size
        camera = points_track @ self.R.T + self.t
        z = camera[:, 2]
        if not np.all(z > 1e-6):
            return 0, 0, width, height
        x, y = camera[:, 0] / z, camera[:, 1] / z
        K = self.K
        u = K[0, 0] * x + K[0, 1] * y + K[0, 2]
        v = K[1, 1] * y + K[1, 2]
        x0 = min(max(math.floor(u.min()) - margin, 0), width - 1)
        y0 = min(max(math.floor(v.min()) - margin, 0), height - 1)
        x1 = min(max(math.ceil(u.max()) + margin, x0 + 1), width)
        y1 = min(max(math.ceil(v.max()) + margin, y0 + 1), height)
        return x0, y0, x1, y1


@dataclass
class _Window:
    """One camera's scoring window of one frame: back-projection and linear feature."""

    probability: ViewImage
    feature: ViewImage


class BoxTracker:
    """Fit a sponge box of known dimensions to both images, frame by frame.

    Parameters
    ----------
    calibration : StereoCalibration
        Poses are in ``calibration.track_frame`` (world if it has T_world_left).
    params : BoxParams
    """

    def __init__(self, calibration: StereoCalibration, params: BoxParams = BoxParams()):
        self.calibration = calibration
        self.params = params
        self.coarse = SpongeTemplate.build(params.sponge, edge_spacing=0.03, face_spacing=0.035)
        self.fine = SpongeTemplate.build(params.sponge, edge_spacing=0.014, face_spacing=0.016)
        T_left_track = invert_transform(calibration.T_track_left)
        size = calibration.image_size
        self.views = (_View(calibration.K1, calibration.D1, T_left_track, size),
                      _View(calibration.K2, calibration.D2,
                            calibration.right.T_cam_ref @ T_left_track, size))
        self.R_track_table: np.ndarray | None = None  # the table's axes (z up), tracking frame
        self.model: ColourModel | None = None
        self.feature: LinearColourFeature | None = None
        self.rng = np.random.default_rng(params.seed)
        self.particles: np.ndarray | None = None
        self.history: deque[np.ndarray] = deque(maxlen=3)  # last valid poses, newest first
        self.blob_offset: np.ndarray | None = None  # sponge centre minus colour-blob centre
        self._sample_cache: dict[tuple, ViewSamples] = {}
        self.recent_contrast: deque[float] = deque(maxlen=30)  # of the last valid frames
        self.tracking = False

    # ------------------------------------------------------------------ public
    def start(self, model: ColourModel, feature: LinearColourFeature,
              R_track_table: np.ndarray, centre: np.ndarray) -> None:
        """Seed the filter: the sponge's colour model and linear colour feature, the table's
        orientation (3, 3) and the box centre's approximate position (3,), tracking frame."""
        if R_track_table is not self.R_track_table:
            self._sample_cache.clear()
        self.model, self.feature, self.R_track_table = model, feature, R_track_table
        self.particles = self._spread(centre, 4 * self.params.particles)
        self.history.clear()
        self.blob_offset = None
        self.tracking = True

    def step(self, left: np.ndarray, right: np.ndarray) -> BoxEstimate:
        """Fit the box to the next frame pair (BGR uint8, one frame period later); after a
        failed fit :attr:`tracking` is False until :meth:`start` is called again."""
        if self.history:
            self._predict()
        estimate = self._measure((left, right))
        self.tracking = estimate.valid
        return estimate

    def _spread(self, centre: np.ndarray, n: int) -> np.ndarray:
        """n particles around a position, any yaw."""
        particles = np.empty((n, 4))
        particles[:, :3] = centre + self.rng.normal(size=(n, 3)) * 0.015
        particles[:, 3] = self.rng.uniform(-0.5 * np.pi, 0.5 * np.pi, n)
        return particles

    # ---------------------------------------------------------------- tracking
    def _predict(self) -> None:
        """Move the particles with the extrapolated motion of the last valid poses."""
        h = self.history
        motion = np.zeros(3)
        if len(h) >= 2:
            velocity = h[0][:3] - h[1][:3]
            acceleration = (velocity - (h[1][:3] - h[2][:3])) if len(h) == 3 else 0.0
            motion = velocity + 0.5 * acceleration
        self.particles[:, :3] += motion
        self._diffuse(1.0)

    def _diffuse(self, scale: float) -> None:
        p = self.params
        n = len(self.particles)
        self.particles[:, :3] += self.rng.normal(size=(n, 3)) * (scale * p.position_noise)
        self.particles[:, 3] += self.rng.normal(size=n) * p.yaw_noise

    def _samples(self, template: SpongeTemplate, pose: np.ndarray, offsets
                 ) -> list[ViewSamples]:
        """Per-camera sample sets for boxes near ``pose`` (visibility decided at ``pose``)."""
        R_track_sponge = self.R_track_table @ yaw_rotation(pose[3])
        sets = []
        for index, view in enumerate(self.views):
            faces, edges = facing_camera(R_track_sponge, pose[:3], view.eye, self.params.sponge)
            key = (id(template), index, faces.tobytes(), offsets)
            if key not in self._sample_cache:  # a few face combinations occur per camera
                self._sample_cache[key] = view_samples(template, view.R @ self.R_track_table,
                                                       faces, edges, offsets)
            sets.append(self._sample_cache[key])
        return sets

    def _windows(self, frames, poses: np.ndarray) -> list[_Window]:
        """Score images of each camera inside a window around the boxes of ``poses``."""
        p = self.params
        # the corners of every pose's box, grown by the farthest sample offset so that the
        # outside samples lie in the window too
        half = p.sponge.half_extents + max(p.search_offsets + p.refine_offsets)
        table = (CORNER_SIGNS * half) @ np.swapaxes(yaw_rotation(poses[:, 3]), 1, 2)
        corners = (poses[:, None, :3] + table @ self.R_track_table.T).reshape(-1, 3)
        windows = []
        for view, frame in zip(self.views, frames):
            x0, y0, x1, y1 = view.window_around(corners, p.window_margin)
            crop = view.undistorter.window(frame, x0, y0, x1, y1)
            feature = self.feature.apply(crop)
            if p.blur_sigma > 0:
                feature = cv2.GaussianBlur(feature, (0, 0), p.blur_sigma)
            origin = (float(x0), float(y0))
            windows.append(_Window(
                ViewImage(self.model.back_project(crop), origin, view.K, view.R, view.t),
                ViewImage(feature, origin, view.K, view.R, view.t)))
        return windows

    def _window_blob(self, windows: list[_Window]) -> np.ndarray | None:
        """Triangulated centre (tracking frame) of the sponge-coloured pixels of both windows,
        or None when a window shows too few of them."""
        rays = []
        for window, view in zip(windows, self.views):
            m00, m10, m01 = threshold_moments(window.probability.probability, 0.5)
            if m00 < self.params.min_blob_area:
                return None
            centre = np.array([m10, m01]) / m00 + window.probability.origin
            rays.append((view.eye, view.R.T @ (view.K_inverse @ np.append(centre, 1.0))))
        return closest_point_of_rays(*rays[0], *rays[1])

    def _score(self, poses: np.ndarray, windows: list[_Window]) -> np.ndarray:
        """Particle score on the back-projection: both cameras' contrast plus half their
        coverage."""
        reference = weighted_pose_mean(poses, np.full(len(poses), 1.0 / len(poses)))
        poses = align_yaw(poses, reference[3])
        total = np.zeros(len(poses))
        samples = self._samples(self.coarse, reference, self.params.search_offsets)
        for view_samples_, window in zip(samples, windows):
            contrast, coverage = score_view(poses, view_samples_, window.probability)
            total += contrast + 0.5 * coverage
        return total

    def _measure(self, frames) -> BoxEstimate:
        p = self.params
        windows = self._windows(frames, self.particles)
        blob = self._window_blob(windows)
        if blob is not None and self.blob_offset is not None and len(self.particles) <= p.particles:
            # half of the particles follow the colour blob instead of the motion model: they
            # catch the sponge when it turns faster than the extrapolation expects
            half = len(self.particles) // 2
            self.particles[half:, :3] = (blob + self.blob_offset
                                         + self.rng.normal(size=(len(self.particles) - half, 3))
                                         * p.position_noise)
        scores = self._score(self.particles, windows)
        weights = normalised_weights(p.likelihood_gain * scores)
        best = self.particles[int(np.argmax(scores))]
        near_best = np.linalg.norm(self.particles[:, :3] - best[:3], axis=1) < 0.01
        estimate = weighted_pose_mean(align_yaw(self.particles[near_best], best[3]),
                                      weights[near_best] / weights[near_best].sum())
        pose = self._refine(estimate, windows)
        contrast, coverage = self._quality(pose, windows)
        typical = statistics.median(self.recent_contrast) if self.recent_contrast else 0.0
        if contrast.sum() < p.retry_below * typical:
            # a weak fit: the outline may have locked onto a hand's edge (a box too small
            # and too far, or too big and too near); try again from further along the line
            # of sight and from the colour blob, keep the best
            ray = estimate[:3] - 0.5 * (self.views[0].eye + self.views[1].eye)
            ray /= np.linalg.norm(ray)
            starts = [estimate + np.append(sign * p.retry_distance * ray, 0.0)
                      for sign in (-1.0, 1.0)]
            if blob is not None and self.blob_offset is not None:
                starts.append(np.append(blob + self.blob_offset, estimate[3]))
            for start in starts:
                candidate = self._refine(start, windows)
                quality = self._quality(candidate, windows)
                if quality[0].sum() > contrast.sum():
                    pose, (contrast, coverage) = candidate, quality
        valid = bool(np.all(contrast >= p.min_contrast) and np.all(coverage >= p.min_coverage)
                     and contrast.sum() >= p.min_relative_contrast * typical)
        if valid:
            keep = systematic_resample(weights, self.rng)
            self.particles = self.particles[keep[np.linspace(0, len(keep) - 1, p.particles)
                                                 .astype(int)]]
            self.history.appendleft(pose.copy())
            self.recent_contrast.append(float(contrast.sum()))
            self.blob_offset = None if blob is None else pose[:3] - blob
        else:
            self.particles = self.particles[self.rng.choice(len(self.particles), p.particles,
                                                            replace=False)]
            self.history.clear()
            pose = np.full(4, np.nan)
        return BoxEstimate(pose, valid, contrast, coverage, self.particles.copy())

    def _refine(self, estimate: np.ndarray, windows: list[_Window]) -> np.ndarray:
        """Newton refinement of a pose on the linear colour feature of both cameras."""
        p = self.params
        contrast = SilhouetteContrast(list(zip(
            self._samples(self.fine, estimate, p.refine_offsets),
            [window.feature for window in windows])))
        pose, _ = contrast.refine(estimate, np.array(p.refine_steps),
                                  iterations=p.refine_iterations)
        pose[3] = wrap_half_turn(pose[3])
        return pose

    def _quality(self, pose: np.ndarray, windows: list[_Window]) -> tuple[np.ndarray, np.ndarray]:
        """Silhouette contrast (2,) and face coverage (2,) of a pose on the back-projections."""
        quality = [score_view(pose[None], samples, window.probability) for samples, window in
                   zip(self._samples(self.fine, pose, self.params.refine_offsets), windows)]
        return (np.array([q[0][0] for q in quality]), np.array([q[1][0] for q in quality]))


