"""Benchmarks of the learn stage (issue 2): frequency, waveform, modulation, peer, speed.

Run: ``python benchmarks/bench_learn.py`` (under a minute on one core). Prints Markdown
tables. Signals (:mod:`wipelab.learning.signals`): two DOFs with an offset, 2nd and 3rd
harmonics and white noise of 2 % of each DOF's amplitude, sampled at 30 Hz (vision) and
500 Hz, fundamentals 0.3-3 Hz, optionally with a frequency step half-way.

Every canonical system is shown twice: as the learner runs it (the start-up period detector
hands its estimate to the oscillators) and with the oscillators alone (``start_up=False``),
so that what the detector contributes and what the oscillators do by themselves are both
on the table.

The last frequency table uses human-like demonstrations instead: synth's motion model
(:class:`wipelab.vision.WipingMotion`: tempo wandering by 4 %, amplitude and centre drifting,
strokes that are not sinusoids), 60 s at 30 Hz with two 1.5 s stretches not observed, as a
tracker delivers them.
"""

from __future__ import annotations

import math
import os
import time
from dataclasses import replace

import numpy as np

from wipelab.learning import (AFOParameters, AFSParameters, OnlineLearner, OnlineParameters,
                              PeriodDetectorParameters, PeriodicModel, fit_weights, learn_offline,
                              learn_online)
from wipelab.learning.demonstrator import HELD_OUT_SEEDS, DemonstratorParams, demonstrate
from wipelab.learning.period_detector import detector_update, new_detector
from wipelab.learning.signals import (WIPING_SHAPES, HarmonicShape, periods_to_tolerance,
                                      waveform_rms_percent, wiping_signal)
from wipelab.vision import PATTERNS, WipingMotion, WipingMotionParams

FREQUENCIES_HZ = (0.3, 0.5, 1.0, 2.0, 3.0)
RATES_HZ = (30.0, 500.0)
SEEDS = (0, 1)
_GAINS = {
    "AFS, wipelab gains (default)": OnlineParameters(),
    "AFO pool, wipelab gains": OnlineParameters(canonical="afo"),
    "AFS, Petric gains (K = K_Omega = 20, nu = 2)": OnlineParameters(afs=AFSParameters.petric()),
    "AFO pool, paper gains (K = K_Omega = 20)": OnlineParameters(canonical="afo", afo=AFOParameters.paper()),
}
SYSTEMS = {f"{name}, {variant}": replace(params, start_up=start_up)
           for start_up, variant in ((True, "start-up detector"), (False, "oscillators alone"))
           for name, params in _GAINS.items()}
DEFAULTS = list(SYSTEMS)[:2]
SCHEDULED = OnlineParameters(afs=AFSParameters(locked_coupling=0.5, residual_gain=100.0))


def table(title: str, header: list[str], rows: list[list]) -> None:
    print(f"\n### {title}\n")
    print("| " + " | ".join(header) + " |")
    print("|" + "|".join("---" for _ in header) + "|")
    for row in rows:
        print("| " + " | ".join(_cell(v) for v in row) + " |")


def _cell(value) -> str:
    if isinstance(value, float):
        return "never" if math.isinf(value) else f"{value:.3g}" if abs(value) < 0.01 else f"{value:.2f}"
    return str(value)


def _summary(values) -> list[float]:
    values = np.asarray(values, dtype=float)
    return [float(np.median(values)), float(values.max()), int((values <= 6.0).sum()), values.size]


