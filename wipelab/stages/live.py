"""The live stage: the paper's on-line chain, one frame at a time, in one process.

A person wipes in front of the cameras (a demo directory played at its frame rate, or two
cameras); for every frame pair:

    tracker (:class:`~wipelab.vision.tracker.SpongeTracker`, one step)
      -> one sample into the online learner (:class:`~wipelab.live.imitation.Imitation`)
      -> the simulated ARMAR-IIIb executes the movement learned so far, phase-locked to the
         person, in the air above the table (:class:`~wipelab.live.robot.LiveRobot`, the
         control periods up to the next frame)
      -> the logs (:class:`~wipelab.live.live_log.LiveLog`), streamed to a viewer.

When imitation learning ends (:mod:`wipelab.live.imitation` lists when: the end of the
demonstration, the user's word, ``--learn-periods``, or a learned waveform that stopped
changing) the robot slows down, moves down until contact, learns the force profile and wipes
at ``--replay-scale`` times the demonstrated tempo, on the same clock (at ``--speed 1`` in
real time).

Outputs, in the formats of the batch stages so that every other command can take over:
``track.csv`` (one row per frame of the demonstration, dropped frames as invalid rows),
``model.json`` (as ``learn``'s), ``adapted_model.json`` (as ``adapt``'s), ``metrics.json``
(timing, imitation, following, adapt, replay), ``live.mcap``, ``live.rrd``, ``manifest.json``.
At ``--speed max`` the files are the same on every run (the wall-clock measurements, which
are not, are printed instead of written).
"""

from __future__ import annotations

import math
import os
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from tqdm import tqdm

from wipelab.blas_threads import single_threaded_blas
from wipelab.errors import InputError
from wipelab.live.following import following_metrics
from wipelab.live.frames import FrameFeed
from wipelab.live.imitation import Imitation, ImitationParams
from wipelab.live.live_log import DEMONSTRATION_FRAME, LearnerView, LiveLog, live_blueprint
from wipelab.live.log_worker import LogWorker
from wipelab.live.robot import Following, LiveRobot, RobotParams
from wipelab.live.sources import LiveSource, open_source
from wipelab.live.stop_requests import StopRequests
from wipelab.live.timing import FrameTimes, SessionClock
from wipelab.live.viewer import parse_viewer, viewer_sinks
from wipelab.logs import StageRecorder
from wipelab.manifest import build_manifest, write_json
from wipelab.stage_output import staged_output
from wipelab.stages.adapt import adapt_metrics, json_parameters
from wipelab.stages.replay import run_metrics
from wipelab.stages.track import (TrackParams, TrackScene, colour_source, sponge_box,
                                  tracked_csv_columns)
from wipelab.trajectory_csv import write_trajectory
from wipelab.vision.tracker import SpongeTracker, TrackerParams

SPEEDS = ("1", "max")
#: Seconds of searching for the sponge of the named colour after which live searches a
#: little above it as well, then a little below it (the track stage's later passes, on line:
#: a sponge whose colour lies between two names).
WIDEN_AFTER_S = ((+1, 10.0), (-1, 20.0))


@dataclass(frozen=True)
class LiveParams:
    """Parameters of ``wipelab live`` (CLI flags in brackets)."""

    speed: str = "1"                      # [--speed] 1: the source's frame rate; max: at once
    viewer: str = "none"                  # [--viewer] none, spawn, serve[=PORT], connect=ADDR
    fps: float | None = None              # [--fps] of cameras that do not report theirs
    track: TrackParams = field(default_factory=TrackParams)
    imitation: ImitationParams = field(default_factory=ImitationParams)
    robot: RobotParams = field(default_factory=RobotParams)

    def __post_init__(self):
        if self.speed not in SPEEDS:
            raise InputError(f"--speed: must be 1 or max, got {self.speed!r}")
        parse_viewer(self.viewer)

    @property
    def realtime(self) -> bool:
        return self.speed == "1"


