"""Moments of the pixels above a threshold, compiled with numba (the tracker's colour blob).

Same numbers as ``cv2.moments(binary, binaryImage=True)`` of the thresholded image (tests
hold the two to each other) without building the binary image: one pass over the pixels.

Numba's on-disk cache (``cache=True``) is refreshed when this file or any wipelab module it
uses changes (:mod:`wipelab.numba_cache`).
"""

from __future__ import annotations

from numba import njit

from wipelab.numba_cache import forget_stale_kernels


@njit(cache=True)
def threshold_moments(image, threshold):
    """(m00, m10, m01) of the pixels of ``image`` (h, w) strictly above ``threshold``: their
    count and the sums of their column and row indices."""
    m00, m10, m01 = 0.0, 0.0, 0.0
    h, w = image.shape
    for y in range(h):
        count, columns = 0, 0
        for x in range(w):
            if image[y, x] > threshold:
                count += 1
                columns += x
        m00 += count
        m10 += columns
        m01 += count * y
    return m00, m10, m01


forget_stale_kernels(__name__)