def frequency_tables() -> None:
    """Periods until the fundamental is within 1 % for good, per canonical system."""
    rows, summaries = [], []
    for name, params in SYSTEMS.items():
        cells = []
        for rate_hz in RATES_HZ:
            for f in FREQUENCIES_HZ:
                t = np.arange(0, 12 / f, 1 / rate_hz)
                worst = 0.0
                for seed in SEEDS:
                    Y, _ = wiping_signal(t, f, seed=seed)
                    _, history = learn_online(t, Y, params)
                    worst = max(worst, periods_to_tolerance(t, history.fundamental_hz, f))
                cells.append(worst)
        rows.append([name] + cells)
        summaries.append([name] + _summary(cells))
    header = ["canonical system"] + [f"{f:g} Hz @ {r:g}" for r in RATES_HZ for f in FREQUENCIES_HZ]
    table("Periods until the frequency is within 1 % and stays (worst of 2 noise seeds, 12 periods)",
          header, rows)
    table("Summary of the table above", ["canonical system", "median", "worst", "cases <= 6",
                                         "cases"], summaries)

    rows = []
    step_systems = {name: SYSTEMS[name] for name in DEFAULTS}
    step_systems["AFS with the gain schedule after the lock (c_L = 0.5, kappa = 100)"] = \
        SCHEDULED
    for name, params in step_systems.items():
        cells = []
        for rate_hz in RATES_HZ:
            for f in FREQUENCIES_HZ:
                step = 1.25 * f if f <= 1.0 else 0.8 * f
                t = np.arange(0, 24 / f, 1 / rate_hz)
                Y, _ = wiping_signal(t, f, seed=0, step_time_s=12 / f, step_frequency_hz=step)
                _, history = learn_online(t, Y, params)
                cells.append(periods_to_tolerance(t, history.fundamental_hz, step, start_s=12 / f))
        rows.append([name] + cells)
    header = ["canonical system"] + [f"{f:g}->{1.25 * f if f <= 1 else 0.8 * f:g} Hz @ {r:g}"
                                     for r in RATES_HZ for f in FREQUENCIES_HZ]
    table("Periods (of the new frequency) to re-converge within 1 % after a step at period 12",
          header, rows)

    rows = []
    for coupling in ("mean", "reference"):
        for start_up in (True, False):
            values = []
            for rate_hz in RATES_HZ:
                for f in FREQUENCIES_HZ:
                    t = np.arange(0, 12 / f, 1 / rate_hz)
                    Y, _ = wiping_signal(t, f, seed=0)
                    params = OnlineParameters(dof_coupling=coupling, start_up=start_up)
                    _, history = learn_online(t, Y, params)
                    values.append(periods_to_tolerance(t, history.fundamental_hz, f))
            rows.append([coupling, "detector" if start_up else "alone"] + _summary(values))
    table("Several DOFs, one phase: who drives it (AFS; periods to 1 %, all 10 cases)",
          ["phase driven by", "start-up", "median", "worst", "cases <= 6", "cases"], rows)


def human_tempo_table() -> None:
    """Model frequency learned from human-like demonstrations with gaps, against the nominal."""
    amplitudes = {"circle": 0.085, "line": 0.14, "figure8": 0.12}
    t = np.arange(0, 60, 1 / 30)
    gaps = ((t >= 17.0) & (t < 18.5)) | ((t >= 44.0) & (t < 45.5))
    variants = {
        "AFS (default): supervisor, tempo segments (change test), mean phase rate over <= 40 "
        "periods, gaps skipped": (OnlineParameters(), True),
        "old: eqs. 13-15, 40-period mean, no change test": (OLD, True),
        "the same, gaps bridged and fed as data": (OnlineParameters(), False),
        "the same, model frequency = fundamental of the last period":
            (OnlineParameters(frequency_periods=1.0), True),
        "the same, no supervisor": (OnlineParameters(relock_tolerance=None), True),
        "the same, gain schedule (c_L = 0.5, kappa = 30)": (replace(SCHEDULED, afs=replace(
            SCHEDULED.afs, residual_gain=30.0)), True),
        "the same, gain schedule (c_L = 0.5, kappa = 100)": (SCHEDULED, True),
        "the same, gain schedule (kappa = 100), no supervisor":
            (replace(SCHEDULED, relock_tolerance=None), True),
        "AFO pool, supervisor": (OnlineParameters(canonical="afo"), True),
        "offline": (None, True),
    }
    errors = {name: [] for name in variants}
    hand_overs = {name: [] for name in variants}
    for pattern in PATTERNS:
        for frequency_hz in (0.5, 1.0, 1.5):
            for seed in (0, 1, 2):
                motion = WipingMotion(WipingMotionParams(pattern, frequency_hz,
                                                         amplitude=amplitudes[pattern]),
                                      0.8, 0.03, seed)
                Y = motion.pose(t)[0][:, :2]
                for j in range(2):                      # bridged, as the learn stage fills gaps
                    Y[gaps, j] = np.interp(t[gaps], t[~gaps], Y[~gaps, j])
                reference = 0 if pattern == "circle" else 1
                for name, (params, skip) in variants.items():
                    valid = ~gaps if skip else None
                    if params is None:
                        model, history = learn_offline(t, Y, reference_dof=reference, valid=valid)
                    else:
                        model, history = learn_online(t, Y, params, reference_dof=reference,
                                                      valid=valid)
                    errors[name].append(abs(model.frequency_hz / frequency_hz - 1.0) * 100)
                    hand_overs[name].append(int(history.hand_overs[-1]))
    rows = [[name, float(np.median(e)), float(np.max(e)), int((np.array(e) <= 1.0).sum()), len(e),
             max(hand_overs[name])] for name, e in errors.items()]
    table("Human-like demonstrations: model frequency error against the nominal, % (3 patterns "
          "x 0.5/1/1.5 Hz x 3 seeds, 60 s at 30 Hz, two 1.5 s gaps)",
          ["learner", "median", "worst", "cases <= 1 %", "cases", "most hand-overs"], rows)


