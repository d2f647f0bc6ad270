"""Learning the force profile of a surface, one control period at a time (the adapt algorithm).

:class:`Adaptation` drives a :class:`~wipelab.sim.task.WipingTask` through:

1. approach: the hand goes above the start of the path, identifies its payload (F/T gravity
   compensation) and moves down to the start height;
2. online learning (the paper, Sec. II-B, III-B2): the x-y path runs slowed down (Omega
   divided by ``slowdown``) with active compliance in z (eqs. 9-12); the commanded height Y
   (eq. 10) is learned into a new DOF z of the DMP, anchored to the x-y phase (eqs. 13-15),
   with Y_r the start height in the first period and the profile learned so far after it
   (:class:`~wipelab.control.force_profile.ProfileLearningParams`), until the profile
   changes by less than the tolerance over a period or after ``periods`` periods;
3. refining at increasing tempos: the learning tempo first, then each of ``tempos`` (multiples
   of the demonstrated frequency; none: the paper's profile as it is), each starting from the
   profile learned so far, by iterative
   learning control of the height profile without force feedback
   (:mod:`~wipelab.control.iterative_learning`); a tempo the arm cannot follow is refined at
   the fastest it can (:meth:`~wipelab.sim.task.WipingTask.executable_frequency`); each new
   tempo is reached over one unscored period in which Omega ramps;
4. ``hold_periods`` periods of the adapted model at the demonstrated tempo with compliance on
   top (what ``replay`` runs at 1x).

The adapted model keeps the heights learned at every tempo as ``z`` (at the demonstrated
frequency) and ``z_per_hz`` (:func:`~wipelab.sim.path.with_height_profiles`).

:meth:`Adaptation.step` runs one control period (``wipelab live`` steps it frame by frame);
:meth:`Adaptation.run` runs it to the end. A safety stop ends it early (``stop_reason``).
"""

from __future__ import annotations

import math
from collections.abc import Generator
from dataclasses import dataclass, field, replace

import numpy as np

from wipelab.control.compliance import feedback_force
from wipelab.control.force_profile import (COMPARISON_PHASES, ConvergenceMonitor,
                                           ForceProfileLearner, ProfileLearningParams)
from wipelab.control.iterative_learning import (IterativeLearningParams, IterativeProfile,
                                                profile_phases)
from wipelab.learning import PeriodicModel
from wipelab.sim.path import PathGenerator, at_frequency, with_height_profiles
from wipelab.sim.recording import Segment
from wipelab.sim.session import SafetyStop
from wipelab.sim.task import CALIBRATION_LIFT, WipingTask

#: Trace segment labels.
MOVE, LEARN, HOLD, REFINE = 0, 1, 2, 3
#: Amplitude r (m) of the learned z DOF: its weights are in metres.
Z_AMPLITUDE = 1.0


@dataclass(frozen=True)
class AdaptationParams:
    """How the force profile is learned (the adapt stage's flags in brackets)."""

    slowdown: float = 4.0            # [--slowdown] Omega is divided by this for online learning
    periods: int = 8                 # [--periods] most periods of online learning
    tempos: tuple[float, ...] = (1.0,)  # [--tempos] multiples of the demonstrated frequency
    hold_periods: int = 1            # [--hold-periods] at the demonstrated tempo, after
    learning: ProfileLearningParams = field(default_factory=ProfileLearningParams)
    iterative: IterativeLearningParams = field(default_factory=IterativeLearningParams)


@dataclass
class TempoStage:
    """The refining at one tempo."""

    requested_hz: float          # the tempo asked for (Hz)
    frequency_hz: float          # the tempo it ran at (the arm's limit may be lower)
    start: float                 # s: the ramp to it started
    errors: list[float]          # RMS force error (N) of each learning period
    stiffness: float             # N/m: the contact stiffness measured at the end
    end: float = math.nan        # s: its last period ended

    def describe(self) -> dict:
        """JSON-ready record."""
        return {"requested_frequency_hz": self.requested_hz, "frequency_hz": self.frequency_hz,
                "arm_limited": self.frequency_hz < self.requested_hz - 1e-9,
                "periods": len(self.errors), "rms_force_error_n": self.errors,
                "contact_stiffness_n_per_m": self.stiffness, "start_time_s": self.start,
                "end_time_s": self.end}


