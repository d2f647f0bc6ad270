"""The replay stage: execute an (adapted) model at any speed on the simulated robot.

For every frequency scale (``--frequency-scale 1 1.5``: multiples of the demonstrated tempo,
the model's ``frequency_hz``; 1 = as fast as the person wiped) it runs the same path in
several modes, one after the other in the same world, so that the results sit side by side:

- ``learned``: the learned z profile alone (no force feedback);
- ``learned+compliance``: the learned profile with active compliance on top (eq. 10 with
  Y_r the learned profile);
- ``compliance``: baseline 1, active compliance alone from a planar reference above the
  surface (what adapt does before it has learned anything);
- ``planar``: baseline 2, the unadapted planar trajectory, at the mean learned height.

The learned profile is the one for the run's tempo (``z + (f - frequency_hz) z_per_hz``,
:func:`~wipelab.sim.path.at_frequency`). A tempo the arm cannot follow (its joint speeds,
:meth:`~wipelab.sim.task.WipingTask.executable_frequency`) runs at the fastest it can; the
run's metrics say so (``arm_limited``) with the tempo it ran at and the TCP tracking error.
Each run lowers the sponge onto its start, runs ``warmup_periods`` unscored periods and
``periods`` scored ones; a safety stop ends the run (its missing time counts as no contact).
A model without z (not adapted) can be replayed in the ``compliance`` mode only.

Outputs: ``metrics.json`` (per scale and mode: the tempo in Hz, force regulation, contact,
peak, coverage, tracking error), ``replay.mcap``, ``replay.rrd``, ``manifest.json``.
"""

from __future__ import annotations

import math
import os
from collections.abc import Generator
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from tqdm import tqdm

from wipelab.control.compliance import ComplianceParams
from wipelab.blas_threads import single_threaded_blas
from wipelab.errors import InputError
from wipelab.learning import PeriodicModel
from wipelab.logs import StageRecorder
from wipelab.long_lived import long_lived_objects
from wipelab.manifest import build_manifest, write_json
from wipelab.sim.metrics import coverage, force_metrics
from wipelab.model_file import read_model
from wipelab.sim.path import PathGenerator, at_frequency, dof_waveform, require_dofs
from wipelab.sim.recording import (ReplayRun, Segment, log_placement, log_run, replay_blueprint,
                                   speed_label)
from wipelab.sim.session import SafetyStop
from wipelab.sim.sponge import SpongeParams
from wipelab.sim.surfaces import load_surface
from wipelab.sim.task import CALIBRATION_LIFT, TaskOptions, WipingTask, build_task, place_task
from wipelab.sim.world import BasePose
from wipelab.stage_output import staged_output
from wipelab.stages.adapt import json_parameters

#: Replay modes, in the order they run.
MODES = ("learned", "learned+compliance", "compliance", "planar")
#: Modes that need the learned z.
_NEEDS_Z = ("learned", "learned+compliance", "planar")
#: Largest frequency scale (x the demonstrated tempo).
MAX_SCALE = 4.0
#: Trace label of the moves between runs.
MOVE = 0


@dataclass(frozen=True)
class ReplayParams:
    """Parameters of ``wipelab replay`` (CLI flags in brackets). ``None`` takes the value the
    model was adapted with (its ``surface`` entry) or the adapt default."""

    surface: str | None = None                 # [--surface]
    frequency_scales: tuple[float, ...] = (1.0, 1.5)  # [--frequency-scale] x demonstrated tempo
    modes: tuple[str, ...] = MODES             # [--mode] (repeatable)
    periods: int = 3                           # [--periods] scored periods per run
    warmup_periods: int = 1                    # [--warmup-periods] unscored, first
    force: float | None = None                 # [--force] F_0 (N)
    feedback: str | None = None                # [--feedback] fz or norm
    center: tuple[float, float] | None = None  # [--center] only for a model without z
    base: tuple[float, float, float] | None = None  # [--base] None: as adapted, or chosen
    sponge_stiffness: float = 1000.0           # [--sponge-stiffness] N/m
    seed: int = 0                              # [--seed]

    def validate(self) -> None:
        if not self.frequency_scales or min(self.frequency_scales) <= 0:
            raise InputError("--frequency-scale: give one or more positive scales")
        if max(self.frequency_scales) > MAX_SCALE:
            raise InputError(f"--frequency-scale: at most {MAX_SCALE:g} times the demonstrated "
                             "tempo")
        unknown = [m for m in self.modes if m not in MODES]
        if unknown or not self.modes:
            raise InputError(f"--mode: unknown {unknown}; choose from {', '.join(MODES)}")
        if self.periods < 1 or self.warmup_periods < 0:
            raise InputError("--periods must be >= 1 and --warmup-periods >= 0")


@dataclass
class RunResult:
    """One (scale, mode) run."""

    scale: float
    mode: str
    requested_hz: float   # the tempo asked for
    frequency_hz: float   # the tempo it ran at (lower when the arm cannot follow)
    motion_start: float   # s: the movement started
    start: float          # s: the scored window started (after the warm-up)
    end: float            # s: the run ended (completed or stopped)
    planned: float        # s: planned scored duration
    stop_reason: str | None

    def scored(self) -> tuple[float, float]:
        """The scored window (start, end] s; a run stopped during its warm-up is scored from
        the start of its movement to the stop."""
        return (self.start if self.end > self.start else self.motion_start), self.end


