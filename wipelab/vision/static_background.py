"""What a camera sees where the sponge is not: a slowly updated background, for telling the
sponge from still things of its colour that it touches or passes over.

A cloth, a stain or a plate of the sponge's colour merges with the sponge's colour region
whenever the sponge comes near. The background holds, per pixel, the *median* appearance of
the scene (started from the median of recent frames, then followed by an approximate median:
each update moves it a few grey levels towards what the pixel shows, McFarlane & Schofield
1995). The sponge and the holding arm pass over a pixel of the wiped area less than half of
the time, so the median there is what lies on the table; where that median is of the
sponge's colour, a still thing of its colour lies, and a pixel that still looks like it is
not the sponge. The median is learnt from the whole frame, the sponge's region included: a
region that took in part of a cloth would otherwise keep that part from ever being learnt.

A sponge that rests, or wipes a path smaller than itself, keeps pixels covered more than
half of the time and turns into a still thing of its own (a ghost): a still thing that lies
under the sponge's region (nine tenths of it), or holds the middle of its path, is
remembered as a ghost until the median there is no longer of the sponge's colour.

A sponge whose shade lies within the still-thing test's grey levels of a cloth it wipes on
would vanish into it: each update also learns how the sponge looks in the camera (its
region's median colour), and a pixel more like the sponge than like the still thing at its
place is not the still thing.

The wiping arm shades a cloth as it passes, and the median takes in the shade where the arm
passes most often: on a still thing larger than any ghost of the sponge, a pixel of its hue
and saturation that is only darker or brighter is still that thing (the chromaticity test of
shadows, Cucchiara et al. 2003), unless it is more like the sponge.

A pixel next to a still thing still shows it when it matches the background at its place
or a background pixel away: the edges of a checkered or grained thing move by a pixel as the
low-resolution background, compression and noise place them.

The background is kept at low resolution in the undistorted canvas of
:class:`~wipelab.vision.undistortion.Undistorter`, so that a measurement window reads it
with one affine warp.
"""

from __future__ import annotations

import cv2
import numpy as np

from wipelab.vision.colour_model import ColourModel
from wipelab.vision.undistortion import Undistorter


#: Background pixels well inside the sponge's region needed to learn how it looks.
MIN_SPONGE_PIXELS = 5
#: A pixel shows a still thing in another light (a shadow, or without the shadow the median
#: took in) when its brightness (HSV value) is within these factors of the still thing's,
#: and its hue and saturation (OpenCV units) within these.
SHADE_BRIGHTNESS = (0.35, 2.5)
SHADE_HUE = 6.0
SHADE_SATURATION = 40.0
#: The four as the kernel takes them.
SHADE = np.array([*SHADE_BRIGHTNESS, SHADE_HUE, SHADE_SATURATION], np.float32)


