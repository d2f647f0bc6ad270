"""Eq. 8 kernels, the forcing target, PeriodicDMP integration and its closed-form limit cycle."""

import numpy as np
import pytest

from wipelab.learning import (PeriodicModel, forcing_target, kernel_activations,
                              kernel_centres, limit_cycle, limit_cycle_basis)
from wipelab.learning.dmp import dmp_step, max_phase_step
from wipelab.learning.limit_cycle import _basis_spectrum


def test_kernels_peak_at_their_centres_and_are_periodic():
    n, h = 25, 62.5
    psi = kernel_activations(kernel_centres(n), n, h)
    np.testing.assert_allclose(np.diag(psi), 1.0)
    assert np.all(psi[~np.eye(n, dtype=bool)] < 1.0)
    assert kernel_centres(4).tolist() == pytest.approx([0.0, np.pi / 2, np.pi, 3 * np.pi / 2])
    np.testing.assert_allclose(kernel_activations(0.3 + 4 * np.pi, n, h), kernel_activations(0.3, n, h))
    # the pitfall of one C++ port: exp(-h cos(x - c)) peaks at c + pi, ours at c
    assert np.argmax(kernel_activations(np.pi, n, h)) == np.argmin(np.abs(kernel_centres(n) - np.pi))


def test_forcing_target_is_the_forcing_that_reproduces_a_sinusoid():
    omega, g, a = 2 * np.pi * 1.5, 0.4, 0.1
    t = np.linspace(0, 1, 50)
    y, yd, ydd = g + a * np.cos(omega * t), -a * omega * np.sin(omega * t), -a * omega ** 2 * np.cos(omega * t)
    f = forcing_target(y, yd, ydd, omega, g)
    # in phase: y'' + 12 y' + 36 (y - g) = f with y = g + a cos(phi)
    phi = omega * t
    np.testing.assert_allclose(f, a * (35 * np.cos(phi) - 12 * np.sin(phi)), atol=1e-12)


def _random_model(seed=0, frequency_hz=1.0):
    rng = np.random.default_rng(seed)
    return PeriodicModel(frequency_hz=frequency_hz, dofs=("x", "y"), kernels=25, width=62.5,
                         alpha_s=12.0, beta_s=3.0, goal=np.array([0.5, 0.1]),
                         amplitude=np.array([0.1, 0.05]), weights=30 * rng.standard_normal((2, 25)),
                         phase_offset=0.3, source={})


def test_limit_cycle_solves_eqs_6_7_in_phase():
    m = _random_model()
    phi = np.linspace(0, 2 * np.pi, 2001)
    y = limit_cycle(phi, m.weights, m.goal, m.amplitude, m.width)
    y1 = limit_cycle(phi, m.weights, m.goal, m.amplitude, m.width, derivative=1)
    y2 = limit_cycle(phi, m.weights, m.goal, m.amplitude, m.width, derivative=2)
    psi = kernel_activations(phi, 25, m.width)
    forcing = (psi @ m.weights.T) / psi.sum(axis=1, keepdims=True) * m.amplitude
    residual = y2 + 12 * y1 + 36 * (y - m.goal) - forcing
    assert np.abs(residual).max() < 1e-5 * np.abs(forcing).max()
    np.testing.assert_allclose(y[0], y[-1], atol=1e-12)


def test_basis_table_matches_the_exact_fourier_series():
    phi = np.random.default_rng(1).uniform(-20, 20, 500)
    spectrum = _basis_spectrum(25, 62.5, 12.0, 3.0)
    exact = (np.exp(1j * np.outer(phi, np.arange(spectrum.shape[0]))) @ spectrum).real
    basis = limit_cycle_basis(phi, 25, 62.5)
    assert np.abs(basis - exact).max() < 1e-6 * np.abs(exact).max()


@pytest.mark.parametrize("rate_hz, frequency_hz", [(30.0, 3.0), (500.0, 0.3)])
def test_dmp_integration_converges_to_the_limit_cycle_at_any_rate(rate_hz, frequency_hz):
    m = _random_model()
    y, s, scratch = m.goal + 0.05, np.zeros(2), np.zeros((3, 2))     # off the cycle
    omega, dt = 2 * np.pi * frequency_hz, 1.0 / rate_hz
    steps = int(3 * rate_hz / frequency_hz)
    for k in range(steps):
        dmp_step(y, s, m.goal, m.amplitude, m.weights, m.width, kernel_centres(25), 12.0, 3.0,
                 omega * k * dt, omega, dt, max_phase_step(m.width), *scratch)
    expected = m.waveform([omega * steps * dt])[0]
    assert np.abs(y - expected).max() < 1e-4 * np.ptp(m.waveform(np.linspace(0, 6.3, 200)))
