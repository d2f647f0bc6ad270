"""Finding the demonstrated sponge among everything of its colour.

A wiping demonstration shows more of the sponge's colour than the sponge: a cloth on the
table, a plate, a stain, a wooden table top of a near hue. The sponge is the region of that
colour that

* is seen by both cameras at one 3D point (its blobs' centres satisfy the epipolar geometry
  within their size, in front of both cameras),
* has the size of a hand-held sponge (2-35 cm across) at that depth, about the same in both
  images, and
* moves: over the last 1.5 s it travelled several centimetres, while a cloth or a plate
  stays where it lies.

:func:`stereo_candidates` pairs the blobs of two images into 3D candidates;
:class:`CandidateTracks` follows them from frame to frame, says which one moves like a
wiping sponge, and remembers the ones that never moved (static objects), so that after an
occlusion the sponge is found again by the same rules without waiting for it to move.
"""

from __future__ import annotations

import itertools
from collections import deque
from dataclasses import dataclass, field

import numpy as np

from wipelab.vision.colour_regions import Blob

#: Plausible size of a hand-held sponge (square root of its visible area), metres.
MIN_SIZE, MAX_SIZE = 0.02, 0.35


@dataclass(frozen=True)
class StereoCandidate:
    """A pair of blobs, one per camera, that may show one object.

    Attributes
    ----------
    point : ndarray, shape (3,)
        Triangulated centre, left optical frame, metres.
    size : float
        Square root of the object's visible area (mean of both views), metres.
    blobs : tuple of Blob
        The left and right blob (in the pixels of the images they were found in).
    epipolar_error : float
        Larger reprojection error of the triangulated centre, full-resolution pixels.
    rays : ndarray, shape (2, 3)
        The blobs' viewing rays (x, y, 1) in the left and right camera.
    vivid_size : float or None
        ``size`` of the blobs' vivid parts (:attr:`Blob.vivid_pixels`, where measured; else
        the blobs'); None: ``size``.
    """

    point: np.ndarray
    size: float
    blobs: tuple[Blob, Blob]
    epipolar_error: float
    rays: np.ndarray = field(default_factory=lambda: np.full((2, 3), np.nan))
    vivid_size: float | None = None


