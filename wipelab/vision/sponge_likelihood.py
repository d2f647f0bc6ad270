"""How well a sponge pose explains a pair of camera images.

A pose is (x, y, z, yaw): the box centre in the tracking frame and its rotation about the
table normal. For each camera, the box's silhouette edges (edges between a face turned
towards the camera and one turned away) are sampled; points just inside the box along each
edge's outward normal ``(n1 + n2) / sqrt(2)`` should look like sponge and points just
outside should not. The points are projected into a window of the camera's undistorted
image (:mod:`wipelab.vision.undistortion`) and read bilinearly. Per camera:

* ``contrast`` = mean(inside - outside) over the silhouette samples: peaks when the model's
  outline lies on the sponge's outline (also under motion blur, which smears the outline
  symmetrically) and does not care about parts hidden by the hand, which read alike inside
  and outside;
* ``coverage`` = mean value at points inside the faces turned towards the camera: how much
  of the sponge is seen (on the back-projection, in [0, 1]); it drops to 0 when the sponge
  is hidden.

The particle filter reads the histogram back-projection (a probability); the refinement
(:class:`SilhouetteContrast`) reads a linear colour feature, whose blurred edges stay
centred on the true outline.

The per-sample loops are compiled with numba and are the only implementation: how a sample
is projected and read, and how the contrast's gradient and Hessian are computed, is
described in :mod:`wipelab.vision._likelihood_kernel`. This module builds the samples and
images and wraps the kernels (:func:`score_view`, :class:`SilhouetteContrast`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wipelab.vision._likelihood_kernel import score_poses
from wipelab.vision.pose_refinement import refine_contrast, summed_contrast, summed_derivatives
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
    # the eye lies outside face f's plane: n_f . eye > n_f . (n_f half) = half along n_f
    faces = FACE_NORMALS @ eye_sponge > np.abs(FACE_NORMALS) @ box.half_extents
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


def score_view(poses: np.ndarray, samples: ViewSamples, image: ViewImage
               ) -> tuple[np.ndarray, np.ndarray]:
    """Contrast and coverage of many poses in one camera
    (:func:`wipelab.vision._likelihood_kernel.score_poses`, which see for the method).

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
    return score_poses(np.ascontiguousarray(poses, dtype=np.float64), samples.MA, samples.MB,
                       samples.MC, samples.weights, samples.is_face, image.R_cam_track,
                       image.t_cam_track, image.K, image.origin, image.probability, True)


class SilhouetteContrast:
    """Summed silhouette contrast of both cameras, for Newton refinement (compiled).

    The image is read bilinearly at the sample pixels and at +-1 pixel around them for its
    gradient and Hessian, chained with the projection's Jacobian (see
    :func:`wipelab.vision._likelihood_kernel.contrast_derivatives`); the sums over the
    cameras and the Newton loop are :mod:`wipelab.vision.pose_refinement`'s.

    Parameters
    ----------
    views : list of (ViewSamples, ViewImage)
        Best on a linear colour feature (see
        :class:`wipelab.vision.colour_model.LinearColourFeature`): its blurred edges stay
        centred on the true outline.
    """

    def __init__(self, views: list[tuple[ViewSamples, ViewImage]]):
        self.views = views
        # the cameras as the compiled loops over them take them (see pose_refinement)
        self._kernel_views = tuple(
            (s.MA, s.MB, s.MC, s.weights, s.is_face, image.R_cam_track, image.t_cam_track,
             image.K, (float(image.origin[0]), float(image.origin[1])), image.probability)
            for s, image in views)

    def __call__(self, poses: np.ndarray) -> np.ndarray:
        """Summed contrast of poses (n, 4), shape (n,)."""
        return summed_contrast(self._kernel_views, np.ascontiguousarray(poses, dtype=np.float64))

    def derivatives(self, pose: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
        """Summed contrast at ``pose`` with its gradient (4,) and Hessian (4, 4)."""
        value, gradient, hessian = summed_derivatives(
            self._kernel_views, np.ascontiguousarray(pose, dtype=np.float64))
        return float(value), gradient, hessian

    def refine(self, start: np.ndarray, scale: np.ndarray, iterations: int = 6,
               max_step: float = 4.0, tolerance: float = 0.1) -> tuple[np.ndarray, float]:
        """Damped Newton ascent of the summed contrast from ``start``
        (:func:`wipelab.vision.pose_refinement.refine_contrast`, which see for the method
        and the parameters).

        Returns
        -------
        pose : ndarray, shape (4,)
        value : float
        """
        pose, value = refine_contrast(self._kernel_views,
                                      np.ascontiguousarray(start, dtype=np.float64),
                                      np.ascontiguousarray(scale, dtype=np.float64),
                                      int(iterations), float(max_step), float(tolerance))
        return pose, float(value)
