"""Executing a model: the tabulated path generator, refitting onto more kernels, placement."""

import math

import numpy as np
import pytest

from wipelab.sim.path import (PathGenerator, dof_waveform, place_model, refit_error,
                              with_kernels)

from sim_models import circle_model


@pytest.fixture(scope="module")
def model():
    return place_model(circle_model(), (0.58, -0.28))


def test_generator_follows_the_limit_cycle_and_its_derivatives(model):
    omega, dt = 2 * math.pi * 0.25, 1 / 120
    path = PathGenerator(model, ("x", "y"), phase=0.3)
    positions, velocities = zip(*(path.step(omega, dt) for _ in range(240)))
    phases = 0.3 + omega * dt * np.arange(1, 241)
    assert np.abs(np.array(positions) - dof_waveform(model, ("x", "y"), phases)).max() < 1e-7
    numeric = np.gradient(np.array(positions), dt, axis=0)
    assert np.abs(np.array(velocities) - numeric)[1:-1].max() < 1e-3 * path.max_speed(omega)
    # a circle of 10 cm radius at 0.25 Hz: 2 pi 0.1 0.25 m/s
    assert path.max_speed(omega) == pytest.approx(2 * math.pi * 0.1 * 0.25, rel=0.1)


def test_refit_onto_more_kernels_keeps_the_path(model):
    refitted = with_kernels(model, 50)
    assert refitted.kernels == 50 and refitted.weights.shape == (2, 50)
    assert refit_error(model, refitted, ("x", "y")) < 1e-4
    assert with_kernels(model, model.kernels) is model
