"""The scheduled shaper (issue 37): re-designed at a sample when the scheduling input changes, every
change of the command shaped by the design in force when it was commanded, with no jump.

The reference is written here from the closed forms (ZV and ZVD of Singer & Seering, paper 002 eq. 3,
split onto the sample grid by hand) and applied as the direct double sum over the command's changes,
y[k] = u0 + sum_j du_j sum_i w_i(s_j) [k - j >= d_i(s_j)]; the kernel computes the same by segments."""

import json
import math

import numpy as np
import pytest

from shapefmu.runtime.scheduled_shaper import ModeFollowingShaper, ModeSchedule, ScheduledShaperKernel
from shapefmu.shapers import Schedule, ScheduledShaper

FS = 2000.0
H = 1.0 / FS
# The bed of models/printer_bed.toml at 0 and 300 g (30 / sqrt(1.3) Hz; zeta = 0.05 / sqrt(1.3)).
BED = ((0.0, 300.0), (30.0, 30.0 / math.sqrt(1.3)), (0.05, 0.05 / math.sqrt(1.3)))


def closed_form_taps(kind, hz, zeta):
    """{delay: weight} of ZV (n = 0) or ZVD (n = 1) at hz, each impulse at t = (n + a) h split as
    (1 - a) at n and a at n + 1 (the split keeps the amplitude and the centroid)."""
    order = {"zv": 1, "zvd": 2}[kind]
    k = math.exp(-zeta * math.pi / math.sqrt(1.0 - zeta**2))
    half_period = 1.0 / (2.0 * hz * math.sqrt(1.0 - zeta**2))
    taps = {}
    for i in range(order + 1):
        amplitude = math.comb(order, i) * k**i / (1.0 + k) ** order
        x = i * half_period / H
        n, a = math.floor(x), x - math.floor(x)
        taps[n] = taps.get(n, 0.0) + (1.0 - a) * amplitude
        taps[n + 1] = taps.get(n + 1, 0.0) + a * amplitude
    return taps


def schedule_mode(value):
    """The bed's table, interpolated by numpy: (Hz, zeta)."""
    values, hz, zetas = BED
    return float(np.interp(value, values, hz)), float(np.interp(value, values, zetas))


def change_by_change(u, u0, values, kind="zv"):
    """The reference: each change du_j shaped by the design for values[j]."""
    du = np.diff(np.asarray(u, dtype=float), prepend=u0)
    y = np.full(len(u), u0)
    for j, (step, value) in enumerate(zip(du, values)):
        if step:
            for d, w in closed_form_taps(kind, *schedule_mode(value)).items():
                y[j + d:] += w * step
    return y


def run(u, values, kind="zv", u0=0.0, resolution=0.0):
    kernel = ScheduledShaperKernel(FS, ModeSchedule(*BED), kind, u0=u0, value0=values[0], resolution=resolution)
    return np.array([kernel.step(a, s) for a, s in zip(u, values)]), kernel


@pytest.mark.parametrize("kind", ["zv", "zvd"])
def test_each_change_is_shaped_by_the_design_in_force_when_it_was_commanded(kind):
    rng = np.random.default_rng(7)
    u = np.cumsum(rng.normal(size=1500)) * (rng.random(1500) < 0.6)  # moves, holds and jumps
    values = np.clip(np.cumsum(rng.normal(0.0, 4.0, 1500)) + 150.0, 0.0, 300.0)  # the load moves every sample
    values[700:900] = 220.0  # and holds for a while
    y, kernel = run(u, values, kind)
    np.testing.assert_allclose(y, change_by_change(u, 0.0, values, kind), rtol=0, atol=1e-12)
    assert kernel.shaper.designs > 1000  # re-designed at every change of the input


def test_while_one_design_holds_the_output_is_that_fixed_shaper():
    """Moves under one load each, the load changed between them: each move's shaped command is the
    fixed ZV for its load (np.convolve of its taps with the move), to 1e-12."""
    move = np.concatenate([np.linspace(0.0, 2.0, 60), np.full(140, 2.0), np.linspace(2.0, 0.0, 60), np.zeros(140)])
    loads = (0.0, 80.0, 300.0, 150.0)
    u = np.tile(move, len(loads))
    values = np.repeat(loads, move.size)
    values[move.size * 2 + 30] = 10.0  # a glitch of the input in the third move, one sample long
    y, _ = run(u, values)
    for i, load in enumerate(loads):
        window = slice(i * move.size, (i + 1) * move.size)
        taps = closed_form_taps("zv", *schedule_mode(load))
        fir = np.zeros(max(taps) + 1)
        fir[list(taps)] = list(taps.values())
        fixed = np.convolve(move, fir)[: move.size]
        if i == 2:  # the glitch shaped one change with the 10 g design: exactly that change differs
            reference = change_by_change(u, 0.0, values)[window]
            np.testing.assert_allclose(y[window], reference, rtol=0, atol=1e-12)
            assert np.max(np.abs(y[window] - fixed)) > 1e-4
        else:
            np.testing.assert_allclose(y[window], fixed, rtol=0, atol=1e-12)


def test_a_redesign_at_rest_leaves_the_command_exactly_where_it_is():
    values = np.linspace(0.0, 300.0, 500)
    y, kernel = run(np.full(500, 3.7), values, u0=3.7)
    assert np.all(y == 3.7)
    assert kernel.shaper.designs == 500