def triangulate_rays(ray_left: np.ndarray, ray_right: np.ndarray, R: np.ndarray,
                     T: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Midpoints of the closest approach of ray pairs and their depths along each ray.

    Parameters
    ----------
    ray_left, ray_right : ndarray, shape (n, 3)
        Viewing rays (x, y, 1) in each camera's optical frame.
    R, T : ndarray
        ``x_right = R x_left + T``.

    Returns
    -------
    points : ndarray, shape (n, 3)
        Left optical frame.
    depths : ndarray, shape (n, 2)
        Parameters s, t of the closest points ``s ray_left`` and ``eye + t R^T ray_right``
        (positive in front of the cameras).
    """
    eye = -R.T @ T
    a_dir = ray_left
    b_dir = ray_right @ R  # R^T r per row
    w = -eye
    a = np.einsum("ij,ij->i", a_dir, a_dir)
    b = np.einsum("ij,ij->i", a_dir, b_dir)
    c = np.einsum("ij,ij->i", b_dir, b_dir)
    d = a_dir @ w
    e = b_dir @ w
    denominator = a * c - b * b
    with np.errstate(divide="ignore", invalid="ignore"):
        s = (b * e - c * d) / denominator
        t = (a * e - b * d) / denominator
    points = 0.5 * (s[:, None] * a_dir + eye + t[:, None] * b_dir)
    return points, np.column_stack([s, t])


def stereo_candidates(blobs_left: list[Blob], blobs_right: list[Blob],
                      rays_left: np.ndarray, rays_right: np.ndarray, R: np.ndarray,
                      T: np.ndarray, focal: tuple[float, float], scale: float,
                      K_left: np.ndarray, K_right: np.ndarray) -> list[StereoCandidate]:
    """Pair blobs of the two images into 3D candidates, each blob used at most once.

    Parameters
    ----------
    blobs_left, blobs_right : list of Blob
        Blobs of the two images, found at ``scale`` times the full resolution.
    rays_left, rays_right : ndarray, shape (n_left, 3), (n_right, 3)
        Undistorted viewing rays of the blobs' centroids.
    R, T : ndarray
        The stereo extrinsics (``x_right = R x_left + T``).
    focal : tuple of float
        Focal lengths of the two cameras, full-resolution pixels.
    scale : float
        Image scale the blobs were found at.
    K_left, K_right : ndarray
        Undistorted camera matrices (3, 3) the reprojection errors are measured with.

    Returns
    -------
    list of StereoCandidate
        Pairs in front of both cameras whose centres agree within 3 pixels plus a quarter
        of the blobs' radii and whose sizes are plausible and alike, best agreement first.
    """
    if not blobs_left or not blobs_right:
        return []
    n_left, n_right = len(blobs_left), len(blobs_right)
    left_index = np.repeat(np.arange(n_left), n_right)
    right_index = np.tile(np.arange(n_right), n_left)
    points, depths = triangulate_rays(rays_left[left_index], rays_right[right_index], R, T)
    in_front = np.all(depths > 0.1, axis=1) & np.all(np.isfinite(points), axis=1)
    error = np.full(len(points), np.inf)
    if in_front.any():
        p = points[in_front]
        left_pixels = _pinhole(p, K_left)
        right_pixels = _pinhole(p @ R.T + T, K_right)
        measured_left = _pinhole(rays_left[left_index[in_front]], K_left)
        measured_right = _pinhole(rays_right[right_index[in_front]], K_right)
        error[in_front] = np.maximum(np.linalg.norm(left_pixels - measured_left, axis=1),
                                     np.linalg.norm(right_pixels - measured_right, axis=1))
    candidates = []
    for k in np.argsort(error):
        if not np.isfinite(error[k]):
            break
        i, j = left_index[k], right_index[k]
        left, right = blobs_left[i], blobs_right[j]
        radius = max(left.radius, right.radius) / scale
        if error[k] > 3.0 + 0.25 * radius:
            continue
        depth_left = points[k, 2]
        depth_right = (R @ points[k] + T)[2]
        size_left = np.sqrt(left.area) / scale * depth_left / focal[0]
        size_right = np.sqrt(right.area) / scale * depth_right / focal[1]
        if not (MIN_SIZE <= 0.5 * (size_left + size_right) <= MAX_SIZE):
            continue
        if max(size_left, size_right) > 2.0 * min(size_left, size_right):
            continue
        vivid_size = 0.5 * (np.sqrt(left.vivid_or_whole_area) / scale * depth_left / focal[0]
                            + np.sqrt(right.vivid_or_whole_area) / scale * depth_right / focal[1])
        candidates.append(StereoCandidate(points[k], 0.5 * (size_left + size_right),
                                          (left, right), float(error[k]),
                                          np.stack([rays_left[i], rays_right[j]]), vivid_size))
    # each blob in one pair at most, the best agreeing pairs first
    used_left, used_right, chosen = set(), set(), []
    for candidate in candidates:
        left_id, right_id = candidate.blobs[0].label, candidate.blobs[1].label
        if left_id in used_left or right_id in used_right:
            continue
        used_left.add(left_id)
        used_right.add(right_id)
        chosen.append(candidate)
    return chosen


def _pinhole(points: np.ndarray, K: np.ndarray) -> np.ndarray:
    return points[:, :2] / points[:, 2:3] * [K[0, 0], K[1, 1]] + K[:2, 2]


@dataclass(eq=False)
class CandidateTrack:
    """One object followed over frames.

    Attributes
    ----------
    frames : deque of int
        Frame indices it was seen in (the most recent last).
    points : deque of ndarray
        Its 3D centre in those frames.
    sizes : deque of float
    vivid_sizes : deque of float
        Its sizes as its blobs' vivid parts show them (its sizes where not measured): the
        sponge's alone when its blob takes in a table of its hue now and then.
    rays : deque of ndarray
        Its viewing rays (2, 3) in the two cameras.
    first_frame : int
    ident : int
        A number no other track of the process has.
    """

    frames: deque = field(default_factory=lambda: deque(maxlen=300))
    points: deque = field(default_factory=lambda: deque(maxlen=300))
    sizes: deque = field(default_factory=lambda: deque(maxlen=300))
    vivid_sizes: deque = field(default_factory=lambda: deque(maxlen=300))
    rays: deque = field(default_factory=lambda: deque(maxlen=300))
    first_frame: int = 0
    ident: int = field(default_factory=itertools.count().__next__)

    def add(self, frame: int, candidate: StereoCandidate) -> None:
        self.frames.append(frame)
        self.points.append(np.asarray(candidate.point, dtype=np.float64))
        self.sizes.append(candidate.size)
        self.vivid_sizes.append(candidate.size if candidate.vivid_size is None
                                else candidate.vivid_size)
        self.rays.append(np.asarray(candidate.rays, dtype=np.float64))

    @property
    def last_point(self) -> np.ndarray:
        return self.points[-1]

    @property
    def size(self) -> float:
        """Median size over the frames it was seen in, metres."""
        return float(np.median(self.sizes))

    def recent(self, frame: int, window: int) -> np.ndarray:
        """Its points (m, 3) in the last ``window`` frames before and at ``frame``."""
        return np.array([p for f, p in zip(self.frames, self.points) if frame - f < window])

    def travel(self, frame: int, window: int) -> float:
        """How far it moved in the last ``window`` frames, metres: in each camera, the 90th
        percentile of its viewing rays' distances from their median, at its distance; the
        smaller of the two (0 with fewer than five points). Measured in the images, not
        in 3D: two things of the same colour paired now one way, now the other, jump in
        depth but not in either image."""
        recent = [(p, r) for f, p, r in zip(self.frames, self.points, self.rays)
                  if frame - f < window]
        if len(recent) < 5:
            return 0.0
        points = np.array([p for p, _ in recent])
        rays = np.array([r for _, r in recent])[:, :, :2]
        depth = float(np.median(points[:, 2]))
        per_camera = [np.percentile(np.linalg.norm(rays[:, k] - np.median(rays[:, k], axis=0),
                                                   axis=1), 90) for k in range(2)]
        return float(min(per_camera)) * depth


    def periodicity(self, frame: int, window: int, lags: tuple[int, int]) -> float:
        """How periodically it moved over the last ``window`` frames: the largest normalised
        autocorrelation, at lags (frames) within ``lags``, of its motion along the main
        direction of its motion in the left image (0 when too few frames were seen)."""
        window = max(1, min(window, frame - self.first_frame + 1))  # a younger track
        series = np.full(window, np.nan)
        for f, r in zip(self.frames, self.rays):
            if frame - f < window:
                series[window - 1 - (frame - f)] = 0.0
        seen = np.isfinite(series)
        if seen.sum() < 0.6 * window or window < 2 * lags[0]:
            return 0.0
        rays = np.array([r[0, :2] for f, r in zip(self.frames, self.rays) if frame - f < window])
        rays = rays - rays.mean(axis=0)
        _, _, axes = np.linalg.svd(rays, full_matrices=False)
        series[seen] = rays @ axes[0]
        best = 0.0
        for lag in range(lags[0], min(lags[1], window // 2) + 1):
            a, b = series[:-lag], series[lag:]
            both = np.isfinite(a) & np.isfinite(b)
            if both.sum() < lags[0]:
                continue
            a, b = a[both] - a[both].mean(), b[both] - b[both].mean()
            norm = np.sqrt((a @ a) * (b @ b))
            if norm > 0:
                best = max(best, float(a @ b / norm))
        return best


@dataclass(frozen=True)
class AcquisitionParams:
    """Rules for telling the sponge from other things of its colour.

    Attributes
    ----------
    window : int
        Frames over which motion is judged (1.5 s at 30 fps).
    min_presence : int
        Frames of the window the object must be seen in (half a second at 30 fps).
    min_travel : float
        How far the sponge must move in the window (see :meth:`CandidateTrack.travel`),
        metres.
    static_travel : float
        An object that moves less than this over ``static_frames`` is static, metres.
    static_frames : int
        Frames an object must be seen without moving to be remembered as static.
    gate : float
        Largest jump of an object between two frames it is seen in, in multiples of its size
        (plus ``gate_floor``).
    gate_floor : float
        Metres.
    max_speed : float
        Fastest a wiping sponge moves, metres per second: over frames a track was not seen
        in, its gate grows by its size per frame but at most by this speed (a still thing
        whose blob the background took away would otherwise take over a candidate far
        away).
    max_size_variation : float
        Largest coefficient of variation of a moving object's size (of its blobs' vivid
        parts, :attr:`CandidateTrack.vivid_sizes`) over the window: a sponge keeps its size
        as it moves, a still thing that an arm passing over half hides seems to move while
        it shrinks and grows.
    fps : float
        Frame rate of the video, frames per second.
    periods : tuple of float
        Shortest and longest period of a wiping movement, seconds.
    min_periodicity : float
        A moving object must move periodically: the largest autocorrelation of its motion
        in the images over lags within ``periods``, over the last ``1.5 * periods[1]``
        seconds, must reach this (a wiping sponge comes back where it was; a still thing
        that an arm passes over moves once).
    """

    window: int = 45
    min_presence: int = 15
    min_travel: float = 0.02
    static_travel: float = 0.01
    static_frames: int = 60
    gate: float = 1.0
    gate_floor: float = 0.05
    max_speed: float = 2.5
    max_size_variation: float = 0.25
    fps: float = 30.0
    periods: tuple[float, float] = (0.3, 2.2)
    min_periodicity: float = 0.5


class CandidateTracks:
    """Follows the stereo candidates of successive frames (nearest neighbour in 3D) and
    picks the one that moves like a wiping sponge."""

    def __init__(self, params: AcquisitionParams = AcquisitionParams()):
        self.params = params
        self.tracks: list[CandidateTrack] = []
        #: static objects: (centre (3,), size) per track that stayed still; a track that
        #: moves later (a sponge resting before the demonstration) is taken out again
        self.static: dict[int, tuple[np.ndarray, float]] = {}
        #: tracks found not to be the sponge although they move (a hand of a near colour
        #: above the table): never picked again
        self.rejected: set[int] = set()

    def update(self, frame: int, candidates: list[StereoCandidate]) -> None:
        """Add one frame's candidates: each continues the nearest track within the gate or
        starts a new one; tracks unseen for a whole window are dropped (and remembered as
        static objects if they never moved)."""
        p = self.params
        free = list(range(len(candidates)))
        for track in sorted(self.tracks, key=lambda tr: -len(tr.frames)):
            if not free:
                break
            distances = [np.linalg.norm(candidates[i].point - track.last_point) for i in free]
            best = int(np.argmin(distances))
            unseen = max(1, frame - track.frames[-1])
            gate = p.gate_floor + min(p.gate * track.size * unseen,
                                      p.gate * track.size + p.max_speed * (unseen - 1) / p.fps)
            if distances[best] <= gate:
                track.add(frame, candidates[free.pop(best)])
        for i in free:
            track = CandidateTrack(first_frame=frame)
            track.add(frame, candidates[i])
            self.tracks.append(track)
        kept = []
        for track in self.tracks:
            if frame - track.frames[-1] < p.window:
                kept.append(track)
        self.tracks = kept
        for track in self.tracks:
            self._remember_if_static(frame, track)

    def _remember_if_static(self, frame: int, track: CandidateTrack) -> None:
        p = self.params
        if len(track.frames) < p.static_frames:
            return
        travel = track.travel(frame, p.static_frames)
        if travel > 3.0 * p.static_travel:
            self.static.pop(track.ident, None)
        elif travel <= p.static_travel:
            self.static[track.ident] = (np.median(track.recent(frame, p.static_frames), axis=0),
                                      track.size)

    def is_static(self, point: np.ndarray, size: float) -> bool:
        """Whether a candidate lies on a remembered static object of a similar size."""
        for centre, static_size in self.static.values():
            if np.linalg.norm(point - centre) < 0.5 * max(size, static_size) and \
                    0.5 < size / static_size < 2.0:
                return True
        return False

    def moving(self, frame: int) -> CandidateTrack | None:
        """The track that moved most over the last window, if it was seen often enough and
        moved at least ``min_travel``; else None."""
        p = self.params
        best, best_travel = None, p.min_travel
        for track in self.tracks:
            if track.ident in self.rejected or self.is_static(track.last_point, track.size):
                continue
            seen = sum(1 for f in track.frames if frame - f < p.window)
            if seen < p.min_presence:
                continue
            sizes = np.array([s for f, s in zip(track.frames, track.vivid_sizes)
                              if frame - f < p.window])
            if sizes.std() > p.max_size_variation * sizes.mean():
                continue
            travel = track.travel(frame, p.window)
            if travel < best_travel:
                continue
            lags = (max(2, int(round(p.periods[0] * p.fps))), int(round(p.periods[1] * p.fps)))
            if track.periodicity(frame, int(1.5 * lags[1]), lags) >= p.min_periodicity:
                best, best_travel = track, travel
        return best
