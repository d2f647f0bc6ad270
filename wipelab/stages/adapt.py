"""The adapt stage: learn the force profile of a surface on the simulated ARMAR-IIIb (Sec. II-B).

The model's x-y path (its oscillation scaled by ``amplitude_scale``) is placed on the surface
and the platform is placed in front of it (:func:`~wipelab.sim.task.place_task`: the
placement search of :mod:`~wipelab.sim.placement`, checked with the full IK; ``center`` and
``base`` fix either or both; the choice is in ``metrics.json``, the manifest, the adapted
model's ``surface`` entry and the logs). The adapted model has ``kernels`` kernels (50 by
default, twice the learn stage's 25: a surface's height profile has sharper features than a
hand's wiping path, and the locally constant fit of eqs. 13-15 smooths it by about a kernel
width); the x-y path is refitted onto them
(:func:`~wipelab.sim.path.with_kernels`, its error is in ``metrics.json``, a few hundredths of
a millimetre). Then :class:`~wipelab.sim.adaptation.Adaptation` runs: online learning at the
slowed-down tempo as in the paper, refining by iterative learning at the learning tempo and
at ``tempos`` times the demonstrated one, and a hold at the demonstrated tempo (its docstring
has the details).

Outputs: ``adapted_model.json`` (x, y as placed, learned ``z`` and ``z_per_hz``; ``surface``
records where and how it was learned), ``metrics.json``, ``adapt.mcap``, ``adapt.rrd``,
``manifest.json``.
"""

from __future__ import annotations

import math
import os
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
from tqdm import tqdm

from wipelab.control.compliance import ComplianceParams
from wipelab.control.force_profile import ProfileLearningParams
from wipelab.control.iterative_learning import IterativeLearningParams
from wipelab.blas_threads import single_threaded_blas
from wipelab.errors import InputError
from wipelab.logs import StageRecorder
from wipelab.long_lived import long_lived_objects
from wipelab.manifest import build_manifest, sha256_file, write_json
from wipelab.model_file import read_model
from wipelab.sim.adaptation import Adaptation, AdaptationParams
from wipelab.sim.metrics import coverage, force_metrics, profile_error
from wipelab.sim.path import (at_frequency, place_model, refit_error, require_dofs,
                              with_kernels)
from wipelab.sim.recording import adapt_blueprint, log_placement, log_run
from wipelab.sim.sponge import SpongeParams
from wipelab.sim.surfaces import load_surface
from wipelab.sim.task import TaskOptions, WipingTask, build_task, place_task
from wipelab.sim.world import BasePose
from wipelab.stage_output import staged_output


@dataclass(frozen=True)
class AdaptParams:
    """Parameters of ``wipelab adapt`` (CLI flags in brackets)."""

    surface: str = "flat"              # [--surface] built-in name or TOML file
    center: tuple[float, float] | None = None  # [--center] m, world; None: chosen
    amplitude_scale: float = 1.0       # [--amplitude-scale] of the x-y oscillation
    slowdown: float = 4.0              # [--slowdown] Omega is divided by this while learning
    periods: int = 8                   # [--periods] most online learning periods
    tempos: tuple[float, ...] = (1.0,)  # [--tempos] refined at these x the demonstrated tempo
    hold_periods: int = 1              # [--hold-periods] at the demonstrated tempo, after
    force: float = 10.0                # [--force] F_0 in N
    feedback: str = "norm"             # [--feedback] fz or norm
    base: tuple[float, float, float] | None = None  # [--base] x, y (m), yaw (rad); None: chosen
    sponge_stiffness: float = 1000.0   # [--sponge-stiffness] N/m
    seed: int = 0                      # [--seed] sensor noise
    kernels: int = 50                  # [--kernels] N of the adapted model (x-y refitted)
    learning: ProfileLearningParams = field(default_factory=ProfileLearningParams)
    iterative: IterativeLearningParams = field(default_factory=IterativeLearningParams)

    def task_options(self) -> TaskOptions:
        """The robot/world options these parameters imply (InputError if invalid)."""
        try:
            compliance = ComplianceParams(target_force=self.force, feedback=self.feedback)
            sponge = SpongeParams(stiffness=self.sponge_stiffness)
        except ValueError as error:
            raise InputError(f"adapt: {error}") from None
        return TaskOptions(sponge=sponge, compliance=compliance, seed=self.seed)

    def adaptation(self) -> AdaptationParams:
        return AdaptationParams(self.slowdown, self.periods, tuple(self.tempos),
                                self.hold_periods, self.learning, self.iterative)

    def validate(self) -> None:
        if not self.slowdown >= 1.0:
            raise InputError(f"--slowdown: must be >= 1, got {self.slowdown}")
        if not (self.periods >= 1 and self.hold_periods >= 0):
            raise InputError("--periods must be >= 1 and --hold-periods >= 0")
        if not 5 <= self.kernels <= 200:
            raise InputError(f"--kernels: must be in [5, 200], got {self.kernels}")
        if not 0 < self.amplitude_scale <= 3:
            raise InputError(f"--amplitude-scale: must be in (0, 3], got {self.amplitude_scale}")
        if any(not 0 < t <= 3 for t in self.tempos):
            raise InputError(f"--tempos: each must be in (0, 3] (x the demonstrated tempo), "
                             f"got {list(self.tempos)}")