@single_threaded_blas
def run_live(source: LiveSource, out_dir: str | os.PathLike, params: LiveParams = LiveParams(),
             quiet: bool = False, listen_stdin: bool = True) -> dict:
    """Run a live session and write its outputs into ``out_dir`` (all or nothing).

    Returns the metrics (also in ``metrics.json``), with the wall-clock ``timing`` also at
    ``--speed max``.

    Raises
    ------
    InputError
        A bad source, calibration, colour option, surface or viewer; a sponge that was never
        found; a movement the learner never locked onto.
    """
    opened = open_source(source, params.realtime, params.fps)
    try:
        toml_name = f"{source.demo}/demo.toml" if source.demo is not None else "--color"
        colour = colour_source(params.track, opened.metadata, toml_name)
        sponge = sponge_box(params.track, opened.metadata, toml_name)
        sinks = viewer_sinks(params.viewer)
        robot = LiveRobot(params.robot)
    except BaseException:
        opened.feed.stop()
        raise
    try:
        tracker = SpongeTracker(opened.calibration, colour, TrackerParams(
            particles=params.track.particles, seed=params.track.seed, sponge=sponge,
            fps=opened.feed.fps))
        parameters = json_parameters(params) | {"source": source.describe(),
                                                "colour_source": colour.option}
        with staged_output(out_dir) as tmp:
            with StageRecorder(tmp, "live", parameters, opened.inputs,
                               live_blueprint(params.imitation.dofs, robot.waiting),
                               {"calibration.yaml": opened.calibration_path}, sinks) as rec, \
                    LogWorker() as worker, StopRequests() as requests:
                scene = TrackScene(opened.calibration, DEMONSTRATION_FRAME, np.eye(3),
                                   None if sponge is None else
                                   (sponge.length, sponge.width, sponge.height), math.nan)
                log = LiveLog(rec, worker, scene, robot, params.imitation.dofs, opened.feed.fps,
                              params.realtime, streaming=params.viewer != "none")
                session = _Session(opened.feed, tracker, robot, params, log, requests, quiet)
                session.run(source)
            metrics = session.outputs(tmp, source, parameters, opened.inputs)
    finally:
        opened.feed.stop()
        robot.close()
    return metrics


