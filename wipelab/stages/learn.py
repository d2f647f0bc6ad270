"""The learn and rollout stages: a demonstration -> a periodic movement model -> a trajectory.

``learn`` reads a Trajectory CSV (or the ``/track/position`` series of a track.mcap), checks
that the chosen DOFs move periodically, learns the
two-layer model (online by default, as the robot watching the demonstration would; or offline
over the whole recording) and writes ``model.json``, ``learn.mcap``, ``learn.rrd`` and
``manifest.json``. ``rollout`` integrates a model into a Trajectory CSV at any frequency,
amplitude and anchor.

Logged topics (MCAP topic = Rerun entity), time = the input's time in seconds:

    /input/trajectory             the demonstration, one series per DOF (m), null in a gap
    /input/valid                  1 where the input was observed, 0 in a gap (learned nothing)
    /oscillators/frequency_hz     every oscillator's frequency (AFO pool: omega_1..3, Fig. 4)
    /oscillators/fundamental_hz   the selected fundamental Omega / 2 pi
    /learner/hand_overs           detected periods handed to the canonical system so far
                                  (1 after the start-up; more when the supervisor re-locks)
    /dmp/<dof>/waveform           input (demonstrated) vs learned movement of one DOF (m,
                                  Fig. 5); the input is null where it was not observed
    /dmp/<dof>/weights            the weights w_00.. as they converge
    /dmp/<dof>/period             one period over the phase: the learned waveform with the
                                  weights so far, and the demonstration's last period
                                  (wipelab.PhaseCurves, up to 60 times)
    /model                        model.json at the end of the input (schema wipelab.Model)
"""

from __future__ import annotations

import math
import os
import sys
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np
import rerun.blueprint as rrb
from tqdm import tqdm

from wipelab.errors import InputError
from wipelab.learning import (CANONICAL_SYSTEMS, MODEL_FORMAT, LearnHistory, OfflineParameters,
                              OnlineParameters, PeriodicModel, harmonic_fit, learn_offline,
                              learn_online, periodicity, to_uniform)
from wipelab.logs import StageRecorder, stage_panels, whole_run
from wipelab.logs.palette import (INPUT_COLOUR, LEARNED_COLOUR, OSCILLATOR_COLOURS,
                                  REFERENCE_COLOUR)
from wipelab.logs.phase_chart import PhaseChart
from wipelab.manifest import build_manifest, sha256_file, write_json
from wipelab.model_file import read_model
from wipelab.stage_output import staged_file, staged_output
from wipelab.trajectory_csv import Trajectory, read_trajectory, write_trajectory

MODES = ("online", "offline")
#: Where a track.mcap holds the sponge position (names x, y, z; valid frames only).
TRACK_TOPIC = "/track/position"
#: Fewest samples a demonstration may have.
MIN_SAMPLES = 20
#: The learned period is logged at most this many times (over the phase, /dmp/<dof>/period).
PERIOD_SNAPSHOTS = 60
#: Phases of the logged period, and the fewest demonstrated samples a period is drawn from.
PERIOD_PHASES = np.linspace(0.0, 2.0 * math.pi, 129)
MIN_PERIOD_SAMPLES = 8
#: Most samples on a time grid, of a demonstration or a rollout (a week at 30 Hz, 5.5 h of
#: 1 kHz motion capture); irregular time stamps or a typo in --periods ask for far more.
MAX_SAMPLES = 20_000_000