class StaticBackground:
    """The median appearance of one camera's scene, in its undistorted canvas.

    Parameters
    ----------
    undistorter : Undistorter
        The camera's undistortion (its canvas is the background's frame).
    scale : float
        Resolution of the background relative to the canvas.
    step : float
        Grey levels by which an update moves each learnt pixel towards what it shows.
    difference : int
        A pixel differs from the background when one of its channels differs by more than
        this (grey levels).
    """

    def __init__(self, undistorter: Undistorter, scale: float, step: float = 4.0,
                 difference: int = 24):
        self.scale = scale
        self.step = step
        self.difference = difference
        width, height = undistorter.size
        self.size = (max(8, int(round(width * scale))), max(8, int(round(height * scale))))
        # canvas pixel of each background pixel, then the distorted frame's pixel there
        xs = (np.arange(self.size[0], dtype=np.float32) + 0.5) / scale - 0.5
        ys = (np.arange(self.size[1], dtype=np.float32) + 0.5) / scale - 0.5
        full_u, full_v = cv2.convertMaps(undistorter.map_xy, undistorter.map_fraction,
                                         cv2.CV_32FC1)
        grid_x, grid_y = np.meshgrid(xs, ys)
        map_u = cv2.remap(full_u, grid_x, grid_y, cv2.INTER_LINEAR,
                          borderMode=cv2.BORDER_CONSTANT, borderValue=-1e4)
        map_v = cv2.remap(full_v, grid_x, grid_y, cv2.INTER_LINEAR,
                          borderMode=cv2.BORDER_CONSTANT, borderValue=-1e4)
        # fixed-point maps, as the undistorter's: resampling is 3x faster than with float maps
        self._map_xy, self._map_fraction = cv2.convertMaps(map_u, map_v, cv2.CV_16SC2)
        shape = (self.size[1], self.size[0])
        # background pixels that see the frame at all (a wide-angle canvas has empty corners)
        frame_width, frame_height = undistorter.frame_size
        self.in_frame = ((map_u >= 0) & (map_v >= 0) & (map_u <= frame_width - 1)
                         & (map_v <= frame_height - 1))
        self._in_frame_pixels = int(np.count_nonzero(self.in_frame))
        self._steps = (step * self.in_frame).astype(np.float32)  # per update and pixel
        self.image = np.zeros(shape + (3,), np.float32)  # median appearance, BGR
        self.coloured = np.zeros(shape, bool)  # the median is of the sponge's colour
        self.ghosts = np.zeros(shape, bool)    # ... but it is the sponge itself
        #: still things of the sponge's colour: 1, or 2 for those larger than any ghost
        self.still = np.zeros(shape, np.uint8)
        #: background pixels a ghost of the sponge covers at most (None before an update)
        self.ghost_limit: float | None = None
        self._mean: np.ndarray | None = None
        # the scene as the background first learnt it (BGR uint8), what a still thing must
        # still look like while the sponge is searched for: the median of the last seconds
        # would take in a sponge that wipes slowly, or a path smaller than itself, and hide
        # it from the search; None once the sponge is tracked (updates)
        self.first: np.ndarray | None = None
        #: how the sponge looks in this camera (BGR uint8 (3,): the median of its region's
        #: pixels at the last update; None before): a pixel more like it than like the still
        #: thing there is not the still thing
        self.sponge_bgr: np.ndarray | None = None
        self.updates = 0

    def canvas_image(self, frame: np.ndarray) -> np.ndarray:
        """A full-resolution frame (BGR uint8) resampled into the background's pixels."""
        return cv2.remap(frame, self._map_xy, self._map_fraction, cv2.INTER_LINEAR,
                         borderMode=cv2.BORDER_CONSTANT)

    def initialise(self, images: np.ndarray, positive: np.ndarray) -> None:
        """Start from a stack of recent frames (:meth:`canvas_image`, (m, h, w, 3)) and
        where each showed the sponge's colour ((m, h, w) bool), taken before the sponge
        was known: the background is their per-pixel median, of the sponge's colour where
        that colour showed in at least half of them (a moving sponge and the arm holding it
        pass; a cloth stays). The first start's median is also what still things look like
        until the first :meth:`update` (:attr:`first`)."""
        self.image = np.median(images, axis=0).astype(np.float32)
        self._mean = None
        if self.updates == 0:
            self.first = self.mean
        self.coloured = (2 * positive.sum(axis=0) >= len(positive)) & self.in_frame
        self.ghosts &= self.coloured
        self.updates += 1
        self._classify()

    def update(self, frame: np.ndarray, models: tuple[ColourModel, ...],
               regions: list[tuple[np.ndarray, np.ndarray, int]], max_ghost: float) -> None:
        """Learn from a frame: move the median towards it, then forget the still things
        that lie under the sponge's region (ghosts).

        Parameters
        ----------
        frame : ndarray
            The camera's frame, BGR uint8, full resolution.
        models : tuple of ColourModel
            The sponge's colour: a pixel is of it when one of these models says so (the
            colour learnt from the sponge, and the colour the user named: a cloth of the
            named colour is a still thing of it even where its shade differs from the
            sponge's).
        regions : list of (mask, origin (2,), step)
            Where the sponge's region is: bool masks of canvas windows (pixel (i, j) at
            canvas ``origin + step (j, i)``), grown by a pixel of the background.
        max_ghost : float
            Canvas pixels a ghost of the sponge covers at most: a larger still thing under
            the region is a cloth that the region took in, not the sponge.
        """
        small = self.canvas_image(frame)
        under = np.zeros(self.in_frame.shape, np.uint8)
        for mask, origin, step in regions:
            x0, y0, x1, y1 = self._bounds(origin, mask.shape, step)
            if x1 > x0 and y1 > y0:
                inside = cv2.resize(mask.astype(np.uint8), (x1 - x0, y1 - y0),
                                    interpolation=cv2.INTER_AREA)
                under[y0:y1, x0:x1] |= cv2.dilate(inside, np.ones((3, 3), np.uint8))
                core = cv2.erode(inside, np.ones((3, 3), np.uint8)) > 0
                if np.count_nonzero(core) >= MIN_SPONGE_PIXELS:
                    self.sponge_bgr = np.median(small[y0:y1, x0:x1][core], axis=0).astype(
                        np.uint8)
        # the sign of (small - image) as two comparisons: np.sign is several times slower
        towards = np.greater(small, self.image).astype(np.float32)
        towards -= np.less(small, self.image)
        towards *= self._steps[..., None]
        self.image += towards
        self._mean = self.first = None
        hsv = cv2.cvtColor(self.mean, cv2.COLOR_BGR2HSV)
        coloured = np.zeros(self.in_frame.shape, bool)
        for model in models:
            coloured |= model.likely(hsv)
        self.coloured = coloured & self.in_frame
        self.ghosts &= self.coloured
        self.updates += 1
        self.ghost_limit = max_ghost * self.scale ** 2
        self._classify()
        self._forget_ghosts(under, max_ghost)

    def forget_ghosts(self) -> None:
        """No still thing is the sponge's ghost any more (what was taken for the sponge was
        a still thing)."""
        self.ghosts[:] = False
        self._classify()

    def _classify(self) -> None:
        self.still = (self.coloured & ~self.ghosts).astype(np.uint8)
        if self.ghost_limit is not None and self.still.any():
            _, labels, stats, _ = cv2.connectedComponentsWithStats(self.still, connectivity=8)
            large = np.flatnonzero(stats[1:, cv2.CC_STAT_AREA] > self.ghost_limit) + 1
            if len(large):
                self.still[np.isin(labels, large)] = 2

    def _forget_ghosts(self, under: np.ndarray, max_area: float) -> None:
        """A still thing that lies (nine tenths of it) under the sponge now is the sponge
        itself, mistaken for one while it rested or wiped a path smaller than itself: a
        ghost. A cloth or a plate the sponge is on reaches beyond it."""
        if not ((self.still > 0) & (under > 0)).any():
            return
        count, labels, stats, _ = cv2.connectedComponentsWithStats(self.still, connectivity=8)
        covered = np.bincount(labels[under > 0], minlength=count)
        area = stats[:, cv2.CC_STAT_AREA]
        ghosts = (covered >= 0.9 * area) & (area <= max_area * self.scale ** 2)
        self._remember_ghosts(labels, np.flatnonzero(ghosts[1:]) + 1)

    def _remember_ghosts(self, labels: np.ndarray, chosen: np.ndarray) -> None:
        """The still things numbered ``chosen`` in ``labels`` (connected components of
        :attr:`still`) are ghosts of the sponge."""
        if len(chosen):
            self.ghosts |= np.isin(labels, chosen)
        self._classify()

    @property
    def coloured_share(self) -> float:
        """Share of the pixels that see the frame whose median is of the sponge's colour."""
        return float(np.count_nonzero(self.coloured)) / max(1, self._in_frame_pixels)

    @property
    def appearance(self) -> np.ndarray:
        """How the still things look, BGR uint8: until the sponge is tracked, as the scene
        first looked (:attr:`first`), then the median."""
        return self.first if self.first is not None else self.mean

    @property
    def mean(self) -> np.ndarray:
        """The background's colours, BGR uint8 (computed when first needed after an update)."""
        if self._mean is None:
            rounded = self.image + 0.5
            self._mean = np.clip(rounded, 0, 255, out=rounded).astype(np.uint8)
        return self._mean

    def median_near(self, canvas_point: np.ndarray, reach: float) -> np.ndarray:
        """The median appearance of the background's pixels within ``reach`` canvas pixels
        (a square) of ``canvas_point`` that see the frame: BGR uint8, (k, 1, 3), an image
        one pixel wide."""
        x0, y0, x1, y1 = self._bounds(np.asarray(canvas_point) - reach, (2 * reach, 2 * reach),
                                      1)
        inside = self.in_frame[y0:y1, x0:x1]
        return self.mean[y0:y1, x0:x1][inside].reshape(-1, 1, 3)

    def _bounds(self, origin, shape, step) -> tuple[int, int, int, int]:
        """Background pixels covering a canvas window."""
        height, width = shape[:2]
        x0 = max(int(np.floor(origin[0] * self.scale)), 0)
        y0 = max(int(np.floor(origin[1] * self.scale)), 0)
        x1 = min(int(np.ceil((origin[0] + width * step) * self.scale)), self.size[0])
        y1 = min(int(np.ceil((origin[1] + height * step) * self.scale)), self.size[1])
        return x0, y0, x1, y1

    def release(self, canvas_points: np.ndarray, max_area: float, max_offset: float) -> None:
        """Forget the still things that hold the middle of a path (``canvas_points`` (n, 2),
        canvas pixels): at most ``max_area`` canvas pixels large and centred within
        ``max_offset`` pixels of the points' median. A sponge wiping a path smaller than
        itself keeps the path's middle covered and looks still there; a cloth the path
        crosses is larger, or lies elsewhere."""
        count, labels, stats, centroids = cv2.connectedComponentsWithStats(self.still,
                                                                            connectivity=8)
        if count <= 1:
            return
        middle = self._background_pixels(np.median(np.asarray(canvas_points), axis=0))
        x, y = np.round(middle).astype(int)
        if not (0 <= x < self.size[0] and 0 <= y < self.size[1]):
            return
        label = labels[y, x]
        if label and stats[label, cv2.CC_STAT_AREA] <= max_area * self.scale ** 2 and \
                np.linalg.norm(centroids[label] - middle) <= max_offset * self.scale:
            self._remember_ghosts(labels, np.array([label]))

    def release_visited(self, canvas_points: np.ndarray, max_area: float) -> None:
        """Forget the still things of at most ``max_area`` canvas pixels that the sponge has
        been on (``canvas_points`` (n, 2), canvas pixels of its valid points): where it
        rested before the demonstration, or dwelt at the ends of its strokes, it left a
        ghost of itself, which would hide it from the search when it rests there again."""
        count, labels, stats, _ = cv2.connectedComponentsWithStats(self.still, connectivity=8)
        if count <= 1:
            return
        pixels = np.round(self._background_pixels(canvas_points)).astype(int)
        inside = (pixels[:, 0] >= 0) & (pixels[:, 1] >= 0) & (pixels[:, 0] < self.size[0]) & \
            (pixels[:, 1] < self.size[1])
        visited = np.unique(labels[pixels[inside, 1], pixels[inside, 0]])
        small = stats[:, cv2.CC_STAT_AREA] <= max_area * self.scale ** 2
        self._remember_ghosts(labels, visited[(visited > 0) & small[visited]])

    def still_in_canvas_image(self, image: np.ndarray) -> np.ndarray | None:
        """Where a :meth:`canvas_image` shows a still thing of the sponge's colour as it
        always did: bool (h, w); None before the background knows anything."""
        if not self.updates or not self.still.any():
            return None
        return self._unchanged(image, self.appearance, self.still, 1)

    def _unchanged(self, image: np.ndarray, background: np.ndarray, still: np.ndarray,
                   reach: int) -> np.ndarray:
        """Where ``image`` (BGR uint8) shows what ``background`` (the same size) shows at the
        pixel or at one ``reach`` pixels from it (a background pixel's width), next to a
        still thing of the sponge's colour (``still``, uint8): the edges of a checkered or
        grained still thing move by a pixel as the low-resolution background, compression
        and noise place them, and a pixel compared only with its own background pixel
        would leave a fringe of the colour round every square of a tablecloth of it."""
        height, width = image.shape[:2]
        near = cv2.dilate((still > 0).astype(np.uint8),
                          np.ones((2 * reach + 1, 2 * reach + 1), np.uint8))
        unchanged = np.zeros((height, width), bool)
        x, y, w, h = cv2.boundingRect(near)  # compared only where still things are
        if w == 0:
            return unchanged
        # the background over the box grown by reach, edges replicated
        padded = cv2.copyMakeBorder(background[max(y - reach, 0):y + h + reach,
                                               max(x - reach, 0):x + w + reach],
                                    reach - min(y, reach), reach - min(height - y - h, reach),
                                    reach - min(x, reach), reach - min(width - x - w, reach),
                                    cv2.BORDER_REPLICATE)
        box = image[y:y + h, x:x + w]
        large = cv2.dilate((still[y:y + h, x:x + w] == 2).astype(np.uint8),
                           np.ones((2 * reach + 1, 2 * reach + 1), np.uint8))
        if large.any():  # a cloth: the arm's shadow passes over it
            box_hsv = cv2.cvtColor(box, cv2.COLOR_BGR2HSV)
            background_hsv = cv2.cvtColor(padded[reach:reach + h, reach:reach + w],
                                          cv2.COLOR_BGR2HSV)
        else:
            box_hsv = background_hsv = np.zeros((1, 1, 3), np.uint8)
        sponge_bgr = sponge_hs = None
        if self.sponge_bgr is not None:
            sponge_bgr = self.sponge_bgr.astype(np.int64)
            sponge_hs = cv2.cvtColor(self.sponge_bgr.reshape(1, 1, 3),
                                     cv2.COLOR_BGR2HSV)[0, 0, :2].astype(np.float32)
        # numba (its import and the kernel's loading, ~0.5 s) only for videos with still
        # things of the sponge's colour
        from wipelab.vision._still_kernel import unchanged_pixels
        unchanged[y:y + h, x:x + w] = unchanged_pixels(
            np.ascontiguousarray(box), padded, reach, np.ascontiguousarray(near[y:y + h, x:x + w]),
            large, box_hsv, background_hsv, self.difference, sponge_bgr, sponge_hs, SHADE)
        return unchanged

    def _background_pixels(self, canvas_points: np.ndarray) -> np.ndarray:
        """Background coordinates (..., 2) of canvas (full-resolution) points (..., 2): the
        inverse of :meth:`canvas_pixels`."""
        return (np.asarray(canvas_points, dtype=np.float64) + 0.5) * self.scale - 0.5

    def canvas_pixels(self, pixels: np.ndarray) -> np.ndarray:
        """Canvas (full-resolution) coordinates (n, 2) of background pixels (n, 2)."""
        return (np.asarray(pixels, dtype=np.float64) + 0.5) / self.scale - 0.5

    def still_colour(self, window: np.ndarray, origin: np.ndarray, step: int
                     ) -> np.ndarray | None:
        """Pixels of a canvas window (BGR uint8, pixel (i, j) at canvas
        ``origin + step (j, i)``) where a still thing of the sponge's colour shows as it
        always did: bool, window shape; None when there is no such thing in the window."""
        if not self.updates:
            return None
        x0, y0, x1, y1 = self._bounds(origin, window.shape, step)
        if x1 <= x0 or y1 <= y0 or not self.still[y0:y1, x0:x1].any():
            return None
        height, width = window.shape[:2]
        s = self.scale
        transform = np.array([[step * s, 0.0, (origin[0] + 0.5) * s - 0.5],
                              [0.0, step * s, (origin[1] + 0.5) * s - 0.5]], np.float32)
        flags = cv2.WARP_INVERSE_MAP | cv2.INTER_LINEAR
        still = cv2.warpAffine(self.still, transform, (width, height),
                               flags=cv2.WARP_INVERSE_MAP | cv2.INTER_NEAREST)
        background = cv2.warpAffine(self.appearance, transform, (width, height), flags=flags,
                                    borderMode=cv2.BORDER_REPLICATE)
        return self._unchanged(window, background, still, max(1, round(1.0 / (step * s))))

    def clear_still(self, probability: np.ndarray, window: np.ndarray, origin: np.ndarray,
                    step: int) -> None:
        """Set the sponge ``probability`` of a canvas window (window shape) to 0 where the
        window shows a still thing of the sponge's colour (:meth:`still_colour`)."""
        still = self.still_colour(window, origin, step)
        if still is not None:
            probability[still] = 0.0
