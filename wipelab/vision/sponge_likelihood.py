"""How well a sponge pose explains a pair of colour back-projections.

A pose is (x, y, z, yaw): the box centre in the tracking frame and its rotation about the
table normal. For each camera, the box's silhouette edges (edges between a face turned
towards the camera and one turned away) are sampled; points just inside the box along each
edge's outward normal ``(n1 + n2) / sqrt(2)`` should be sponge-coloured and points just
outside should not. Both kinds of points are projected through the calibration, lens
distortion included, and read from the back-projection (bilinear). Per camera:

* ``contrast`` = mean(p_inside - p_outside) over the silhouette samples, in [-1, 1]: peaks
  when the model's outline lies on the sponge's outline (also under motion blur, which
  smears the outline symmetrically) and does not care about parts hidden by the hand,
  which read 0 inside and outside alike;
* ``coverage`` = mean p over points inside the faces turned towards the camera, in [0, 1]:
  how much of the sponge is seen; it drops to 0 when the sponge is hidden.

Everything is numpy over (poses x samples) arrays; the tracker scores hundreds of poses per
frame.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from wipelab.vision.projection import project_points
from wipelab.vision.sampling import sample_bilinear
from wipelab.vision.sponge_box import EDGE_FACES, EDGES, FACE_NORMALS, SpongeBox


@dataclass(frozen=True)
class SpongeTemplate:
    """Sample points on a sponge box, sponge frame, metres.

    Attributes
    ----------
    edge_points : ndarray, shape (m, 3)
        Points along the 12 edges.
    edge_normals : ndarray, shape (m, 3)
        Unit outward direction (n1 + n2) / sqrt(2) at each edge point.
    edge_index : ndarray, shape (m,)
        Which edge (row of ``sponge_box.EDGES``) each point lies on.
    face_points : ndarray, shape (f, 3)
        Points inside the faces (away from their borders).
    face_index : ndarray, shape (f,)
        Which face each of them lies on.
    """

    edge_points: np.ndarray
    edge_normals: np.ndarray
    edge_index: np.ndarray
    face_points: np.ndarray
    face_index: np.ndarray

    @classmethod
    def build(cls, box: SpongeBox, edge_spacing: float = 0.012,
              face_spacing: float = 0.016) -> "SpongeTemplate":
        """Sample ``box``: edge points every ``edge_spacing``, a face grid every
        ``face_spacing`` (metres), at least two per edge and one per face."""
        corners = box.corners()
        points, normals, index = [], [], []
        for e, ((a, b), faces) in enumerate(zip(EDGES, EDGE_FACES)):
            length = np.linalg.norm(corners[b] - corners[a])
            count = max(2, int(round(length / edge_spacing)))
            s = (np.arange(count) + 0.5) / count
            points.append(corners[a] + s[:, None] * (corners[b] - corners[a]))
            normal = FACE_NORMALS[faces].sum(axis=0) / np.sqrt(2.0)
            normals.append(np.repeat(normal[None], count, axis=0))
            index.append(np.full(count, e))
        face_points, face_index = [], []
        half = box.half_extents
        for f, normal in enumerate(FACE_NORMALS):
            axes = [i for i in range(3) if normal[i] == 0]
            grids = []
            for axis in axes:
                count = max(1, int(round(2 * half[axis] * 0.7 / face_spacing)))
                grids.append(((np.arange(count) + 0.5) / count * 2 - 1) * 0.7 * half[axis])
            u, v = np.meshgrid(*grids, indexing="ij")
            grid = np.zeros((u.size, 3))
            grid[:, axes[0]], grid[:, axes[1]] = u.ravel(), v.ravel()
            grid += normal * half
            face_points.append(grid)
            face_index.append(np.full(len(grid), f))
        return cls(np.concatenate(points), np.concatenate(normals), np.concatenate(index),
                   np.concatenate(face_points), np.concatenate(face_index))


def facing_camera(R_track_sponge: np.ndarray, centre: np.ndarray, eye: np.ndarray,
                  box: SpongeBox) -> tuple[np.ndarray, np.ndarray]:
    """Which faces turn towards a camera, and which edges are silhouette edges.

    Parameters
    ----------
    R_track_sponge : ndarray, shape (3, 3)
        Sponge orientation in the tracking frame.
    centre, eye : ndarray, shape (3,)
        Sponge centre and camera centre in the tracking frame.
    box : SpongeBox

    Returns
    -------
    faces : ndarray of bool, shape (6,)
    edges : ndarray of bool, shape (12,)
    """
    eye_sponge = R_track_sponge.T @ (eye - centre)
    face_centres = FACE_NORMALS * box.half_extents
    faces = np.einsum("fi,fi->f", FACE_NORMALS, eye_sponge - face_centres) > 0
    edges = faces[EDGE_FACES[:, 0]] != faces[EDGE_FACES[:, 1]]
    return faces, edges


@dataclass(frozen=True)
class ViewSamples:
    """One camera's sample set for one frame, expressed for fast scoring of many yaws.

    A sample point s (sponge frame) of a pose (p, yaw) lands in the camera at
    ``a(p) + cos(yaw) MA + sin(yaw) MB + MC`` with ``a(p) = R_cam_track p + t_cam_track`` and
    MA, MB, MC (k, 3) precomputed from s (see :func:`view_samples`).

    Attributes
    ----------
    MA, MB, MC : ndarray, shape (k, 3)
    weights : ndarray, shape (k,)
        +1/count inside the outline, -1/count outside, 0 for face points (contrast).
    is_face : ndarray of bool, shape (k,)
        Face-interior points (coverage).
    """

    MA: np.ndarray
    MB: np.ndarray
    MC: np.ndarray
    weights: np.ndarray
    is_face: np.ndarray


def view_samples(template: SpongeTemplate, R_cam_table: np.ndarray, faces: np.ndarray,
                 edges: np.ndarray, offsets: tuple[float, ...]) -> ViewSamples:
    """Samples of one camera: silhouette edges at +-``offsets`` (metres) and visible faces.

    Parameters
    ----------
    template : SpongeTemplate
    R_cam_table : ndarray, shape (3, 3)
        Rotation from the table frame (z = table normal) to the camera's optical frame.
    faces, edges : ndarray of bool
        From :func:`facing_camera`.
    offsets : tuple of float
        Distances of the inside/outside samples from the edge, metres.
    """
    on_edge = edges[template.edge_index]
    base = template.edge_points[on_edge]
    normal = template.edge_normals[on_edge]
    inside = np.concatenate([base - d * normal for d in offsets])
    outside = np.concatenate([base + d * normal for d in offsets])
    face = template.face_points[faces[template.face_index]]
    s = np.concatenate([inside, outside, face])
    n_edge = len(inside)
    weights = np.zeros(len(s))
    if n_edge:
        weights[:n_edge], weights[n_edge:2 * n_edge] = 1.0 / n_edge, -1.0 / n_edge
    is_face = np.zeros(len(s), bool)
    is_face[2 * n_edge:] = True
    # R Rz(yaw) s = cos(yaw) R A + sin(yaw) R B + R C
    zero = np.zeros(len(s))
    A = np.column_stack([s[:, 0], s[:, 1], zero])
    B = np.column_stack([-s[:, 1], s[:, 0], zero])
    C = np.column_stack([zero, zero, s[:, 2]])
    return ViewSamples(A @ R_cam_table.T, B @ R_cam_table.T, C @ R_cam_table.T, weights, is_face)


@dataclass(frozen=True)
class ViewImage:
    """A score image of one camera for one frame: a window of the *undistorted* image.

    Windows are resampled through the lens model once per frame (see
    :class:`Undistorter`), so that projecting the thousands of sample points per frame is a
    plain pinhole projection.

    Attributes
    ----------
    probability : ndarray, shape (h, w)
        Values (sponge probability or a colour feature), float32.
    origin : tuple of float
        Undistorted pixel (u, v) of the window's top-left pixel.
    K : ndarray, shape (3, 3)
        Camera matrix of the undistorted image.
    R_cam_track, t_cam_track : ndarray, shapes (3, 3), (3,)
        Tracking frame to camera optical frame.
    """

    probability: np.ndarray
    origin: tuple[float, float]
    K: np.ndarray
    R_cam_track: np.ndarray
    t_cam_track: np.ndarray


class Undistorter:
    """Resample windows of a camera's frames into an undistorted (pinhole) image.

    The undistorted canvas is large enough to hold every pixel of the distorted frame (a
    wide-angle lens's corners land outside the frame's own rectangle); its camera matrix
    ``K`` is the camera's with the principal point moved accordingly.

    Parameters
    ----------
    K, D : ndarray
        Camera matrix and distortion.
    size : tuple of int
        (width, height) of the frames.
    """

    def __init__(self, K: np.ndarray, D: np.ndarray, size: tuple[int, int]):
        width, height = size
        edge = np.concatenate([np.column_stack([np.linspace(0, width - 1, 64), np.full(64, y)])
                               for y in (0, height - 1)]
                              + [np.column_stack([np.full(48, x), np.linspace(0, height - 1, 48)])
                                 for x in (0, width - 1)])
        rays = cv2.undistortPoints(edge.reshape(-1, 1, 2), K, D).reshape(-1, 2)
        ideal = rays @ K[:2, :2].T + K[:2, 2]
        low = np.floor(np.minimum(ideal.min(axis=0), 0.0)) - 1
        high = np.ceil(np.maximum(ideal.max(axis=0), [width - 1, height - 1])) + 1
        self.K = K.copy()
        self.K[:2, 2] -= low
        self.size = tuple(int(v) for v in np.minimum(high - low + 1, 3 * np.array(size)))
        self.K_distorted, self.D = K, D
        self.map_u, self.map_v = cv2.initUndistortRectifyMap(K, D, None, self.K, self.size,
                                                             cv2.CV_32FC1)

    def window(self, frame: np.ndarray, x0: int, y0: int, x1: int, y1: int) -> np.ndarray:
        """Undistorted pixels [y0, y1) x [x0, x1) of ``frame`` (black outside the frame)."""
        return cv2.remap(frame, self.map_u[y0:y1, x0:x1], self.map_v[y0:y1, x0:x1],
                         cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT)

    def distorted(self, pixels: np.ndarray) -> np.ndarray:
        """Frame pixels (n, 2) of undistorted-canvas pixels (n, 2)."""
        rays = np.column_stack([(pixels - self.K[:2, 2]) / np.diag(self.K)[:2],
                                np.ones(len(pixels))])
        rays[:, 0] -= self.K[0, 1] / self.K[0, 0] * rays[:, 1]
        return project_points(rays, self.K_distorted, self.D)


def pinhole(points: np.ndarray, K: np.ndarray) -> np.ndarray:
    """Pixels (..., 2) of camera-frame points (..., 3) in an undistorted image (NaN if z <= 0)."""
    z = points[..., 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        inverse = 1.0 / np.where(z > 1e-6, z, np.nan)
    x, y = points[..., 0] * inverse, points[..., 1] * inverse
    return np.stack([K[0, 0] * x + K[0, 1] * y + K[0, 2], K[1, 1] * y + K[1, 2]], axis=-1)


def _camera_points(poses: np.ndarray, samples: ViewSamples, image: ViewImage) -> np.ndarray:
    a = poses[:, :3] @ image.R_cam_track.T + image.t_cam_track
    c, s = np.cos(poses[:, 3])[:, None, None], np.sin(poses[:, 3])[:, None, None]
    return a[:, None, :] + c * samples.MA + s * samples.MB + samples.MC  # (n, k, 3)


def project_view_samples(poses: np.ndarray, samples: ViewSamples, image: ViewImage
                         ) -> np.ndarray:
    """Pixels of every pose's sample points in the window of ``image``.

    Parameters
    ----------
    poses : ndarray, shape (n, 4)
        (x, y, z, yaw) in the tracking frame (metres, rad).

    Returns
    -------
    ndarray, shape (n, k, 2)
        (u, v) relative to the window's top-left pixel (undistorted image).
    """
    return pinhole(_camera_points(poses, samples, image), image.K) - np.asarray(image.origin)


def read_scores(uv: np.ndarray, samples: ViewSamples, image: ViewImage
                ) -> tuple[np.ndarray, np.ndarray]:
    """Contrast (n,) and coverage (n,) from sample pixels (n, k, 2) of ``image``'s window."""
    values = sample_bilinear(image.probability, uv).astype(np.float64)
    contrast = values @ samples.weights
    faces = values[:, samples.is_face]
    coverage = faces.mean(axis=1) if faces.shape[1] else np.zeros(len(uv))
    return contrast, coverage


