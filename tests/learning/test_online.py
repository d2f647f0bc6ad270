"""The online two-layer learner: numba kernel == numpy reference (also through gaps and
re-locks); waveform accuracy, also from ten samples per period; gaps in the input; a human's
wandering tempo; chunking."""

import numpy as np
import pytest

from wipelab.learning import OnlineParameters, learn_online
from wipelab.learning import AFSParameters
from wipelab.learning.signals import WIPING_SHAPES, waveform_rms_percent, wiping_signal
from wipelab.vision import WipingMotion, WipingMotionParams


@pytest.mark.parametrize("canonical, rate_hz, start_up", [
    ("afs", 500.0, True), ("afs", 30.0, True), ("afo", 100.0, True), ("afs", 100.0, False),
])
def test_compiled_kernel_matches_the_numpy_reference(canonical, rate_hz, start_up):
    """4 s at 1.3 Hz: detection, hand-over (lock) and the locked phase when start_up."""
    t = np.arange(0, 4, 1 / rate_hz)
    Y, _ = wiping_signal(t, 1.3, seed=1)
    params = OnlineParameters(canonical=canonical, start_up=start_up)
    model, history = learn_online(t, Y, params)
    reference_model, reference = learn_online(t, Y, params, reference=True)
    for name in ("output", "phase", "fundamental_hz", "oscillators_hz", "weights"):
        np.testing.assert_allclose(getattr(history, name), getattr(reference, name),
                                   rtol=1e-9, atol=1e-9, err_msg=name)
    np.testing.assert_allclose(model.weights, reference_model.weights, rtol=1e-9, atol=1e-9)
    assert model.frequency_hz == pytest.approx(reference_model.frequency_hz, rel=1e-12)


@pytest.mark.parametrize("canonical, rate_hz, relock_tolerance", [
    ("afs", 30.0, 0.02), ("afo", 100.0, 0.15),
])
def test_compiled_kernel_matches_the_numpy_reference_through_gaps_and_relocks(
        canonical, rate_hz, relock_tolerance):
    """9 s, 1.3 Hz then 2.2 Hz from 5 s, not observed over 4-5 s: free run, detector restart,
    hand-overs after the start-up (a tight tolerance makes the AFS re-lock at the step)."""
    t = np.arange(0, 9, 1 / rate_hz)
    Y, _ = wiping_signal(t, 1.3, seed=1, step_time_s=5.0, step_frequency_hz=2.2)
    valid = (t < 4.0) | (t >= 5.0)
    params = OnlineParameters(canonical=canonical, relock_tolerance=relock_tolerance)
    model, history = learn_online(t, Y, params, valid=valid)
    reference_model, reference = learn_online(t, Y, params, reference=True, valid=valid)
    assert history.hand_overs[-1] >= 2
    for name in ("output", "phase", "fundamental_hz", "oscillators_hz", "weights", "hand_overs"):
        np.testing.assert_allclose(getattr(history, name), getattr(reference, name),
                                   rtol=1e-9, atol=1e-9, err_msg=name)
    np.testing.assert_allclose(model.weights, reference_model.weights, rtol=1e-9, atol=1e-9)
    assert model.frequency_hz == pytest.approx(reference_model.frequency_hz, rel=1e-12)


def test_a_gap_teaches_nothing_and_the_oscillator_runs_through_it():
    """1 Hz at 30 Hz, not observed over 6-7.5 s (the samples bridged by straight lines, as
    the learn stage fills them): the gap-aware learner keeps its weights, runs on at its
    frequency and comes out close to the input; fed the bridge as data it is thrown off."""
    rate_hz = 30.0
    t = np.arange(0, 14, 1 / rate_hz)
    Y, clean = wiping_signal(t, 1.0, seed=3)
    gap = (t >= 6.0) & (t < 7.5)
    before, after = np.flatnonzero(gap)[[0, -1]] + [-1, 1]
    for j in range(Y.shape[1]):
        Y[gap, j] = np.interp(t[gap], t[[before, after]], Y[[before, after], j])
    last = t >= t[-1] - 1.0
    results = {}
    for name, valid in (("aware", ~gap), ("bridged", None)):
        model, history = learn_online(t, Y, OnlineParameters(), valid=valid)
        _, y = model.rollout(t[-1] + 0.5 / rate_hz, rate_hz)
        inside = (history.weights_t >= 6.0) & (history.weights_t < 7.5)
        results[name] = (np.abs(np.diff(history.weights[inside], axis=0)).max(),
                         np.abs(history.fundamental_hz[~gap & (t >= 6.0)] - 1.0).max(),
                         waveform_rms_percent(y[last], clean[last]).max(), model.frequency_hz)
    frozen, deviation, waveform, frequency_hz = results["aware"]
    assert frozen == 0.0 and results["bridged"][0] > 1.0
    assert deviation < 0.15 < 0.3 < results["bridged"][1]
    assert waveform < 1.6 and waveform < results["bridged"][2]
    assert frequency_hz == pytest.approx(1.0, rel=1e-3)