class _Session:
    """The frame loop and what it records (see the module docstring)."""

    def __init__(self, feed: FrameFeed, tracker: SpongeTracker, robot: LiveRobot,
                 params: LiveParams, log: LiveLog, requests: StopRequests, quiet: bool):
        self.feed, self.tracker, self.robot, self.params = feed, tracker, robot, params
        self.fps = feed.fps
        self.widenings = 0  # of WIDEN_AFTER_S, done
        self.imitation = Imitation(self.fps, params.imitation)
        self.log, self.requests, self.quiet = log, requests, quiet
        self.scene_known = False
        self.times = FrameTimes()
        self.rows: list[tuple] = []       # per frame: pose (4,), valid, quality
        self.hand: list[np.ndarray] = []  # per frame: the robot's hand x-y (m, world)
        self.clock: SessionClock | None = None
        self.imitating = False
        self.busy_s = 0.0   # wall time spent working (s)

    # -- imitation: one frame at a time -----------------------------------------------------
    def run(self, source: LiveSource) -> None:
        feed, imitation = self.feed, self.imitation
        feed.start()
        self.clock = SessionClock(self.params.realtime, feed.start_time)
        with tqdm(desc="live: imitating", unit="frame", disable=self.quiet, file=sys.stderr,
                  leave=False) as bar:
            while imitation.stop_reason is None:
                if self.requests.reason is not None:
                    imitation.request_stop(self.requests.reason)
                pair = feed.next()
                if pair is None:
                    imitation.request_stop("end of the video")
                    break
                taken = time.perf_counter()
                self._frame(pair)
                self.busy_s += time.perf_counter() - taken
                bar.update()
        self.imitation_wall_s = self.clock.elapsed()
        if not imitation.locked:
            self._never_locked(source)
        feed.stop()
        self._finish_imitation()
        with tqdm(desc="live: learning the surface", unit="s", disable=self.quiet,
                  file=sys.stderr, leave=False) as bar:
            self._robot_only(bar)

    def _frame(self, pair) -> None:
        late = self.params.realtime and self.feed.waiting() > 0
        for index in range(len(self.rows), pair.index):    # dropped by the frame buffer
            self._advance(index, np.full(4, np.nan), False, "")
            self.log.dropped(index / self.fps)
        while not self.tracker.identified and self.widenings < len(WIDEN_AFTER_S) and \
                pair.index >= WIDEN_AFTER_S[self.widenings][1] * self.fps:
            self.tracker.widen_colour(WIDEN_AFTER_S[self.widenings][0])
            self.widenings += 1
        estimate = self.tracker.step(pair.left, pair.right)
        if self.tracker.ready and not self.scene_known:
            self.scene_known = True   # draw the sponge at its size and turn from now
            self.log.scene_known(self.tracker.table_axes_in_track(), self.tracker.region.size)
        self._advance(pair.index, estimate.pose, estimate.valid, estimate.quality)
        commanded = time.perf_counter()
        self.times.add(pair.arrived, commanded, late, self.imitating)
        t = pair.index / self.fps
        if self.params.realtime:
            self.log.latency(t, commanded - pair.arrived)
        self.log.frame(t, pair, estimate, LearnerView.of(self.imitation), self.hand[-1])
        self.log.robot_trace()

    def _advance(self, index: int, pose: np.ndarray, valid: bool, quality: str) -> None:
        """One sample into the learner, then the robot up to the next frame."""
        imitation, robot = self.imitation, self.robot
        imitation.step(pose[:2], valid)
        t = index / self.fps
        if imitation.locked and not self.imitating:
            self.imitating = True
            scale = robot.imitate(imitation.area.centre, imitation.area.half_size,
                                  imitation.learner.frequency_hz)
            if not self.quiet:
                tqdm.write(f"live: the robot imitates from {t:.1f} s ({imitation.learner.frequency_hz:.2f} "
                           f"Hz, scale {scale:.2f}); Enter or SIGUSR1 ends imitation learning",
                           file=sys.stderr)
        if self.imitating:
            learner = imitation.learner
            robot.follow(Following(t, learner.output.copy(),
                                   learner.omega * learner.state.velocity))
        # where the hand is at the frame's time (the end of the last control period)
        self.hand.append(np.asarray(robot.task.session.trace.last("tcp")[:2], dtype=float))
        robot.advance(t + 1.0 / self.fps)
        self.rows.append((np.asarray(pose, dtype=float), bool(valid), quality))

    def _never_locked(self, source: LiveSource) -> None:
        tracked = sum(valid for _, valid, _ in self.rows)
        if not self.tracker.identified:
            raise InputError(f"{source.describe()}: the sponge was never found (nothing of its "
                             f"colour moved like a wiping sponge in both cameras in "
                             f"{len(self.rows)} frames); give its colour with --color or --hsv")
        raise InputError(f"{source.describe()}: the learner never locked onto a periodic "
                         f"movement ({tracked} of {len(self.rows)} frames tracked; it needs "
                         f"about two periods without a gap)")

    def _finish_imitation(self) -> None:
        imitation, learner = self.imitation, self.imitation.learner
        t_last = (len(self.rows) - 1) / self.fps
        self.model = imitation.model(self._model_source())
        phase = learner.phase + learner.omega * (self.robot.time - t_last)
        self.robot.finish(self.model, phase)
        self.log.flush()

    # -- after the demonstration: the robot alone, on the same clock -------------------------
    def _robot_only(self, bar) -> None:
        t = self.robot.time
        step = 1.0 / self.fps
        frames = 0
        while self.robot.advance(t + step):
            t += step
            self.clock.wait_until(t)
            frames += 1
            self.log.robot_trace()
            if frames % self.log.every == 0:
                self.log.flush()
                bar.update(self.log.every * step)
        self.log.robot_trace(final=True)
        self.log.flush()
        self.wall_s = self.clock.elapsed()
        self.busy_s += self.wall_s - self.imitation_wall_s - self.clock.waited

    # -- outputs ---------------------------------------------------------------------------
    def _model_source(self) -> dict:
        imitation = self.imitation
        return {"stage": "live", "reference_dof": imitation.params.dofs[
            imitation.learner.settings.reference]}

    def outputs(self, tmp: Path, source: LiveSource, parameters: dict, inputs: dict) -> dict:
        """Write track.csv, model.json, adapted_model.json, metrics.json and manifest.json
        into ``tmp``; returns the metrics with the wall-clock timing."""
        imitation, robot = self.imitation, self.robot
        t = np.arange(len(self.rows)) / self.fps
        poses = np.array([pose for pose, _, _ in self.rows])
        valid = np.array([v for _, v, _ in self.rows])
        quality = np.array([q for _, _, q in self.rows], dtype="<U8")
        normalised = np.where(valid[:, None], imitation.area.normalise(poses[:, :2]), np.nan)
        write_trajectory(tmp / "track.csv", t,
                         tracked_csv_columns(poses, valid, quality, normalised))
        write_json(tmp / "model.json", self.model.to_dict())
        metrics = {"format": "wipelab.live_metrics/1",
                   "frames": self._frame_counts(),
                   "imitation": self._imitation_metrics(),
                   "following": following_metrics(
                       t, imitation.area.normalise(np.where(valid[:, None], poses[:, :2],
                                                            np.nan)),
                       imitation.area.normalise(robot.in_demonstration(np.array(self.hand))),
                       self.model.frequency_hz, imitation.lock_time, imitation.first_tracked,
                       imitation.stop_time)}
        metrics.update(self._robot_metrics(tmp, parameters))
        timing = self.times.summary(self.feed.dropped, len(self.rows), robot.time, self.wall_s,
                                    self.imitation_wall_s, self.busy_s)
        if self.params.realtime:
            metrics["timing"] = timing
        write_json(tmp / "metrics.json", metrics)
        write_json(tmp / "manifest.json", build_manifest("live", inputs, parameters,
                                                         self.params.track.seed))
        return metrics | {"timing": timing}

    def _frame_counts(self) -> dict:
        processed = len(self.times.latencies)
        total = len(self.rows)
        return {"total": total, "processed": processed, "dropped": total - processed,
                "late": self.times.late, "fps": self.fps}

    def _imitation_metrics(self) -> dict:
        imitation = self.imitation
        area = imitation.area
        return {"first_tracked_s": imitation.first_tracked, "lock_s": imitation.lock_time,
                "converged_s": None if math.isnan(imitation.converged_time)
                else imitation.converged_time,
                "stop_s": imitation.stop_time, "stop_reason": imitation.stop_reason,
                "periods_since_lock": imitation.periods,
                "frequency_hz": self.model.frequency_hz,
                "tempo_changes": imitation.learner.tempo_changes,
                "demonstration_area": {"lower_left": area.lower_left.tolist(),
                                       "upper_right": area.upper_right.tolist(),
                                       "window_s": list(area.window)},
                "robot_scale": self.robot.scale}

    def _robot_metrics(self, tmp: Path, parameters: dict) -> dict:
        robot = self.robot
        out = {"placement": robot.placement, "safety_stop": robot.stop_reason,
               "sim_time_s": robot.time}
        run = robot.adaptation
        if run is None or robot.adapted is None:
            return out
        trace = robot.task.session.trace.arrays()
        adapt_params = self.params.robot.adapt
        surface_entry = {"spec": adapt_params.surface, **robot.task.surface.describe(),
                         "placement": robot.placement,
                         "learning_frequency_hz": run.learning_omega / (2.0 * math.pi),
                         "tempos_hz": sorted(run.heights),
                         "target_force_n": adapt_params.force,
                         "feedback": adapt_params.feedback}
        adapted = run.adapted_model({"stage": "live", "parameters": parameters}, surface_entry)
        write_json(tmp / "adapted_model.json", adapted.to_dict())
        out["adapt"] = adapt_metrics(robot.adapt_task, run, trace, adapted, adapt_params)
        if robot.replay_run is not None:
            out["replay"] = {"scale": self.params.robot.replay_scale, "mode": "learned",
                             **run_metrics(robot.adapt_task, trace, robot.replay_run,
                                           adapt_params.force)}
        return out
