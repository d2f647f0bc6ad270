"""The track stage: a stereo video of a wiping demonstration -> the sponge's 3D trajectory.

Reads a demo directory (DESIGN.md: left.mp4, right.mp4, calibration.yaml, optional
demo.toml), tracks the sponge with :class:`wipelab.vision.tracker.SpongeTracker` and writes

* ``track.csv``: t, x, y, z (the sponge's point, metres, world frame, or the left camera's
  optical frame when the calibration has no T_world_left), valid (0 while occluded or lost;
  positions are then empty), quality (how the row was measured: ``box`` — the sponge box
  fitted, its centre; ``mono`` — one camera's colour region placed on the table's plane, the
  other camera's hidden or cut by the image's edge; ``centroid`` — the sponge's colour region
  in both cameras placed on the
  table's plane; empty when not valid), yaw (rad, about the table normal; box rows only),
  and the normalised offsets ``x_norm``, ``y_norm`` from the centre of the demonstration
  area (paper Fig. 3);
* ``track.mcap`` / ``track.rrd``: both videos (video references), both camera calibrations,
  /tf of the cameras, the track (x, y, z; the sponge box per frame; the trajectory growing
  piece by piece), the particles, the demonstration area, the per-frame quality (a state);
  the sponge box and the particles drawn over both images (``/stereo/*/overlay``);
* ``manifest.json``.

Everything is checked before anything is written; bad input raises InputError.
"""

from __future__ import annotations

import os
import queue
import sys
import tempfile
import threading
from collections import deque
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import cv2
import numpy as np
import rerun as rr
import rerun.blueprint as rrb
from tqdm import tqdm

from wipelab.errors import InputError, interrupts_deferred
from wipelab.input_files import read_input_toml
from wipelab.logs import TIMELINE, StageRecorder, stage_panels, whole_run
from wipelab.logs.palette import XYZ_COLOURS
from wipelab.logs.timebase import seconds_array_to_ns
from wipelab.long_lived import long_lived_objects
from wipelab.manifest import build_manifest, write_json
from wipelab.rotations import (quaternion_xyzw_from_rotation, quaternions_xyzw_from_rotations,
                               rotation_about_axis)
from wipelab.stage_output import staged_output
from wipelab.thread_priority import run_as_helper
from wipelab.trajectory_csv import write_trajectory
from wipelab.vision.calibration import StereoCalibration, load_calibration
from wipelab.vision.colour_model import NAMED_COLOURS, ColourSource, parse_hsv_range
from wipelab.vision.demonstration_area import DemonstrationArea, measure_demonstration_area
from wipelab.vision.projection import invert_transform
from wipelab.vision.sponge_box import CORNER_SIGNS, EDGES, SpongeBox, yaw_rotation
from wipelab.vision.tracker import (QUALITY_BOX, QUALITY_CENTROID, QUALITY_MONO, QUALITY_NONE,
                                    FrameEstimate, SpongeTracker, TrackerParams,
                                    commonest_failure, fleeting_runs, still_runs)
from wipelab.vision.video_io import H264Writer, ReplayedStart, StereoVideoReader

DEFAULT_COLOUR = "yellow"
#: Frames before the tracking pass's first valid one are kept, up to this many bytes, to
#: follow the sponge back to the start (:func:`track_backwards`).
BACKWARD_BYTES = 400_000_000
#: Frame pairs of the warm-up kept, up to this many bytes, for the tracking pass to start
#: from without decoding them again (:class:`~wipelab.vision.video_io.ReplayedStart`; a
#: 3 s warm-up of 1280x720 pairs is 500 MB).
WARMUP_BYTES = 600_000_000
#: Points of the first valid frames that start the backward track.
SEED_FRAMES = 3
LEFT_FRAME, RIGHT_FRAME = "stereo_left_optical", "stereo_right_optical"


@dataclass(frozen=True)
class TrackParams:
    """Settings of one track run (the command-line options).

    Attributes
    ----------
    colour : str or None
        Named sponge colour; with ``hsv`` and ``roi`` None, demo.toml's ``sponge_colour``
        or :data:`DEFAULT_COLOUR`.
    hsv : str or None
        HSV range ``"H,S,V,H,S,V"`` (low then high, OpenCV units).
    roi : tuple of int or None
        (x, y, width, height) of a region of the first left frame showing the sponge.
    particles : int
        Particle count.
    seed : int
        Seed of the particle filter.
    sponge_size : tuple of float or None
        (length, width, height) of the sponge, metres, when known; None: demo.toml's
        ``sponge_size``, else unknown (the sponge is then tracked by its colour region alone;
        with a size the box refinement gives its centre).
    area_window : tuple of float
        Time window (start, end), seconds, in which the demonstration area is measured.
    logged_particles : int
        Particles per frame written to the logs.
    warmup : float
        Seconds of video read first to find the sponge and measure the table before the
        tracking pass from the first frame (more when the sponge takes longer to find).
    """

    colour: str | None = None
    hsv: str | None = None
    roi: tuple[int, int, int, int] | None = None
    particles: int = 100
    seed: int = 0
    sponge_size: tuple[float, float, float] | None = None
    area_window: tuple[float, float] = (0.0, 10.0)
    logged_particles: int = 40
    warmup: float = 3.0