@dataclass(frozen=True)
class LearnParams:
    """Parameters of ``wipelab learn`` (CLI flags in brackets)."""

    mode: str = "online"                 # [--mode] online (sample by sample) or offline
    dofs: tuple[str, ...] = ("x", "y")   # [--dofs] columns to learn, world frame (m)
    kernels: int = 25                    # [--kernels] N
    width: float | None = None           # [--width] h of eq. 8; None -> 2.5 N
    canonical: str = "afs"               # [--canonical] afs or afo (online mode)
    seed: int = 0                        # [--seed] recorded; learning draws no random numbers
    min_frequency_hz: float = 0.1        # fundamentals searched in [min, max] (Hz)
    max_frequency_hz: float = 5.0
    min_periodicity: float = 0.7         # refuse input whose periodicity score is lower
    min_periods: float = 3.0             # refuse input shorter than this many periods

    def __post_init__(self):
        if self.mode not in MODES:
            raise InputError(f"--mode: must be one of {', '.join(MODES)}, got {self.mode!r}")
        if self.canonical not in CANONICAL_SYSTEMS:
            raise InputError(f"--canonical: must be one of {', '.join(CANONICAL_SYSTEMS)}, "
                             f"got {self.canonical!r}")
        if not self.dofs or len(set(self.dofs)) != len(self.dofs) or "t" in self.dofs \
                or not all(self.dofs):
            raise InputError(f"--dofs: need distinct column names other than t, got "
                             f"{','.join(self.dofs)!r}")
        if self.kernels < 2:
            raise InputError(f"--kernels: must be at least 2, got {self.kernels}")
        if self.width is not None and not self.width > 0:
            raise InputError(f"--width: must be positive, got {self.width}")


def learn_blueprint(dofs) -> rrb.Blueprint:
    """Default Rerun layout: the frequencies from t = 0; per DOF the demonstration against
    the learned movement over time, and the learned period over the phase."""
    return rrb.Blueprint(
        rrb.Vertical(
            rrb.TimeSeriesView(origin="/oscillators", name="frequency adaptation (Hz)",
                               axis_x=whole_run(), plot_legend=rrb.PlotLegend("RightTop")),
            rrb.Horizontal(*[rrb.TimeSeriesView(origin=f"/dmp/{dof}/waveform",
                                                name=f"{dof}: input (demonstrated) vs learned (m)",
                                                axis_x=whole_run(),
                                                plot_legend=rrb.PlotLegend("RightTop"))
                             for dof in dofs]),
            rrb.Horizontal(*[rrb.Spatial2DView(origin=f"/dmp/{dof}/period",
                                               name=f"{dof}: the learned period over the phase "
                                                    f"(rad), as learning goes",
                                               visual_bounds=PhaseChart.bounds())
                             for dof in dofs]),
            row_shares=[1, 1.2, 1.3]),
        *stage_panels())


def _track_mcap(path: Path, params: LearnParams) -> Trajectory:
    """The sponge position of a track.mcap (topic /track/position, valid frames) as a Trajectory."""
    from mcap.exceptions import McapError

    from wipelab.logs import read_mcap_scalars

    try:
        t, values, names = read_mcap_scalars(path, TRACK_TOPIC)
    except FileNotFoundError:
        raise InputError(f"{path}: file not found") from None
    except (OSError, McapError, ValueError) as error:
        raise InputError(f"{path}: cannot be read as MCAP ({error.__class__.__name__}: {error})") from None
    except KeyError:
        raise InputError(f"{path}: no {TRACK_TOPIC} messages (not a track.mcap)") from None
    missing = [dof for dof in params.dofs if dof not in names]
    if missing:
        raise InputError(f"{path}: {TRACK_TOPIC} has no {', '.join(missing)} "
                         f"(has {', '.join(names)})")
    if np.any(np.diff(t) <= 0) or not np.all(np.isfinite(values)):
        raise InputError(f"{path}: {TRACK_TOPIC} times not increasing or values not finite")
    return Trajectory(path=str(path), t=t, columns={n: values[:, j] for j, n in enumerate(names)})


