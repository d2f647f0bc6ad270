"""Sponge-coloured regions of an image: a soft colour prior from a named colour, and the
connected regions (blobs) of a colour probability image with sub-pixel centroids.

The named colours of :data:`~wipelab.vision.colour_model.NAMED_COLOURS` are boxes in HSV.
A real sponge's body drifts out of such a box under coloured light and shading, so the
prior is soft: full inside the box, falling off over a few hue and saturation units outside.
A name is a hint: a sponge between two names (a lemon yellow, a golden orange) shows in the
box grown a little to one side (:func:`widened_hues`), and once found, the box spans the
hues its own pixels show beyond it (:func:`spanning_hues` of :func:`hue_range`). The tracker
then learns the sponge's own colour model from its pixels
(:meth:`~wipelab.vision.colour_model.ColourModel.fit`), bounded by that prior: the sponge's
body is of the named colour as the sponge shows it, a table of a neighbouring hue is not.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from wipelab.vision.colour_model import H_BINS, S_BINS, ColourModel, HsvRange, vivid_part

#: Width of the prior's fall-off outside the named box: hue (OpenCV units, 0-179) and
#: saturation (0-255).
HUE_MARGIN, SATURATION_MARGIN = 5.0, 30.0


def hue_centre(colour: HsvRange) -> float:
    """The middle of the box's hue range on the hue circle (OpenCV units)."""
    return _hue_centre_and_half(colour)[0]


def _hue_centre_and_half(colour: HsvRange) -> tuple[float, float]:
    """Centre and half-width of the box's hue range on the hue circle (OpenCV units)."""
    low, high = colour.low[0], colour.high[0]
    centre = 0.5 * (low + high) if low <= high else (0.5 * (low + high + 180.0)) % 180.0
    return centre, 0.5 * ((high - low) % 180.0)


def _with_hues(colour: HsvRange, low: float, high: float) -> HsvRange:
    """``colour`` with the hue range [low, high] (on the circle: numbers outside 0-179 wrap,
    rounded outwards; the whole circle when it spans it)."""
    if high - low >= 179.0:
        low, high = 0.0, 179.0
    return HsvRange((int(np.floor(low)) % 180,) + colour.low[1:],
                    (int(np.ceil(high)) % 180,) + colour.high[1:])


def widened_hues(colour: HsvRange, units: float, side: int = 0) -> HsvRange:
    """The box with its hue range grown by ``units`` above it (``side`` +1), below it (-1) or
    on both sides (0): a sponge whose colour lies between two named colours (a lemon yellow,
    a golden orange) shows in it."""
    centre, half = _hue_centre_and_half(colour)
    return _with_hues(colour, centre - half - (units if side <= 0 else 0.0),
                      centre + half + (units if side >= 0 else 0.0))


def spanning_hues(colour: HsvRange, low: float, high: float, margin: float) -> HsvRange:
    """The box grown where the hues [low, high] (OpenCV units, on the circle) reach beyond it,
    to hold them and ``margin`` more: the named colour as this sponge shows it. Hues inside
    the box leave it as it is."""
    centre, half = _hue_centre_and_half(colour)
    start = (low - centre + 90.0) % 180.0 - 90.0   # circular, relative to the box's centre
    end = start + (high - low) % 180.0
    return _with_hues(colour, centre + (start - margin if start < -half else -half),
                      centre + (end + margin if end > half else half))


def hue_range(images_bgr: list[np.ndarray], masks: list[np.ndarray], near: float,
              share: float = 0.05) -> tuple[float, float] | None:
    """The ``share`` and 1 - ``share`` quantiles (OpenCV units) of the hues of the pixels of
    ``masks`` (0/255) in ``images_bgr``, on the hue circle around ``near`` (the second may be
    past 179: the range wraps); None when the masks hold no pixel."""
    offsets = [(cv2.cvtColor(image, cv2.COLOR_BGR2HSV)[..., 0][mask > 0].astype(np.float64)
                - near + 90.0) % 180.0 - 90.0 for image, mask in zip(images_bgr, masks)]
    offsets = np.concatenate(offsets) if offsets else np.zeros(0)
    if not offsets.size:
        return None
    low, high = np.quantile(offsets, [share, 1.0 - share])
    return float(near + low) % 180.0, float(near + low) % 180.0 + float(high - low)


def hue_distance(hue, other):
    """Circular distance between OpenCV hues (0-179; numbers or arrays)."""
    return np.abs((hue - other + 90.0) % 180.0 - 90.0)


