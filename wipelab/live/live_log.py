"""What a live session writes to ``live.mcap`` and ``live.rrd`` (and streams to a viewer),
frame by frame.

Topics (MCAP topic = Rerun entity; time = the session's, seconds from the first frame):

* the cameras: ``/stereo/left|right/video`` (H.264 encoded as the frames arrive, Rerun
  ``VideoStream``, ``foxglove.CompressedVideo``), ``/stereo/*/calibration``, ``/stereo/*/overlay``
  (the sponge box and particles drawn over the images), ``/tf`` of the cameras;
* the track as the track stage logs it (:func:`~wipelab.stages.track.log_track_frame`), in
  the frame ``demonstration`` (the demo's world, or its left camera's frame), which ``/tf``
  places in the robot's world once the demonstration area is known: the area's centre on
  the robot's wiping centre, the tracked sponge's median height on the surface. So the
  3D view shows the person's sponge under the robot's hand. ``/track/position`` (m),
  ``/track/quality`` (a state), ``/track/demonstration_area`` (JSON and outline);
* imitation learning: ``/oscillators/frequency_hz``, ``/oscillators/fundamental_hz``,
  ``/oscillators/model_frequency_hz`` (the frequency converging), ``/live/imitation/<dof>``:
  the demonstrated movement, the learned one (the online DMP's output) and the robot's hand,
  normalised to the demonstration area (the paper's Fig. 5, with the robot);
* the robot as adapt and replay log it (:mod:`wipelab.sim.recording`, stage name ``live``):
  joints and ``/tf``, TCP and contact heights, |F|, the segment (``/live/segment``: waiting,
  imitating, slowing down, learning, ..., wiping);
* at ``--speed 1`` only, ``/live/latency_ms`` per frame (wall clock: a rerun differs).

Series are buffered and written every :data:`FLUSH_FRAMES` frames; the Rerun stream is
flushed then too (what a viewer sees is at most that old). Both points depend on the frame
count only, so a rerun at ``--speed max`` writes the same bytes.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import rerun as rr
import rerun.blueprint as rrb

from wipelab.logs import StageRecorder, stage_panels, whole_run
from wipelab.logs.palette import INPUT_COLOUR, LEARNED_COLOUR, REFERENCE_COLOUR, segment_colour
from wipelab.logs.video_encoder import LiveVideoEncoder
from wipelab.sim.kinematics import quaternion_xyzw_from_rotation
from wipelab.sim.recording import POSE_RATE_HZ, log_scene, log_trace
from wipelab.stages.track import (AREA_COLOUR, LEFT_FRAME, LOST, QUALITY_COLOURS, RIGHT_FRAME,
                                  TrackScene, log_track_frame, log_track_setup)
from wipelab.vision.tracker import QUALITY_NONE

#: The frame of the tracked positions in a live recording (see the module docstring).
DEMONSTRATION_FRAME = "demonstration"
#: Series are written (and the stream flushed) every this many frames.
FLUSH_FRAMES = 3
#: The robot's trace is logged in slices of this many control periods (a multiple of the
#: pose logging stride, so that the slices sample it evenly).
ROBOT_SLICE_PERIODS = 16
#: Colour of the robot's hand in the imitation plots.
ROBOT_COLOUR = (40, 175, 120)


def live_blueprint(dofs) -> rrb.Blueprint:
    """Both cameras with the track drawn; the robot imitating in 3D and what it does; the
    frequency converging, input vs learned (and the robot's hand) per DOF, height and |F|."""
    scene = rrb.Spatial3DView(
        origin="/", name="the robot imitating; the person's sponge under its hand",
        contents=["+ /**", "- /stereo/**", "- /track/particles/**"],
        eye_controls=rrb.EyeControls3D(position=[1.6, -1.1, 1.7], look_target=[0.5, -0.2, 0.85],
                                       eye_up=[0.0, 0.0, 1.0]))
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


class LiveLog:
    """Writes a live session into ``rec`` frame by frame (see the module docstring).

    Parameters
    ----------
    rec : StageRecorder
    scene : TrackScene
        Its frame is :data:`DEMONSTRATION_FRAME`.
    robot : LiveRobot
    dofs : tuple of str
    fps : float
    latency : bool
        Log the per-frame latency (wall clock; ``--speed 1``).
    """

    def __init__(self, rec: StageRecorder, scene: TrackScene, robot, dofs, fps: float,
                 latency: bool):
        self.rec, self.scene, self.robot, self.dofs = rec, scene, robot, tuple(dofs)
        self.fps = float(fps)
        width, height = scene.calibration.image_size
        self.encoders = [LiveVideoEncoder((width, height), fps) for _ in range(2)]
        self.frames = 0
        self.previous: np.ndarray | None = None
        self.quality = None
        self.logged_rows = 0
        self.logged_segments = 0
        self.area_logged = False
        self.heights: list[float] = []        # tracked sponge z (m, track frame)
        oscillator = (INPUT_COLOUR,)
        self.series = {
            "/track/position": _Series(["x", "y", "z"]),
            "/oscillators/frequency_hz": _Series(["omega"], np.array(oscillator)),
            "/oscillators/fundamental_hz": _Series(["fundamental"], np.array([REFERENCE_COLOUR])),
            "/oscillators/model_frequency_hz": _Series(["model"], np.array([LEARNED_COLOUR])),
            **{f"/live/imitation/{dof}": _Series(
                ["demonstrated", "learned", "robot"],
                np.array([INPUT_COLOUR, LEARNED_COLOUR, ROBOT_COLOUR])) for dof in dofs},
        }
        if latency:
            self.series["/live/latency_ms"] = _Series(["latency"])
        log_track_setup(rec, scene)
        log_scene(rec, robot.task, 0.0)
        rec.json("/live/placement", 0.0, robot.placement, "wipelab.Placement")

    def frame(self, t: float, pair, estimate, imitation, hand_xy) -> None:
        """One processed frame: the images, the track, the learner, the robot's hand
        ``hand_xy`` (2,) (m, robot world) at the frame's time."""
        rec, scene = self.rec, self.scene
        for side, encoder, image, frame_id in zip(("left", "right"), self.encoders,
                                                  (pair.left, pair.right),
                                                  (LEFT_FRAME, RIGHT_FRAME)):
            for unit in encoder.encode(image, t):
                rec.video_sample(f"/stereo/{side}/video", t, unit, frame_id)
        particles = estimate.particles[:, :3] if len(estimate.particles) else np.zeros((0, 3))
        log_track_frame(rec, scene, pair.index, t, estimate.pose, estimate.quality, particles,
                        self.previous)
        self.previous = estimate.pose[:3].copy() if estimate.valid else None
        if estimate.valid:
            self.series["/track/position"].add(t, estimate.pose[:3])
            self.heights.append(float(estimate.pose[2]))
        quality = LOST if estimate.quality == QUALITY_NONE else estimate.quality
        if quality != self.quality:
            rec.states("/track/quality", [t], [quality], {quality: QUALITY_COLOURS[quality]})
            self.quality = quality
        self._learner(t, estimate, imitation, hand_xy)
        self.frames += 1
        if self.frames % FLUSH_FRAMES == 0:
            self.flush()

    def dropped(self, t: float) -> None:
        """A frame the session never saw (dropped from the frame buffer)."""
        log_track_frame(self.rec, self.scene, -1, t, np.full(4, np.nan), QUALITY_NONE,
                        np.zeros((0, 3)), None)
        self.previous = None

    def latency(self, t: float, seconds: float) -> None:
        self.series["/live/latency_ms"].add(t, [1000.0 * seconds])

    def _learner(self, t: float, estimate, imitation, hand_xy) -> None:
        learner = imitation.learner
        if learner is None:
            return
        self.series["/oscillators/frequency_hz"].add(t, learner.oscillators_hz[:1])
        self.series["/oscillators/fundamental_hz"].add(t, [learner.fundamental_hz])
        self.series["/oscillators/model_frequency_hz"].add(t, [learner.frequency_hz])
        if not imitation.locked:
            return
        area = imitation.area
        if not self.area_logged:
            self._area(t, area)
        shown = area.normalise(np.stack([
            estimate.pose[:2] if estimate.valid else np.full(2, np.nan), learner.output,
            self.robot.in_demonstration(hand_xy)]))
        for j, dof in enumerate(self.dofs):
            self.series[f"/live/imitation/{dof}"].add(t, shown[:, j])

    def _area(self, t: float, area) -> None:
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
        translation, rotation = self.robot.demonstration_pose(area.centre, height,
                                                              self.scene.R_track_table)
        rec.transforms(t, [("world", DEMONSTRATION_FRAME, translation,
                            quaternion_xyzw_from_rotation(rotation))])

    def robot_trace(self, final: bool = False) -> None:
        """Log the robot's control periods since the last call, in slices of
        :data:`ROBOT_SLICE_PERIODS` (all that is left when ``final``), and its new segments."""
        robot, rec = self.robot, self.rec
        rows = robot.task.session.trace.rows
        start = max(self.logged_rows, robot.first_session_row)
        count = len(rows) - start
        if not final:
            count -= count % ROBOT_SLICE_PERIODS
        if count > 0:
            trace = robot.trace_arrays(start, start + count)
            log_trace(rec, "live", robot.task, trace)
            self.logged_rows = start + count
        for segment in robot.segments[self.logged_segments:]:
            time = max(segment.start, 0.0)
            rec.states("/live/segment", [time], [segment.name],
                       {segment.name: segment_colour(segment.name)})
            rec.events("/live/events", [time], [segment.name])
        self.logged_segments = len(robot.segments)

    def flush(self) -> None:
        """Write the buffered series and let a viewer see them."""
        for topic, series in self.series.items():
            series.write(self.rec, topic)
        self.rec.rerun.flush(timeout_sec=0.0)