def detector_table() -> None:
    """The start-up period detector on its own: when it fires and how far off it is."""
    rows = []
    for rate_hz in RATES_HZ:
        for f in FREQUENCIES_HZ:
            t = np.arange(0, 12 / f, 1 / rate_hz)
            found, errors = [], []
            for seed in SEEDS:
                Y, _ = wiping_signal(t, f, seed=seed)
                settings, state = new_detector(2, 1 / rate_hz, PeriodDetectorParameters(), 0.1, 10.0)
                k = next(k for k in range(t.size) if detector_update(settings, state, Y[k]) > 0)
                found.append(t[k] * f)
                errors.append(abs(1.0 / (state.period_s[0] * f) - 1.0) * 100.0)
            rows.append([f"{f:g}", f"{rate_hz:g}", max(found), max(errors)])
    table("Start-up period detector (YIN difference function, confirm = 1): periods of data "
          "until it hands over, and its frequency error (worst of 2 noise seeds)",
          ["f (Hz)", "rate (Hz)", "hand-over after (periods)", "frequency error (%)"], rows)


def _last_period(model: PeriodicModel, t, clean, f, rate_hz) -> float:
    _, y = model.rollout(t[-1] + 0.5 / rate_hz, rate_hz)
    last = t >= t[-1] - 1 / f
    return float(waveform_rms_percent(y[last], clean[last]).max())


def waveform_table() -> None:
    """Rollout of the learned model vs the noise-free waveform over the last period."""
    rows = []
    for rate_hz in RATES_HZ:
        for f in FREQUENCIES_HZ:
            t = np.arange(0, 10 / f, 1 / rate_hz)
            Y, clean = wiping_signal(t, f, seed=0)
            online, history = learn_online(t, Y, OnlineParameters())
            per_sample, _ = learn_online(t, Y, OnlineParameters(update_spacing=None))
            offline, _ = learn_offline(t, Y)
            last = t >= t[-1] - 1 / f
            rows.append([f"{f:g}", f"{rate_hz:g}",
                         _last_period(online, t, clean, f, rate_hz),
                         float(waveform_rms_percent(history.output[last], clean[last]).max()),
                         _last_period(per_sample, t, clean, f, rate_hz),
                         _last_period(offline, t, clean, f, rate_hz)])
    table("Waveform RMS error, % of peak-to-peak (worst DOF), after 10 periods "
          "(limits: online 3, offline 1)",
          ["f (Hz)", "rate (Hz)", "online: model rollout", "online: DMP while learning (Fig. 5)",
           "online, one LWR update per sample (as printed): rollout", "offline: model rollout"],
          rows)


def modulation_table() -> None:
    """Frequency, amplitude and anchor modulation of a learned model's rollout."""
    rows = []
    for f in (0.5, 2.0):
        t = np.arange(0, 10 / f, 1 / 500)
        Y, _ = wiping_signal(t, f, seed=0)
        model, _ = learn_online(t, Y, OnlineParameters())
        samples = 200
        _, y1 = model.rollout(1 / model.frequency_hz, samples * model.frequency_hz)
        _, y2 = model.rollout(0.5 / model.frequency_hz, 2 * samples * model.frequency_hz,
                              frequency_hz=2 * model.frequency_hz)
        goal = model.goal + np.array([0.1, -0.05])
        _, y3 = model.rollout(1 / model.frequency_hz, samples * model.frequency_hz,
                              amplitude=1.5 * model.amplitude, goal=goal)
        shape = float(waveform_rms_percent(y2, y1).max())
        scaled = float(np.abs((y3 - goal) - 1.5 * (y1 - model.goal)).max())
        rows.append([f"{f:g}", shape, scaled * 1e3])
    table("Modulation: rollout at 2x frequency vs 1x time-scaled (RMS % p2p), and r x 1.5 with "
          "g shifted (max deviation from 1.5 (y - g), mm)",
          ["learned at (Hz)", "2x frequency shape error (%)", "amplitude/goal error (mm)"], rows)


