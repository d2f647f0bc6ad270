"""The steady-state (limit-cycle) solution of the periodic DMP, eqs. 6-7, in closed form.

Written in the phase phi (d phi = Omega dt) eqs. 6-7 become the linear system
y'' + alpha_s y' + alpha_s beta_s (y - g) = r F(phi), with ' = d/d phi and
F = sum psi_i w_i / sum psi_i. Its periodic solution does not depend on Omega, and because
the system is linear it is y(phi) = g + r sum_i w_i B_i(phi), where B_i is the periodic
response to the normalised kernel psi_i / sum psi. Each B_i is computed once from the Fourier
series of its input: harmonic k is divided by (-k^2 + i alpha_s k + alpha_s beta_s).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from numba import njit

from wipelab.learning.kernels import kernel_activations
from wipelab.numba_cache import forget_stale_kernels

#: Harmonics whose magnitude is below this fraction of the largest are dropped (numerical zero).
_NEGLIGIBLE = 1e-14
#: Phases per period in the interpolation table of the basis.
TABLE_SIZE = 16384


@lru_cache(maxsize=32)
def _basis_spectrum(n_kernels: int, width: float, alpha_s: float, beta_s: float) -> np.ndarray:
    """Fourier coefficients of B_i, shape (K + 1, N) complex, k = 0..K (one-sided)."""
    # The grid must resolve a kernel of std ~ 1/sqrt(h) rad by many samples.
    grid_size = int(max(1024, 2 ** np.ceil(np.log2(64.0 * np.sqrt(width) + 8 * n_kernels))))
    grid = 2.0 * np.pi * np.arange(grid_size) / grid_size
    psi = kernel_activations(grid, n_kernels, width)
    shapes = psi / psi.sum(axis=1, keepdims=True)                  # (G, N)
    spectrum = np.fft.rfft(shapes, axis=0) / grid_size             # (G/2 + 1, N)
    k = np.arange(spectrum.shape[0])
    spectrum = spectrum / (-(k ** 2) + 1j * alpha_s * k + alpha_s * beta_s)[:, None]
    magnitude = np.abs(spectrum).max(axis=1)
    keep = int(np.flatnonzero(magnitude > _NEGLIGIBLE * magnitude.max())[-1]) + 1
    result = spectrum[:keep].copy()
    result[1:] *= 2.0                                               # one-sided real series
    result.setflags(write=False)
    return result


@lru_cache(maxsize=32)
def _basis_table(n_kernels: int, width: float, alpha_s: float, beta_s: float,
                 derivative: int) -> np.ndarray:
    """B_i (or its m-th phase derivative) on a uniform grid of TABLE_SIZE phases, plus the
    first row again at the end for wrap-around; shape (TABLE_SIZE + 1, N)."""
    spectrum = _basis_spectrum(n_kernels, width, alpha_s, beta_s)
    k = np.arange(spectrum.shape[0])
    one_sided = np.zeros((TABLE_SIZE // 2 + 1, n_kernels), dtype=complex)
    one_sided[:spectrum.shape[0]] = spectrum * ((1j * k) ** derivative)[:, None]
    one_sided[1:] /= 2.0
    table = np.fft.irfft(one_sided, n=TABLE_SIZE, axis=0) * TABLE_SIZE
    table = np.vstack([table, table[:1]])
    table.setflags(write=False)
    return table


def basis_table(n_kernels: int, width: float, alpha_s: float = 12.0, beta_s: float = 3.0,
                derivative: int = 0) -> np.ndarray:
    """The table :func:`basis_row` interpolates: B_i (or a phase derivative) at TABLE_SIZE
    phases per period, plus the first row again; shape (TABLE_SIZE + 1, N), read-only."""
    return _basis_table(int(n_kernels), float(width), float(alpha_s), float(beta_s), int(derivative))


@njit(cache=True)
def basis_row(table, phase: float, out) -> None:
    """B(phi) (N,) into out by linear interpolation in a :func:`basis_table`."""
    size = table.shape[0] - 1
    position = (phase % (2.0 * np.pi)) * (size / (2.0 * np.pi))
    index = min(int(position), size - 1)
    fraction = position - index
    for i in range(out.shape[0]):
        out[i] = table[index, i] * (1.0 - fraction) + table[index + 1, i] * fraction


@njit(cache=True)
def _basis_rows(table, phases, out):
    for k in range(phases.shape[0]):
        basis_row(table, phases[k], out[k])


def limit_cycle_basis(phase, n_kernels: int, width: float, alpha_s: float = 12.0,
                      beta_s: float = 3.0, derivative: int = 0) -> np.ndarray:
    """Responses B_i(phi) (or their phase derivatives) of eqs. 6-7 to each normalised kernel.

    Evaluated by linear interpolation in a table of TABLE_SIZE phases per period, built from
    the exact Fourier series (relative error ~1e-8).

    Parameters
    ----------
    phase : array, shape (n,)
        Phases in rad.
    n_kernels, width : int, float
        N and h of eq. 8.
    alpha_s, beta_s : float
        Gains of eq. 6.
    derivative : int
        0 for B_i, m for d^m B_i / d phi^m.

    Returns
    -------
    ndarray, shape (n, N)
    """
    table = basis_table(n_kernels, width, alpha_s, beta_s, derivative)
    phases = np.ascontiguousarray(np.asarray(phase, dtype=np.float64).reshape(-1))
    out = np.empty((phases.size, table.shape[1]))
    _basis_rows(table, phases, out)
    return out


def limit_cycle(phase, weights: np.ndarray, goal: np.ndarray, amplitude: np.ndarray, width: float,
                alpha_s: float = 12.0, beta_s: float = 3.0, derivative: int = 0) -> np.ndarray:
    """The periodic DMP's steady-state output y(phi) = g + r sum_i w_i B_i(phi).

    Parameters
    ----------
    phase : array, shape (n,)
        Phases in rad.
    weights : ndarray, shape (d, N)
    goal, amplitude : ndarray, shape (d,)
        Anchor g and amplitude r per DOF.
    width, alpha_s, beta_s : float
        As in eqs. 6 and 8.
    derivative : int
        0 for y; m for d^m y / d phi^m (then the goal drops out). Multiply by Omega^m for
        time derivatives.

    Returns
    -------
    ndarray, shape (n, d)
    """
    weights = np.asarray(weights, dtype=np.float64)
    basis = limit_cycle_basis(phase, weights.shape[1], width, alpha_s, beta_s, derivative)
    y = (basis @ weights.T) * np.asarray(amplitude, dtype=np.float64)
    return y + np.asarray(goal, dtype=np.float64) if derivative == 0 else y


forget_stale_kernels(__name__)