@dataclass
class TrackResult:
    """What track measured (also written to track.csv).

    Attributes
    ----------
    t : ndarray, shape (n,)
    poses : ndarray, shape (n, 4)
        x, y, z (metres) and yaw (rad) in ``frame``; NaN where invalid (yaw also in
        ``centroid`` rows).
    valid : ndarray of bool, shape (n,)
    quality : ndarray of str, shape (n,)
        ``box``, ``centroid``, ``mono`` or ``""`` per frame (see the module docstring).
    area : DemonstrationArea
    normalised : ndarray, shape (n, 2)
    frame : str
        ``world`` or ``left_optical``.
    areas : ndarray, shape (n, 2)
        Pixels of the sponge's colour region in the left and right image (0 where not
        measured).
    particles : ndarray, shape (n, m, 4)
        A sample of each frame's particles of the box refinement (NaN without it).
    sponge_size : tuple of float or None
        (length, width, height) of the sponge box when known, metres.
    region_size : float
        Size of the sponge's visible colour region (square root of its area), metres.
    """

    t: np.ndarray
    poses: np.ndarray
    valid: np.ndarray
    quality: np.ndarray
    area: DemonstrationArea
    normalised: np.ndarray
    frame: str
    areas: np.ndarray
    particles: np.ndarray = field(repr=False)
    sponge_size: tuple[float, float, float] | None = None
    region_size: float = float("nan")


@dataclass(frozen=True)
class Demo:
    """A validated demo directory."""

    left: Path
    right: Path
    calibration_path: Path
    calibration: StereoCalibration
    reader: StereoVideoReader
    metadata: dict


def open_demo(demo_dir: str | os.PathLike) -> Demo:
    """Check a demo directory and open its videos (nothing is decoded yet).

    Raises
    ------
    InputError
        Missing directory or files, unreadable videos, frame counts / fps / size that differ,
        a bad calibration, a demo.toml that is not TOML.
    """
    demo = Path(demo_dir)
    if not demo.is_dir():
        raise InputError(f"{demo}: not a directory (expected a demo directory with left.mp4, "
                         "right.mp4 and calibration.yaml)")
    left, right, calibration_path = demo / "left.mp4", demo / "right.mp4", demo / "calibration.yaml"
    for path in (left, right, calibration_path):
        if not path.is_file():
            raise InputError(f"{path}: file not found")
    calibration = load_calibration(calibration_path)
    reader = StereoVideoReader(left, right, calibration.image_size)
    metadata = {}
    toml_path = demo / "demo.toml"
    if toml_path.is_file():
        metadata = read_input_toml(toml_path)
    return Demo(left, right, calibration_path, calibration, reader, metadata)


def colour_source(params: TrackParams, metadata: dict, toml_name: str) -> ColourSource:
    given = [v is not None for v in (params.colour, params.hsv, params.roi)]
    if sum(given) > 1:
        raise InputError("--color, --hsv and --roi: give only one of them")
    try:
        if params.hsv is not None:
            return ColourSource(hsv=parse_hsv_range(params.hsv))
        if params.roi is not None:
            return ColourSource(roi=tuple(int(v) for v in params.roi))
        name = params.colour or metadata.get("sponge_colour") or DEFAULT_COLOUR
        if params.colour is None and name not in NAMED_COLOURS:
            raise InputError(f"{toml_name}: sponge_colour {name!r} is not a known colour "
                             f"({', '.join(NAMED_COLOURS)})")
        return ColourSource(name=name)
    except ValueError as error:
        option = "--hsv" if params.hsv is not None else "--roi" if params.roi is not None \
            else "--color"
        raise InputError(f"{option}: {error}") from None


def sponge_box(params: TrackParams, metadata: dict, toml_name: str) -> SpongeBox | None:
    size = params.sponge_size or metadata.get("sponge_size")
    if size is None:
        return None
    option = "--sponge-size" if params.sponge_size else f"{toml_name}: sponge_size"
    try:
        values = [float(v) for v in size]
        return SpongeBox(*values)
    except (TypeError, ValueError):
        raise InputError(f"{option}: expected three positive lengths in metres, got {size!r}") \
            from None


