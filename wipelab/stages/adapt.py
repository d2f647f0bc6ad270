"""The adapt stage: learn the force profile of a surface on the simulated ARMAR-IIIb (Sec. II-B).

Flow (paper Sec. III-A3, III-B2):

1. The model's x-y path is placed on the table (:func:`~wipelab.sim.path.place_model`:
   centre of its bounding box at ``center``, default the surface's wiping centre) and slowed
   down: Omega is divided by ``slowdown``. The adapted model has ``kernels`` kernels (50 by
   default, twice the learn stage's 25: a surface's height profile has sharper features than
   a hand's wiping path, and the locally constant fit of eqs. 13-15 smooths it by about a
   kernel width); the x-y path is refitted onto them (:func:`~wipelab.sim.path.with_kernels`,
   its error is in ``metrics.json``, a few hundredths of a millimetre).
2. The hand goes above the start of the path, identifies its payload (F/T gravity
   compensation), then the movement starts with active compliance in z (eqs. 9-12): without
   contact the hand moves down at the velocity cap until the sponge presses with F_0.
3. In every control period the commanded height Y (eq. 10) is learned as a new DOF z of the
   DMP, anchored to the x-y phase (eqs. 13-15). The reference Y_r of eq. 10 is the start
   height in the first period; from the second on it is the profile learned so far (the
   default ``reference="learned"``, see
   :class:`~wipelab.control.force_profile.ProfileLearningParams`; ``"start"`` keeps the
   paper's constant Y_r). Learning stops when the learned waveform changes by less than
   ``tolerance`` over a period (the convergence criterion of
   :class:`~wipelab.control.force_profile.ConvergenceMonitor`) or after ``periods`` periods.
4. ``hold_periods`` more periods run the learned profile with compliance on top (the end of
   learning is marked in the logs, as the dashed line of the paper's Figs. 6-7).

Outputs: ``adapted_model.json`` (x, y as placed, learned z; ``surface`` records where it was
learned), ``metrics.json``, ``adapt.mcap``, ``adapt.rrd``, ``manifest.json``.
"""

from __future__ import annotations

import math
import os
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numpy as np
from tqdm import tqdm

from wipelab.control.compliance import ComplianceParams
from wipelab.control.force_profile import (COMPARISON_PHASES, ConvergenceMonitor,
                                           ForceProfileLearner, ProfileLearningParams)
from wipelab.errors import InputError
from wipelab.learning import PeriodicModel
from wipelab.logs import StageRecorder
from wipelab.manifest import build_manifest, sha256_file, write_json
from wipelab.sim.metrics import coverage, force_metrics, profile_error
from wipelab.model_file import read_model
from wipelab.sim.path import (PathGenerator, place_model, refit_error, require_dofs,
                              with_kernels)
from wipelab.sim.recording import Segment, log_run, wiping_blueprint
from wipelab.sim.session import SafetyStop
from wipelab.sim.sponge import SpongeParams
from wipelab.sim.surfaces import load_surface
from wipelab.sim.task import CALIBRATION_LIFT, TaskOptions, WipingTask, build_task
from wipelab.sim.world import BasePose
from wipelab.stage_output import staged_output

#: Trace segment labels.
MOVE, LEARN, HOLD = 0, 1, 2
#: Amplitude r (m) of the learned z DOF: its weights are in metres.
Z_AMPLITUDE = 1.0


@dataclass(frozen=True)
class AdaptParams:
    """Parameters of ``wipelab adapt`` (CLI flags in brackets)."""

    surface: str = "flat"              # [--surface] built-in name or TOML file
    center: tuple[float, float] | None = None  # [--center] m, world; None: the surface's
    amplitude_scale: float = 1.0       # [--amplitude-scale] of the x-y oscillation
    slowdown: float = 4.0              # [--slowdown] Omega is divided by this while learning
    periods: int = 8                   # [--periods] most learning periods
    hold_periods: int = 1              # [--hold-periods] periods with the learned profile after
    force: float = 10.0                # [--force] F_0 in N
    feedback: str = "norm"             # [--feedback] fz or norm
    base: tuple[float, float, float] = (0.0, 0.0, 0.0)  # [--base] x, y (m), yaw (rad)
    sponge_stiffness: float = 1000.0   # [--sponge-stiffness] N/m
    seed: int = 0                      # [--seed] sensor noise
    kernels: int = 50                  # [--kernels] N of the adapted model (x-y refitted)
    learning: ProfileLearningParams = field(default_factory=ProfileLearningParams)

    def task_options(self) -> TaskOptions:
        """The robot/world options these parameters imply (InputError if invalid)."""
        try:
            compliance = ComplianceParams(target_force=self.force, feedback=self.feedback)
            sponge = SpongeParams(stiffness=self.sponge_stiffness)
        except ValueError as error:
            raise InputError(f"adapt: {error}") from None
        return TaskOptions(base=BasePose(*self.base), sponge=sponge, compliance=compliance,
                           seed=self.seed)

    def validate(self) -> None:
        if not self.slowdown >= 1.0:
            raise InputError(f"--slowdown: must be >= 1, got {self.slowdown}")
        if not (self.periods >= 1 and self.hold_periods >= 0):
            raise InputError("--periods must be >= 1 and --hold-periods >= 0")
        if not 5 <= self.kernels <= 200:
            raise InputError(f"--kernels: must be in [5, 200], got {self.kernels}")
        if not 0 < self.amplitude_scale <= 3:
            raise InputError(f"--amplitude-scale: must be in (0, 3], got {self.amplitude_scale}")


