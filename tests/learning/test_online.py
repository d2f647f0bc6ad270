"""The online two-layer learner: numba kernel == numpy reference; waveform accuracy, also from
ten samples per period; chunking."""

import numpy as np
import pytest

from wipelab.learning import OnlineParameters, learn_online
from wipelab.learning.signals import WIPING_SHAPES, waveform_rms_percent, wiping_signal


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