def peer_table() -> None:
    """pydmps' DMPs_rhythmic vs the batch fit, on the same single period, 25 kernels each."""
    from pydmps.dmp_rhythmic import DMPs_rhythmic

    rows = []
    for rate_hz in RATES_HZ:
        for f in (0.5, 2.0):
            t = np.arange(0, 1 / f, 1 / rate_hz)
            Y, _ = wiping_signal(t, f, seed=0)
            truth_at = lambda phase: np.column_stack([shape(phase) for shape in WIPING_SHAPES])
            start = time.perf_counter()
            peer = DMPs_rhythmic(n_dmps=2, n_bfs=25)
            peer.imitate_path(y_des=Y.T.copy())
            peer_fit = time.perf_counter() - start
            steps = peer.timesteps
            y_peer, _, _ = peer.rollout(timesteps=2 * steps)
            phase = 2 * np.pi * np.arange(steps) / steps
            first = float(waveform_rms_percent(y_peer[:steps], truth_at(phase)).max())
            steady = float(waveform_rms_percent(y_peer[steps:], truth_at(phase)).max())
            start = time.perf_counter()
            phase_t = 2 * np.pi * f * t
            goal = Y.mean(axis=0)
            amplitude = np.sqrt(2.0) * Y.std(axis=0)
            weights = fit_weights(phase_t, Y, goal, amplitude, 25, 62.5)
            ours_fit = time.perf_counter() - start
            model = PeriodicModel(frequency_hz=f, dofs=("x", "y"), kernels=25, width=62.5,
                                  alpha_s=12.0, beta_s=3.0, goal=goal, amplitude=amplitude,
                                  weights=weights, phase_offset=0.0)
            ours = float(waveform_rms_percent(model.waveform(phase), truth_at(phase)).max())
            rows.append([f"{f:g}", f"{rate_hz:g}", first, steady, peer_fit * 1e3, ours,
                         ours_fit * 1e3])
    table("Peer: pydmps DMPs_rhythmic vs wipelab batch fit on one noisy period, 25 kernels "
          "(RMS % p2p vs the noise-free period, worst DOF; fit time in ms)",
          ["f (Hz)", "rate (Hz)", "pydmps: 1st period", "pydmps: 2nd period", "pydmps fit (ms)",
           "wipelab", "wipelab fit (ms)"], rows)


