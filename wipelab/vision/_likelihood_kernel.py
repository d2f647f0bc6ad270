"""The sponge likelihood's per-sample loops, compiled with numba: the only implementation.

:mod:`wipelab.vision.sponge_likelihood` builds the samples and the images and calls these
through :func:`~wipelab.vision.sponge_likelihood.score_view` and
:class:`~wipelab.vision.sponge_likelihood.SilhouetteContrast`;
:mod:`wipelab.vision.pose_refinement` sums them over the cameras in its Newton loop. Fused
per pose and sample, a camera's score costs a few microseconds per pose.

**Where a sample lands.** A sample point s of the sponge (its frame) lands, for a pose
(x, y, z, yaw) in the tracking frame, at the camera point

    X = R (x, y, z) + t + cos(yaw) MA + sin(yaw) MB + MC,

(``R Rz(yaw) s`` split into its yaw terms, precomputed per sample by
:func:`~wipelab.vision.sponge_likelihood.view_samples`) and is projected with the pinhole
``K`` (focal lengths fx, fy, skew, principal point) into the window whose top-left pixel is
``origin``: ``u = (fx X + skew Y) / Z + cx - origin_u``, ``v = fy Y / Z + cy - origin_v``.
Points nearer than :data:`MIN_DEPTH` along the optical axis (behind the camera) are not
projected and read nothing, so a pose behind the camera scores 0.

**What is read there.** :func:`bilinear` interpolates the image at the exact coordinates,
zero outside it (as ``cv2.BORDER_CONSTANT``) and for NaN. :func:`score_poses` sums, per
pose, the reads weighted by the samples' ``weights`` (+1/n just inside the silhouette edges,
-1/n just outside, 0 for face points): the *contrast*; and averages the reads at the face
points (``is_face``): the *coverage*.

**Derivatives for Newton.** :func:`contrast_derivatives` gives the contrast of one pose
with its gradient and Hessian in the pose. Per sample with a nonzero weight it reads the
4 x 4 pixel block around its pixel (:func:`_read_block`) and from it the bilinear values f
at the pixel and at +-1 pixel around it (:func:`_block_bilinear`): central differences give
the image's gradient ``g = ((f[+1,0] - f[-1,0]) / 2, (f[0,+1] - f[0,-1]) / 2)`` and Hessian
``H = [[f[+1,0] - 2 f0 + f[-1,0], h_uv], [h_uv, f[0,+1] - 2 f0 + f[0,-1]]]`` with
``h_uv = (f[+1,+1] - f[+1,-1] - f[-1,+1] + f[-1,-1]) / 4``. They are chained with the
pinhole's analytic Jacobian J (2 x 4) of the pixel (u, v) in the pose: the columns of
dX/d(x, y, z, yaw) are R's and ``-sin(yaw) MA + cos(yaw) MB``, and

    du = (fx dX + skew dY) / Z - (fx X + skew Y) dZ / Z^2,   dv = fy (dY / Z - Y dZ / Z^2),

so that ``grad = sum w J^T g`` and ``Hess = sum w J^T H J`` over the samples. The
projection's second derivatives (the term ``sum w g . d2(u, v)/d pose2``) are left out: the
image's curvature dominates (on the tests' rendered silhouettes the term is below 1 % of the
Hessian's largest entry). The result is the local quadratic model of the contrast that
:mod:`wipelab.vision.pose_refinement` climbs, at the cost of nine bilinear reads from one
pixel block per sample; its value is :func:`score_poses`' contrast.

Numba's on-disk cache (``cache=True``) is refreshed when this file or any wipelab module it
uses changes (:mod:`wipelab.numba_cache`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from wipelab.numba_cache import forget_stale_kernels

#: Camera points nearer than this (metres along the optical axis) are not projected.
MIN_DEPTH = 1e-6


@njit(cache=True)
def bilinear(image, u, v):
    """``image`` (h, w) at pixel (u, v), bilinearly interpolated, 0 outside (and for NaN)."""
    h, w = image.shape
    if not (u > -1.0 and u < w and v > -1.0 and v < h):
        return 0.0
    x0 = math.floor(u)
    y0 = math.floor(v)
    fx = u - x0
    fy = v - y0
    i0 = int(x0)
    j0 = int(y0)
    value = 0.0
    if j0 >= 0:
        if i0 >= 0:
            value += (1.0 - fx) * (1.0 - fy) * image[j0, i0]
        if i0 + 1 < w:
            value += fx * (1.0 - fy) * image[j0, i0 + 1]
    if j0 + 1 < h:
        if i0 >= 0:
            value += (1.0 - fx) * fy * image[j0 + 1, i0]
        if i0 + 1 < w:
            value += fx * fy * image[j0 + 1, i0 + 1]
    return value


@njit(cache=True)
def sample_points(image, uv):
    """``image`` at pixels uv (n, 2): the kernels' bilinear read, shape (n,)."""
    out = np.empty(uv.shape[0])
    for i in range(uv.shape[0]):
        out[i] = bilinear(image, uv[i, 0], uv[i, 1])
    return out