def prior_model(colour: HsvRange, hue_margin: float = HUE_MARGIN,
                saturation_margin: float = SATURATION_MARGIN) -> ColourModel:
    """A colour model that reads 1 inside the HSV box ``colour`` and falls off linearly to 0
    within ``hue_margin`` and ``saturation_margin`` outside it (value: pixels darker than
    60 % of the box's lowest value are never sponge)."""
    hue = (np.arange(H_BINS) + 0.5) * 180.0 / H_BINS
    saturation = (np.arange(S_BINS) + 0.5) * 256.0 / S_BINS
    centre, half = _hue_centre_and_half(colour)
    distance = hue_distance(hue, centre)
    hue_membership = np.clip(1.0 - (distance - half) / hue_margin, 0.0, 1.0)
    saturation_membership = np.clip(
        1.0 - np.maximum(colour.low[1] - saturation, saturation - colour.high[1])
        / saturation_margin, 0.0, 1.0)
    ratio = np.outer(hue_membership, saturation_membership)
    return ColourModel(ratio, v_min=int(0.6 * colour.low[2]))


@dataclass(frozen=True)
class Blob:
    """A connected region of a probability image (its outer outline; holes, such as a hand
    on top of the sponge, are inside it).

    Attributes
    ----------
    centroid : ndarray, shape (2,)
        Centre (u, v) of the area its outline encloses, pixels of the image it was found in.
    area : float
        Pixels its outline encloses.
    bbox : tuple of int
        (x0, y0, x1, y1), exclusive upper bounds.
    outline : ndarray, shape (k, 1, 2)
        The outline, int32 pixel coordinates (OpenCV contour).
    label : int
        Its index in the list :func:`find_blobs` returned.
    vivid_pixels : float or None
        Pixels of its vivid part (:func:`vivid_area`), where that was measured.
    """

    centroid: np.ndarray
    area: float
    bbox: tuple[int, int, int, int]
    outline: np.ndarray
    label: int
    vivid_pixels: float | None = None

    @property
    def vivid_or_whole_area(self) -> float:
        """Pixels of its vivid part where measured, else :attr:`area`."""
        return self.area if self.vivid_pixels is None else self.vivid_pixels

    @property
    def radius(self) -> float:
        """Radius of a disc of the same area, pixels."""
        return float(np.sqrt(self.area / np.pi))


def find_blobs(probability: np.ndarray, min_area: float, threshold: float = 0.5,
               opening: int = 3) -> list[Blob]:
    """Connected regions of ``probability > threshold`` (after an opening of ``opening``
    pixels) whose outlines enclose at least ``min_area`` pixels, largest first."""
    mask = (probability > threshold).astype(np.uint8)
    if opening > 1:
        mask = cv2.morphologyEx(mask, cv2.MORPH_OPEN, np.ones((opening, opening), np.uint8))
    outlines, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    found = []
    for outline in outlines:
        m = cv2.moments(outline)
        # the polygon through the boundary pixels' centres misses half a pixel all round
        area = m["m00"] + 0.5 * cv2.arcLength(outline, True) + 1.0
        if area < min_area:
            continue
        x, y, w, h = cv2.boundingRect(outline)
        centroid = (np.array([m["m10"], m["m01"]]) / m["m00"] if m["m00"] > 0
                    else outline.reshape(-1, 2).mean(axis=0).astype(float))
        found.append((area, centroid, (x, y, x + w, y + h), outline))
    found.sort(key=lambda item: -item[0])
    return [Blob(centroid, float(area), bbox, outline, k)
            for k, (area, centroid, bbox, outline) in enumerate(found)]


def vivid_area(image: np.ndarray, probability: np.ndarray, blob: Blob,
               threshold: float = 0.5) -> float:
    """Pixels of the blob's vivid part (:func:`vivid_part` of its pixels above ``threshold``
    in ``image``, BGR): the sponge's area when its region took in a duller thing of a near
    hue next to it (a wooden table), the blob's pixels when it holds one colour group."""
    x0, y0, x1, y1 = blob.bbox
    inside = np.zeros((y1 - y0, x1 - x0), np.uint8)
    cv2.drawContours(inside, [blob.outline], -1, 255, thickness=-1, offset=(-x0, -y0))
    inside[probability[y0:y1, x0:x1] <= threshold] = 0
    return float(np.count_nonzero(vivid_part(image[y0:y1, x0:x1], inside)))


def blob_mask(probability: np.ndarray, blobs: list[Blob], grow: int = 1,
              threshold: float = 0.5) -> np.ndarray:
    """Bool mask of the blobs' pixels: those above ``threshold`` inside their outlines (a
    hole, such as a hand on the sponge, stays out), grown by ``grow`` pixels (so that the
    soft edge just outside the threshold counts too)."""
    mask = np.zeros(probability.shape, np.uint8)
    cv2.drawContours(mask, [blob.outline for blob in blobs], -1, 1, thickness=-1)
    mask &= (probability > threshold).astype(np.uint8)
    if grow > 0:
        mask = cv2.dilate(mask, np.ones((2 * grow + 1, 2 * grow + 1), np.uint8))
    return mask > 0


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