def score_view(poses: np.ndarray, samples: ViewSamples, image: ViewImage
               ) -> tuple[np.ndarray, np.ndarray]:
    """Contrast and coverage of many poses in one camera.

    Parameters
    ----------
    poses : ndarray, shape (n, 4)
        (x, y, z, yaw) in the tracking frame (metres, rad).

    Returns
    -------
    contrast : ndarray, shape (n,)
        Mean inside-minus-outside probability along the silhouette, in [-1, 1].
    coverage : ndarray, shape (n,)
        Mean probability inside the visible faces, in [0, 1].
    """
    return read_scores(project_view_samples(poses, samples, image), samples, image)


@dataclass(frozen=True)
class DerivativeImage:
    """An image with its first and second derivatives, for Newton steps on the contrast.

    Attributes
    ----------
    values : ViewImage
        The (blurred) image.
    first : ndarray, shape (h, w, 3)
        (f, df/du, df/dv) per pixel, float32.
    second : ndarray, shape (h, w, 3)
        (d2f/du2, d2f/dudv, d2f/dv2) per pixel, float32.
    """

    values: ViewImage
    first: np.ndarray
    second: np.ndarray

    @classmethod
    def of(cls, image: ViewImage) -> "DerivativeImage":
        """Derivatives by 3x3 Sobel filters (exact for quadratics)."""
        f = image.probability
        sobel = {order: cv2.Sobel(f, cv2.CV_32F, *order, ksize=3, scale=scale)
                 for order, scale in (((1, 0), 1 / 8), ((0, 1), 1 / 8), ((2, 0), 1 / 4),
                                      ((1, 1), 1 / 4), ((0, 2), 1 / 4))}
        return cls(image, cv2.merge([f, sobel[1, 0], sobel[0, 1]]),
                   cv2.merge([sobel[2, 0], sobel[1, 1], sobel[0, 2]]))


