"""Colour model of the sponge: an HSV histogram ratio, applied by back-projection.

The model is learnt from pixels known to show the sponge (a seed mask) against the rest of
the frame: ``p(sponge | colour) = h_s / (h_s + h_b)`` over (hue, saturation) bins, with
``h_s`` and ``h_b`` the normalised histograms of the sponge and of the background. Dark
pixels (value below ``v_min``), whose hue is noise, are never sponge. The seed mask comes
from a named colour, an HSV range, or a region of a frame (:func:`seed_mask`).

OpenCV HSV units: hue 0-179 (degrees / 2), saturation and value 0-255.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

H_BINS, S_BINS = 45, 32


@dataclass(frozen=True)
class HsvRange:
    """An HSV box, OpenCV units; ``low[0] > high[0]`` wraps the hue through red (179 -> 0)."""

    low: tuple[int, int, int]
    high: tuple[int, int, int]

    def __post_init__(self):
        limits = (179, 255, 255)
        for value, top in zip(self.low + self.high, limits + limits):
            if not 0 <= value <= top:
                raise ValueError(f"HSV values must lie in 0-179 (hue) and 0-255 (saturation, "
                                 f"value), got low={self.low} high={self.high}")
        if self.low[1] > self.high[1] or self.low[2] > self.high[2]:
            raise ValueError(f"HSV range low={self.low} must not exceed high={self.high} in "
                             "saturation and value")

    def mask(self, hsv: np.ndarray) -> np.ndarray:
        """Pixels inside the range, uint8 0/255, shape (h, w)."""
        low, high = np.array(self.low), np.array(self.high)
        if low[0] <= high[0]:
            return cv2.inRange(hsv, low, high)
        upper = cv2.inRange(hsv, low, np.array([179, high[1], high[2]]))
        lower = cv2.inRange(hsv, np.array([0, low[1], low[2]]), high)
        return cv2.bitwise_or(upper, lower)


#: Named sponge colours: saturated ranges, so that skin, wood and grey stay outside.
NAMED_COLOURS = {
    "red": HsvRange((172, 130, 70), (6, 255, 255)),
    "orange": HsvRange((7, 150, 90), (17, 255, 255)),
    "yellow": HsvRange((20, 130, 90), (34, 255, 255)),
    "green": HsvRange((38, 90, 50), (85, 255, 255)),
    "cyan": HsvRange((86, 90, 50), (99, 255, 255)),
    "blue": HsvRange((100, 110, 50), (128, 255, 255)),
    "purple": HsvRange((129, 80, 50), (150, 255, 255)),
    "pink": HsvRange((151, 70, 100), (171, 255, 255)),
}


def parse_hsv_range(text: str) -> HsvRange:
    """``"H,S,V,H,S,V"`` (low then high) -> HsvRange; raises ValueError with the reason."""
    parts = [p.strip() for p in text.replace(";", ",").split(",") if p.strip()]
    if len(parts) != 6:
        raise ValueError(f"expected six integers H,S,V,H,S,V (low then high), got {text!r}")
    try:
        values = [int(p) for p in parts]
    except ValueError:
        raise ValueError(f"expected six integers H,S,V,H,S,V, got {text!r}") from None
    return HsvRange(tuple(values[:3]), tuple(values[3:]))


def largest_blob(mask: np.ndarray, min_area: int) -> np.ndarray | None:
    """The largest 8-connected component of a 0/255 mask, after a 3x3 opening; None if none
    reaches ``min_area`` pixels."""
    opened = cv2.morphologyEx(mask, cv2.MORPH_OPEN, np.ones((3, 3), np.uint8))
    count, labels, stats, _ = cv2.connectedComponentsWithStats(opened, connectivity=8)
    if count <= 1:
        return None
    best = 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))
    if stats[best, cv2.CC_STAT_AREA] < min_area:
        return None
    return (labels == best).astype(np.uint8) * 255


def vivid_part(frame_bgr: np.ndarray, mask: np.ndarray, separation: float = 0.25
               ) -> np.ndarray:
    """The more vivid of two colour groups in a region, if it holds two: a region of a
    named colour often takes in a duller thing of a near hue (skin, a wooden table, a
    shadow); the sponge body is the vivid one.

    The region's pixels (``mask``, 0/255) are split by their chroma (saturation times value,
    HSV) at Otsu's threshold; when the two groups' mean chromas differ by more than
    ``separation`` of the higher one and the vivid group holds a fifth of the pixels, the
    mask of that group (0/255) is returned, else ``mask`` itself."""
    hsv = cv2.cvtColor(frame_bgr, cv2.COLOR_BGR2HSV)
    chroma = (hsv[..., 1].astype(np.uint16) * hsv[..., 2] // 255).astype(np.uint8)
    values = chroma[mask > 0]
    if values.size < 20:
        return mask
    threshold, _ = cv2.threshold(values.reshape(-1, 1), 0, 255,
                                 cv2.THRESH_BINARY | cv2.THRESH_OTSU)
    vivid = values > threshold
    if not vivid.any() or vivid.all() or vivid.mean() < 0.2:
        return mask
    high, low = values[vivid].mean(), values[~vivid].mean()
    if high - low < separation * high:
        return mask
    return np.where((mask > 0) & (chroma > threshold), 255, 0).astype(np.uint8)


class ColourModel:
    """Back-projects frames to the probability that a pixel shows the sponge.

    Parameters
    ----------
    ratio : ndarray, shape (H_BINS, S_BINS)
        ``p(sponge | hue, saturation)`` per bin, in [0, 1].
    v_min : int
        Pixels darker than this (HSV value) are never sponge.
    """

    def __init__(self, ratio: np.ndarray, v_min: int = 40):
        self.ratio = ratio.astype(np.float32)
        self.v_min = int(v_min)
        self._hist = np.clip(ratio * 255.0, 0, 255).astype(np.float32)

    @classmethod
    def fit(cls, frames_bgr: list[np.ndarray], masks: list[np.ndarray], v_min: int = 40,
            smoothing_bins: float = 1.0, unsure: list[np.ndarray] | None = None
            ) -> "ColourModel":
        """Learn the model from frames and the masks (0/255) of their sponge pixels; the
        pixels of ``unsure`` (0/255 masks, optional) count neither as sponge nor as
        background."""
        sponge = np.zeros((H_BINS, S_BINS), np.float32)
        background = np.zeros_like(sponge)
        if unsure is None:
            unsure = [np.zeros_like(mask) for mask in masks]
        for frame, mask, skip in zip(frames_bgr, masks, unsure):
            hsv = cv2.cvtColor(frame, cv2.COLOR_BGR2HSV)
            bright = cv2.inRange(hsv[..., 2], v_min, 255)
            rest = cv2.bitwise_and(cv2.bitwise_not(cv2.bitwise_or(mask, skip)), bright)
            for hist, region in ((sponge, cv2.bitwise_and(mask, bright)), (background, rest)):
                hist += cv2.calcHist([hsv], [0, 1], region, [H_BINS, S_BINS],
                                     [0, 180, 0, 256])
        if sponge.sum() == 0:
            raise ValueError("the seed mask holds no pixel bright enough to learn a colour")
        sponge = cls._smooth(sponge / sponge.sum(), smoothing_bins)
        background = cls._smooth(background / max(1.0, background.sum()), smoothing_bins)
        ratio = sponge / np.maximum(sponge + background, 1e-12)
        ratio[sponge < 1e-3 * sponge.max()] = 0.0  # colours the sponge (almost) never shows
        return cls(ratio, v_min)

    @staticmethod
    def _smooth(hist: np.ndarray, sigma: float) -> np.ndarray:
        """Blur a (hue, saturation) histogram; hue wraps around."""
        if sigma <= 0:
            return hist
        pad = int(np.ceil(3 * sigma))
        wrapped = np.concatenate([hist[-pad:], hist, hist[:pad]], axis=0)
        blurred = cv2.GaussianBlur(wrapped, (0, 0), sigma, borderType=cv2.BORDER_REPLICATE)
        return blurred[pad:-pad]

    def at_most(self, bound: "ColourModel") -> "ColourModel":
        """This model where it says no more than ``bound`` (e.g. the named colour's prior),
        ``bound`` elsewhere: a model learnt from a few windows has smoothed tails that reach
        colours the windows did not show (a table of a neighbouring hue), and there the
        ratio reads 1."""
        return ColourModel(np.minimum(self.ratio, bound.ratio), self.v_min)

    def back_project(self, frame_bgr: np.ndarray) -> np.ndarray:
        """Sponge probability per pixel, float32 in [0, 1], shape (h, w)."""
        return np.multiply(self._probability_bytes(cv2.cvtColor(frame_bgr, cv2.COLOR_BGR2HSV)),
                           1.0 / 255.0, dtype=np.float32)

    def likely(self, hsv: np.ndarray) -> np.ndarray:
        """Where the sponge probability exceeds one half, bool (h, w), of a frame converted to
        HSV (``cv2.COLOR_BGR2HSV``: one conversion serves several models): the same pixels
        as ``back_project(frame) > 0.5``."""
        return self._probability_bytes(hsv) >= 128  # 128 / 255 > 0.5 > 127 / 255

    def _probability_bytes(self, hsv: np.ndarray) -> np.ndarray:
        """Sponge probability per pixel of an HSV image, uint8 0-255."""
        probability = cv2.calcBackProject([hsv], [0, 1], self._hist, [0, 180, 0, 256], 1.0)
        bright = cv2.inRange(hsv, (0, 0, self.v_min), (180, 255, 255))
        return cv2.bitwise_and(probability, bright)


@dataclass(frozen=True)
class ColourSource:
    """Where the sponge's colour comes from: exactly one of a name, an HSV range or a region.

    Attributes
    ----------
    name : str or None
        A key of :data:`NAMED_COLOURS`.
    hsv : HsvRange or None
    roi : tuple of int or None
        (x, y, width, height) of a region of the first left frame that shows the sponge.
    """

    name: str | None = None
    hsv: HsvRange | None = None
    roi: tuple[int, int, int, int] | None = None

    def __post_init__(self):
        given = [v is not None for v in (self.name, self.hsv, self.roi)]
        if sum(given) != 1:
            raise ValueError("give exactly one of a colour name, an HSV range or a region")
        if self.name is not None and self.name not in NAMED_COLOURS:
            raise ValueError(f"unknown colour {self.name!r}; known: {', '.join(NAMED_COLOURS)}")
        if self.roi is not None and (len(self.roi) != 4 or min(self.roi[2:]) <= 0
                                     or min(self.roi[:2]) < 0):
            raise ValueError(f"region must be x,y,width,height with width, height > 0, "
                             f"got {self.roi}")

    @property
    def option(self) -> str:
        """How the user gave it, for messages: ``--color red``, ``--hsv ...``, ``--roi ...``."""
        if self.name is not None:
            return f"--color {self.name}"
        if self.hsv is not None:
            return "--hsv " + ",".join(map(str, self.hsv.low + self.hsv.high))
        return "--roi " + ",".join(map(str, self.roi))

    @property
    def hsv_range(self) -> HsvRange | None:
        """The HSV range of a name or range source (None for a region)."""
        return NAMED_COLOURS[self.name] if self.name is not None else self.hsv


class LinearColourFeature:
    """A colour feature linear in the pixel values: ``f = w . bgr + b``, about 1 on the sponge
    and 0 on what surrounds it.

    Where the histogram back-projection is a sharp, nonlinear classifier (a pixel that is
    30 % sponge may already read 1), a linear feature of a pixel that mixes sponge and
    background in proportion alpha (anti-aliasing, lens and motion blur, chroma subsampling)
    reads alpha between the two levels. The blurred outline of the sponge therefore stays
    centred on the true outline, which is what the sub-pixel pose refinement needs.

    Parameters
    ----------
    w : ndarray, shape (3,)
        Weights of B, G, R (per grey level).
    b : float
    """

    def __init__(self, w: np.ndarray, b: float):
        self.w = np.asarray(w, dtype=np.float64)
        self.b = float(b)
        self._transform = np.append(self.w, self.b).reshape(1, 4).astype(np.float32)

    @classmethod
    def fit(cls, frames_bgr: list[np.ndarray], masks: list[np.ndarray], ring: int = 9,
            ridge: float = 1e-3) -> "LinearColourFeature":
        """Least squares on sponge pixels (target 1, the mask eroded by 2 px) against a ring of
        background pixels around it (target 0, ``ring`` px wide, 3 px away from the mask)."""
        inside, outside = [], []
        for frame, mask in zip(frames_bgr, masks):
            core = cv2.erode(mask, np.ones((5, 5), np.uint8))
            near = cv2.dilate(mask, np.ones((7, 7), np.uint8))
            far = cv2.dilate(mask, np.ones((7 + 2 * ring, 7 + 2 * ring), np.uint8))
            inside.append(frame[core > 0])
            outside.append(frame[(far > 0) & (near == 0)])
        inside, outside = np.concatenate(inside), np.concatenate(outside)
        if len(inside) == 0 or len(outside) == 0:
            raise ValueError("the seed mask is too small or fills the frame")
        X = np.vstack([inside, outside]).astype(np.float64) / 255.0
        y = np.concatenate([np.ones(len(inside)), np.zeros(len(outside))])
        weights = np.concatenate([np.full(len(inside), 0.5 / len(inside)),
                                  np.full(len(outside), 0.5 / len(outside))])
        A = np.column_stack([X, np.ones(len(X))])
        Aw = A * weights[:, None]
        solution = np.linalg.solve(A.T @ Aw + ridge * np.diag([1, 1, 1, 0]), Aw.T @ y)
        return cls(solution[:3] / 255.0, solution[3])

    def apply(self, frame_bgr: np.ndarray) -> np.ndarray:
        """The feature per pixel, float32, shape (h, w)."""
        return cv2.transform(frame_bgr.astype(np.float32), self._transform)