@njit(cache=True)
def _centre_in_camera(R, t, pose):
    """``R pose[:3] + t`` as three scalars."""
    return (R[0, 0] * pose[0] + R[0, 1] * pose[1] + R[0, 2] * pose[2] + t[0],
            R[1, 0] * pose[0] + R[1, 1] * pose[1] + R[1, 2] * pose[2] + t[1],
            R[2, 0] * pose[0] + R[2, 1] * pose[1] + R[2, 2] * pose[2] + t[2])


@njit(cache=True)
def _sample_in_camera(a, c, s, MA, MB, MC, j):
    """Camera point (x, y, z) of sample j for a pose with centre ``a`` (camera frame) and
    yaw cosine, sine c, s."""
    return (a[0] + c * MA[j, 0] + s * MB[j, 0] + MC[j, 0],
            a[1] + c * MA[j, 1] + s * MB[j, 1] + MC[j, 1],
            a[2] + c * MA[j, 2] + s * MB[j, 2] + MC[j, 2])


@njit(cache=True)
def score_poses(poses, MA, MB, MC, weights, is_face, R, t, K, origin, image, coverage_too):
    """Contrast (n,) and coverage (n,) of poses (n, 4) in one camera's window.

    (The method in full: the module docstring.) Per pose (x, y, z, yaw) and sample k the
    camera point is
    ``R (x, y, z) + t + cos(yaw) MA_k + sin(yaw) MB_k + MC_k``, projected with the pinhole
    ``K`` into the window whose top-left pixel is ``origin``; contrast is the
    ``weights``-weighted sum of the values read there, coverage the mean over the face
    samples (``is_face``), only computed when ``coverage_too`` (else 0).
    """
    n, k = poses.shape[0], MA.shape[0]
    contrast = np.zeros(n)
    coverage = np.zeros(n)
    n_face = 0
    for j in range(k):
        if is_face[j]:
            n_face += 1
    fx, skew, cx, fy, cy = K[0, 0], K[0, 1], K[0, 2] - origin[0], K[1, 1], K[1, 2] - origin[1]
    for i in range(n):
        c, s = math.cos(poses[i, 3]), math.sin(poses[i, 3])
        a = _centre_in_camera(R, t, poses[i])
        total, face_total = 0.0, 0.0
        for j in range(k):
            face = is_face[j]
            if weights[j] == 0.0 and not (coverage_too and face):
                continue
            x, y, z = _sample_in_camera(a, c, s, MA, MB, MC, j)
            if not z > MIN_DEPTH:
                continue
            value = bilinear(image, (fx * x + skew * y) / z + cx, fy * y / z + cy)
            total += weights[j] * value
            if face:
                face_total += value
        contrast[i] = total
        if coverage_too and n_face > 0:
            coverage[i] = face_total / n_face
    return contrast, coverage


@njit(cache=True)
def _read_block(image, u, v, block):
    """Fill ``block`` (4, 4) with the pixels [y0 - 1, y0 + 2] x [x0 - 1, x0 + 2] around
    (u, v), (x0, y0) = floor(u, v), zero outside the image; return the fractions
    (u - x0, v - y0), or (-1, -1) when all of them lie outside (or u, v is NaN)."""
    h, w = image.shape
    if not (u > -2.0 and u < w + 1.0 and v > -2.0 and v < h + 1.0):
        return -1.0, -1.0
    x0 = math.floor(u)
    y0 = math.floor(v)
    i0 = int(x0) - 1
    j0 = int(y0) - 1
    if i0 >= 0 and j0 >= 0 and i0 + 3 < w and j0 + 3 < h:
        for b in range(4):
            for a in range(4):
                block[b, a] = image[j0 + b, i0 + a]
    else:
        for b in range(4):
            for a in range(4):
                inside = 0 <= i0 + a < w and 0 <= j0 + b < h
                block[b, a] = image[j0 + b, i0 + a] if inside else 0.0
    return u - x0, v - y0