def track(demo_dir: str | os.PathLike, out_dir: str | os.PathLike,
          params: TrackParams = TrackParams(), quiet: bool = False) -> TrackResult:
    """Track the sponge of a demo directory and write track.csv, track.mcap, track.rrd and
    manifest.json into ``out_dir`` (all or nothing).

    Raises
    ------
    InputError
        Bad demo directory (see :func:`open_demo`), a bad colour option, a truncated video,
        or a sponge colour that never shows in the videos.
    """
    demo = open_demo(demo_dir)
    toml_name = str(Path(demo_dir) / "demo.toml")
    colour = colour_source(params, demo.metadata, toml_name)
    if colour.roi is not None:
        x, y, w, h = colour.roi
        width, height = demo.calibration.image_size
        if x + w > width or y + h > height:
            raise InputError(f"--roi: region {x},{y},{w},{h} does not fit in the "
                             f"{width}x{height} frames")
    tracker_params = TrackerParams(particles=params.particles, seed=params.seed,
                                   sponge=sponge_box(params, demo.metadata, toml_name),
                                   fps=demo.reader.fps)
    with long_lived_objects():  # the libraries and the tracker: kept to the end
        tracker = SpongeTracker(demo.calibration, colour, tracker_params)
    failures: list[str] = []   # why the tracking pass's frames were not valid

    def remember_failure(_: int, estimate: FrameEstimate) -> None:
        if not estimate.valid:
            failures.append(estimate.reason)

    with tempfile.TemporaryDirectory(prefix="wipelab-track-") as workdir, opencv_on_one_thread():
        videos = LogVideos(demo, Path(workdir))
        try:
            result = run_tracker(tracker, demo.reader, params, quiet, on_frame=remember_failure,
                                 frame_sink=videos.write)
        finally:
            videos.close()
        if result is None and not tracker.region.frames_with_candidates:
            raise InputError(f"{colour.option}: this colour never shows in both {demo.left} "
                             f"and {demo.right}; give the sponge's colour with --color, --hsv "
                             "or --roi")
        if result is None and not tracker.identified:
            raise InputError(f"{demo.left}, {demo.right}: nothing of this colour "
                             f"({colour.option}) moves like a wiping sponge in both cameras; "
                             "give the sponge's colour with --color, --hsv or --roi")
        if result is None:
            kind, share = commonest_failure(failures)
            raise InputError(f"{demo.left}, {demo.right}: a sponge of this colour "
                             f"({colour.option}) was found but could be followed in fewer than "
                             f"two frames: in {share:.0%} of the frames, {kind}. Things of the "
                             "sponge's colour where it wipes (a cloth, a plate) do this; if "
                             "their shade differs from the sponge's, give the sponge's colour "
                             "more closely with --hsv or --roi")
        _write_outputs(demo, out_dir, params, colour, tracker, tracker_params, result, videos,
                       quiet)
    return result


@contextmanager
def opencv_on_one_thread() -> Iterator[None]:
    """OpenCV's thread pool off (each call on its caller's thread) until the block ends:
    the decoders, the previews' encoder and the tracker keep the cores busy already, and the
    pool's workers spin while they wait for work (CPU time for nothing)."""
    before = cv2.getNumThreads()
    cv2.setNumThreads(1)
    try:
        yield
    finally:
        cv2.setNumThreads(before)


def _write_outputs(demo: Demo, out_dir, params: TrackParams, colour: ColourSource,
                   tracker: SpongeTracker, tracker_params: TrackerParams, result: TrackResult,
                   videos: LogVideos, quiet: bool) -> None:
    """track.csv, track.mcap, track.rrd and manifest.json of a run (all or nothing)."""
    sponge = tracker_params.sponge
    parameters = asdict(params) | {"colour_source": colour.option,
                                   "sponge": None if sponge is None else asdict(sponge)}
    inputs = {"left_video": demo.left, "right_video": demo.right,
              "calibration": demo.calibration_path}
    scene = TrackScene(videos.calibration(demo.calibration),
                       "world" if result.frame == "world" else LEFT_FRAME,
                       tracker.table_axes_in_track(), result.sponge_size, result.region_size)
    blueprint = track_blueprint(scene, result.area,
                                float(np.nanmean(result.poses[result.valid, 2])))
    with staged_output(out_dir) as tmp:
        write_trajectory(tmp / "track.csv", result.t,
                         tracked_csv_columns(result.poses, result.valid, result.quality,
                                             result.normalised))
        with StageRecorder(tmp, "track", parameters, inputs, blueprint,
                           attachments={"calibration.yaml": demo.calibration_path}) as rec:
            log_track(rec, videos.paths, result, scene, quiet)
        write_json(tmp / "manifest.json", build_manifest("track", inputs, parameters,
                                                         params.seed, rec.input_hashes))


def run_tracker(tracker: SpongeTracker, reader: StereoVideoReader, params: TrackParams,
                quiet: bool = False,
                on_frame: Callable[[int, FrameEstimate], None] | None = None,
                frame_sink: Callable[[np.ndarray, np.ndarray], None] | None = None
                ) -> TrackResult | None:
    """Run ``tracker`` over every frame pair of ``reader``; None if fewer than two
    frames were valid.

    Two passes: a warm-up over the first ``params.warmup`` seconds (longer until the sponge
    is found and the plane it moves in is known; when a whole warm-up pass finds nothing of
    the named colour, it is searched for again a little above that colour, then a little
    below it, then with any motion accepted), then, with what it learnt, the tracking
    pass from the first frame (so that the first seconds are tracked too); the frames before
    that pass's first valid one are then followed backwards from it
    (:func:`track_backwards`). Runs of valid frames too short to be the sponge are then
    dropped (:func:`~wipelab.vision.tracker.fleeting_runs`), and so are those that kept
    still once the sponge had moved (:func:`~wipelab.vision.tracker.still_runs`). The
    tracking pass replays the frames the warm-up decoded from memory (up to
    :data:`WARMUP_BYTES`) rather than decoding them again. ``on_frame`` is called with each frame's index and estimate of the tracking
    pass, ``frame_sink`` with each of its frame pairs.
    """
    replayed = ReplayedStart(reader, WARMUP_BYTES)
    try:
        return _run_tracker(tracker, replayed, params, quiet, on_frame, frame_sink)
    finally:
        replayed.close()


