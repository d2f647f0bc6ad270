"""The simulated ARMAR-IIIb of a live session: it imitates while the person demonstrates, then
learns the surface and wipes (paper, Sec. III-A3).

The robot program is one generator of control periods (:meth:`LiveRobot.advance` runs it up
to a time): the session calls it after every frame, so the simulated time keeps up with the
video.

1. before the session starts: the platform and the torso are placed for a movement of up to
   ``reach_radius`` around the surface's wiping centre (:func:`~wipelab.sim.task.place_task`
   with a circle of that radius: the demonstration is not known yet), the F/T sensor's
   payload is identified in free air and the hand waits above the centre, ``start_height``
   (3 cm above the surface under that circle);
2. imitation, from when the learner has locked onto the person's movement: the hand follows
   the movement learned so far (the online DMP's output, extrapolated over the frame with
   its velocity) in the air at the waiting height, phase-locked to the person: the
   demonstration's offset from the centre of the demonstration area (Fig. 3) is put around
   the wiping centre, scaled down if it would leave the circle or ask more speed of the arm
   than that circle at the fastest tempo the arm follows it (the placement's
   ``max_frequency_hz``); it blends in from the waiting pose over ``blend_seconds``;
3. when imitation learning ends (:meth:`LiveRobot.finish` with the learned model, placed as
   adapt places a model: at the same scale, the centre of its path's bounding box on the
   wiping centre): over one period the hand moves onto the learned model's path while
   Omega slows down to the learning tempo (Omega / ``slowdown``); then the adapt algorithm
   (:class:`~wipelab.sim.adaptation.Adaptation`, from that phase on: compliance brings the
   sponge down until contact, the force profile is learned in a few periods, refined at the
   demonstrated tempo and held);
4. the adapted movement at ``replay_scale`` times the demonstrated tempo with the learned
   profile for ``replay_periods`` periods (the replay stage's run, mode ``learned``).

All positions in the robot's world frame (metres); times are the session's (s).
"""

from __future__ import annotations

import math
from collections.abc import Generator
from dataclasses import dataclass, field, replace

import numpy as np

from wipelab.learning import PeriodicModel, default_width, fit_weights
from wipelab.sim.adaptation import MOVE, Adaptation
from wipelab.sim.path import PathGenerator, place_model, with_kernels
from wipelab.sim.recording import Segment
from wipelab.sim.session import SafetyStop, Trace
from wipelab.sim.surfaces import load_surface
from wipelab.sim.task import CALIBRATION_LIFT, WipingTask, build_task, place_task, retarget_task
from wipelab.stages.adapt import AdaptParams
from wipelab.stages.replay import ReplayParams, RunResult, run_steps

#: Trace labels of the live program's own parts (adapt's are MOVE 0, LEARN 1, HOLD 2,
#: REFINE 3; the replay run gets the next).
IMITATE, SLOW_DOWN, REPLAY = 4, 5, 6


@dataclass(frozen=True)
class RobotParams:
    """The robot's side of a live session (CLI flags in brackets)."""

    adapt: AdaptParams = field(default_factory=AdaptParams)  # surface, force, slowdown, ...
    reach_radius: float = 0.15            # m: the movement the robot is placed for
    blend_seconds: float = 0.3            # s: from the waiting pose into the imitation
    replay_scale: float = 1.0             # [--replay-scale] x the demonstrated tempo
    replay_periods: int = 3               # [--replay-periods]


@dataclass(frozen=True)
class Following:
    """What the hand follows from one frame on: the learned movement at the frame's time
    ``t`` (s), its position ``y`` (2,) (m, track frame) and velocity ``v`` (2,) (m/s)."""

    t: float
    y: np.ndarray
    v: np.ndarray


def circle_model(radius: float, frequency_hz: float = 1.0, kernels: int = 25) -> PeriodicModel:
    """A circular x-y movement of ``radius`` (m) around the origin, as a periodic DMP: what
    the robot is placed for before the demonstration is known."""
    phases = np.linspace(0.0, 2.0 * math.pi, 8 * kernels, endpoint=False)
    circle = np.column_stack([np.cos(phases), np.sin(phases)])
    width = default_width(kernels)
    goal, amplitude = np.zeros(2), np.full(2, float(radius))
    weights = fit_weights(phases, radius * circle, goal, amplitude, kernels, width, 12.0, 3.0,
                          smoothing=1e-8)
    return PeriodicModel(frequency_hz=frequency_hz, dofs=("x", "y"), kernels=kernels,
                         width=width, alpha_s=12.0, beta_s=3.0, goal=goal, amplitude=amplitude,
                         weights=weights, phase_offset=0.0, source={"stage": "live"})


