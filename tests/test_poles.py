"""identification.poles.PoleForm against its own definition, computed here point by point: the model
is sum_j w_j |H(f_ij)|^2 with H the partial fractions of the module docstring at every frequency of
the smeared grid (PoleForm evaluates H once per distinct frequency, where neighbouring bins' kernels
overlap, and spreads it back), and its slopes are the model's central differences."""

import numpy as np
import pytest

from shapefmu.identification.poles import PoleForm
from shapefmu.identification.spectra import spectral_kernel

SHAPES = [(False, False), (True, False), (True, True)]


def grid_of(freq: np.ndarray, window: str = "hann") -> tuple[np.ndarray, np.ndarray]:
    """The grid fit_poles smears on: each bin's frequency plus the kernel's offsets, a quarter bin apart."""
    offsets, weights = spectral_kernel(window, 4)
    return freq[:, None] + offsets[None, :] * (freq[1] - freq[0]), weights


def response(grid, params, count, asymmetric, tilted) -> np.ndarray:
    """H at every grid frequency, from the module docstring's partial fractions, one point at a time."""
    per_pole = 4 if asymmetric else 3
    reference = grid.mean()
    h = np.empty(grid.shape, dtype=complex)
    for index, f in np.ndenumerate(grid):
        total = complex(params[per_pole * count], 0.0)
        if tilted:
            total += (f / reference - 1) * complex(params[per_pole * count + 1], params[per_pole * count + 2])
        for k in range(count):
            fk, sk = np.exp(params[per_pole * k]), np.exp(params[per_pole * k + 1])
            residue = sk * complex(params[per_pole * k + 2], params[per_pole * k + 3] if asymmetric else 0.0)
            pole = complex(-sk, fk)
            total += residue / (1j * f - pole) + residue.conjugate() / (1j * f - pole.conjugate())
        h[index] = total
    return h


def params_of(count, asymmetric, tilted, rng) -> np.ndarray:
    per_pole = 4 if asymmetric else 3
    values = []
    for k in range(count):
        values += [np.log(30.0 + 25.0 * k + rng.uniform(-2, 2)), np.log(rng.uniform(0.5, 3.0)), rng.uniform(0.5, 2.0)]
        values += [rng.uniform(-0.5, 0.5)] if asymmetric else []
    values += [rng.uniform(0.01, 0.1)] + ([rng.uniform(-0.05, 0.05), rng.uniform(-0.05, 0.05)] if tilted else [])
    assert len(values) == per_pole * count + (3 if tilted else 1)
    return np.array(values)


@pytest.mark.parametrize("asymmetric, tilted", SHAPES)
@pytest.mark.parametrize("stride", [1, 3])
def test_the_model_is_the_smeared_power_of_the_partial_fractions(asymmetric, tilted, stride):
    """Bins next to each other (their kernels share frequencies) and every third bin (as a wide band is fitted)."""
    rng = np.random.default_rng(stride)
    grid, weights = grid_of(np.arange(20.0, 90.0, 0.1)[::stride])
    params = params_of(2, asymmetric, tilted, rng)
    form = PoleForm(grid, weights, 2, asymmetric, tilted)
    if stride == 1:  # the case the sharing is for: neighbouring kernels meet on the same frequencies
        assert form.points.size < grid.size / 2
    model, _ = form.evaluate(params)
    expected = (np.abs(response(grid, params, 2, asymmetric, tilted)) ** 2) @ weights
    np.testing.assert_allclose(model, expected, rtol=1e-12)


@pytest.mark.parametrize("asymmetric, tilted", SHAPES)
def test_the_slopes_are_the_models_central_differences(asymmetric, tilted):
    rng = np.random.default_rng(5)
    grid, weights = grid_of(np.arange(25.0, 70.0, 0.1))
    params = params_of(2, asymmetric, tilted, rng)
    form = PoleForm(grid, weights, 2, asymmetric, tilted)
    _, slopes = form.evaluate(params)
    step = 1e-6
    for i in range(params.size):
        up, down = params.copy(), params.copy()
        up[i] += step
        down[i] -= step
        difference = (form.evaluate(up)[0] - form.evaluate(down)[0]) / (2 * step)
        np.testing.assert_allclose(slopes[:, i], difference, rtol=1e-5, atol=1e-7 * np.abs(difference).max())
