"""What a live session writes to ``live.mcap`` and ``live.rrd`` (and streams to a viewer),
frame by frame.

Topics (MCAP topic = Rerun entity; time = the session's, seconds from the first frame):

* the cameras: ``/stereo/left|right/video`` (H.264 encoded as the frames arrive, Rerun
  ``VideoStream``, ``foxglove.CompressedVideo``), ``/stereo/*/calibration``, ``/stereo/*/overlay``
  (the sponge box and particles drawn over the images), ``/tf`` of the cameras;
* the track as the track stage logs it (:func:`~wipelab.stages.track.log_track_frames`), in
  the frame ``demonstration`` (the demo's world, or its left camera's frame), which ``/tf``
  places in the robot's world once the demonstration area is known: the area's centre on
  the robot's wiping centre, the tracked sponge's median height on the surface. So the
  3D view shows the person's sponge under the robot's hand. Before, from the session's
  start, the first tracked point stands for the area's centre (a frame without a place
  made the viewer mark the 3D view with an error until the area was known).
  ``/track/position`` (m), ``/track/quality`` (a state), ``/track/demonstration_area``
  (JSON and outline);
* imitation learning, from the lock on: ``/oscillators/frequency_hz``,
  ``/oscillators/fundamental_hz``, ``/oscillators/model_frequency_hz`` (the frequency
  converging), ``/live/imitation/<dof>``: the demonstrated movement, the learned one (the
  online DMP's output) and the robot's hand, normalised to the demonstration area (the
  paper's Fig. 5, with the robot); ``/live/hand_path``: the hand's path (the last 2 s are
  drawn behind it, as the person's track);
* the robot as adapt and replay log it (:mod:`wipelab.sim.recording`, stage name ``live``):
  joints and ``/tf``, TCP and contact heights, |F|, the segment (``/live/segment``: waiting,
  imitating, slowing down, learning, ..., wiping);
* at ``--speed 1`` only, ``/live/latency_ms`` per frame (wall clock: a rerun differs).

Series and the track's drawings are buffered and written every :data:`STREAM_FRAMES` frames
while a viewer watches (and the Rerun stream is flushed then: what it shows is at most that
old), every :data:`FILE_FRAMES` otherwise. Both depend on the frame count only, so a rerun
at ``--speed max`` writes the same bytes.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import rerun.blueprint as rrb

from wipelab.logs import StageRecorder, stage_panels, whole_run
from wipelab.logs.palette import INPUT_COLOUR, LEARNED_COLOUR, REFERENCE_COLOUR, segment_colour
from wipelab.live.log_worker import LogWorker
from wipelab.logs.video_encoder import LiveVideoEncoder
from wipelab.rotations import quaternion_xyzw_from_rotation
from wipelab.sim.recording import log_scene, log_trace
from wipelab.stages.track import (AREA_COLOUR, LEFT_FRAME, LOST, QUALITY_COLOURS, RIGHT_FRAME,
                                  TrackScene, log_track_frames, log_track_setup)
from wipelab.vision.demonstration_area import DemonstrationArea
from wipelab.vision.tracker import QUALITY_NONE

#: The frame of the tracked positions in a live recording (see the module docstring).
DEMONSTRATION_FRAME = "demonstration"
#: Series are written (and the stream flushed) every this many frames while a viewer
#: watches, every FILE_FRAMES otherwise.
STREAM_FRAMES, FILE_FRAMES = 3, 30
#: The robot's trace is logged in slices of this many control periods while a viewer
#: watches, of the other many otherwise (multiples of the pose logging stride, so that the
#: slices sample it evenly; each slice is a chunk per series in the .rrd).
STREAM_SLICE_PERIODS, FILE_SLICE_PERIODS = 16, 120
#: Seconds of the person's and the hand's paths shown behind them in the 3D view.
TRAIL_SECONDS = 2.0
#: Colour of the robot's hand in the imitation plots.
ROBOT_COLOUR = (40, 175, 120)


def live_blueprint(dofs, target) -> rrb.Blueprint:
    """Both cameras with the track drawn; the robot imitating in 3D (seen from the front
    left of ``target`` (3,), m, world: the wiping centre) and what it does; the frequency
    converging, input vs learned (and the robot's hand) per DOF, height and |F|."""
    trail = rrb.VisibleTimeRanges(timeline="time",
                                  start=rrb.TimeRangeBoundary.cursor_relative(-TRAIL_SECONDS),
                                  end=rrb.TimeRangeBoundary.cursor_relative())
    target = np.asarray(target, dtype=float)
    scene = rrb.Spatial3DView(
        origin="/", name="the robot imitating; the person's sponge under its hand",
        contents=["+ /**", "- /stereo/**", "- /track/particles/**"],
        eye_controls=rrb.EyeControls3D(position=target + [0.8, -1.2, 0.7],
                                       look_target=target - [0.15, 0.0, 0.1],
                                       eye_up=[0.0, 0.0, 1.0]),
        overrides={"/track/trajectory": trail, "/live/hand_path": trail})
    series = [rrb.TimeSeriesView(origin="/oscillators", name="frequency (Hz)",
                                 axis_x=whole_run(), plot_legend=rrb.PlotLegend("RightTop"))]
    series += [rrb.TimeSeriesView(origin=f"/live/imitation/{dof}",
                                  name=f"{dof}: demonstrated, learned, robot (normalised)",
                                  axis_x=whole_run(), plot_legend=rrb.PlotLegend("RightTop"))
               for dof in dofs]
    series += [rrb.TimeSeriesView(origin="/live/tcp_height", name="hand (TCP) z (m)",
                                  axis_x=whole_run(), plot_legend=rrb.PlotLegend("RightTop")),
               rrb.TimeSeriesView(origin="/live/force_norm", name="|F| and F0 (N)",
                                  axis_x=whole_run(), plot_legend=rrb.PlotLegend("RightTop"))]
    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Vertical(rrb.Spatial2DView(origin="/stereo/left", name="left camera"),
                         rrb.Spatial2DView(origin="/stereo/right", name="right camera")),
            rrb.Vertical(scene, rrb.StateTimelineView(origin="/live/segment",
                                                      name="what the robot does",
                                                      time_view=whole_run()),
                         row_shares=[6, 1]),
            rrb.Vertical(*series),
            column_shares=[1, 1.4, 1]),
        *stage_panels())