def contrast_derivatives(pose: np.ndarray, views: list[tuple[ViewSamples, DerivativeImage]]
                         ) -> tuple[float, np.ndarray, np.ndarray]:
    """Summed contrast of both cameras at ``pose`` with its gradient and Hessian.

    With the sample pixels' Jacobian J (k, 2, 4) with respect to the pose (analytic, pinhole)
    and the image gradient g and Hessian H at each sample: ``grad = sum w J^T g`` and
    ``Hess = sum w J^T H J`` (the projection's own curvature is negligible over the
    millimetres a step spans).

    Parameters
    ----------
    pose : ndarray, shape (4,)
    views : list of (ViewSamples, DerivativeImage)
        Best on a linear colour feature (see
        :class:`wipelab.vision.colour_model.LinearColourFeature`): its blurred edges stay
        centred on the true outline.

    Returns
    -------
    value : float
    gradient : ndarray, shape (4,)
    hessian : ndarray, shape (4, 4)
    """
    value, gradient, hessian = 0.0, np.zeros(4), np.zeros((4, 4))
    c, s = np.cos(pose[3]), np.sin(pose[3])
    for samples, image in views:
        K = image.values.K
        X = _camera_points(pose[None], samples, image.values)[0]  # (k, 3)
        inverse_z = 1.0 / X[:, 2]
        uv = pinhole(X, K) - np.asarray(image.values.origin)
        # d(u, v)/dX of the pinhole, (k, 2, 3)
        d_pixel = np.zeros((len(X), 2, 3))
        d_pixel[:, 0, 0] = K[0, 0] * inverse_z
        d_pixel[:, 0, 1] = K[0, 1] * inverse_z
        d_pixel[:, 0, 2] = -(K[0, 0] * X[:, 0] + K[0, 1] * X[:, 1]) * inverse_z ** 2
        d_pixel[:, 1, 1] = K[1, 1] * inverse_z
        d_pixel[:, 1, 2] = -K[1, 1] * X[:, 1] * inverse_z ** 2
        # dX/d(x, y, z, yaw), (k, 3, 4)
        d_point = np.empty((len(X), 3, 4))
        d_point[:, :, :3] = image.values.R_cam_track
        d_point[:, :, 3] = -s * samples.MA + c * samples.MB
        J = d_pixel @ d_point
        first = sample_bilinear(image.first, uv).astype(np.float64)  # (k, 3)
        second = sample_bilinear(image.second, uv).astype(np.float64)
        w = samples.weights
        value += w @ first[:, 0]
        gradient += np.tensordot(J, w[:, None] * first[:, 1:], axes=([0, 1], [0, 1]))
        H = second[:, [0, 1, 1, 2]].reshape(-1, 2, 2)
        hessian += np.tensordot(J, w[:, None, None] * (H @ J), axes=([0, 1], [0, 1]))
    return float(value), gradient, hessian


def summed_contrast(poses: np.ndarray, views: list[tuple[ViewSamples, DerivativeImage]]
                    ) -> np.ndarray:
    """Summed contrast of both cameras for poses (n, 4), shape (n,)."""
    return sum(score_view(poses, samples, image.values)[0] for samples, image in views)
