"""Imitation learning of a live session, driven sample by sample with synthetic signals of
the learning package's independent generator (wipelab.learning.demonstrator, development
seeds) through the real online learner: the online demonstration area, the lock, a tempo
step followed, and every way imitation learning ends."""

import math

import numpy as np
import pytest

from wipelab.learning.demonstrator import DemonstratorParams, demonstrate
from wipelab.learning.signals import periods_to_tolerance
from wipelab.live.imitation import Imitation, ImitationParams
from wipelab.vision.demonstration_area import AreaMeter


def run(imitation: Imitation, Y: np.ndarray, valid: np.ndarray, until=None) -> np.ndarray:
    """Feed every sample (stopping after the stop when ``until`` is None); the model's
    frequency after each sample (NaN before the learner starts)."""
    frequency = np.full(len(Y), np.nan)
    for k in range(len(Y)):
        imitation.step(Y[k], valid[k])
        if imitation.learner is not None:
            frequency[k] = imitation.learner.frequency_hz
        if until is None and imitation.stop_reason is not None:
            return frequency[:k + 1]
    return frequency


def test_the_area_meter_grows_until_frozen():
    meter = AreaMeter()
    meter.add(0.0, [0.5, 0.1])
    assert meter.area is None
    meter.add(0.1, [0.7, -0.1])
    meter.add(0.2, [0.6, 0.3])
    np.testing.assert_allclose(meter.area.lower_left, [0.5, -0.1])
    np.testing.assert_allclose(meter.area.upper_right, [0.7, 0.3])
    assert meter.area.window == (0.0, 0.2)
    meter.freeze()
    meter.add(0.3, [2.0, 2.0])
    np.testing.assert_allclose(meter.area.upper_right, [0.7, 0.3])


def test_the_robot_may_imitate_once_locked_and_the_area_is_that_of_the_first_periods():
    """Not tracked for the first second: the learner starts a second after the first tracked
    sample and locks about two periods later; the area spans what was tracked until then and
    normalises the movement to about [-1, 1]."""
    demo = demonstrate(DemonstratorParams(frequency_hz=1.2, duration_s=12.0), seed=3)
    valid = demo.valid & (demo.t >= 1.0)
    imitation = Imitation(30.0, ImitationParams(stop_on_convergence=False))
    run(imitation, demo.Y, valid, until="end")
    assert imitation.first_tracked == pytest.approx(1.0)
    assert imitation.locked and 1.5 <= (imitation.lock_time - 1.0) * 1.2 <= 3.5
    area = imitation.area
    assert area.window == (pytest.approx(1.0), pytest.approx(imitation.lock_time))
    inside = (demo.t >= 1.0) & (demo.t <= imitation.lock_time)
    np.testing.assert_allclose(area.lower_left, demo.Y[inside].min(axis=0))
    offsets = area.normalise(demo.Y[demo.t > imitation.lock_time])
    assert 0.8 < np.abs(offsets).max() < 1.4
    span = np.ptp(demo.Y[inside], axis=0)
    assert imitation.learner.settings.reference == int(np.argmax(span))
    assert imitation.stop_reason is None
    assert imitation.learner.frequency_hz == pytest.approx(1.2, rel=0.03)


@pytest.mark.parametrize("factor", [1.3, 1 / 1.3])
def test_a_tempo_step_of_30_percent_is_followed_within_three_periods(factor):
    demo = demonstrate(DemonstratorParams(frequency_hz=1.0, duration_s=24.0, tempo_wander=0.0,
                                          amplitude_wander=0.0, tempo_steps=((12.0, factor),)),
                       seed=5)
    frequency = run(Imitation(30.0, ImitationParams(stop_on_convergence=False)), demo.Y,
                    demo.valid, until="end")
    step_s = demo.t[np.flatnonzero(demo.base_hz != demo.base_hz[0])[0]]
    assert periods_to_tolerance(demo.t, frequency, factor, start_s=step_s) <= 3.0


def test_learning_ends_after_learn_periods():
    demo = demonstrate(DemonstratorParams(frequency_hz=1.5, duration_s=20.0), seed=4)
    imitation = Imitation(30.0, ImitationParams(learn_periods=5, stop_on_convergence=False))
    run(imitation, demo.Y, demo.valid)
    assert imitation.stop_reason == "learn-periods"
    assert 5.0 <= imitation.periods < 5.1
    assert imitation.stop_time == pytest.approx(imitation.lock_time + 5 / 1.5, abs=0.4)


def test_learning_ends_when_the_learned_waveform_stops_changing():
    """A steady demonstration: the waveform settles within a few periods after the lock (the
    criterion then held: the learned period's change and the frequency's below tolerance);
    with a noisier, wandering one it takes longer, and without the criterion nothing stops."""
    steady = demonstrate(DemonstratorParams(frequency_hz=1.0, duration_s=40.0, tempo_wander=0.0,
                                            amplitude_wander=0.0, noise=0.005), seed=6)
    imitation = Imitation(30.0)
    run(imitation, steady.Y, steady.valid)
    assert imitation.stop_reason == "converged"
    assert 4.0 <= imitation.periods <= 10.0
    assert imitation.converged_time == imitation.stop_time
    going_on = Imitation(30.0, ImitationParams(stop_on_convergence=False))
    run(going_on, steady.Y, steady.valid, until="end")
    assert going_on.stop_reason is None
    assert going_on.converged_time == pytest.approx(imitation.converged_time)


@pytest.mark.parametrize("ending", ["gone", "still"])
def test_learning_ends_when_the_sponge_is_gone_or_still(ending):
    demo = demonstrate(DemonstratorParams(frequency_hz=1.0, duration_s=20.0), seed=7)
    Y, valid = demo.Y.copy(), demo.valid.copy()
    after = demo.t >= 10.0
    if ending == "gone":
        valid[after] = False
    else:
        Y[after] = Y[np.flatnonzero(after)[0]] + 0.001 * np.sin(demo.t[after])[:, None]
    imitation = Imitation(30.0, ImitationParams(stop_on_convergence=False))
    run(imitation, Y, valid)
    assert imitation.stop_reason == f"sponge {ending}"
    limit = imitation.params.gone_seconds if ending == "gone" else imitation.params.still_seconds
    assert 10.0 + 0.5 * limit <= imitation.stop_time <= 10.0 + limit + 0.1


def test_a_request_before_the_lock_ends_learning_at_the_lock():
    demo = demonstrate(DemonstratorParams(frequency_hz=1.0, duration_s=10.0), seed=8)
    imitation = Imitation(30.0, ImitationParams(stop_on_convergence=False))
    imitation.request_stop("Enter")
    run(imitation, demo.Y, demo.valid)
    assert imitation.stop_reason == "Enter" and imitation.stop_time == imitation.lock_time
    later = Imitation(30.0, ImitationParams(stop_on_convergence=False))
    for k in range(240):
        later.step(demo.Y[k], demo.valid[k])
    later.request_stop("SIGUSR1")
    assert later.stop_reason == "SIGUSR1" and later.stop_time == pytest.approx(239 / 30)
    model = later.model({"stage": "live"})
    assert model.dofs == ("x", "y") and model.frequency_hz == pytest.approx(1.0, rel=0.05)
    assert math.isfinite(model.phase_offset)