class LiveRobot:
    """ARMAR-IIIb placed, calibrated and waiting above the surface (step 1 of the module
    docstring runs here, before the session's clock starts).

    Attributes
    ----------
    task : WipingTask
        The world and the control session (its ``model`` is the placement circle until
        :meth:`finish`).
    placement : dict
        Where the path's centre and the platform went (``place_task``'s record).
    time_offset : float
        Simulated time (s) at the session's t = 0 (after the preparation).
    segments : list of Segment
        Parts of the program, at session times.
    adaptation : Adaptation or None
        The adapt algorithm, once it runs.
    replay_run : RunResult or None
        The replay at ``replay_scale``, once it ended.
    stop_reason : str or None
        A safety stop that ended the program.
    """

    def __init__(self, params: RobotParams):
        self.params = params
        adapt = params.adapt
        adapt.validate()
        surface = load_surface(adapt.surface)
        placed = place_task(circle_model(params.reach_radius), surface, adapt.task_options(),
                            f"--surface {adapt.surface}")
        self.placement = placed.record
        self.centre = np.array(placed.record["center"], dtype=float)
        self.task = build_task(placed.model, surface, placed.options, adapt.surface,
                               placed.plan)
        session = self.task.session
        self.waiting = np.array([*self.centre, self.task.start_height])
        for _ in session.moving_to(self.waiting + [0.0, 0.0, CALIBRATION_LIFT], 0.5, mode=MOVE):
            pass
        for _ in session.calibrating():
            pass
        for _ in session.moving_to(self.waiting, 0.8, mode=MOVE):
            pass
        self.time_offset = session.time
        self._first_row = len(session.trace)
        self.segments = [Segment("waiting", MOVE, 0.0)]
        self.adaptation: Adaptation | None = None
        self.replay_run: RunResult | None = None
        self.stop_reason: str | None = None
        self.model: PeriodicModel | None = None     # the placed learned model (finish)
        self.adapt_task: WipingTask | None = None   # the task retargeted to it
        self.adapted: PeriodicModel | None = None
        self._following: Following | None = None
        self._mapping: tuple[np.ndarray, float] | None = None   # area centre, scale
        self._imitation_start = math.nan
        self._program = self._run()
        self.done = False

    @property
    def scale(self) -> float | None:
        """How the demonstration was scaled into the robot's reach (None before imitating)."""
        return None if self._mapping is None else self._mapping[1]

    @property
    def time(self) -> float:
        """The session's time (s) the simulation has reached."""
        return self.task.session.time - self.time_offset

    def close(self) -> None:
        self.task.close()

    # -- where the demonstration goes ---------------------------------------------------
    def in_demonstration(self, xy) -> np.ndarray:
        """Robot-world x-y (..., 2) (m) as the demonstration's x-y they imitate (the inverse
        of the placement of :meth:`imitate`)."""
        centre, scale = self._mapping
        return centre + (np.asarray(xy, dtype=float) - self.centre) / scale

    def demonstration_pose(self, area_centre, height: float, R_track_table: np.ndarray
                           ) -> tuple[np.ndarray, np.ndarray]:
        """Translation (3,) and rotation (3, 3) of the track frame in the robot's world that
        put the demonstration area's centre (2,) at ``height`` (m, track frame) on the
        surface at the wiping centre, the table's axes along the world's (for drawing)."""
        rotation = np.asarray(R_track_table, dtype=float).T
        point = rotation @ np.array([*area_centre, height])
        surface = float(self.task.surface.height_at(self.centre[None])[0])
        return np.array([*self.centre, surface]) - point, rotation

    # -- the trace, on the session's clock --------------------------------------------
    @property
    def first_session_row(self) -> int:
        """Index of the first trace row of the session (the preparation's come before)."""
        return self._first_row

    def trace_arrays(self, start: int, stop: int) -> dict[str, np.ndarray]:
        """Trace rows [start, stop) as arrays (:meth:`~wipelab.sim.session.Trace.arrays`),
        times on the session's clock."""
        part = Trace()
        part.rows = self.task.session.trace.rows[start:stop]
        arrays = part.arrays()
        arrays["t"] = arrays["t"] - self.time_offset
        return arrays

    # -- driven by the session ------------------------------------------------------------
    def imitate(self, area_centre: np.ndarray, half_size: np.ndarray,
                frequency_hz: float) -> float:
        """Start imitating (at the next control period) a movement at ``frequency_hz`` (Hz):
        the demonstration area's centre (2,) and half size (2,) (m, track frame) place it
        around the wiping centre. Returns the scale applied (1: as demonstrated)."""
        reach = self.params.reach_radius / max(float(np.linalg.norm(half_size)), 1e-9)
        speed = self.placement["max_frequency_hz"] / frequency_hz
        scale = min(1.0, reach * min(1.0, speed))
        self._mapping = (np.asarray(area_centre, dtype=float), scale)
        return scale

    def follow(self, following: Following) -> None:
        """What the hand follows from this frame on (see :class:`Following`)."""
        self._following = following

    def finish(self, model: PeriodicModel, phase: float) -> None:
        """Imitation learning ended with ``model`` (x, y, track frame) at canonical phase
        ``phase`` (rad, at the time of the last :meth:`follow`): slow down, learn the
        surface, then wipe (steps 3 and 4)."""
        # as adapt places a model: the centre of the path's bounding box on the wiping
        # centre (where the robot was placed for, so that replay finds the same posture)
        placed = place_model(model, self.centre, self._mapping[1])
        self.model = with_kernels(placed, self.params.adapt.kernels)
        self._finish_phase = float(phase)

    def advance(self, t: float) -> bool:
        """Run the program up to session time ``t`` (s); False once it has ended."""
        session = self.task.session
        while not self.done and session.time - self.time_offset < t - 1e-9:
            try:
                next(self._program)
            except StopIteration:
                self.done = True
        return not self.done

    # -- the program ----------------------------------------------------------------------
    def _run(self) -> Generator[None, None, None]:
        try:
            while self._mapping is None:
                yield from self._hold()
            self._segment("imitating", IMITATE)
            self._imitation_start = self.time
            while self.model is None:
                yield from self._imitate()
            yield from self._adapt_and_wipe()
        except SafetyStop as stop:
            self.stop_reason = str(stop)
        self._segment("end", MOVE)

    def _segment(self, name: str, mode: int) -> None:
        self.segments.append(Segment(name, mode, self.time))

    def _tick(self, xy, velocity, mode: int, phase: float = math.nan):
        session = self.task.session
        session.tick(xy, self.waiting[2], False, phase,
                     velocity=np.array([velocity[0], velocity[1], 0.0]), mode=mode)
        yield

    def _hold(self):
        yield from self._tick(self.waiting[:2], np.zeros(2), MOVE)

    def _target(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """Where the hand goes at session time ``t``: the followed movement extrapolated
        from its frame and placed around the wiping centre; position (2,), velocity (2,)."""
        f = self._following
        centre, scale = self._mapping
        y = f.y + f.v * (t - f.t)
        return self.centre + scale * (y - centre), scale * f.v

    def _imitate(self):
        t = self.time + self.task.session.dt
        xy, velocity = self._target(t)
        s = min(1.0, (t - self._imitation_start) / self.params.blend_seconds)
        s = s * s * (3.0 - 2.0 * s)
        self.task.world.set_tool_speed(1.5 * float(np.linalg.norm(velocity)))
        yield from self._tick(self.waiting[:2] + s * (xy - self.waiting[:2]), s * velocity,
                              IMITATE)

    def _adapt_and_wipe(self):
        task = self.adapt_task = retarget_task(self.task, self.model)
        params = self.params.adapt.adaptation()
        omega, slow = self.model.omega, self.model.omega / params.slowdown
        path = PathGenerator(self.model, ("x", "y"), phase=self._finish_phase)
        self._segment("slowing down", SLOW_DOWN)
        start_xy = np.asarray(task.session.trace.last("tcp_cmd"), dtype=float)[:2]
        self.task.world.set_tool_speed(path.max_speed(omega))
        begin, end = path.phase, path.phase + 2.0 * math.pi
        while path.phase < end:
            s = (path.phase - begin) / (end - begin)
            xy, velocity = path.step(omega + s * (slow - omega), task.session.dt)
            blend = min(1.0, 2.0 * s)
            yield from self._tick(start_xy + blend * (xy - start_xy), velocity, SLOW_DOWN,
                                  path.phase)
        self.adaptation = Adaptation(task, self.model, params, start_phase=path.phase)
        seen = 1   # the adaptation's first segment is its approach, skipped here
        while self.adaptation.step():
            new = self.adaptation.segments[seen:]
            self.segments += [replace(s, start=s.start - self.time_offset) for s in new]
            seen += len(new)
            yield
        self.adapted = self.adaptation.adapted_model({}, None)
        if self.adaptation.stop_reason is not None:
            self.stop_reason = self.adaptation.stop_reason
            return
        scale = self.params.replay_scale
        self._segment(f"wiping at {scale:g}x", REPLAY)
        replay = ReplayParams(frequency_scales=(scale,), modes=("learned",),
                              periods=self.params.replay_periods, warmup_periods=1)
        z_plane = float(np.mean(self.adapted.waveform(np.linspace(0, 2 * math.pi, 64))[
            :, self.adapted.dofs.index("z")]))
        self.replay_run = yield from run_steps(task, self.adapted, scale, "learned", REPLAY,
                                               replay, z_plane)
