"""A sponge box at a known pose, rendered as a blurred silhouette into two cameras: the
scene the likelihood and the refinement tests score."""

import cv2
import numpy as np

from wipelab.vision.sponge_box import SpongeBox, yaw_rotation
from wipelab.vision.sponge_likelihood import (SilhouetteContrast, SpongeTemplate, ViewImage,
                                              facing_camera, view_samples)

BOX = SpongeBox()
POSE = np.array([0.02, -0.01, 0.03, 0.4])
K = np.array([[530.0, 0.0, 320.0], [0.0, 530.0, 240.0], [0.0, 0.0, 1.0]])
#: Two cameras, 0.6 m apart, looking down at the sponge from either side.
EYES = (np.array([-0.3, -0.2, 0.35]), np.array([0.3, -0.25, 0.4]))


def look_at(eye: np.ndarray, pixel: np.ndarray | None = None) -> np.ndarray:
    """Rotation (track -> optical frame) of a camera at ``eye`` that sees the sponge's centre
    at ``pixel`` (u, v) (default: the principal point, looking straight at it)."""
    z = (POSE[:3] - eye) / np.linalg.norm(POSE[:3] - eye)
    x = np.cross(z, [0.0, 0.0, 1.0])
    x /= np.linalg.norm(x)
    R = np.array([x, np.cross(z, x), z])
    if pixel is None:
        return R
    # turn the optical axis onto the ray of ``pixel``
    ray = np.linalg.solve(K, np.append(pixel, 1.0))
    ray /= np.linalg.norm(ray)
    axis = np.cross([0.0, 0.0, 1.0], ray)
    turn = cv2.Rodrigues(axis / np.linalg.norm(axis) * np.arccos(ray[2]))[0]
    return turn @ R


def feature_image(R: np.ndarray, t: np.ndarray, supersampling: int = 16) -> ViewImage:
    """The sponge's silhouette at POSE, its pixels covered by area (rendered ``supersampling``
    times finer, pixel centres at integer coordinates), blurred: the feature the refinement
    climbs. (OpenCV's anti-aliased fill grows a shape by about half a pixel.)"""
    corners = (BOX.corners() @ yaw_rotation(POSE[3]).T + POSE[:3]) @ R.T + t
    pixels = corners[:, :2] / corners[:, 2:] * [K[0, 0], K[1, 1]] + K[:2, 2]
    fine = np.zeros((480 * supersampling, 640 * supersampling), np.uint8)
    hull = cv2.convexHull(np.round(((pixels + 0.5) * supersampling - 0.5) * 16).astype(np.int32))
    cv2.fillConvexPoly(fine, hull, 255, shift=4)
    image = cv2.resize(fine.astype(np.float32) / 255, (640, 480), interpolation=cv2.INTER_AREA)
    return ViewImage(cv2.GaussianBlur(image, (0, 0), 1.5), (0.0, 0.0), K, R, t)


def rendered_views(pixels: tuple | None = None) -> list:
    """(ViewSamples, ViewImage) of both cameras, the samples of the sponge at POSE; the
    cameras see the sponge's centre at ``pixels`` (one (u, v) each; default: the principal
    point)."""
    views = []
    for eye, pixel in zip(EYES, pixels or (None, None)):
        R = look_at(eye, pixel)
        faces, edges = facing_camera(yaw_rotation(POSE[3]), POSE[:3], eye, BOX)
        samples = view_samples(SpongeTemplate.build(BOX, 0.014, 0.016), R, faces, edges,
                               (0.001, 0.0025, 0.0045))
        views.append((samples, feature_image(R, -R @ eye)))
    return views


def rendered_contrast() -> SilhouetteContrast:
    """The summed contrast of both cameras: the sponge's pose is its peak. (A short-baseline
    pair puts the peak up to a millimetre along the line of sight, where the silhouette's
    size alone tells depth and the blur's rounded corners shrink it.)"""
    return SilhouetteContrast(rendered_views())