def _run_tracker(tracker: SpongeTracker, reader: ReplayedStart, params: TrackParams,
                 quiet: bool, on_frame, frame_sink) -> TrackResult | None:
    """:func:`run_tracker`'s passes over ``reader``."""
    n = reader.frame_count
    poses = np.full((n, 4), np.nan)
    valid = np.zeros(n, bool)
    quality = np.full(n, QUALITY_NONE, dtype="<U8")
    areas = np.zeros((n, 2))
    m = params.logged_particles
    particles = np.full((n, m, 4), np.nan)
    least = int(round(params.warmup * reader.fps))
    # what a pass that finds nothing leaves for the next: a sponge whose colour lies between
    # two names (a lemon yellow named yellow, a golden orange), one side of the named colour
    # at a time; then, for a video too short for the wiping to show as periodic motion, any
    # motion of the named colour
    for attempt, (side, any_motion) in enumerate(((0, False), (+1, False), (-1, False),
                                                  (0, True))):
        if attempt:
            tracker.widen_colour(side)
            if any_motion:
                tracker.accept_any_motion()
            tracker.restart()
        with tqdm(total=n, desc="track: finding the sponge", unit="frame", disable=quiet,
                  file=sys.stderr, leave=False) as bar:
            for k, (left, right) in enumerate(reader):
                tracker.step(left, right)
                bar.update()
                if k + 1 >= least and tracker.ready:
                    break
        if tracker.identified:
            break
    if not tracker.identified:
        return None
    tracker.restart()
    pair_bytes = 6 * reader.reader.left.width * reader.reader.left.height
    before_first: deque = deque(maxlen=max(1, BACKWARD_BYTES // pair_bytes))
    first, seed = None, []

    def keep(k: int, estimate: FrameEstimate) -> None:
        poses[k], valid[k], quality[k] = estimate.pose, estimate.valid, estimate.quality
        areas[k] = estimate.areas
        if len(estimate.particles):
            pick = np.linspace(0, len(estimate.particles) - 1, m).astype(int)
            particles[k] = estimate.particles[pick]

    with tqdm(total=n, desc="track", unit="frame", disable=quiet, file=sys.stderr,
              leave=False) as bar:
        for k, (left, right) in enumerate(reader.frames(keep=False)):
            if frame_sink is not None:
                frame_sink(left, right)
            estimate = tracker.step(left, right)
            keep(k, estimate)
            if on_frame is not None:
                on_frame(k, estimate)
            if first is None and estimate.valid:
                first = k
            if first is None:
                before_first.append((k, left, right))
            elif k < first + SEED_FRAMES:  # the region's points of the first valid frames
                seed = [p for f, p in tracker.region.history if f >= first] or seed
            bar.update()
    still_tracks = list(tracker.region.still_tracks)  # the backward pass restarts the tracker
    if before_first and seed and not any(start <= first < end for start, end in still_tracks):
        # (a first track that followed a still thing leads back to nothing but it)
        track_backwards(tracker, seed, reversed(before_first), keep)
    dropped = np.zeros(n, bool)
    for start, end in still_tracks:
        # what was followed there stood still: a cloth or a plate, not the sponge
        dropped[start:end] = True
    dropped |= fleeting_runs(valid & ~dropped, reader.fps)
    dropped |= still_runs(valid & ~dropped, poses[:, :3], tracker.region.size or 0.0,
                          tracker.params.region)
    valid[dropped], poses[dropped], quality[dropped] = False, np.nan, QUALITY_NONE
    if valid.sum() < 2:  # no movement to measure the demonstration area from
        return None
    t = np.arange(n) / reader.fps
    area = measure_demonstration_area(t, poses[:, :2], valid, params.area_window)
    normalised = np.where(valid[:, None], area.normalise(poses[:, :2]), np.nan)
    sponge = tracker.params.sponge
    return TrackResult(t, poses, valid, quality, area, normalised,
                       tracker.calibration.track_frame, areas, particles,
                       None if sponge is None else (sponge.length, sponge.width, sponge.height),
                       float(tracker.region.size))


def track_backwards(tracker: SpongeTracker, seed: list[np.ndarray], pairs,
                    keep: Callable[[int, FrameEstimate], None]) -> None:
    """Follow the sponge back in time from the tracking pass's first valid frame over the
    frames before it (``pairs``: (index, left, right), latest first), handing each valid
    estimate to ``keep`` (valid by the rules of the forward pass; a miss leaves its
    verdict). The sponge often rests where the demonstration starts, as still as a thing of
    its colour: the search cannot tell it, but the track that leaves that place, followed
    backwards, leads to it. ``seed``: the region's points (left optical frame) of the first
    valid frames, earliest first."""
    tracker.restart()
    for point in reversed(seed):
        tracker.region.observe(point)
    for k, left, right in pairs:
        estimate = tracker.step(left, right)
        if estimate.valid:
            keep(k, estimate)


def tracked_csv_columns(poses: np.ndarray, valid: np.ndarray, quality: np.ndarray,
                        normalised: np.ndarray) -> dict[str, np.ndarray]:
    """track.csv's columns after t (see the module docstring) from poses (n, 4), valid (n,),
    quality (n,) and normalised offsets (n, 2)."""
    return {"x": poses[:, 0], "y": poses[:, 1], "z": poses[:, 2], "valid": valid.astype(int),
            "quality": quality, "yaw": poses[:, 3], "x_norm": normalised[:, 0],
            "y_norm": normalised[:, 1]}


#: Colours of the logs: sponge box, particles, trajectory, demonstration area.
SPONGE_COLOUR, PARTICLE_COLOUR = (255, 70, 50), (80, 220, 80)
TRAJECTORY_COLOUR, AREA_COLOUR = (255, 200, 0), (90, 160, 255)
#: Length (m) of the camera frustums drawn in the 3D view.
FRUSTUM_LENGTH = 0.1
#: How each frame was tracked (``/track/quality``: the quality column, "lost" for empty)
#: and its colour in the logs.
LOST = "lost"
QUALITY_COLOURS = {QUALITY_BOX: (40, 175, 120), QUALITY_CENTROID: (240, 150, 40),
                   QUALITY_MONO: (190, 120, 220), LOST: (200, 60, 60)}
#: Frames whose drawings are logged at once (a chunk per entity in the .rrd; what the MCAP
#: writer holds to write them in time order).
LOGGED_FRAMES_AT_ONCE = 1000
#: Thickness of the flat box drawn where only the colour region was measured, as a fraction
#: of the region's size.
REGION_THICKNESS = 0.15


@dataclass(frozen=True)
class TrackScene:
    """What logging a frame needs: the cameras, the frame tracks are reported in, how the
    table lies in it, and the size of what is drawn at the sponge.

    Attributes
    ----------
    calibration : StereoCalibration
    frame : str
        Frame id of the track frame in the logs: ``world`` or the left camera's optical frame.
    R_track_table : ndarray, shape (3, 3)
        Table axes in the track frame (the sponge's yaw turns about the table normal).
    sponge_size : tuple of float or None
        (length, width, height) of the sponge box, m, when known: drawn on ``box`` frames.
    region_size : float
        Size of the sponge's visible colour region, m: a flat square of this size is drawn on
        ``centroid`` frames (and on box frames when the box size is unknown).
    """

    calibration: StereoCalibration
    frame: str
    R_track_table: np.ndarray
    sponge_size: tuple[float, float, float] | None
    region_size: float

    @property
    def T_left_track(self) -> np.ndarray:
        return invert_transform(self.calibration.T_track_left)

    def camera_centres(self) -> np.ndarray:
        """Left and right camera centres (2, 3) in the track frame."""
        T_track_right = self.calibration.T_track_left @ invert_transform(
            self.calibration.right.T_cam_ref)
        return np.stack([self.calibration.T_track_left[:3, 3], T_track_right[:3, 3]])

    def box_sizes(self, quality: np.ndarray) -> np.ndarray:
        """Sizes (n, 3) m of what is drawn at the sponge on frames of ``quality`` (n,): the
        sponge box, or a flat square the size of the colour region."""
        side = self.region_size if np.isfinite(self.region_size) else 0.1
        square = np.array([side, side, REGION_THICKNESS * side])
        if self.sponge_size is None:
            return np.tile(square, (len(quality), 1))
        return np.where((np.asarray(quality) == QUALITY_BOX)[:, None],
                        np.asarray(self.sponge_size, dtype=float), square)

    def sponge_rotations(self, yaw: np.ndarray) -> np.ndarray:
        """Sponge axes (n, 3, 3) in the track frame at ``yaw`` (n,) (rad; 0 where unknown)."""
        return self.R_track_table @ yaw_rotation(np.where(np.isfinite(yaw), yaw, 0.0))

    def box_edges_px(self, poses: np.ndarray, sizes: np.ndarray) -> list[np.ndarray]:
        """The 12 edges of boxes of ``sizes`` (n, 3) at ``poses`` (n, 4) (x, y, z, yaw)
        projected into the left and right images: two arrays (n, 12, 2, 2) of pixels
        (top-left pixel corner = 0)."""
        corners = CORNER_SIGNS * (0.5 * sizes[:, None, :])
        corners = poses[:, None, :3] + corners @ np.swapaxes(self.sponge_rotations(poses[:, 3]),
                                                             1, 2)
        return [self._pixels(camera, corners)[:, EDGES] for camera in self.cameras()]

    def particles_px(self, particles: np.ndarray) -> list[np.ndarray]:
        """Particle centres (..., 3) in the track frame -> pixels (..., 2) in each image."""
        return [self._pixels(camera, particles) for camera in self.cameras()]

    def cameras(self):
        return self.calibration.left, self.calibration.right

    def _pixels(self, camera, points_track: np.ndarray) -> np.ndarray:
        T = self.T_left_track
        return camera.project(points_track @ T[:3, :3].T + T[:3, 3]) + 0.5


def track_blueprint(scene: TrackScene, area: DemonstrationArea, height: float) -> rrb.Blueprint:
    """Both images with the projected sponge box and particles; the 3D view framed on the
    demonstration area, with both camera frustums and the trajectory growing over time;
    x, y, z each on its own axes; whether the sponge was tracked."""
    centre = np.array([*area.centre, height])
    cameras = scene.camera_centres().mean(axis=0)
    up = scene.R_track_table[:, 2]
    # from the cameras' side, turned 40 degrees about the table normal: the cameras at the
    # edge of the view, the demonstration in the middle
    side = rotation_about_axis(up, np.radians(40.0)) @ (cameras - centre)
    eye = rrb.EyeControls3D(position=centre + 1.5 * side, look_target=centre + 0.3 * (cameras - centre),
                            eye_up=up)
    growing = rrb.VisibleTimeRanges(timeline="time", start=rrb.TimeRangeBoundary.infinite(),
                                    end=rrb.TimeRangeBoundary.cursor_relative())
    axes = [rrb.TimeSeriesView(
        origin="/track/position", name=f"sponge {axis} (m)", axis_x=whole_run(),
        plot_legend=rrb.PlotLegend(visible=False),
        overrides={"/track/position": rr.SeriesLines.from_fields(
            visible_series=[a == axis for a in "xyz"])}) for axis in "xyz"]
    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Vertical(rrb.Spatial2DView(origin="/stereo/left", name="left camera"),
                         rrb.Spatial2DView(origin="/stereo/right", name="right camera")),
            rrb.Vertical(rrb.Spatial3DView(origin="/", name="sponge, cameras and demonstration area",
                                           contents=["+ /**", "- /tf/**",
                                                     *(f"- /stereo/{side}/{what}"
                                                       for side in ("left", "right")
                                                       for what in ("video", "overlay"))],
                                           eye_controls=eye,
                                           overrides={"/track/trajectory": growing}),
                         *axes,
                         rrb.StateTimelineView(origin="/track/quality", name="sponge tracked?",
                                               time_view=whole_run()),
                         row_shares=[4, 1, 1, 1, 0.8]),
            column_shares=[1, 1]),
        *stage_panels())


