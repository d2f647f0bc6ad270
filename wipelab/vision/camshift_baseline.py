"""Baseline tracker: OpenCV CamShift in each image, the two window centres triangulated.

The textbook recipe (OpenCV's CamShift tutorial): a hue histogram of the sponge region,
back-projection, ``cv2.CamShift`` per camera, then ``cv2.triangulatePoints`` of the two
centres. It reports the centre of the *visible colour blob*, which the demonstrator's hand
partly covers, not the sponge's centre; the benchmark compares it with
:class:`wipelab.vision.tracker.SpongeTracker` on the same videos.
"""

from __future__ import annotations

import cv2
import numpy as np

from wipelab.vision.calibration import StereoCalibration
from wipelab.vision.colour_model import ColourSource, largest_blob
from wipelab.vision.projection import transform_points
from wipelab.vision.stereo_geometry import reprojection_errors, triangulate_pixels

_CRITERIA = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 10, 1.0)


class CamShiftBaseline:
    """CamShift per camera + triangulation.

    Parameters
    ----------
    calibration : StereoCalibration
        Points are reported in ``calibration.track_frame``.
    colour : ColourSource
        A name or HSV range (the region variant uses the region as the start window).
    min_area : int
        Fewest pixels of a window (and of the seed blob) to count as tracking; a window that
        grows beyond six times its seed's area is lost too.
    max_reprojection : float
        Largest reprojection error (pixels) of the triangulated centre; beyond, the two
        windows are taken to be on different things and the frame is invalid.
    """

    def __init__(self, calibration: StereoCalibration, colour: ColourSource, min_area: int = 150,
                 max_reprojection: float = 8.0):
        self.calibration = calibration
        self.colour = colour
        self.min_area = min_area
        self.max_reprojection = max_reprojection
        self.max_area = 0
        self.hist: np.ndarray | None = None
        self.windows: list[tuple[int, int, int, int] | None] = [None, None]

    def _seed(self, hsv_frames: list[np.ndarray]) -> bool:
        masks = []
        for index, hsv in enumerate(hsv_frames):
            if self.colour.hsv_range is not None:
                mask = largest_blob(self.colour.hsv_range.mask(hsv), self.min_area)
            elif index == 0:
                x, y, w, h = self.colour.roi
                mask = np.zeros(hsv.shape[:2], np.uint8)
                mask[y:y + h, x:x + w] = 255
            else:
                mask = None
            masks.append(mask)
        if masks[0] is None:
            return False
        if self.hist is None:
            saturated = cv2.inRange(hsv_frames[0], (0, 60, 32), (180, 255, 255))
            hist = cv2.calcHist([hsv_frames[0]], [0], cv2.bitwise_and(masks[0], saturated),
                                [32], [0, 180])
            self.hist = cv2.normalize(hist, None, 0, 255, cv2.NORM_MINMAX)
        if masks[1] is None:  # region seed: find the sponge in the right image by its colour
            masks[1] = largest_blob((self._back_project(hsv_frames[1]) > 127).astype(np.uint8)
                                    * 255, self.min_area)
            if masks[1] is None:
                return False
        self.windows = [cv2.boundingRect(mask) for mask in masks]
        self.max_area = 6 * max(w * h for _, _, w, h in self.windows)
        return True

    def _back_project(self, hsv: np.ndarray) -> np.ndarray:
        """Hue back-projection, zero where saturation or value are too low for a hue."""
        probability = cv2.calcBackProject([hsv], [0], self.hist, [0, 180], 1)
        return cv2.bitwise_and(probability, cv2.inRange(hsv, (0, 60, 32), (180, 255, 255)))

    def step(self, left: np.ndarray, right: np.ndarray) -> tuple[np.ndarray, bool]:
        """Sponge point (3,) in the tracking frame (NaN when lost) and whether it is valid."""
        hsv = [cv2.cvtColor(frame, cv2.COLOR_BGR2HSV) for frame in (left, right)]
        if any(window is None for window in self.windows) and not self._seed(hsv):
            return np.full(3, np.nan), False
        centres = []
        for index, image in enumerate(hsv):
            probability = self._back_project(image)
            box, window = cv2.CamShift(probability, self.windows[index], _CRITERIA)
            x, y, w, h = window
            if not self.min_area <= w * h <= self.max_area or \
                    probability[y:y + h, x:x + w].sum() < 255 * self.min_area / 4:
                return self._lost()  # collapsed onto nothing, or spread over the table
            self.windows[index] = window
            centres.append(np.array(box[0], dtype=np.float64))
        point_left = triangulate_pixels(self.calibration, centres[0][None], centres[1][None])
        if not 0.05 < point_left[0, 2] < 5.0 or reprojection_errors(
                self.calibration, point_left, centres[0][None],
                centres[1][None])[0] > self.max_reprojection:
            return self._lost()  # the two windows are not on the same object
        return transform_points(self.calibration.T_track_left, point_left[0]), True

    def _lost(self) -> tuple[np.ndarray, bool]:
        self.windows = [None, None]
        return np.full(3, np.nan), False