@dataclass
class AdaptRun:
    """What the learning loop produced."""

    learner: ForceProfileLearner
    monitor: ConvergenceMonitor
    segments: list[Segment]
    profiles: list[tuple[float, np.ndarray]]   # (time s, learned z at COMPARISON_PHASES)
    omega: float
    end_of_learning: float
    stop_reason: str | None = None


def _learn(task: WipingTask, model: PeriodicModel, params: AdaptParams, quiet: bool) -> AdaptRun:
    session = task.session
    dt = session.dt
    omega = model.omega / params.slowdown
    path = PathGenerator(model, ("x", "y"), phase=0.0)
    start = np.array([*path.position, task.start_height])
    segments = [Segment("approach", MOVE, 0.0)]
    session.move_to(start + [0.0, 0.0, CALIBRATION_LIFT], 1.5, mode=MOVE)
    session.calibrate()
    session.move_to(start, 0.8, mode=MOVE)
    learner = ForceProfileLearner(model.kernels, model.width, model.alpha_s, model.beta_s,
                                  goal=task.start_height, amplitude=Z_AMPLITUDE, dt=dt,
                                  params=params.learning)
    monitor = ConvergenceMonitor(params.learning)
    run = AdaptRun(learner, monitor, segments, [], omega, math.nan)
    segments.append(Segment("learning", LEARN, session.time))
    task.world.set_tool_speed(path.max_speed(omega))
    period_steps = int(math.ceil(2.0 * math.pi / (omega * dt)))
    total = period_steps * (params.periods + params.hold_periods)
    reference = None   # Y_r: the start height, or (reference "learned") the profile so far
    with tqdm(total=total, desc="adapt", unit="step", disable=quiet, leave=False) as bar:
        try:
            period_end = 2.0 * math.pi
            while monitor.periods_ < params.periods and not monitor.converged:
                xy, velocity = path.step(omega, dt)
                z = ((task.start_height, 0.0, 0.0) if reference is None else
                     [value[0] for value in reference.step(omega, dt)])
                session.tick(xy, z[0], True, path.phase,
                             velocity=np.array([velocity[0], velocity[1], z[1]]), mode=LEARN)
                learner.update(session.trace.last("tcp_cmd")[2], path.phase, omega)
                bar.update()
                if path.phase >= period_end:
                    period_end += 2.0 * math.pi
                    profile = learner.waveform(COMPARISON_PHASES)
                    monitor.end_of_period(profile)
                    run.profiles.append((session.time, profile))
                    if params.learning.reference == "learned":
                        reference = PathGenerator(adapted_model(model, learner, {}, None),
                                                  ("z",), phase=path.phase)
                        # Y of eq. 10 continues where it is: the offset takes the difference
                        session.integrator.offset_ = session.trace.last("tcp_cmd")[2] - \
                            reference.position[0]
            run.end_of_learning = session.time
            segments.append(Segment("learned profile", HOLD, session.time))
            adapted = adapted_model(model, learner, {}, None)
            replay = PathGenerator(adapted, ("x", "y", "z"), phase=path.phase)
            task.world.set_tool_speed(replay.max_speed(omega))
            z_now = session.trace.last("tcp_cmd")[2]
            # continuity at the switch: compliance keeps the small difference and corrects it
            session.integrator.offset_ = z_now - replay.position[2]
            hold_end = path.phase + 2.0 * math.pi * params.hold_periods
            while replay.phase < hold_end:
                position, velocity = replay.step(omega, dt)
                session.tick(position[:2], position[2], True, replay.phase, velocity=velocity,
                             mode=HOLD)
                bar.update()
        except SafetyStop as stop:
            run.stop_reason = str(stop)
            if math.isnan(run.end_of_learning):
                run.end_of_learning = session.time
    segments.append(Segment("end", MOVE, session.time))
    return run


def adapted_model(model: PeriodicModel, learner: ForceProfileLearner, source: dict,
                  surface: dict | None) -> PeriodicModel:
    """The placed x-y model plus the learned z (goal moved to the profile's mean; the weights
    shifted by alpha_s beta_s dg / r so that the limit cycle is unchanged)."""
    weights = learner.weights_
    goal = float(np.mean(learner.waveform(COMPARISON_PHASES)))
    weights = weights - model.alpha_s * model.beta_s * (goal - learner.goal) / Z_AMPLITUDE
    base = model
    if "z" in model.dofs:  # a demonstrated height is replaced by the learned one
        keep = [i for i, d in enumerate(model.dofs) if d != "z"]
        base = replace(model, dofs=tuple(model.dofs[i] for i in keep), goal=model.goal[keep],
                       amplitude=model.amplitude[keep], weights=model.weights[keep])
    return replace(base.with_dof("z", weights, goal, Z_AMPLITUDE), source=source,
                   surface=surface)