#: Widest video written for the logs when the demo's own videos cannot be logged as they are
#: (1280x720 -> 426x240, 960x540 -> 480x270: about half the pixels, and of the scaling and
#: encoding time, of 640 wide, whose previews took a quarter of the CPU time of tracking a
#: 1280x720 H.264 demo with B-frames).
PREVIEW_WIDTH = 480
#: Heaviest demo video (bits per second) the logs hold as it is: each log (MCAP and RRD)
#: would otherwise be about as large as the demo's videos, and take seconds to write (dev
#: scene 31, 2 x 9 Mbit/s: 140 MB of logs, written in 2 of the command's 8 s; with
#: previews, a few MB made beside the tracker, the command ran about 7 % faster).
LOGGED_AS_IT_IS_MAX_BITRATE = 4e6
#: Frame pairs waiting for the previews' encoder at most.
PREVIEW_QUEUE = 8


def playable(path: Path) -> bool:
    """Whether the Rerun viewer (and Foxglove) can play a video file as it is: H.264, H.265
    or AV1 without B-frames."""
    import av

    with av.open(str(path)) as container:
        context = container.streams.video[0].codec_context
        return context.name in ("h264", "hevc", "av1") and not context.has_b_frames


def loggable_as_it_is(path: Path, frames: int, fps: float) -> bool:
    """Whether the logs hold a demo video as it is: :func:`playable`, and no heavier than
    :data:`LOGGED_AS_IT_IS_MAX_BITRATE`."""
    bitrate = 8.0 * Path(path).stat().st_size * fps / max(frames, 1)
    return bitrate <= LOGGED_AS_IT_IS_MAX_BITRATE and playable(path)