def _demonstration(path: Path, params: LearnParams) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The chosen DOFs on a uniform time grid (t, Y, valid); InputError for unusable input."""
    trajectory = _track_mcap(path, params) if path.suffix == ".mcap" else \
        read_trajectory(path, required=("t", *params.dofs))
    if trajectory.t[0] < 0.0:
        raise InputError(f"{path}: time column t starts at {trajectory.t[0]:g} s; "
                         f"times are seconds since the start of the recording (>= 0)")
    if int(trajectory.valid.sum()) < MIN_SAMPLES:
        raise InputError(f"{path}: too short, {int(trajectory.valid.sum())} valid rows, "
                         f"need at least {MIN_SAMPLES}")
    t_valid = trajectory.t[trajectory.valid]
    interval = float(np.median(np.diff(trajectory.t)))
    if (t_valid[-1] - t_valid[0]) / interval >= MAX_SAMPLES:
        raise InputError(f"{path}: {t_valid[-1] - t_valid[0]:.3g} s at the median sample "
                         f"interval of {interval:.3g} s are more than {MAX_SAMPLES:.0e} samples "
                         f"(irregular time stamps?)")
    return to_uniform(trajectory.t, trajectory.array(params.dofs), trajectory.valid)


def _check_periodic(path: Path, t: np.ndarray, Y: np.ndarray, valid: np.ndarray,
                    params: LearnParams):
    try:
        estimate = periodicity(t, Y, params.min_frequency_hz, params.max_frequency_hz,
                               valid=valid)
    except ValueError as error:  # e.g. samples too far apart for any wiping frequency
        raise InputError(f"{path}: {error} from {t.size} samples {t[1] - t[0]:.3g} s apart")\
            from None
    if estimate.periods < params.min_periods:
        raise InputError(f"{path}: too short, {estimate.periods:.1f} periods of "
                         f"{estimate.frequency_hz:.3g} Hz, need at least {params.min_periods:g}")
    if estimate.score < params.min_periodicity:
        raise InputError(f"{path}: the movement of {','.join(params.dofs)} is not periodic "
                         f"(periodicity {estimate.score:.2f} < {params.min_periodicity:g})")
    return estimate


def learn(trajectory: str | os.PathLike, out_dir: str | os.PathLike,
          params: LearnParams = LearnParams(), quiet: bool = False) -> PeriodicModel:
    """Learn a periodic movement model from a Trajectory CSV.

    Parameters
    ----------
    trajectory : path-like
        Trajectory CSV (DESIGN.md) with columns t and ``params.dofs``, or a track.mcap.
    out_dir : path-like
        Receives model.json, learn.mcap, learn.rrd, manifest.json (all or nothing).
    params : LearnParams
    quiet : bool
        No progress bar.

    Returns
    -------
    PeriodicModel

    Raises
    ------
    InputError
        Missing/unreadable file, missing columns, NaN/inf, too short, time not increasing,
        or movement not periodic. Online learning that never locks onto a period (never two
        periods without a gap) falls back to the offline fit, with a line on stderr and
        ``online_never_locked`` in the model's source.
    """
    path = Path(trajectory)
    t, Y, valid = _demonstration(path, params)
    estimate = _check_periodic(path, t, Y, valid, params)
    # Phase 0 is where the DOF with the strongest fundamental peaks.
    reference = int(np.argmax(harmonic_fit(t, Y, estimate.frequency_hz).fundamental))
    parameters = asdict(params) | {"dofs": list(params.dofs)}
    source = {"file": path.name, "sha256": sha256_file(path), "stage": "learn",
              "parameters": parameters, "reference_dof": params.dofs[reference],
              "periodicity": round(estimate.score, 6)}
    whole_recording = params.mode == "offline"
    if not whole_recording:
        online = OnlineParameters(canonical=params.canonical, kernels=params.kernels,
                                  width=params.width)
        with tqdm(total=t.size, desc="learn", unit="sample", disable=quiet, file=sys.stderr,
                  leave=False) as bar:
            model, history = learn_online(t, Y, online, params.dofs, reference, source,
                                          progress=bar.update, valid=valid)
        if history.hand_overs[-1] == 0:
            # gaps too many for the detector's two periods in a row: the whole recording still
            # holds the movement, and the user gets a model, told how it was made
            source["online_never_locked"] = whole_recording = True
            print(f"learn: {path}: online learning never locked onto a period (its detector "
                  f"needs two periods without a gap); the model is fitted offline to the whole "
                  f"recording", file=sys.stderr)
    if whole_recording:
        offline = OfflineParameters(kernels=params.kernels, width=params.width,
                                    min_frequency_hz=params.min_frequency_hz,
                                    max_frequency_hz=params.max_frequency_hz)
        model, history = learn_offline(t, Y, offline, params.dofs, reference, source, valid)
    inputs = {"trajectory": path}
    with staged_output(out_dir) as tmp:
        write_json(tmp / "model.json", model.to_dict())
        with StageRecorder(tmp, "learn", parameters, inputs, learn_blueprint(params.dofs)) as rec:
            _log(rec, model, history)
        write_json(tmp / "manifest.json", build_manifest("learn", inputs, parameters, params.seed))
    return model


def _log(rec: StageRecorder, model: PeriodicModel, history: LearnHistory) -> None:
    """Everything the learner went through (see the module docstring for the topics)."""
    t = history.t
    gaps = ~history.valid
    # what the learner did not see is not drawn: a gap in the demonstration stays a gap
    demonstrated = np.where(gaps[:, None], np.nan, history.input)
    rec.scalars("/input/trajectory", t, demonstrated, names=model.dofs)
    rec.scalars("/input/valid", t, history.valid.astype(np.float64), names=["valid"])
    count = history.oscillators_hz.shape[1]
    names = ["omega"] if count == 1 else [f"omega_{i + 1}" for i in range(count)]
    rec.scalars("/oscillators/frequency_hz", t, history.oscillators_hz, names=names,
                colors=np.array(OSCILLATOR_COLOURS[:count]))
    rec.scalars("/oscillators/fundamental_hz", t, history.fundamental_hz, names=["fundamental"],
                colors=np.array([REFERENCE_COLOUR]))
    rec.scalars("/learner/hand_overs", t, history.hand_overs.astype(np.float64),
                names=["hand_overs"])
    weight_names = [f"w_{i:02d}" for i in range(model.kernels)]
    for j, dof in enumerate(model.dofs):
        rec.scalars(f"/dmp/{dof}/waveform", t,
                    np.column_stack([demonstrated[:, j], history.output[:, j]]),
                    names=["input", "learned"], colors=np.array([INPUT_COLOUR, LEARNED_COLOUR]))
        rec.scalars(f"/dmp/{dof}/weights", history.weights_t, history.weights[:, j, :],
                    names=weight_names)
    _log_periods(rec, model, history, demonstrated)
    rec.json("/model", float(t[-1]), model.to_dict(), schema_name="wipelab.Model",
             schema={"title": "wipelab.Model", "type": "object",
                     "properties": {"format": {"const": MODEL_FORMAT}},
                     "required": ["format", "frequency_hz", "dofs", "weights"]})


def _log_periods(rec: StageRecorder, model: PeriodicModel, history: LearnHistory,
                 demonstrated: np.ndarray) -> None:
    """Per DOF, over one period of the phase: the learned waveform with the weights learned
    so far (and the model's goal and amplitude) and the demonstration's last period, at up to
    :data:`PERIOD_SNAPSHOTS` of the weight snapshots."""
    step = max(1, int(np.ceil(len(history.weights_t) / PERIOD_SNAPSHOTS)))
    picks = list(range(0, len(history.weights_t), step))
    if picks[-1] != len(history.weights_t) - 1:
        picks.append(len(history.weights_t) - 1)
    snapshots = []
    for k in picks:
        time = float(history.weights_t[k])
        learned = replace(model, weights=history.weights[k]).waveform(PERIOD_PHASES)
        now = min(np.searchsorted(history.t, time, side="right"), len(history.t)) - 1
        period = 1.0 / max(float(history.fundamental_hz[now]), 1e-6)
        window = (history.t > time - period) & (history.t <= time) & history.valid
        shown = np.full((len(PERIOD_PHASES), len(model.dofs)), np.nan)
        if window.sum() >= MIN_PERIOD_SAMPLES:
            phase = np.mod(history.phase[window], 2.0 * math.pi)
            order = np.argsort(phase)
            for j in range(len(model.dofs)):
                shown[:, j] = np.interp(PERIOD_PHASES, phase[order],
                                        demonstrated[window, j][order], period=2.0 * math.pi)
        snapshots.append((time, learned, shown))
    for j, dof in enumerate(model.dofs):
        values = np.concatenate([np.concatenate([learned[:, j], shown[:, j]])
                                 for _, learned, shown in snapshots])
        chart = PhaseChart.fitting(values, f"{dof} (m)")
        topic = f"/dmp/{dof}/period"
        rec.phase_chart(topic, chart)
        rec.phase_legend(topic, chart, {"demonstrated, last period": INPUT_COLOUR,
                                        "learned so far": LEARNED_COLOUR})
        for time, learned, shown in snapshots:
            rec.phase_curves(topic, time, chart, PERIOD_PHASES,
                             {"demonstrated": shown[:, j], "learned": learned[:, j]},
                             {"demonstrated": INPUT_COLOUR, "learned": LEARNED_COLOUR})


def _per_dof(option: str, values, model: PeriodicModel) -> np.ndarray | None:
    if values is None:
        return None
    values = np.asarray(values, dtype=np.float64)
    if values.shape != (len(model.dofs),) or not np.all(np.isfinite(values)):
        raise InputError(f"{option}: need {len(model.dofs)} finite numbers "
                         f"({','.join(model.dofs)}), got {values.tolist()}")
    return values


def rollout(model_path: str | os.PathLike, out_csv: str | os.PathLike, periods: float = 10.0,
            frequency_hz: float | None = None, rate_hz: float = 100.0,
            amplitude_scale: float = 1.0, goal=None) -> tuple[np.ndarray, np.ndarray]:
    """Integrate a model (eqs. 6-7) and write t and one column per DOF to a Trajectory CSV.

    Parameters
    ----------
    model_path : path-like
        model.json (``wipelab.periodic_dmp/1``).
    out_csv : path-like
        Output Trajectory CSV (written atomically).
    periods : float
        Length in periods of the rollout frequency.
    frequency_hz : float, optional
        Rollout frequency (default: the learned one).
    rate_hz : float
        Sample rate (Hz).
    amplitude_scale : float
        Factor on the amplitudes r.
    goal : sequence of float, optional
        New anchors g, one per DOF (m).

    Returns
    -------
    t, y : ndarray, shapes (n,) and (n, d)
    """
    model = read_model(model_path)
    for option, value in (("--periods", periods), ("--rate", rate_hz),
                          ("--amplitude-scale", amplitude_scale)):
        if not (math.isfinite(value) and value > 0):
            raise InputError(f"{option}: must be a positive number, got {value}")
    if frequency_hz is not None and not (math.isfinite(frequency_hz) and frequency_hz > 0):
        raise InputError(f"--frequency: must be a positive number, got {frequency_hz}")
    frequency_hz = model.frequency_hz if frequency_hz is None else frequency_hz
    samples = periods / frequency_hz * rate_hz
    if not 2 <= samples <= MAX_SAMPLES:
        raise InputError(f"--periods, --frequency, --rate: {periods:g} periods at "
                         f"{frequency_hz:g} Hz sampled at {rate_hz:g} Hz make {samples:.3g} "
                         f"samples; give between 2 and {MAX_SAMPLES:.0e}")
    t, y = model.rollout(periods / frequency_hz, rate_hz, frequency_hz,
                         amplitude=model.amplitude * amplitude_scale,
                         goal=_per_dof("--goal", goal, model))
    with staged_file(out_csv) as tmp:
        write_trajectory(tmp, t, {dof: y[:, j] for j, dof in enumerate(model.dofs)})
    return t, y
