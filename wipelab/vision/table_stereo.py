"""The table top's plane from dense stereo around the sponge.

The sponge's own stereo points fix its plane of motion poorly: each camera sees a
different part of it, and the difference changes across the image (a 1.8 degree tilt on
synth's demo). The table around it is textured (wood grain, stone, cloth) and flat: dense
block matching of a rectified frame pair (``cv2.StereoSGBM``) gives tens of thousands of
table points, and a robust plane through those near the sponge fixes the normal to a few
hundredths of a degree. Image scale and disparity range are chosen from the sponge's
depth, so that wide baselines, big images and vertical stereo pairs all work.
"""

from __future__ import annotations

import cv2
import numpy as np

from wipelab.vision.calibration import StereoCalibration
from wipelab.vision.table_plane import Plane, fit_plane

#: The table points used lie between these factors of the sponge's depth.
DEPTH_RANGE = (0.6, 1.8)
#: Most disparity levels searched (the images are scaled down to fit).
MAX_DISPARITIES = 96
#: Fewest table points for a plane, and the most a plane is fitted to.
MIN_POINTS, MAX_POINTS = 500, 20000
#: Largest angle between the table's normal and the world's up axis (when known), radians.
MAX_TILT = np.deg2rad(10.0)


class TableStereo:
    """Rectification of a calibrated pair, and the table plane near a point.

    Parameters
    ----------
    calibration : StereoCalibration
    """

    def __init__(self, calibration: StereoCalibration):
        self.calibration = calibration
        size = calibration.image_size
        R1, R2, P1, P2, *_ = cv2.stereoRectify(
            calibration.K1, calibration.D1, calibration.K2, calibration.D2, size,
            calibration.R, calibration.T.reshape(3, 1).astype(np.float64), alpha=0)
        self.R1, self.R2, self.P1, self.P2 = R1, R2, P1, P2
        self.vertical = abs(P2[1, 3]) > abs(P2[0, 3])
        axis = 1 if self.vertical else 0
        # disparity = f * baseline / depth, positive when the second image is displaced the
        # usual way; otherwise the images swap roles
        self.swap = P2[axis, 3] > 0
        self.focal = float(P1[0, 0])
        self.baseline = abs(float(P2[axis, 3])) / self.focal
        # per frame pair's points (by identity): the pair, the centre and radius, its points
        # within that radius (a pool grows by a pair at a time; the others are not filtered
        # again)
        self._near: dict[int, tuple[np.ndarray, tuple[bytes, float], np.ndarray]] = {}

    def _maps(self, scale: float) -> list[tuple[np.ndarray, np.ndarray]]:
        c = self.calibration
        width, height = c.image_size
        size = (max(16, int(round(width * scale))), max(16, int(round(height * scale))))
        maps = []
        for K, D, R, P in ((c.K1, c.D1, self.R1, self.P1), (c.K2, c.D2, self.R2, self.P2)):
            P = P.copy()
            P[:2] *= scale
            maps.append(cv2.initUndistortRectifyMap(K, D, R, P, size, cv2.CV_32FC1))
        return maps

    def table_points(self, left: np.ndarray, right: np.ndarray, near: np.ndarray) -> np.ndarray:
        """3D points (n, 3), left optical frame, of the surfaces seen around ``near`` (3,)
        (left optical frame) by dense block matching of one frame pair (BGR uint8)."""
        depth = float((self.R1 @ near)[2])
        if depth <= 0:
            return np.zeros((0, 3))
        d_low = self.focal * self.baseline / (DEPTH_RANGE[1] * depth)
        d_high = self.focal * self.baseline / (DEPTH_RANGE[0] * depth)
        scale = min(1.0, MAX_DISPARITIES / max(d_high - d_low, 1e-6),
                    800.0 / max(self.calibration.image_size))
        minimum = int(np.floor(d_low * scale))
        count = int(np.ceil((d_high - d_low) * scale / 16.0 + 1)) * 16
        block = 5
        along = self.calibration.image_size[1 if self.vertical else 0] * scale
        if minimum + count + block >= along:
            return np.zeros((0, 3))   # so near the cameras that no match fits in the image
        images = [cv2.remap(cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY), mx, my, cv2.INTER_LINEAR)
                  for frame, (mx, my) in zip((left, right), self._maps(scale))]
        if self.vertical:
            images = [np.ascontiguousarray(image.T) for image in images]
        first, second = images[::-1] if self.swap else images
        matcher = cv2.StereoSGBM_create(
            minDisparity=minimum, numDisparities=count, blockSize=block,
            P1=8 * block * block, P2=32 * block * block, uniquenessRatio=10,
            speckleWindowSize=100, speckleRange=2, mode=cv2.STEREO_SGBM_MODE_SGBM_3WAY)
        disparity = matcher.compute(first, second).astype(np.float32) / 16.0
        rows, columns = np.nonzero(disparity >= minimum)  # unmatched pixels read minimum - 1
        d = disparity[rows, columns].astype(np.float64)
        if self.swap:
            # the map is the right camera's: its pixel (u, v) matches (u - d, v) in the left
            columns = columns - d
        if self.vertical:
            rows, columns = columns, rows
        f = self.focal * scale
        cx, cy = self.P1[0, 2] * scale, self.P1[1, 2] * scale
        z = f * self.baseline / d
        rectified = np.column_stack([(columns - cx) * z / f, (rows - cy) * z / f, z])
        # R1 maps left optical to rectified (x_rect = R1 x); einsum, not BLAS: the same bits
        # whatever the number of BLAS threads
        points = np.einsum("ni,ij->nj", rectified, self.R1)
        return points

    def plane_near(self, pairs: list[tuple[np.ndarray, np.ndarray]], near: np.ndarray,
                   radius: float, prior_normal: np.ndarray | None = None,
                   seed: int = 0) -> Plane | None:
        """The dominant plane of the surfaces within ``radius`` (metres) of ``near`` (3,),
        seen in one or more frame pairs; its normal points towards the cameras. None when
        too few points match (a plain, untextured table)."""
        return self.plane_of_points(
            np.concatenate([self.table_points(left, right, near) for left, right in pairs]),
            near, radius, prior_normal, seed)

    def plane_of_points(self, points: np.ndarray, near: np.ndarray, radius: float,
                        prior_normal: np.ndarray | None = None, seed: int = 0
                        ) -> Plane | None:
        """The dominant plane of ``points`` (n, 3) within ``radius`` of ``near`` (see
        :meth:`plane_near` and :meth:`plane_of_pairs`)."""
        return self.plane_of_pairs([points], near, radius, prior_normal, seed, remember=False)

    def plane_of_pairs(self, pairs: list[np.ndarray], near: np.ndarray, radius: float,
                       prior_normal: np.ndarray | None = None, seed: int = 0,
                       remember: bool = True) -> Plane | None:
        """The dominant plane of the points of several frame pairs (a list of arrays (n_i, 3),
        pooled in their order) within ``radius`` of ``near`` (3,), pulled towards
        ``prior_normal`` (the world's up axis, when known) by
        :func:`~wipelab.vision.table_plane.fit_plane`'s prior; with a prior, only planes
        within :data:`MAX_TILT` of it count (a camera low over the table sees more of the
        wall or the person behind it than of the table).

        The same plane as of the pairs' points concatenated; with ``remember``, each array's
        points near ``near`` are kept (by the array's identity) for the next call with the
        same centre and radius, so that a pool that grows by a pair filters only that pair.
        """
        kept = [self._points_near(points, near, radius, remember) for points in pairs]
        count = sum(len(points) for points in kept)
        if count < MIN_POINTS:
            return None
        if count > MAX_POINTS:  # evenly thinned: as good a plane, a fraction of the time
            points = _rows(kept, np.linspace(0, count - 1, MAX_POINTS).astype(int))
        else:
            points = np.concatenate(kept)
        inliers = ransac_plane(points, tolerance=0.004 * float(np.linalg.norm(near)),
                               rng=np.random.default_rng(seed), towards=prior_normal)
        if inliers.sum() < MIN_POINTS:
            return None
        return fit_plane(points[inliers], towards=np.zeros(3), prior_normal=prior_normal)

    def _points_near(self, points: np.ndarray, near: np.ndarray, radius: float,
                     remember: bool) -> np.ndarray:
        """The rows of ``points`` (n, 3) within ``radius`` of ``near`` (3,)."""
        key = (np.asarray(near, dtype=np.float64).tobytes(), float(radius))
        known = self._near.get(id(points))
        if known is not None and known[0] is points and known[1] == key:
            return known[2]
        kept = points[np.linalg.norm(points - near, axis=1) < radius]
        if remember:
            self._near[id(points)] = (points, key, kept)
        return kept