class _Series:
    """Rows of one scalar topic waiting to be written."""

    def __init__(self, names, colors=None):
        self.names, self.colors = list(names), colors
        self.t: list[float] = []
        self.rows: list[np.ndarray] = []

    def add(self, t: float, values) -> None:
        self.t.append(t)
        self.rows.append(np.asarray(values, dtype=float))

    def write(self, rec: StageRecorder, topic: str) -> None:
        if self.t:
            rec.scalars(topic, np.array(self.t), np.array(self.rows), names=self.names,
                        colors=self.colors)
            self.t, self.rows = [], []


class _TrackFrames:
    """Frames of the track waiting to be drawn (:func:`~wipelab.stages.track.log_track_frames`)."""

    def __init__(self):
        self.previous: np.ndarray | None = None  # the last drawn position, if it was tracked
        self.rows: list[tuple] = []

    def add(self, index: int, t: float, pose: np.ndarray, quality: str,
            particles: np.ndarray) -> None:
        """One frame: ``pose`` (4,), ``particles`` (m, >= 3) (copied)."""
        self.rows.append((index, t, np.array(pose, dtype=float), quality,
                          np.array(particles[:, :3], dtype=float)))

    def write(self, rec: StageRecorder, scene: TrackScene) -> None:
        if not self.rows:
            return
        index, t, poses, quality, particles = zip(*self.rows)
        padded = np.full((len(particles), max(len(p) for p in particles), 3), np.nan)
        for row, frame_particles in zip(padded, particles):
            row[:len(frame_particles)] = frame_particles
        self.previous = log_track_frames(rec, scene, np.array(index), np.array(t),
                                         np.array(poses), np.array(quality), padded,
                                         self.previous)
        self.rows = []


@dataclass(frozen=True)
class LearnerView:
    """What the logs show of the learner after a frame (copied: the learner goes on).

    Attributes
    ----------
    omega_hz, fundamental_hz, frequency_hz : float
        The oscillator's frequency, the fundamental and the model's frequency (Hz).
    output : ndarray, shape (d,)
        The learned movement now (m, track frame).
    area : DemonstrationArea or None
        The demonstration area once the learner has locked (None before).
    """

    omega_hz: float
    fundamental_hz: float
    frequency_hz: float
    output: np.ndarray
    area: DemonstrationArea | None

    @classmethod
    def of(cls, imitation) -> "LearnerView | None":
        learner = imitation.learner
        if learner is None:
            return None
        return cls(float(learner.oscillators_hz[0]), learner.fundamental_hz,
                   learner.frequency_hz, learner.output.copy(),
                   imitation.area if imitation.locked else None)