def _model_setting(model: PeriodicModel, key: str, default):
    return (model.surface or {}).get(key, default)


def _adapted_pose(model: PeriodicModel, source: str) -> tuple[BasePose, float | None]:
    """The platform pose and the hip pitch (rad) adapt placed the robot with (the model's
    ``surface.placement``); the platform at the origin for a model without one."""
    placement = _model_setting(model, "placement", {})
    try:
        x, y, yaw = (float(value) for value in placement.get("base", (0.0, 0.0, 0.0)))
        hip = placement.get("torso", [None])[0]
        hip = None if hip is None else float(hip)
        if not all(map(math.isfinite, (x, y, yaw, 0.0 if hip is None else hip))):
            raise ValueError
    except (AttributeError, TypeError, ValueError, IndexError, KeyError):
        raise InputError(f"{source}: surface.placement is not what adapt writes (base: x, y, "
                         "yaw; torso: hip pitch first)") from None
    return BasePose(x, y, yaw), hip


def _lowering_onto(task: WipingTask, xy: np.ndarray, z: float, label: int):
    session = task.session
    yield from session.moving_to([*xy, task.start_height + 0.03], 0.8, mode=MOVE)
    if z < task.start_height + 0.03:
        yield from session.moving_to([*xy, z], 0.6, mode=label)


def run_steps(task: WipingTask, model: PeriodicModel, scale: float, mode: str, label: int,
              params: ReplayParams, z_plane: float) -> Generator[bool, None, RunResult]:
    """One run of the model's x, y and, if adapted, its z for the run's tempo, from phase 0,
    one control period per iteration (True while it wipes, None while the hand moves to and
    from the surface; ``wipelab live`` runs it on its clock); returns its
    :class:`RunResult`."""
    session = task.session
    dt = session.dt
    requested = scale * model.frequency_hz
    frequency = task.executable_frequency(requested)
    omega = 2.0 * math.pi * frequency
    learned = mode.startswith("learned")
    path = PathGenerator(at_frequency(model, frequency), ("x", "y", "z") if learned else ("x", "y"))
    start = path.position
    compliance_on = mode in ("learned+compliance", "compliance")
    reference = {"learned": None, "learned+compliance": None, "compliance": task.start_height,
                 "planar": z_plane}[mode]
    period = 2.0 * math.pi / omega
    planned = params.periods * period
    end_phase = 2.0 * math.pi * (params.warmup_periods + params.periods)
    motion_start = score_from = math.inf
    stop = None
    try:
        yield from _lowering_onto(task, start[:2], start[2] if learned else reference, label)
        session.integrator.offset_ = 0.0
        task.world.set_tool_speed(path.max_speed(omega))
        motion_start = session.time
        score_from = motion_start + params.warmup_periods * period
        while path.phase < end_phase:
            position, velocity = path.step(omega, dt)
            z_ref = position[2] if learned else reference
            vz = velocity[2] if learned else 0.0   # z_r moves?
            session.tick(position[:2], z_ref, compliance_on, path.phase,
                         velocity=np.array([velocity[0], velocity[1], vz]), mode=label)
            yield True
    except SafetyStop as error:
        stop = str(error)
        motion_start = min(motion_start, session.time)
    end = session.time
    session.integrator.offset_ = 0.0
    if stop is None:
        tcp = session.trace.last("tcp_cmd")
        yield from session.moving_to([tcp[0], tcp[1], task.start_height + 0.03], 0.5, mode=MOVE)
    return RunResult(scale, mode, requested, frequency, motion_start, score_from, end, planned,
                     stop)


def run_metrics(task: WipingTask, trace: dict, run: RunResult, target_force: float) -> dict:
    """Metrics of the run's scored window (:meth:`RunResult.scored`)."""
    start, end = run.scored()
    window = (trace["t"] > start) & (trace["t"] <= end)
    tempo = {"frequency_hz": run.frequency_hz, "requested_frequency_hz": run.requested_hz,
             "arm_limited": run.frequency_hz < run.requested_hz - 1e-9}
    if not window.any():
        return {**tempo, "safety_stop": run.stop_reason, "scored_time_s": 0.0,
                "contact_fraction": 0.0}
    result = {**tempo, **force_metrics(trace["force"][window], trace["sponge_force"][window],
                                       target_force)}
    scored = float(window.sum() * task.session.dt)
    # a stopped run did not wipe for the rest of its planned time
    result["contact_fraction"] *= min(1.0, scored / run.planned)
    result.update(coverage(task.surface.height_at, trace["sponge_pos"][window],
                           trace["sponge_quat"][window], trace["sponge_force"][window],
                           task.options.sponge.size))
    tracking = np.linalg.norm(trace["tcp"][window] - trace["tcp_cmd"][window], axis=1)
    result.update(tracking_error_rms_m=float(np.sqrt(np.mean(tracking ** 2))),
                  tracking_error_max_m=float(tracking.max()))
    result["safety_stop"] = run.stop_reason
    result["scored_time_s"] = scored
    return result


