"""Eqs. 13-15: the per-kernel recursion is exactly exponentially weighted least squares."""

import numpy as np
import pytest

from wipelab.learning import IncrementalLWR, kernel_activations


def _stream(n=400, seed=0):
    rng = np.random.default_rng(seed)
    phase = rng.uniform(0, 2 * np.pi, n)
    psi = kernel_activations(phase, 10, 25.0)
    r = rng.uniform(0.5, 1.5, (n, 2))
    f = np.column_stack([np.cos(phase), np.sin(2 * phase)]) * 3 + 0.1 * rng.standard_normal((n, 2))
    return psi, r, f


def _weighted_least_squares(psi, r, f, forgetting, p0):
    """Closed form of the recursion: prior weight lambda^n / p0, sample k weight lambda^(n-k) psi_k."""
    n = psi.shape[0]
    decay = forgetting ** (n - 1 - np.arange(n))[:, None]                 # (n, 1)
    numerator = np.einsum("ki,kd->di", decay * psi, r * f)
    denominator = forgetting ** n / p0 + np.einsum("ki,kd->di", decay * psi, r * r)
    return numerator / denominator


@pytest.mark.parametrize("forgetting, p0", [(0.99, 1.0), (0.995, 100.0), (1.0, 1.0)])
def test_recursion_equals_the_weighted_least_squares_it_implements(forgetting, p0):
    psi, r, f = _stream()
    lwr = IncrementalLWR(10, 2, forgetting, p0)
    for k in range(psi.shape[0]):
        lwr.update(psi[k], r[k], f[k])
    np.testing.assert_allclose(lwr.weights_, _weighted_least_squares(psi, r, f, forgetting, p0),
                               rtol=1e-9, atol=1e-12)


def test_without_forgetting_it_converges_to_the_batch_lwr_solution():
    psi, r, f = _stream(n=20000, seed=3)
    lwr = IncrementalLWR(10, 2, forgetting=1.0, p0=1.0)
    for k in range(psi.shape[0]):
        lwr.update(psi[k], r[k], f[k])
    batch = np.einsum("ki,kd->di", psi, r * f) / np.einsum("ki,kd->di", psi, r * r)
    np.testing.assert_allclose(lwr.weights_, batch, rtol=1e-3)


def test_starts_at_zero_and_rejects_bad_settings():
    assert not IncrementalLWR(5, 3).weights_.any()
    with pytest.raises(ValueError, match="forgetting"):
        IncrementalLWR(5, 1, forgetting=1.5)
    with pytest.raises(ValueError, match="p0"):
        IncrementalLWR(5, 1, p0=0.0)
