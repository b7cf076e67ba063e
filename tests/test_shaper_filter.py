"""The streaming runtime filter against offline convolution, and the cost of off-grid impulses."""

import math
import tracemalloc

import numpy as np
import pytest

from shapefmu.analysis import residual_vibration
from shapefmu.runtime.shaper_filter import StreamingShaper, grid_impulses
from shapefmu.shapers import convolve_modes, zv, zvd


def _stream(filt, u):
    return np.array([filt.step(x) for x in u])


def test_streaming_equals_offline_convolution_for_impulses_on_the_grid():
    h = 1e-4
    # Half periods of 37 and 52 steps: every impulse of the convolved ZVD lies on the grid.
    shaper = convolve_modes([(math.pi / (37 * h), 0.0), (math.pi / (52 * h), 0.0)], base=zvd)
    u = np.random.default_rng(7).normal(size=5000)
    filt = StreamingShaper.from_impulses(shaper.times, shaper.amplitudes, h)
    offline = np.convolve(u, shaper.on_grid(h).taps)[: u.size]
    np.testing.assert_allclose(_stream(filt, u), offline, rtol=0, atol=1e-12)


def test_streaming_fir_taps_equal_offline_convolution():
    rng = np.random.default_rng(3)
    taps = rng.uniform(size=400)
    u = rng.normal(size=3000)
    np.testing.assert_allclose(
        _stream(StreamingShaper.from_taps(list(taps)), u), np.convolve(u, taps)[: u.size], rtol=0, atol=1e-12
    )


@pytest.mark.parametrize("kept", [lambda k: k % 4 != 0, lambda k: k % 40 == 0], ids=["dense-with-zeros", "sparse"])
def test_taps_with_zeros_and_a_rest_value_equal_offline_convolution(kept):
    # Zeros inside the span and before the first non-zero tap: the filter sums the span in one go
    # where the non-zero taps fill it (3 of 4) and loops over them where they are scattered.
    rng = np.random.default_rng(5)
    taps = np.array([rng.normal() if k >= 7 and kept(k) else 0.0 for k in range(300)])
    u0, u = 1.5, rng.normal(size=2000)
    history = np.concatenate([np.full(taps.size, u0), u])
    offline = np.convolve(history, taps)[taps.size : taps.size + u.size]
    np.testing.assert_allclose(_stream(StreamingShaper.from_taps(list(taps), u0), u), offline, rtol=0, atol=1e-12)


def test_streaming_filter_started_at_rest_on_a_held_value_stays_there():
    shaper = zvd(10.0, 0.1)
    filt = StreamingShaper.from_impulses(shaper.times, shaper.amplitudes, 1e-3, u0=2.5)
    assert all(filt.step(2.5) == pytest.approx(2.5, rel=1e-15) for _ in range(1000))


def test_memory_does_not_grow_over_a_million_steps():
    shaper = zvd(50.0, 0.05)
    filt = StreamingShaper.from_impulses(shaper.times, shaper.amplitudes, 1e-3)
    for k in range(1000):
        filt.step(math.sin(k))
    tracemalloc.start()
    before = tracemalloc.get_traced_memory()[0]
    for k in range(1_000_000):
        filt.step(1.0 if k & 1024 else -1.0)
    grown = tracemalloc.get_traced_memory()[0] - before
    tracemalloc.stop()
    assert grown < 1024


def test_off_grid_split_keeps_amplitude_sum_and_time_centroid():
    times, amplitudes, h = [0.0, 0.0123, 0.0377], [0.2, 0.5, 0.3], 0.005
    delays, weights = grid_impulses(times, amplitudes, h)
    assert math.fsum(weights) == pytest.approx(1.0, abs=1e-15)
    centroid = math.fsum(d * h * w for d, w in zip(delays, weights))
    assert centroid == pytest.approx(math.fsum(t * a for t, a in zip(times, amplitudes)), rel=1e-13)


@pytest.mark.parametrize("steps_per_half_period", [10.3, 20.6, 41.2, 82.4])
def test_off_grid_residual_cost_is_the_second_order_split_error(steps_per_half_period):
    # ZV at zeta = 0: only the second impulse (A = 1/2 at T/2) is off the grid, by a fraction alpha
    # of a step. Splitting it leaves |(1 - alpha) + alpha e^{-j w h} - e^{-j w alpha h}| / 2
    # ~ alpha (1 - alpha) (w h)^2 / 4 of residual vibration.
    omega = 1.0
    h = math.pi / (omega * steps_per_half_period)
    alpha = steps_per_half_period % 1.0
    sampled = zv(omega, 0.0).on_grid(h)
    predicted = alpha * (1 - alpha) * (omega * h) ** 2 / 4
    assert residual_vibration(sampled, omega, 0.0) == pytest.approx(predicted, rel=0.02 + (omega * h))


def test_off_grid_residual_stays_below_the_documented_bound():
    # The module's bound: (w h)^2 / 8 per unit of amplitude, for any split.
    omega = 2 * math.pi * 10.0
    for h in (1e-3, 5e-4, 3.3e-4):
        assert residual_vibration(zvd(omega, 0.05).on_grid(h), omega, 0.05) <= (omega * h) ** 2 / 8


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda: StreamingShaper([], []), "non-empty and of equal length"),
        (lambda: StreamingShaper([0, -1], [0.5, 0.5]), "delays must be integers >= 0, got -1"),
        (lambda: StreamingShaper.from_impulses([0.0], [1.0], 0.0), "h must be > 0, got 0.0"),
        (lambda: StreamingShaper.from_impulses([-0.1], [1.0], 0.1), "impulse times must be >= 0"),
        (lambda: StreamingShaper.from_taps([0.0, 0.0]), "at least one non-zero"),
        (lambda: StreamingShaper([0], [float("nan")]), "weight must be a finite real number"),
    ],
)
def test_bad_input_names_the_parameter(call, message):
    with pytest.raises(ValueError) as error:
        call()
    assert message in str(error.value)