def _rows(arrays: list[np.ndarray], index: np.ndarray) -> np.ndarray:
    """Rows ``index`` (ascending) of the concatenation of ``arrays``, without concatenating
    them."""
    ends = np.cumsum([len(a) for a in arrays])
    which = np.searchsorted(ends, index, side="right")
    starts = ends - [len(a) for a in arrays]
    return np.concatenate([a[index[which == i] - start]
                           for i, (a, start) in enumerate(zip(arrays, starts))])


def ransac_plane(points: np.ndarray, tolerance: float, rng: np.random.Generator,
                 trials: int = 100, towards: np.ndarray | None = None) -> np.ndarray:
    """Inliers (bool (n,)) of the plane through three of ``points`` (n, 3) that has the most
    points within ``tolerance`` metres (of the planes whose normal lies within
    :data:`MAX_TILT` of ``towards`` (3,), when given)."""
    least_alignment = float(np.cos(MAX_TILT))
    sample = points if len(points) <= 5000 else points[rng.choice(len(points), 5000,
                                                                   replace=False)]
    best_count, best_plane = 0, None
    for _ in range(trials):
        a, b, c = sample[rng.choice(len(sample), 3, replace=False)]
        normal = np.cross(b - a, c - a)
        length = np.linalg.norm(normal)
        if length < 1e-9:
            continue
        normal /= length
        if towards is not None and abs(float(normal @ towards)) < least_alignment:
            continue
        count = int(np.count_nonzero(np.abs(np.einsum("ni,i->n", sample - a, normal))
                                     < tolerance))
        if count > best_count:
            best_count, best_plane = count, (normal, a)
    if best_plane is None:
        return np.zeros(len(points), bool)
    normal, a = best_plane
    return np.abs(np.einsum("ni,i->n", points - a, normal)) < tolerance
