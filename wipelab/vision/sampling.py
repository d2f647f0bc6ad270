"""Sample an image at many sub-pixel points (bilinear), fast, via ``cv2.remap``."""

from __future__ import annotations

import cv2
import numpy as np

_ROW = 1024  # cv2.remap maps must be narrower than 32767 columns: fold long point lists


def sample_bilinear(image: np.ndarray, uv: np.ndarray, border_value: float = 0.0,
                    reflect: bool = False) -> np.ndarray:
    """Values of ``image`` at pixel coordinates ``uv``, bilinearly interpolated.

    Parameters
    ----------
    image : ndarray, shape (h, w) or (h, w, c)
        Any dtype ``cv2.remap`` accepts (uint8, float32, ...).
    uv : ndarray, shape (..., 2)
        Pixel coordinates (column, row); NaN coordinates read ``border_value``.
    border_value : float
        Value outside the image (unless ``reflect``).
    reflect : bool
        Mirror the image at its borders instead.

    Returns
    -------
    ndarray, shape (...) or (..., c)
        Same dtype as ``image``.
    """
    uv = np.asarray(uv, dtype=np.float32)
    lead = uv.shape[:-1]
    flat = uv.reshape(-1, 2)
    n = len(flat)
    rows = max(1, -(-n // _ROW))
    columns = min(max(n, 1), _ROW)
    padded = np.full((rows * columns, 2), -1e6, np.float32)
    padded[:n] = flat
    if not np.isfinite(padded.sum()):  # cv2.remap is undefined for NaN coordinates
        padded[~np.isfinite(padded)] = -1e6
    border = cv2.BORDER_REFLECT if reflect else cv2.BORDER_CONSTANT
    values = cv2.remap(image, padded.reshape(rows, columns, 2), None, cv2.INTER_LINEAR,
                       borderMode=border, borderValue=border_value)
    channels = image.shape[2:] if image.ndim == 3 else ()
    return values.reshape((rows * columns,) + channels)[:n].reshape(lead + channels)