def _window(trace: dict, start: float, end: float) -> np.ndarray:
    return (trace["t"] > start) & (trace["t"] <= end)


def _metrics(task: WipingTask, run: AdaptRun, trace: dict, adapted: PeriodicModel,
             params: AdaptParams) -> dict:
    f0 = params.force
    period = 2.0 * math.pi / run.omega
    learning_start = run.segments[1].start
    last_learning = _window(trace, max(learning_start, run.end_of_learning - period),
                            run.end_of_learning)
    hold = _window(trace, run.end_of_learning, run.segments[-1].start)
    z_index = adapted.dofs.index("z")

    def profile(window):
        if not window.any():
            return None
        expected = task.expected_contact_height(trace["tcp"][window, :2], trace["tcp_rot"][window])
        learned = adapted.waveform(trace["phase"][window])[:, z_index]
        return profile_error(learned, expected)

    def forces(window):
        if not window.any():
            return None
        result = force_metrics(trace["force"][window], trace["sponge_force"][window], f0)
        result.update(coverage(task.surface.height_at, trace["sponge_pos"][window],
                               trace["sponge_quat"][window], trace["sponge_force"][window],
                               task.options.sponge.size))
        return result

    changes = [None if math.isinf(c) else c for c in run.monitor.changes_]
    return {
        "format": "wipelab.adapt_metrics/1",
        "surface": task.surface.describe(),
        "target_force_n": f0,
        "feedback": params.feedback,
        "learning_frequency_hz": run.omega / (2.0 * math.pi),
        "learning": {
            "periods": run.monitor.periods_,
            "converged": run.monitor.converged,
            "tolerance_m": params.learning.tolerance,
            "waveform_change_per_period_m": changes,
            "end_time_s": run.end_of_learning,
        },
        "profile_last_learning_period": profile(last_learning),
        "profile_hold": profile(hold),
        "force_last_learning_period": forces(last_learning),
        "force_hold": forces(hold),
        "safety_stop": run.stop_reason,
        "sim_time_s": float(trace["t"][-1]) if len(trace["t"]) else 0.0,
    }


def run_adapt(model_path: str | os.PathLike, out_dir: str | os.PathLike,
              params: AdaptParams = AdaptParams(), quiet: bool = False) -> dict:
    """Run the adapt stage; returns the metrics (also written to ``metrics.json``).

    Raises
    ------
    InputError
        Bad model file, unknown surface, bad heightfield, unreachable movement, bad options.
    """
    params.validate()
    model_path = Path(model_path)
    model = read_model(model_path)
    require_dofs(model, ("x", "y"), str(model_path))
    surface = load_surface(params.surface)
    options = params.task_options()
    centre = surface.wipe_center if params.center is None else np.asarray(params.center)
    as_learned = place_model(model, centre, params.amplitude_scale)
    placed = with_kernels(as_learned, params.kernels)
    parameters = json_parameters(params)
    task = build_task(placed, surface, options, str(model_path))
    try:
        run = _learn(task, placed, params, quiet)
        trace = task.session.trace.arrays()
        source = {"stage": "adapt", "model_sha256": sha256_file(model_path),
                  "parameters": parameters}
        surface_entry = {"spec": params.surface, **surface.describe(),
                         "learning_frequency_hz": run.omega / (2.0 * math.pi),
                         "target_force_n": params.force, "feedback": params.feedback}
        adapted = adapted_model(placed, run.learner, source, surface_entry)
        metrics = _metrics(task, run, trace, adapted, params)
        metrics["kernels"] = {"model": model.kernels, "adapted": adapted.kernels,
                              "xy_refit_error_m": refit_error(as_learned, placed, ("x", "y"))}
        inputs = {"model": model_path}
        if Path(params.surface).suffix.lower() == ".toml":
            inputs["surface"] = Path(params.surface)
        with staged_output(out_dir) as tmp:
            write_json(tmp / "adapted_model.json", adapted.to_dict())
            write_json(tmp / "metrics.json", metrics)
            with StageRecorder(tmp, "adapt", parameters, inputs, wiping_blueprint("adapt")) as rec:
                log_run(rec, "adapt", task, trace, run.segments, run.profiles, adapted)
            write_json(tmp / "manifest.json",
                       build_manifest("adapt", inputs, parameters, params.seed))
    finally:
        task.close()
    return metrics


def json_parameters(params) -> dict:
    """Stage parameters as plain JSON."""
    data = asdict(params)
    return {k: (list(v) if isinstance(v, tuple) else v) for k, v in data.items()}
