"""The static background's per-pixel loops, compiled with numba: where an image still shows
its background (:meth:`wipelab.vision.static_background.StaticBackground.still_in_canvas_image`),
and the approximate median's step towards a new image.

Only the pixels near a still thing are compared, and each stops at the first background
pixel it matches: a frame with a small still thing costs little, where comparing whole
images at nine offsets cost more than the search that uses them.

Numba's on-disk cache (``cache=True``) is refreshed when this file or any wipelab module it
uses changes (:mod:`wipelab.numba_cache`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from wipelab.numba_cache import forget_stale_kernels


@njit(cache=True)
def matches_background_near(image, background, near, reach, largest):
    """bool (h, w): pixels where ``near`` (h, w, non-zero: next to a still thing) and
    ``image`` (h, w, 3 uint8) matches ``background`` (h, w, 3 uint8) at the same pixel or at
    one of the eight ``reach`` pixels away (edges replicated): every channel differs by at
    most ``largest``."""
    height, width = near.shape
    out = np.zeros((height, width), np.bool_)
    for y in range(height):
        rows = (y, max(y - reach, 0), min(y + reach, height - 1))
        for x in range(width):
            if near[y, x] == 0:
                continue
            b0, g0, r0 = np.int32(image[y, x, 0]), np.int32(image[y, x, 1]), np.int32(image[y, x, 2])
            columns = (x, max(x - reach, 0), min(x + reach, width - 1))
            for by in rows:
                for bx in columns:
                    if abs(b0 - background[by, bx, 0]) <= largest and \
                            abs(g0 - background[by, bx, 1]) <= largest and \
                            abs(r0 - background[by, bx, 2]) <= largest:
                        out[y, x] = True
                        break
                if out[y, x]:
                    break
    return out


@njit(cache=True)
def step_towards(median, image, steps):
    """Move ``median`` (h, w, 3 float32, C-contiguous; in place) by ``steps`` (h, w float32)
    towards ``image`` (h, w, 3 uint8) in each channel (none where they are equal): the
    approximate running median of McFarlane & Schofield (1995)."""
    flat_median, flat_image, flat_steps = median.reshape(-1), image.reshape(-1), steps.reshape(-1)
    for i in range(flat_steps.size):
        step = flat_steps[i]
        for c in range(3):
            j = 3 * i + c
            difference = np.float32(flat_image[j]) - flat_median[j]
            flat_median[j] += step * (np.float32(difference > 0) - np.float32(difference < 0))


forget_stale_kernels(__name__)