def _window(trace: dict, start: float, end: float) -> np.ndarray:
    return (trace["t"] > start) & (trace["t"] <= end)


def adapt_metrics(task: WipingTask, run: Adaptation, trace: dict, adapted, params: AdaptParams
                  ) -> dict:
    """metrics.json of an adaptation ``run`` on ``task`` (``trace``: the session's trace as
    arrays; ``adapted``: its adapted model; ``params``: force, feedback and tolerance)."""
    f0 = params.force
    learning_hz = run.learning_omega / (2.0 * math.pi)
    learning_start = run.segments[1].start if len(run.segments) > 1 else math.inf
    last_learning = _window(trace, max(learning_start, run.end_of_online_learning
                                       - 1.0 / learning_hz), run.end_of_online_learning)
    hold = _window(trace, run.hold_start, run.segments[-1].start)

    def profile(window, frequency_hz):
        if not window.any():
            return None
        expected = task.expected_contact_height(trace["tcp"][window, :2], trace["tcp_rot"][window])
        model = at_frequency(adapted, frequency_hz)
        learned = model.waveform(trace["phase"][window])[:, model.dofs.index("z")]
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
        "demonstrated_frequency_hz": adapted.frequency_hz,
        "learning_frequency_hz": learning_hz,
        "hold_frequency_hz": run.hold_frequency_hz,
        "max_frequency_hz": task.max_frequency_hz,
        "learning": {
            "periods": run.monitor.periods_,
            "converged": run.monitor.converged,
            "tolerance_m": params.learning.tolerance,
            "waveform_change_per_period_m": changes,
            "online_end_time_s": run.end_of_online_learning,
            "end_time_s": run.end_of_learning,
        },
        "tempos": [stage.describe() for stage in run.stages],
        "profile_last_learning_period": profile(last_learning, learning_hz),
        "profile_hold": profile(hold, run.hold_frequency_hz),
        "force_last_learning_period": forces(last_learning),
        "force_hold": forces(hold),
        "safety_stop": run.stop_reason,
        "sim_time_s": float(trace["t"][-1]) if len(trace["t"]) else 0.0,
    }


@single_threaded_blas
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
    with long_lived_objects():  # kernels and simulator: kept to the end
        model = read_model(model_path)
        require_dofs(model, ("x", "y"), str(model_path))
        surface = load_surface(params.surface)
        as_learned = place_model(model, (0.0, 0.0), params.amplitude_scale)
        refitted = with_kernels(as_learned, params.kernels)
        base = None if params.base is None else BasePose(*params.base)
        placement = place_task(refitted, surface, params.task_options(), str(model_path),
                               params.center, base)
        placed = placement.model
        parameters = json_parameters(params)
        task = build_task(placed, surface, placement.options, str(model_path), placement.plan)
    try:
        run = Adaptation(task, placed, params.adaptation())
        with tqdm(desc="adapt", unit="step", disable=quiet, leave=False) as bar:
            while run.step():
                bar.update()
        trace = task.session.trace.arrays()
        source = {"stage": "adapt", "model_sha256": sha256_file(model_path),
                  "parameters": parameters}
        surface_entry = {"spec": params.surface, **surface.describe(),
                         "placement": placement.record,
                         "learning_frequency_hz": run.learning_omega / (2.0 * math.pi),
                         "tempos_hz": sorted(run.heights),
                         "target_force_n": params.force, "feedback": params.feedback}
        adapted = run.adapted_model(source, surface_entry)
        metrics = adapt_metrics(task, run, trace, adapted, params)
        metrics["placement"] = placement.record
        metrics["kernels"] = {"model": model.kernels, "adapted": adapted.kernels,
                              "xy_refit_error_m": refit_error(as_learned, refitted, ("x", "y"))}
        inputs = {"model": model_path}
        if Path(params.surface).suffix.lower() == ".toml":
            inputs["surface"] = Path(params.surface)
        with staged_output(out_dir) as tmp:
            write_json(tmp / "adapted_model.json", adapted.to_dict())
            write_json(tmp / "metrics.json", metrics)
            with StageRecorder(tmp, "adapt", parameters, inputs, adapt_blueprint(trace)) as rec:
                log_run(rec, "adapt", task, trace, run.segments, run.profiles, adapted)
                log_placement(rec, "adapt", float(trace["t"][0]), placement.record)
            write_json(tmp / "manifest.json",
                       {**build_manifest("adapt", inputs, parameters, params.seed),
                        "placement": placement.record})
    finally:
        task.close()
    return metrics


def json_parameters(params) -> dict:
    """Stage parameters as plain JSON."""
    data = asdict(params)
    return {k: (list(v) if isinstance(v, tuple) else v) for k, v in data.items()}