@njit(cache=True)
def _block_bilinear(block, fx, fy, dx, dy):
    """The bilinear read at (u + dx, v + dy), dx, dy in {-1, 0, 1}, from :func:`_read_block`."""
    return ((1.0 - fx) * (1.0 - fy) * block[1 + dy, 1 + dx]
            + fx * (1.0 - fy) * block[1 + dy, 2 + dx]
            + (1.0 - fx) * fy * block[2 + dy, 1 + dx] + fx * fy * block[2 + dy, 2 + dx])


@njit(cache=True)
def contrast_derivatives(pose, MA, MB, MC, weights, R, t, K, origin, image):
    """Contrast of one pose (4,) in one camera with its gradient (4,) and Hessian (4, 4)
    (the method in full: the module docstring).

    The image's derivatives come from bilinear reads at +-1 pixel around each sample
    (central differences, one 4 x 4 pixel block per sample), chained with the pinhole's
    analytic Jacobian J (2, 4) of the sample's pixel in the pose: ``grad = sum w J^T g``,
    ``Hess = sum w J^T H J``.
    """
    gradient = np.zeros(4)
    hessian = np.zeros((4, 4))
    value = 0.0
    fx, skew, cx, fy, cy = K[0, 0], K[0, 1], K[0, 2] - origin[0], K[1, 1], K[1, 2] - origin[1]
    c, s = math.cos(pose[3]), math.sin(pose[3])
    a = _centre_in_camera(R, t, pose)
    dX = np.empty((3, 4))
    dX[:, :3] = R
    Ju = np.empty(4)
    Jv = np.empty(4)
    block = np.empty((4, 4))
    for j in range(MA.shape[0]):
        w = weights[j]
        if w == 0.0:
            continue
        x, y, z = _sample_in_camera(a, c, s, MA, MB, MC, j)
        if not z > MIN_DEPTH:
            continue
        inverse_z = 1.0 / z
        tx, ty = _read_block(image, (fx * x + skew * y) * inverse_z + cx,
                             fy * y * inverse_z + cy, block)
        if tx < 0.0:
            continue
        for m in range(3):
            dX[m, 3] = -s * MA[j, m] + c * MB[j, m]
        for q in range(4):
            Ju[q] = (fx * dX[0, q] + skew * dX[1, q]) * inverse_z \
                - (fx * x + skew * y) * inverse_z * inverse_z * dX[2, q]
            Jv[q] = fy * (dX[1, q] * inverse_z - y * inverse_z * inverse_z * dX[2, q])
        f0 = _block_bilinear(block, tx, ty, 0, 0)
        fr, fl = _block_bilinear(block, tx, ty, 1, 0), _block_bilinear(block, tx, ty, -1, 0)
        fd, fup = _block_bilinear(block, tx, ty, 0, 1), _block_bilinear(block, tx, ty, 0, -1)
        gu, gv = 0.5 * (fr - fl), 0.5 * (fd - fup)
        huu, hvv = fr - 2.0 * f0 + fl, fd - 2.0 * f0 + fup
        huv = 0.25 * (_block_bilinear(block, tx, ty, 1, 1) - _block_bilinear(block, tx, ty, 1, -1)
                      - _block_bilinear(block, tx, ty, -1, 1)
                      + _block_bilinear(block, tx, ty, -1, -1))
        value += w * f0
        for q in range(4):
            gradient[q] += w * (gu * Ju[q] + gv * Jv[q])
            for r in range(q, 4):
                hessian[q, r] += w * (huu * Ju[q] * Ju[r] + hvv * Jv[q] * Jv[r]
                                      + huv * (Ju[q] * Jv[r] + Jv[q] * Ju[r]))
    for q in range(4):
        for r in range(q):
            hessian[q, r] = hessian[r, q]
    return value, gradient, hessian


forget_stale_kernels(__name__)
