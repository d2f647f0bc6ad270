"""Where a window still shows the static background's still things, compiled with numba
(:meth:`wipelab.vision.static_background.StaticBackground.still_colour`, the per-pixel tests
of its module docstring): one pass over the pixels instead of a dozen whole-window array
operations, and without the interpreter's lock, so that both cameras' windows are tested at
once.

The chromaticity arithmetic is float32, as OpenCV's HSV images converted to float32 give it.
Numba's on-disk cache (``cache=True``) is refreshed when this file or any wipelab module it
uses changes (:mod:`wipelab.numba_cache`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from wipelab.numba_cache import forget_stale_kernels

_F90, _F180 = np.float32(90.0), np.float32(180.0)


@njit(cache=True, nogil=True, inline="always")
def _hue_distance(hue, other):
    """Circular distance of two OpenCV hues, in float32 (the arithmetic of
    :func:`wipelab.vision.colour_regions.hue_distance` on float32 images; that function,
    compiled as it is, would divide in float64 against its float64 literals)."""
    return abs((hue - other + _F90) % _F180 - _F90)


@njit(cache=True, nogil=True)
def unchanged_pixels(box, padded, reach, near, large, box_hsv, background_hsv, difference,
                     sponge_bgr, sponge_hs, shade):
    """Bool (h, w): the pixels of ``box`` (BGR uint8, (h, w, 3)) next to a still thing
    (``near`` > 0) that show the background there or one ``reach`` pixels away (``padded``:
    the background under the box grown by ``reach`` on each side): the largest channel of
    the difference under ``difference`` grey levels and, when the sponge's look is known
    (``sponge_bgr``, int (3,); None before), under its difference from the sponge too. On a
    large still thing (``large`` > 0) a pixel also shows it when it is only shaded
    (Cucchiara et al. 2003): of the background's hue and saturation (HSV uint8 ``box_hsv``
    against ``background_hsv``, both (h, w, 3)) within ``shade`` = (darkest, brightest
    brightness factor, hue unit, saturation unit, float32) and nearer them than the sponge's
    (``sponge_hs``: float32 (2,))."""
    h, w = near.shape
    out = np.zeros((h, w), np.bool_)
    darkest, brightest, hue_unit, saturation_unit = shade[0], shade[1], shade[2], shade[3]
    for i in range(h):
        for j in range(w):
            if near[i, j] == 0:
                continue
            # shows the background at some offset: within ``difference`` of it and nearer
            # it than the sponge
            threshold = difference
            if sponge_bgr is not None:
                from_sponge = 0
                for c in range(3):
                    from_sponge = max(from_sponge,
                                      abs(np.int32(box[i, j, c]) - np.int32(sponge_bgr[c])))
                threshold = min(threshold, from_sponge)
            matched = False
            for dy in (0, -1, 1):
                for dx in (0, -1, 1):
                    y, x = i + reach + dy * reach, j + reach + dx * reach
                    largest = 0
                    for c in range(3):
                        largest = max(largest,
                                      abs(np.int32(box[i, j, c]) - np.int32(padded[y, x, c])))
                    if largest < threshold:
                        matched = True
                        break
                if matched:
                    break
            if not matched and large[i, j] > 0:
                hue, saturation = np.float32(box_hsv[i, j, 0]), np.float32(box_hsv[i, j, 1])
                value = np.float32(box_hsv[i, j, 2])
                still_value = np.float32(background_hsv[i, j, 2])
                off_hue = _hue_distance(hue, np.float32(background_hsv[i, j, 0])) / hue_unit
                off_saturation = abs(saturation - np.float32(background_hsv[i, j, 1])) \
                    / saturation_unit
                matched = (value >= darkest * still_value and value <= brightest * still_value
                           and off_hue <= 1.0 and off_saturation <= 1.0)
                if matched and sponge_bgr is not None:
                    chroma_from_sponge = (_hue_distance(hue, sponge_hs[0]) / hue_unit
                                          + abs(saturation - sponge_hs[1]) / saturation_unit)
                    matched = off_hue + off_saturation < chroma_from_sponge
            out[i, j] = matched
    return out


forget_stale_kernels(__name__)