@single_threaded_blas
def run_replay(model_path: str | os.PathLike, out_dir: str | os.PathLike,
               params: ReplayParams = ReplayParams(), quiet: bool = False) -> dict:
    """Run the replay stage; returns the metrics (also written to ``metrics.json``)."""
    params.validate()
    model_path = Path(model_path)
    model = read_model(model_path)
    require_dofs(model, ("x", "y"), str(model_path))
    has_z = "z" in model.dofs
    modes = tuple(params.modes) if has_z else tuple(m for m in params.modes if m not in _NEEDS_Z)
    if not modes:
        raise InputError(f"{model_path}: the model has no learned z (run adapt first); "
                         "only --mode compliance can replay it")
    surface_spec = params.surface or _model_setting(model, "spec", "flat")
    surface = load_surface(surface_spec)
    force = params.force if params.force is not None else _model_setting(model, "target_force_n",
                                                                           10.0)
    feedback = params.feedback or _model_setting(model, "feedback", "norm")
    try:
        options = TaskOptions(sponge=SpongeParams(stiffness=params.sponge_stiffness),
                              compliance=ComplianceParams(target_force=force, feedback=feedback),
                              seed=params.seed)
    except ValueError as error:
        raise InputError(f"replay: {error}") from None
    base = None if params.base is None else BasePose(*params.base)
    with long_lived_objects():  # kernels and simulator: kept to the end
        if has_z:   # the path, the platform and the torso as adapted, unless --base moves it
            adapted_base, hip_pitch = _adapted_pose(model, str(model_path))
            centre = dof_waveform(model, ("x", "y"))
            centre = 0.5 * (centre.min(axis=0) + centre.max(axis=0))
            placement = place_task(model, surface, options, str(model_path), centre,
                                   base or adapted_base, hip_pitch)
        else:
            placement = place_task(model, surface, options, str(model_path), params.center, base)
        model = placement.model
        z_plane = float(np.mean(dof_waveform(model, ("z",)))) if has_z else math.nan
        parameters = json_parameters(replace(params, modes=modes))
        parameters.update(surface=surface_spec, force=force, feedback=feedback)
        task = build_task(model, surface, placement.options, str(model_path), placement.plan)
    try:
        session = task.session
        start = dof_waveform(model, ("x", "y"), [0.0])[0]
        session.move_to([*start, task.start_height + CALIBRATION_LIFT], 1.5, mode=MOVE)
        session.calibrate()
        segments = [Segment("approach", MOVE, 0.0)]
        runs = []
        steps = sum(int(math.ceil((params.periods + params.warmup_periods) / (
            task.executable_frequency(s * model.frequency_hz) * session.dt)))
            for s in params.frequency_scales) * len(modes)
        with tqdm(total=steps, desc="replay", unit="step", disable=quiet, leave=False) as bar:
            for scale in params.frequency_scales:
                for mode in modes:
                    label = len(runs) + 1
                    hz = task.executable_frequency(scale * model.frequency_hz)
                    segments.append(Segment(f"{speed_label(scale, hz)} {mode}", label,
                                            session.time))
                    periods = run_steps(task, model, scale, mode, label, params, z_plane)
                    while True:
                        try:
                            wiping = next(periods)
                        except StopIteration as done:
                            runs.append(done.value)
                            break
                        bar.update(bool(wiping))
        segments.append(Segment("end", MOVE, session.time))
        trace = session.trace.arrays()
        metrics = {"format": "wipelab.replay_metrics/1", "surface": surface.describe(),
                   "demonstrated_frequency_hz": model.frequency_hz,
                   "learning_frequency_hz": _model_setting(model, "learning_frequency_hz", None),
                   "max_frequency_hz": task.max_frequency_hz, "placement": placement.record,
                   "target_force_n": force,
                   "feedback": feedback, "periods": params.periods, "scales": {}}
        for run in runs:
            metrics["scales"].setdefault(f"{run.scale:g}", {})[run.mode] = \
                run_metrics(task, trace, run, force)
        metrics["sim_time_s"] = float(trace["t"][-1])
        inputs = {"model": model_path}
        if Path(surface_spec).suffix.lower() == ".toml":
            inputs["surface"] = Path(surface_spec)
        with staged_output(out_dir) as tmp:
            write_json(tmp / "metrics.json", metrics)
            with StageRecorder(tmp, "replay", parameters, inputs,
                               replay_blueprint(trace, modes)) as rec:
                log_run(rec, "replay", task, trace, segments, (), model,
                        [ReplayRun(run.mode, run.scale, run.frequency_hz, *run.scored())
                         for run in runs])
                log_placement(rec, "replay", float(trace["t"][0]), placement.record)
            write_json(tmp / "manifest.json",
                       {**build_manifest("replay", inputs, parameters, params.seed),
                        "placement": placement.record})
    finally:
        task.close()
    return metrics