def test_no_jump_when_the_design_changes_during_a_move():
    """A ramp of slope s per sample, the mode halved in the middle of it. Each change keeps its design,
    so the output moves at a sample only by the impulses falling there: |dy| <= s (sum of the weights of
    the two designs in flight) = 2 s. Re-designing in place (y = sum_i w_i(new) u[k - d_i(new)], what a
    firmware that swaps its taps does) jumps at the change by s times the shift of the centroid."""
    s = 0.01
    u = s * np.arange(1, 801)
    schedule = ModeSchedule([0.0, 1.0], [30.0, 15.0], [0.05, 0.05])
    values = np.where(np.arange(800) < 400, 0.0, 1.0)
    kernel = ScheduledShaperKernel(FS, schedule, value0=0.0, resolution=0.0)
    y = np.array([kernel.step(a, v) for a, v in zip(u, values)])
    assert np.max(np.abs(np.diff(y))) <= 2.0 * s + 1e-12
    old, new = closed_form_taps("zv", 30.0, 0.05), closed_form_taps("zv", 15.0, 0.05)
    in_place = [sum(w * (u[k - d] if k >= d else 0.0) for d, w in (old if k < 400 else new).items()) for k in range(800)]
    shift = sum(d * w for d, w in new.items()) - sum(d * w for d, w in old.items())
    assert in_place[400] - in_place[399] == pytest.approx(s * (1.0 - shift), rel=1e-9)
    assert abs(in_place[400] - in_place[399]) > 10.0 * s


def test_the_table_is_linear_between_rows_and_held_beyond():
    schedule = ModeSchedule([0.0, 100.0, 300.0], [30.0, 28.0, 26.0], [0.05, 0.04, 0.03])
    for value in (-50.0, 0.0, 37.0, 100.0, 250.0, 400.0):
        omega, zeta = schedule.mode(value)
        assert omega == pytest.approx(2 * math.pi * np.interp(value, [0, 100, 300], [30, 28, 26]), rel=1e-14)
        assert zeta == pytest.approx(np.interp(value, [0, 100, 300], [0.05, 0.04, 0.03]), rel=1e-14)


def test_the_linear_law_is_marlins_dynamic_frequency_everywhere():
    """Marlin FT_MOTION: f = base frequency + gain * z (or * grams)."""
    law = ModeSchedule.linear_law(30.0, -0.0123, 0.05)
    for grams in (-100.0, 0.0, 150.0, 300.0, 1000.0):
        assert law.mode(grams)[0] == pytest.approx(2 * math.pi * (30.0 - 0.0123 * grams), rel=1e-13)
    with pytest.raises(ValueError, match=r"scheduling value 3000.0 lies where the schedule gives f = -6.9 Hz"):
        law.mode(3000.0)


@pytest.mark.parametrize("arguments, message", [
    (([0.0, 0.0], [30.0, 26.0], [0.05, 0.05]), "values must be strictly increasing"),
    (([0.0, 1.0], [30.0, -1.0], [0.05, 0.05]), r"frequencies\[1\] must be > 0, got -1.0"),
    (([0.0, 1.0], [30.0, 26.0], [0.05, 1.0]), r"zetas\[1\] must be in \[0, 1\), got 1.0"),
    (([0.0], [30.0, 26.0], [0.05]), "must be non-empty and of equal length"),
])
def test_a_bad_table_is_refused_naming_the_row(arguments, message):
    with pytest.raises(ValueError, match=message):
        ModeSchedule(*arguments)


def test_a_mode_the_sampling_cannot_reach_is_refused():
    with pytest.raises(ValueError, match="at or above the Nyquist frequency"):
        ModeFollowingShaper(100.0, 2 * math.pi * 60.0, 0.0)


def test_the_design_layer_shaper_runs_the_kernel_and_round_trips_through_json():
    shaper = ScheduledShaper(Schedule(*BED), ts=H)
    rng = np.random.default_rng(3)
    u = np.cumsum(rng.normal(size=300))
    values = np.linspace(0.0, 300.0, 300)
    kernel = shaper.kernel(float(u[0]), 0.0)
    np.testing.assert_array_equal(shaper.shape(u, values), [kernel.step(a, s) for a, s in zip(u, values)])
    again = ScheduledShaper.from_json(shaper.to_json())
    assert again == shaper and json.loads(shaper.to_json())["kind"] == "scheduled"
    zv = shaper.design_at(300.0)
    hz, zeta = schedule_mode(300.0)
    assert zv.times[1] == pytest.approx(1.0 / (2.0 * hz * math.sqrt(1.0 - zeta**2)), rel=1e-14)


def test_the_design_layer_refuses_a_kind_it_cannot_schedule():
    with pytest.raises(ValueError, match="kind must be one of zv, zvd"):
        ScheduledShaper(Schedule(*BED), ts=H, kind="simultaneous")


def test_a_shaper_too_long_for_its_sampling_is_refused_before_its_memory_is_taken():
    with pytest.raises(ValueError, match=r"would be 6\.283e\+09 samples long, more than the limit of 1,000,000"):
        ModeFollowingShaper(FS, 1e-6, 0.0)


def test_a_command_or_value_that_is_not_a_number_is_refused_naming_it():
    kernel = ScheduledShaperKernel(FS, ModeSchedule(*BED))
    with pytest.raises(ValueError, match="command must be a finite real number, got nan"):
        kernel.step(math.nan, 0.0)
    with pytest.raises(ValueError, match="scheduling value must be a finite real number, got inf"):
        kernel.step(0.0, math.inf)