class LiveLog:
    """Writes a live session into ``rec`` frame by frame (see the module docstring); the
    work runs on a :class:`~wipelab.live.log_worker.LogWorker` (the methods only hand it
    over).

    Parameters
    ----------
    rec : StageRecorder
    worker : LogWorker
    scene : TrackScene
        Its frame is :data:`DEMONSTRATION_FRAME`.
    robot : LiveRobot
    dofs : tuple of str
    fps : float
    latency : bool
        Log the per-frame latency (wall clock; ``--speed 1``).
    streaming : bool
        A viewer watches (see the module docstring).
    """

    def __init__(self, rec: StageRecorder, worker: LogWorker, scene: TrackScene, robot, dofs,
                 fps: float, latency: bool, streaming: bool):
        self.rec, self.worker, self.scene, self.robot = rec, worker, scene, robot
        self.dofs, self.fps = tuple(dofs), float(fps)
        width, height = scene.calibration.image_size
        self.encoders = [LiveVideoEncoder((width, height), fps) for _ in range(2)]
        self.frames = 0
        self.streaming = streaming
        self.every = STREAM_FRAMES if streaming else FILE_FRAMES
        self.slice = STREAM_SLICE_PERIODS if streaming else FILE_SLICE_PERIODS
        self.track = _TrackFrames()
        self.quality = None
        self.logged_rows = 0
        self.logged_segments = 0
        self.hand: np.ndarray | None = None   # the last logged hand position (1, 3)
        self.area_logged = False
        self.placed = False   # whether the frame demonstration has a place in the world
        self.heights: list[float] = []        # tracked sponge z (m, track frame)
        self.series = {
            "/track/position": _Series(["x", "y", "z"]),
            "/oscillators/frequency_hz": _Series(["omega"], np.array([INPUT_COLOUR])),
            "/oscillators/fundamental_hz": _Series(["fundamental"], np.array([REFERENCE_COLOUR])),
            "/oscillators/model_frequency_hz": _Series(["model"], np.array([LEARNED_COLOUR])),
            **{f"/live/imitation/{dof}": _Series(
                ["demonstrated", "learned", "robot"],
                np.array([INPUT_COLOUR, LEARNED_COLOUR, ROBOT_COLOUR])) for dof in dofs},
        }
        if latency:
            self.series["/live/latency_ms"] = _Series(["latency"])
        worker.submit(self._setup)

    # -- what the session hands over (in its thread) ------------------------------------------
    def frame(self, t: float, pair, estimate, learner: LearnerView | None, hand_xy) -> None:
        """One processed frame: the images, the track, the learner, the robot's hand
        ``hand_xy`` (2,) (m, robot world) at the frame's time."""
        self.worker.submit(self._frame, t, pair, estimate, learner, np.array(hand_xy))
        self.frames += 1
        if self.frames % self.every == 0:
            self.flush()

    def dropped(self, t: float) -> None:
        """A frame the session never saw (dropped from the frame buffer)."""
        self.worker.submit(self._dropped, t)

    def latency(self, t: float, seconds: float) -> None:
        self.worker.submit(self.series["/live/latency_ms"].add, t, [1000.0 * seconds])

    def scene_known(self, R_track_table: np.ndarray, region_size: float) -> None:
        """The tracker knows the table and the sponge's size: draw the sponge so from now."""
        self.worker.submit(self._scene_known, np.array(R_track_table), float(region_size))

    def robot_trace(self, final: bool = False) -> None:
        """Log the robot's control periods since the last call, in slices of ``slice``
        control periods (all that is left when ``final``), and its new segments."""
        robot = self.robot
        start = max(self.logged_rows, robot.first_session_row)
        count = len(robot.task.session.trace) - start
        if not final:
            count -= count % self.slice
        if count > 0:
            self.worker.submit(self._robot_slice, start, start + count)
            self.logged_rows = start + count
        segments = robot.segments[self.logged_segments:]
        if segments:
            self.worker.submit(self._segments, list(segments))
            self.logged_segments += len(segments)

    def flush(self) -> None:
        """Write the buffered series and let a viewer see them."""
        self.worker.submit(self._flush)

    # -- the work (on the worker's thread) ---------------------------------------------------
    def _setup(self) -> None:
        log_track_setup(self.rec, self.scene)
        log_scene(self.rec, self.robot.task, 0.0)
        self.rec.json("/live/placement", 0.0, self.robot.placement, "wipelab.Placement")

    def _frame(self, t: float, pair, estimate, learner: LearnerView | None, hand_xy) -> None:
        rec = self.rec
        for side, encoder, image, frame_id in zip(("left", "right"), self.encoders,
                                                  (pair.left, pair.right),
                                                  (LEFT_FRAME, RIGHT_FRAME)):
            for unit in encoder.encode(image, t):
                rec.video_sample(f"/stereo/{side}/video", t, unit, frame_id)
        self.track.add(pair.index, t, estimate.pose, estimate.quality, estimate.particles)
        if estimate.valid:
            self.series["/track/position"].add(t, estimate.pose[:3])
            self.heights.append(float(estimate.pose[2]))
            if not self.placed:   # from the session's start, until the area is known
                self._place(0.0, estimate.pose[:2], float(estimate.pose[2]))
        quality = LOST if estimate.quality == QUALITY_NONE else estimate.quality
        if quality != self.quality:
            rec.states("/track/quality", [t], [quality], {quality: QUALITY_COLOURS[quality]})
            self.quality = quality
        if learner is not None:
            self._learner(t, estimate, learner, hand_xy)

    def _dropped(self, t: float) -> None:
        self.track.add(-1, t, np.full(4, np.nan), QUALITY_NONE, np.zeros((0, 3)))

    def _scene_known(self, R_track_table: np.ndarray, region_size: float) -> None:
        self.track.write(self.rec, self.scene)   # drawn as they were known then
        self.scene = replace(self.scene, R_track_table=R_track_table, region_size=region_size)

    def _learner(self, t: float, estimate, learner: LearnerView, hand_xy) -> None:
        area = learner.area
        if area is None:   # not locked yet: nothing the robot follows
            return
        self.series["/oscillators/frequency_hz"].add(t, [learner.omega_hz])
        self.series["/oscillators/fundamental_hz"].add(t, [learner.fundamental_hz])
        self.series["/oscillators/model_frequency_hz"].add(t, [learner.frequency_hz])
        if not self.area_logged:
            self._area(t, area)
        shown = area.normalise(np.stack([
            estimate.pose[:2] if estimate.valid else np.full(2, np.nan), learner.output,
            self.robot.in_demonstration(hand_xy)]))
        for j, dof in enumerate(self.dofs):
            self.series[f"/live/imitation/{dof}"].add(t, shown[:, j])

    def _area(self, t: float, area: DemonstrationArea) -> None:
        """The demonstration area (once frozen) and where the demonstration goes in the
        robot's world."""
        self.area_logged = True
        rec = self.rec
        rec.json("/track/demonstration_area", t,
                 {"lower_left": area.lower_left, "upper_right": area.upper_right,
                  "centre": area.centre, "window_s": list(area.window),
                  "frame": DEMONSTRATION_FRAME}, "wipelab.DemonstrationArea")
        height = float(np.median(self.heights))
        (x0, y0), (x1, y1) = area.lower_left, area.upper_right
        rectangle = np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1], [x0, y0]])
        rec.line_strip3d("/track/demonstration_area/outline", t,
                         np.column_stack([rectangle, np.full(5, height)]), color=AREA_COLOUR,
                         frame_id=DEMONSTRATION_FRAME)
        self._place(t, area.centre, height)

    def _place(self, t: float, centre, height: float) -> None:
        """Place the frame ``demonstration`` in the robot's world from ``t`` on: the point
        ``centre`` (2,) at ``height`` (m, track frame) on the surface at the wiping centre."""
        translation, rotation = self.robot.demonstration_pose(centre, height,
                                                              self.scene.R_track_table)
        self.rec.transforms(t, [("world", DEMONSTRATION_FRAME, translation,
                                 quaternion_xyzw_from_rotation(rotation))])
        self.placed = True

    def _robot_slice(self, start: int, stop: int) -> None:
        trace = self.robot.trace_arrays(start, stop)
        log_trace(self.rec, "live", self.robot.task, trace)
        path = trace["tcp"] if self.hand is None else np.vstack([self.hand, trace["tcp"]])
        self.rec.line_strip3d("/live/hand_path", float(trace["t"][-1]), path,
                              color=ROBOT_COLOUR, thickness=0.005,
                              entity_id=f"/live/hand_path/{start}")
        self.hand = trace["tcp"][-1:]

    def _segments(self, segments) -> None:
        for segment in segments:
            time = max(segment.start, 0.0)
            self.rec.states("/live/segment", [time], [segment.name],
                            {segment.name: segment_colour(segment.name)})
            self.rec.events("/live/events", [time], [segment.name])

    def _flush(self) -> None:
        self.track.write(self.rec, self.scene)
        for topic, series in self.series.items():
            series.write(self.rec, topic)
        if self.streaming:
            self.rec.rerun.flush(timeout_sec=0.0)