class LogVideos:
    """The two videos the logs show: the demo's own when they can be logged as they are
    (:func:`loggable_as_it_is`), else H.264 previews (at most :data:`PREVIEW_WIDTH` wide,
    fast x264 settings) written from the frames of the tracking pass, so that nothing is
    decoded twice. The previews are scaled and encoded on a thread of their own, beside the
    tracker.

    Parameters
    ----------
    demo : Demo
    workdir : Path
        Where previews are written.
    """

    def __init__(self, demo: Demo, workdir: Path):
        width, height = demo.calibration.image_size
        self.paths = [demo.left, demo.right]
        self.scale = 1.0
        self._writers = []
        frames, fps = demo.reader.frame_count, demo.reader.fps
        if all(loggable_as_it_is(path, frames, fps) for path in self.paths):
            return
        factor = max(1, int(np.ceil(width / PREVIEW_WIDTH)))
        self.scale = 1.0 / factor
        self.size = (width // factor // 2 * 2, height // factor // 2 * 2)  # x264: even sides
        self.paths = [workdir / "left.mp4", workdir / "right.mp4"]
        self._writers = [H264Writer(path, int(round(demo.reader.fps)), self.size, crf=28,
                                    preset="ultrafast") for path in self.paths]
        self._pending: queue.Queue = queue.Queue(PREVIEW_QUEUE)
        self._failure: BaseException | None = None
        self._encoder = threading.Thread(target=self._encode, name="preview", daemon=True)
        with interrupts_deferred():   # started, or not at all
            self._encoder.start()

    def write(self, left: np.ndarray, right: np.ndarray) -> None:
        """One frame pair of the tracking pass (BGR uint8, full resolution; not to be changed
        afterwards: they are encoded on the previews' thread)."""
        if not self._writers:
            return
        if self._failure is not None:
            raise self._failure
        self._pending.put((left, right))

    def _encode(self) -> None:
        run_as_helper()  # the tracker comes first
        try:
            while (pair := self._pending.get()) is not None:
                for writer, frame in zip(self._writers, pair):
                    if self.scale < 1.0:  # a preview: linear is enough, and a few times faster
                        frame = cv2.resize(frame, self.size, interpolation=cv2.INTER_LINEAR)
                    writer.write(frame)
        except BaseException as error:  # raised in the tracking pass's thread
            self._failure = error
            while self._pending.get() is not None:  # nobody waits on a full queue
                pass

    def close(self) -> None:
        """Finish the previews (all frames written so far)."""
        if not self._writers:
            return
        with interrupts_deferred():   # no thread left inside FFmpeg
            self._pending.put(None)
            self._encoder.join()
            for writer in self._writers:
                writer.close()
        if self._failure is not None:
            raise self._failure

    def calibration(self, calibration: StereoCalibration) -> StereoCalibration:
        """The calibration of the logged videos (the cameras' matrices and the image size
        scaled with them; the lens distortion is in normalised coordinates and stays)."""
        if self.scale == 1.0:
            return calibration
        S = np.diag([self.scale, self.scale, 1.0])
        return replace(calibration, image_size=self.size, K1=S @ calibration.K1,
                       K2=S @ calibration.K2)


def log_track_setup(rec: StageRecorder, scene: TrackScene) -> None:
    """What does not change from frame to frame: /tf of the cameras and their calibrations
    (the 3D view draws their frustums)."""
    calibration = scene.calibration
    width, height = calibration.image_size
    T_track_left = calibration.T_track_left
    T_track_right = T_track_left @ invert_transform(calibration.right.T_cam_ref)
    tf = [(scene.frame, RIGHT_FRAME, T_track_right[:3, 3],
           quaternion_xyzw_from_rotation(T_track_right[:3, :3]))]
    if scene.frame != LEFT_FRAME:   # the world (of the demo) with the cameras in it
        tf.insert(0, (scene.frame, LEFT_FRAME, T_track_left[:3, 3],
                      quaternion_xyzw_from_rotation(T_track_left[:3, :3])))
    rec.transforms(0.0, tf)
    for side, K, D, frame_id in (("left", calibration.K1, calibration.D1, LEFT_FRAME),
                                 ("right", calibration.K2, calibration.D2, RIGHT_FRAME)):
        rec.camera_calibration(f"/stereo/{side}/calibration", 0.0, K, _five(D), width, height,
                               frame_id, image_plane_distance=FRUSTUM_LENGTH)


def log_track_frames(rec: StageRecorder, scene: TrackScene, index: np.ndarray, t: np.ndarray,
                     poses: np.ndarray, quality: np.ndarray, particles: np.ndarray,
                     previous: np.ndarray | None = None) -> np.ndarray | None:
    """Frames ``index`` (n,) at times ``t`` (n,) s, all at once: per frame the sponge box (a
    flat square the size of the colour region where only that was measured; removed while
    lost), the particles, the new piece of the trajectory (from the frame before, if it was
    tracked) and the same drawn over both images.

    ``poses`` (n, 4) x, y, z (m) and yaw (rad) in the track frame; ``quality`` (n,) ``box``,
    ``centroid``, ``mono`` or ``""`` (lost); ``particles`` (n, m, >= 3) their positions first
    (NaN rows are skipped); ``previous`` (3,) the position of the frame before the first if
    it was tracked, else None. Returns the same for the frame after the last.
    """
    if not len(t):
        return previous
    valid = quality != QUALITY_NONE
    positions = np.where(valid[:, None], poses[:, :3], np.nan)
    particles = particles[:, :, :3]
    finite = np.isfinite(particles[:, :, 0])
    counts = finite.sum(axis=1)
    drawn = counts > 0
    colours = np.where((quality == QUALITY_BOX)[:, None], SPONGE_COLOUR,
                       QUALITY_COLOURS[QUALITY_CENTROID])
    sizes = scene.box_sizes(quality)
    before = np.vstack([np.full((1, 3), np.nan) if previous is None else previous,
                        positions[:-1]])
    piece = valid & np.isfinite(before).all(axis=1)
    edges = scene.box_edges_px(poses, sizes)
    dots = scene.particles_px(particles)
    with rec.in_time_order():   # in the MCAP frame by frame, as they are shown
        rec.points3d_series("/track/particles", t[drawn], particles[finite], counts[drawn],
                            colors=PARTICLE_COLOUR, radii=0.0015, frame_id=scene.frame)
        rotations = scene.sponge_rotations(poses[:, 3])
        rec.box3d_series("/track/sponge", t, sizes, positions,
                         quaternions_xyzw_from_rotations(rotations), colours,
                         frame_id=scene.frame)
        rec.line_strip3d_series("/track/trajectory", t[piece],
                                np.stack([before[piece], positions[piece]], axis=1),
                                color=TRAJECTORY_COLOUR, frame_id=scene.frame,
                                entity_ids=[f"/track/trajectory/{k}" for k in index[piece]])
        for side, frame_id, lines, points in zip(("left", "right"), (LEFT_FRAME, RIGHT_FRAME),
                                                 edges, dots):
            rec.image_overlay_series(
                f"/stereo/{side}/overlay", t, frame_id,
                [frame_lines if shown else frame_lines[:0]
                 for frame_lines, shown in zip(lines, valid)],
                [frame_points[np.isfinite(frame_points).all(axis=1)] for frame_points in points],
                colours, PARTICLE_COLOUR)
    return positions[-1] if valid[-1] else None


def log_track(rec: StageRecorder, videos: list[Path], result: TrackResult, scene: TrackScene,
              quiet: bool = True) -> None:
    """Write the run into the MCAP and Rerun recordings of ``rec``; ``videos`` the left and
    right video files to log (``scene.calibration`` is theirs)."""
    log_track_setup(rec, scene)
    for side, video, frame_id in (("left", videos[0], LEFT_FRAME),
                                  ("right", videos[1], RIGHT_FRAME)):
        rec.video(f"/stereo/{side}/video", video, result.t, frame_id=frame_id)

    t, valid = result.t, result.valid
    rec.scalars("/track/position", t[valid], result.poses[valid, :3], names=["x", "y", "z"],
                colors=np.array([XYZ_COLOURS[a] for a in "xyz"]))
    # Rerun only (the MCAP keeps the tracked frames, what learn reads): a NaN row where the
    # sponge is lost, so that the plots break there instead of bridging the gap
    lost = np.flatnonzero(~valid & np.concatenate([[True], valid[:-1]]))
    if lost.size:
        rec.rerun.send_columns("/track/position", indexes=[rr.TimeColumn(
            TIMELINE, duration=seconds_array_to_ns(t[lost]).astype("timedelta64[ns]"))],
            columns=rr.Scalars.columns(scalars=np.full((lost.size, 3), np.nan)))
    rec.scalars("/track/valid", t, valid.astype(float))
    quality = np.where(result.quality == QUALITY_NONE, LOST, result.quality)
    changes = np.flatnonzero(np.concatenate([[True], quality[1:] != quality[:-1]]))
    rec.states("/track/quality", t[changes], quality[changes].tolist(),
               {q: QUALITY_COLOURS[q] for q in dict.fromkeys(quality.tolist())})
    rec.scalars("/track/normalised", t[valid], result.normalised[valid], names=["x_norm", "y_norm"])
    rec.scalars("/track/region_area_px", t, result.areas, names=["left", "right"])
    rec.scalars("/track/box_fit", t, (result.quality == QUALITY_BOX).astype(float))
    area = result.area
    rec.json("/track/demonstration_area", 0.0,
             {"lower_left": area.lower_left, "upper_right": area.upper_right,
              "centre": area.centre, "window_s": list(area.window), "frame": scene.frame},
             "wipelab.DemonstrationArea")
    height_mean = float(np.nanmean(result.poses[valid, 2]))
    (x0, y0), (x1, y1) = area.lower_left, area.upper_right
    rectangle = np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1], [x0, y0]])
    rec.line_strip3d("/track/demonstration_area/outline", 0.0,
                     np.column_stack([rectangle, np.full(5, height_mean)]), color=AREA_COLOUR,
                     frame_id=scene.frame)
    previous = None
    with tqdm(total=len(t), desc="logs", unit="frame", disable=quiet, file=sys.stderr,
              leave=False) as bar:
        for start in range(0, len(t), LOGGED_FRAMES_AT_ONCE):
            block = slice(start, start + LOGGED_FRAMES_AT_ONCE)
            previous = log_track_frames(rec, scene, np.arange(len(t))[block], t[block],
                                        result.poses[block], result.quality[block],
                                        result.particles[block], previous)
            bar.update(len(t[block]))


def _five(D: np.ndarray) -> np.ndarray:
    """The plumb-bob part (k1, k2, p1, p2, k3) of an OpenCV distortion vector."""
    return np.concatenate([D, np.zeros(5)])[:5]
