"""Sponge-coloured regions of an image: a soft colour prior from a named colour, and the
connected regions (blobs) of a colour probability image with sub-pixel centroids.

The named colours of :data:`~wipelab.vision.colour_model.NAMED_COLOURS` are boxes in HSV.
A real sponge's body drifts out of such a box under coloured light and shading, so the
prior is soft: full inside the box, falling off over a few hue and saturation units outside.
Once the tracker has found the sponge it learns its own colour model from the sponge's
pixels (:meth:`~wipelab.vision.colour_model.ColourModel.fit`) and no longer needs the box.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from wipelab.vision.colour_model import H_BINS, S_BINS, ColourModel, HsvRange

#: Width of the prior's fall-off outside the named box: hue (OpenCV units, 0-179) and
#: saturation (0-255).
HUE_MARGIN, SATURATION_MARGIN = 5.0, 30.0


def prior_model(colour: HsvRange, hue_margin: float = HUE_MARGIN,
                saturation_margin: float = SATURATION_MARGIN) -> ColourModel:
    """A colour model that reads 1 inside the HSV box ``colour`` and falls off linearly to 0
    within ``hue_margin`` and ``saturation_margin`` outside it (value: pixels darker than
    60 % of the box's lowest value are never sponge)."""
    hue = (np.arange(H_BINS) + 0.5) * 180.0 / H_BINS
    saturation = (np.arange(S_BINS) + 0.5) * 256.0 / S_BINS
    low, high = colour.low[0], colour.high[0]
    centre = 0.5 * (low + high) if low <= high else (0.5 * (low + high + 180.0)) % 180.0
    half = 0.5 * ((high - low) % 180.0)
    distance = np.abs((hue - centre + 90.0) % 180.0 - 90.0)  # circular hue distance
    hue_membership = np.clip(1.0 - (distance - half) / hue_margin, 0.0, 1.0)
    saturation_membership = np.clip(
        1.0 - np.maximum(colour.low[1] - saturation, saturation - colour.high[1])
        / saturation_margin, 0.0, 1.0)
    ratio = np.outer(hue_membership, saturation_membership)
    return ColourModel(ratio, v_min=int(0.6 * colour.low[2]))


@dataclass(frozen=True)
class Blob:
    """A connected region of a probability image.

    Attributes
    ----------
    centroid : ndarray, shape (2,)
        Probability-weighted centre (u, v) of the region and the pixel around it (its soft
        edge), pixels of the image it was found in.
    area : float
        Pixels of the region (above the threshold).
    mass : float
        Sum of the probabilities inside the region and the pixel around it.
    bbox : tuple of int
        (x0, y0, x1, y1), exclusive upper bounds.
    label : int
        Its label in the label image of :func:`find_blobs`.
    """

    centroid: np.ndarray
    area: float
    mass: float
    bbox: tuple[int, int, int, int]
    label: int

    @property
    def radius(self) -> float:
        """Radius of a disc of the same area, pixels."""
        return float(np.sqrt(self.area / np.pi))


def find_blobs(probability: np.ndarray, min_area: float, threshold: float = 0.5,
               opening: int = 3) -> tuple[list[Blob], np.ndarray]:
    """Connected regions of ``probability > threshold`` (8-connected, after an opening of
    ``opening`` pixels) with at least ``min_area`` pixels, largest first, and the label
    image (int32, 0 = no region; labels of dropped small regions are kept in it)."""
    mask = (probability > threshold).astype(np.uint8)
    if opening > 1:
        mask = cv2.morphologyEx(mask, cv2.MORPH_OPEN, np.ones((opening, opening), np.uint8))
    count, labels, stats, _ = cv2.connectedComponentsWithStats(mask, connectivity=8)
    blobs = []
    for label in range(1, count):
        area = stats[label, cv2.CC_STAT_AREA]
        if area < min_area:
            continue
        x, y = stats[label, cv2.CC_STAT_LEFT], stats[label, cv2.CC_STAT_TOP]
        w, h = stats[label, cv2.CC_STAT_WIDTH], stats[label, cv2.CC_STAT_HEIGHT]
        # one pixel around the region too: its soft edge counts in proportion
        x0, y0 = max(x - 1, 0), max(y - 1, 0)
        x1, y1 = min(x + w + 1, labels.shape[1]), min(y + h + 1, labels.shape[0])
        inside = cv2.dilate((labels[y0:y1, x0:x1] == label).astype(np.uint8),
                            np.ones((3, 3), np.uint8)) > 0
        centroid, _, mass, _, _ = region_moments(probability[y0:y1, x0:x1], inside, (x0, y0))
        blobs.append(Blob(centroid, float(area), mass,
                          bbox=(int(x), int(y), int(x + w), int(y + h)), label=label))
    blobs.sort(key=lambda blob: -blob.area)
    return blobs, labels


def region_moments(probability: np.ndarray, inside: np.ndarray, origin: tuple[float, float],
                   step: float = 1.0) -> tuple[np.ndarray, float, float, np.ndarray, float]:
    """Moments of the pixels ``inside`` (bool, same shape) of a probability image whose
    pixel (i, j) sits at ``origin + step (j, i)``, each weighted by its probability (soft
    edges of blur and mixed pixels count in proportion).

    Returns
    -------
    centroid : ndarray, shape (2,)
        (u, v), NaN for an empty region.
    area : float
        Pixels inside, in units of the origin's pixels.
    mass : float
        Sum of the probabilities inside (in the image's own pixels).
    axis : ndarray, shape (2,)
        Unit direction of the region's longer axis.
    elongation : float
        Ratio of the second moments along and across that axis (1 for a round region).
    """
    weights = np.where(inside, probability, 0.0).astype(np.float32)
    m = cv2.moments(weights)
    mass = float(m["m00"])
    area = float(np.count_nonzero(inside)) * step * step
    if mass <= 0.0:
        return np.full(2, np.nan), area, mass, np.array([1.0, 0.0]), 1.0
    centroid = np.array([m["m10"], m["m01"]]) / mass * step + np.asarray(origin, float)
    covariance = np.array([[m["mu20"], m["mu11"]], [m["mu11"], m["mu02"]]]) / mass
    values, vectors = np.linalg.eigh(covariance)
    return centroid, area, mass, vectors[:, 1], float(values[1] / max(values[0], 1e-12))