def _best_seconds(run, repeats: int = 3) -> float:
    """Fastest of a few runs: the machine is shared, the minimum is the cost of the code."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        run()
        times.append(time.perf_counter() - start)
    return min(times)


def speed_table() -> None:
    """Cost per sample of the online learner; offline fit of a long recording."""
    shapes = WIPING_SHAPES + (HarmonicShape(0.8, 0.02, (1.0, 0.2), (0.3, 0.0)),)
    rows = []
    for canonical in ("afs", "afo"):
        for rate_hz in RATES_HZ:
            t = np.arange(0, 60, 1 / rate_hz)
            Y, _ = wiping_signal(t, 1.0, shapes=shapes)
            params = OnlineParameters(canonical=canonical)
            learn_online(t[:100], Y[:100], params)                      # compile / load the kernel
            fast = _best_seconds(lambda: learn_online(t, Y, params)) / t.size * 1e6
            learner = OnlineLearner(3, 1 / rate_hz, params)
            costs = []
            for row in Y[:600]:
                start = time.perf_counter()
                learner.step(row)
                costs.append((time.perf_counter() - start) * 1e6)
            rows.append([canonical, f"{rate_hz:g}", fast, fast * rate_hz / 1e3,
                         float(np.median(costs[1:])), float(np.percentile(costs[1:], 99))])
    table(f"Online learner, 3 DOFs, N = 25: microseconds per sample, process() (60 s of data, "
          f"best of 3) and step() one sample at a time from Python (median, p99 over 600); "
          f"load average {os.getloadavg()[0]:.1f}",
          ["canonical", "rate (Hz)", "process() (us)", "per second of data (ms)",
           "step() median (us)", "step() p99 (us)"], rows)
    rows = []
    for n_dofs in (2, 3):
        t = np.arange(0, 60, 1 / 500)
        Y, _ = wiping_signal(t, 1.0, shapes=shapes[:n_dofs])
        learn_offline(t[:2000], Y[:2000])
        rows.append([n_dofs, _best_seconds(lambda: learn_offline(t, Y))])
    table("Offline fit of 60 s at 500 Hz (30 000 samples), seconds (limit 1)",
          ["DOFs", "time (s)"], rows)


OLD = OnlineParameters(regression="lwr", change_threshold=None, change_relock_tolerance=None)
LEARNERS = {"new (default)": OnlineParameters(), "old: eqs. 13-15, 40-period mean, no change test": OLD}


def _held_out(seeds: int = 4):
    return range(HELD_OUT_SEEDS, HELD_OUT_SEEDS + seeds)


def _first_staying_below(t, values, limit, start_s, frequency_hz) -> float:
    inside = t >= start_s
    above = np.flatnonzero(values[inside] > limit)
    if above.size == 0:
        return 0.0
    if above[-1] == inside.sum() - 1:
        return float("inf")
    return float((t[inside][above[-1] + 1] - start_s) * frequency_hz)


def live_tables() -> None:
    """Issue 11 on held-out demonstrations of the independent generator (30 Hz)."""
    rows = []
    for name, params in LEARNERS.items():
        for f in (0.5, 1.0, 2.0):
            frequency, follow = [], []
            for seed in _held_out():
                demo = demonstrate(DemonstratorParams(frequency_hz=f, duration_s=20 / f), seed)
                _, h = learn_online(demo.t, demo.Y, params, valid=demo.valid)
                frequency.append(periods_to_tolerance(demo.t, h.frequency_hz, f, tolerance=0.05))
                window = int(round(30 / f))
                squares = np.convolve(((h.output - demo.clean) ** 2).mean(axis=1),
                                      np.ones(window) / window)[:demo.t.size]
                follow.append(_first_staying_below(
                    demo.t, np.sqrt(squares) / np.ptp(demo.clean, axis=0).mean() * 100, 10.0,
                    0.0, f))
            rows.append([name, f"{f:g}", max(frequency), max(follow)])
    table("(a) From the start: periods until the model frequency stays within 5 % of the start "
          "tempo (3 % tempo wander) and until the robot's learned output stays within 10 % RMS "
          "of the peak-to-peak over the last period (worst of 4 held-out seeds)",
          ["learner", "f (Hz)", "frequency (periods)", "robot follows (periods)"], rows)
    rows = []
    for name, params in LEARNERS.items():
        for f in (0.5, 1.0, 2.0):
            for factor in (1.3, 1 / 1.3):
                omega, model = [], []
                for seed in _held_out():
                    demo = demonstrate(DemonstratorParams(
                        frequency_hz=f, duration_s=30 / f, tempo_wander=0.0,
                        amplitude_wander=0.0, tempo_steps=((15 / f, factor),)), seed)
                    _, h = learn_online(demo.t, demo.Y, params)
                    step_s = demo.t[np.flatnonzero(demo.base_hz != demo.base_hz[0])[0]]
                    omega.append(periods_to_tolerance(demo.t, h.fundamental_hz, f * factor,
                                                      start_s=step_s))
                    model.append(periods_to_tolerance(demo.t, h.frequency_hz, f * factor,
                                                      start_s=step_s))
                rows.append([name, f"{f:g} -> {f * factor:.3g}", float(np.median(omega)),
                             max(omega), float(np.median(model)), max(model)])
    table("(b) Tempo steps of +-30 %: periods (of the new tempo) until within 1 % and staying "
          "(4 held-out seeds)",
          ["learner", "step (Hz)", "Omega median", "Omega worst", "model median",
           "model worst"], rows)
    rows = []
    for f in (0.5, 1.0, 2.0, 3.0):
        cells = {name: [] for name in (*LEARNERS, "offline")}
        for seed in _held_out():
            demo = demonstrate(DemonstratorParams(frequency_hz=f, duration_s=10 / f,
                                                  tempo_wander=0.0, amplitude_wander=0.0,
                                                  drift_m=0.0), seed)
            last = demo.t >= demo.t[-1] - 1 / f
            for name in cells:
                model = learn_offline(demo.t, demo.Y)[0] if name == "offline" else \
                    learn_online(demo.t, demo.Y, LEARNERS[name])[0]
                _, y = model.rollout(demo.t[-1] + 0.5 / 30, 30.0)
                cells[name].append(float(waveform_rms_percent(y[last], demo.clean[last]).max()))
        rows.append([f"{f:g}"] + [v for name in cells for v in (np.median(cells[name]),
                                                                   max(cells[name]))])
    table("(c) Waveform RMS % of peak-to-peak after 10 periods, model rollout vs the noise-free "
          "signal (random 2nd/3rd harmonics and phases, 2 % noise, 30 Hz; 4 held-out seeds)",
          ["f (Hz)", "new median", "new worst", "old median", "old worst", "offline median",
           "offline worst"], rows)


def main() -> None:
    start = time.perf_counter()
    live_tables()
    frequency_tables()
    human_tempo_table()
    detector_table()
    waveform_table()
    modulation_table()
    peer_table()
    speed_table()
    print(f"\n(benchmark took {time.perf_counter() - start:.0f} s)")


if __name__ == "__main__":
    main()