def test_follows_a_human_tempo_and_keeps_the_demonstrated_frequency():
    """60 s of a person's line strokes at 0.5 Hz (synth's motion model: tempo wandering by
    4 %, amplitude and centre drifting): the model's frequency is within 1 % of 0.5 Hz. With
    the strong gain schedule of the synthetic benchmark (kappa = 100) and no supervisor the
    AFS drifts down to a fraction of it."""
    t = np.arange(0, 60, 1 / 30)
    motion = WipingMotion(WipingMotionParams("line", 0.5, amplitude=0.14), 0.8, 0.03, seed=0)
    Y = motion.pose(t)[0][:, :2]
    model, history = learn_online(t, Y, OnlineParameters(), reference_dof=1)
    assert model.frequency_hz == pytest.approx(0.5, rel=0.01)
    assert history.hand_overs[-1] <= 2
    strong = OnlineParameters(relock_tolerance=None, afs=AFSParameters(residual_gain=100.0))
    _, drifting = learn_online(t, Y, strong, reference_dof=1)
    assert drifting.fundamental_hz[-1] < 0.3


@pytest.mark.parametrize("frequency_hz, rate_hz", [(1.0, 500.0), (0.5, 30.0), (2.0, 30.0),
                                                   (3.0, 30.0)])
def test_rollout_reproduces_the_noise_free_waveform_after_10_periods(frequency_hz, rate_hz):
    t = np.arange(0, 10 / frequency_hz, 1 / rate_hz)
    Y, clean = wiping_signal(t, frequency_hz, noise=0.02, seed=3)
    model, _ = learn_online(t, Y, OnlineParameters(), dofs=("x", "y"))
    _, y = model.rollout(t[-1] + 0.5 / rate_hz, rate_hz)
    last = t >= t[-1] - 1 / frequency_hz
    assert waveform_rms_percent(y[last], clean[last]).max() <= 3.0


def test_updates_between_samples_cover_the_kernels_at_ten_samples_per_period():
    """3 Hz at 30 Hz: 10 sample phases for 25 kernels; updates at most half a kernel apart help."""
    t = np.arange(0, 10 / 3.0, 1 / 30)
    Y, clean = wiping_signal(t, 3.0, seed=3)
    last = t >= t[-1] - 1 / 3.0
    errors = []
    for spacing in (0.5, None):
        model, _ = learn_online(t, Y, OnlineParameters(update_spacing=spacing))
        _, y = model.rollout(t[-1] + 1 / 60, 30.0)
        errors.append(waveform_rms_percent(y[last], clean[last]).max())
    assert errors[0] <= 2.5 < 3.0 < errors[1]


def test_chunking_does_not_change_the_result():
    t = np.arange(0, 5, 1 / 200)
    Y, _ = wiping_signal(t, 1.0, seed=2)
    a, history_a = learn_online(t, Y, chunk=97)
    b, history_b = learn_online(t, Y, chunk=5000)
    np.testing.assert_array_equal(history_a.output, history_b.output)
    np.testing.assert_array_equal(history_a.weights, history_b.weights)
    assert a.to_dict() == b.to_dict()


def test_history_shapes_and_progress():
    t = np.arange(0, 3, 1 / 100)
    Y, _ = wiping_signal(t, 1.0)
    seen = []
    model, history = learn_online(t, Y, OnlineParameters(canonical="afo", weights_every_s=0.1),
                                  dofs=("x", "y"), progress=seen.append, chunk=100)
    assert sum(seen) == t.size and len(seen) == 3
    assert history.oscillators_hz.shape == (t.size, 3) and history.output.shape == (t.size, 2)
    assert history.weights.shape == (30, 2, 25) and history.weights_t.shape == (30,)
    assert model.dofs == ("x", "y") and 0.0 <= model.phase_offset < 2 * np.pi
    assert len(WIPING_SHAPES) == 2