class Adaptation:
    """The adapt algorithm on a task, stepped one control period at a time.

    Parameters
    ----------
    task : WipingTask
        Built for ``model`` (:func:`~wipelab.sim.task.build_task`).
    model : PeriodicModel
        The placed x-y model (its ``frequency_hz`` is the demonstrated tempo).
    params : AdaptationParams

    Attributes
    ----------
    segments : list of Segment
        Parts of the run (for the logs).
    profiles : list of (float, ndarray)
        (time s, learned height at COMPARISON_PHASES) after each learning period.
    learner, monitor : the online learning's (step 2).
    stages : list of TempoStage
        The refining (step 3).
    learning_omega : float
        Omega (rad/s) of online learning.
    end_of_online_learning, end_of_learning, hold_start : float
        s; NaN until reached.
    hold_frequency_hz : float
        Tempo of the hold periods.
    stop_reason : str or None
        Set by a safety stop.
    """

    def __init__(self, task: WipingTask, model: PeriodicModel, params: AdaptationParams):
        self.task, self.model, self.params = task, model, params
        session = task.session
        self.learning_omega = model.omega / params.slowdown
        self.learner = ForceProfileLearner(model.kernels, model.width, model.alpha_s,
                                           model.beta_s, goal=task.start_height,
                                           amplitude=Z_AMPLITUDE, dt=session.dt,
                                           params=params.learning)
        self.monitor = ConvergenceMonitor(params.learning)
        self.segments = [Segment("approach", MOVE, session.time)]
        self.profiles: list[tuple[float, np.ndarray]] = []
        self.stages: list[TempoStage] = []
        self.heights: dict[float, np.ndarray] = {}    # tempo (Hz) -> heights on the grid
        self.end_of_online_learning = self.end_of_learning = self.hold_start = math.nan
        self.hold_frequency_hz = task.executable_frequency(model.frequency_hz)
        self.stop_reason: str | None = None
        self._steps = self._run()
        self.done = False

    # -- driving ------------------------------------------------------------------------------
    def step(self) -> bool:
        """Run one control period; False when the adaptation has ended."""
        if not self.done:
            try:
                next(self._steps)
            except StopIteration:
                self.done = True
        return not self.done

    def run(self) -> Adaptation:
        """Run to the end."""
        while self.step():
            pass
        return self

    def adapted_model(self, source: dict, surface: dict | None) -> PeriodicModel:
        """The placed model with the learned heights (``z``, ``z_per_hz``)."""
        heights = self.heights or {self.learning_omega / (2.0 * math.pi): self._online_profile()}
        return replace(with_height_profiles(self.model, heights), source=source, surface=surface)

    # -- the algorithm ----------------------------------------------------------------------------
    def _run(self) -> Generator[None, None, None]:
        try:
            yield from self._approach()
            yield from self._learn_online()
            omega = self.learning_omega
            for requested in self._tempos_hz():
                omega = yield from self._refine(requested, omega)
            self.end_of_learning = self.task.session.time
            yield from self._hold(omega)
        except SafetyStop as stop:
            self.stop_reason = str(stop)
            for name in ("end_of_online_learning", "end_of_learning"):
                if math.isnan(getattr(self, name)):
                    setattr(self, name, self.task.session.time)
        self.segments.append(Segment("end", MOVE, self.task.session.time))

    def _approach(self):
        session, task = self.task.session, self.task
        self._path = PathGenerator(self.model, ("x", "y"), phase=0.0)
        start = np.array([*self._path.position, task.start_height])
        yield from session.moving_to(start + [0.0, 0.0, CALIBRATION_LIFT], 1.5, mode=MOVE)
        yield from session.calibrating()
        yield from session.moving_to(start, 0.8, mode=MOVE)

    def _online_profile(self) -> np.ndarray:
        """The online learner's profile on the iterative learning's phase grid."""
        return self.learner.waveform(profile_phases(self.params.iterative.grid))

    def _learn_online(self):
        """Step 2: the paper's online learning at the slowed-down tempo."""
        session, task, path = self.task.session, self.task, self._path
        dt, omega = session.dt, self.learning_omega
        self.segments.append(Segment("learning", LEARN, session.time))
        task.world.set_tool_speed(path.max_speed(omega))
        reference = None   # Y_r: the start height, or (reference "learned") the profile so far
        period_end = 2.0 * math.pi
        while self.monitor.periods_ < self.params.periods and not self.monitor.converged:
            xy, velocity = path.step(omega, dt)
            z = ((task.start_height, 0.0) if reference is None else
                 [value[0] for value in reference.step(omega, dt)])
            session.tick(xy, z[0], True, path.phase,
                         velocity=np.array([velocity[0], velocity[1], z[1]]), mode=LEARN)
            self.learner.update(session.trace.last("tcp_cmd")[2], path.phase, omega)
            yield
            if path.phase >= period_end:
                period_end += 2.0 * math.pi
                profile = self.learner.waveform(COMPARISON_PHASES)
                self.monitor.end_of_period(profile)
                self.profiles.append((session.time, profile))
                if self.params.learning.reference == "learned":
                    reference = PathGenerator(self._profile_model(self._online_profile()),
                                              ("z",), phase=path.phase)
                    # Y of eq. 10 continues where it is: the offset takes the difference
                    session.integrator.offset_ = session.trace.last("tcp_cmd")[2] - \
                        reference.position[0]
        self.end_of_online_learning = session.time
        self.heights[omega / (2.0 * math.pi)] = self._online_profile()

    def _tempos_hz(self) -> list[float]:
        """The tempos (Hz) to refine at: the learning tempo, then the faster of ``tempos``;
        none without ``tempos`` (the paper's profile)."""
        if not self.params.tempos:
            return []
        slow = self.learning_omega / (2.0 * math.pi)
        faster = sorted(t * self.model.frequency_hz for t in self.params.tempos)
        return [slow] + [f for f in faster if f > slow * (1.0 + 1e-9)]

    def _profile_model(self, heights: np.ndarray) -> PeriodicModel:
        return with_height_profiles(self.model, {self.model.frequency_hz: heights})

    def _refine(self, requested_hz: float, omega_from: float):
        """Step 3 at one tempo; returns its Omega (rad/s)."""
        session, params = self.task.session, self.params.iterative
        frequency = self.task.executable_frequency(requested_hz)
        omega = 2.0 * math.pi * frequency
        previous = self.stages[-1] if self.stages else None
        if previous is not None and frequency <= previous.frequency_hz * (1.0 + 1e-9):
            return omega_from                         # the arm cannot go faster
        heights = self.heights[max(self.heights)]     # the profile learned so far
        stage = TempoStage(requested_hz, frequency, session.time, [],
                           params.stiffness if previous is None else previous.stiffness)
        self.stages.append(stage)
        self.segments.append(Segment(f"refining at {frequency:.3g} Hz", REFINE, session.time))
        learning = IterativeProfile(heights, omega, session.compliance.target_force, params,
                                    stage.stiffness)
        path = PathGenerator(self._profile_model(learning.profile_), ("x", "y", "z"),
                             phase=self._path.phase)
        yield from self._ramp(path, omega_from, omega, REFINE)
        going_on = True
        while going_on:
            period_end = path.phase + 2.0 * math.pi
            while path.phase < period_end:
                position, velocity = path.step(omega, session.dt)
                session.tick(position[:2], position[2], False, path.phase, velocity=velocity,
                             mode=REFINE)
                learning.record(path.phase, feedback_force(
                    session.force, session.compliance.feedback) - session.compliance.target_force)
                yield
            going_on = learning.end_of_period()
            stage.errors, stage.stiffness = list(learning.errors_), learning.stiffness_
            self.profiles.append((session.time, np.interp(
                COMPARISON_PHASES, profile_phases(params.grid), learning.profile_,
                period=2.0 * math.pi)))
            path = PathGenerator(self._profile_model(learning.profile_), ("x", "y", "z"),
                                 phase=path.phase)
        stage.end = session.time
        self.heights[frequency] = learning.best_
        self._path = path
        return omega

    def _ramp(self, path: PathGenerator, omega_from: float, omega_to: float, mode: int):
        """One period of ``path`` (x, y, z) while Omega goes linearly from ``omega_from`` to
        ``omega_to``, force feedback off; the compliance offset left from before fades out."""
        session = self.task.session
        self.task.world.set_tool_speed(path.max_speed(max(omega_from, omega_to)))
        offset = session.trace.last("tcp_cmd")[2] - path.position[2]
        start, end = path.phase, path.phase + 2.0 * math.pi
        while path.phase < end:
            s = (path.phase - start) / (end - start)
            position, velocity = path.step(omega_from + s * (omega_to - omega_from), session.dt)
            session.integrator.offset_ = offset * (1.0 - min(s, 1.0))
            session.tick(position[:2], position[2], False, path.phase, velocity=velocity,
                         mode=mode)
            yield
        session.integrator.offset_ = 0.0

    def _hold(self, omega_from: float):
        """Step 4: the adapted model at the demonstrated tempo, compliance on top."""
        session = self.task.session
        omega = 2.0 * math.pi * self.hold_frequency_hz
        model = at_frequency(self.adapted_model({}, None), self.hold_frequency_hz)
        path = PathGenerator(model, ("x", "y", "z"), phase=self._path.phase)
        self.segments.append(Segment("learned profile", HOLD, session.time))
        if abs(omega - omega_from) > 1e-9 * omega:
            yield from self._ramp(path, omega_from, omega, HOLD)
        self.hold_start = session.time
        self.task.world.set_tool_speed(path.max_speed(omega))
        end = path.phase + 2.0 * math.pi * self.params.hold_periods
        while path.phase < end:
            position, velocity = path.step(omega, session.dt)
            session.tick(position[:2], position[2], True, path.phase, velocity=velocity,
                         mode=HOLD)
            yield
