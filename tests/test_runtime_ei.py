"""The standard-library EI family (runtime/ei.py) against the EI definition and its measured domain.

runtime/ei.py is the one implementation: a Shaper FMU runs it and the design layer (shapers/ei.py)
returns its impulses. The independent reference is the definition itself, checked on the impulses
alone by ``ei_constraint_residual`` (tests/support/ei_definition.py) (numpy: humps of height exactly vtol, the
zeros between and beyond them, the design frequency on the middle element, V <= vtol between the
outermost zeros), and the measured domain stated in the runtime/ei.py docstring.
"""

import importlib

import numpy as np
import pytest

from support.ei_definition import ei_constraint_residual

from shapefmu.shapers import ImpulseShaper

runtime_ei = importlib.import_module("shapefmu.runtime.ei")
design_ei = importlib.import_module("shapefmu.shapers.ei")

KINDS = ("ei", "ei2", "ei3")
HUMPS = {"ei": 1, "ei2": 2, "ei3": 3}
OMEGA = 2.0 * np.pi * 7.0
# Every kind over zeta in [0, 0.3], vtol up to past the two-hump threshold (0.1396), and the
# three-hump fold region: the vtol = 0.05 branch turns back at zeta 0.2756 and forward at 0.2751.
GRID = [(k, v, z) for k in KINDS for v in (0.01, 0.05, 0.1, 0.14) for z in (0.0, 0.1, 0.2, 0.3)] + [
    ("ei3", v, z)
    for v in (0.03, 0.035, 0.04, 0.045, 0.05)
    for z in (0.26, 0.27, 0.275, 0.2752, 0.2755, 0.2758, 0.28, 0.29)
]
# The measured domain (runtime/ei.py docstring) where it ends a branch of the grid below zeta = 0.3:
# two-hump vtol 0.14 at 0.2994, three-hump vtol 0.1 at 0.2441 and vtol 0.14 at 0.2060.
BRANCH_ENDS = {("ei2", 0.14): 0.2994, ("ei3", 0.1): 0.2441, ("ei3", 0.14): 0.2060}
# Beyond the measured domain: (kind, vtol, zeta, where the branch ends, a zeta below it where the
# design exists). Two-hump vtol 0.2 ends at zeta 0.2424, three-hump vtol 0.1 at 0.2441 and vtol
# 0.25 at 0.1228, where the band without an EI shape (0.1165-0.1225) reaches up to the end.
REFUSED = [
    ("ei2", 0.2, 0.3, 0.2424, 0.2404),
    ("ei3", 0.1, 0.3, 0.2441, 0.2421),
    ("ei3", 0.25, 0.2, 0.1228, 0.116),
]


def _constraint_residual(kind, vtol, zeta):
    """Largest residual of the EI definition for the runtime's design, in dimensionless time."""
    times, amplitudes = getattr(runtime_ei, kind)(OMEGA, zeta, vtol)
    assert len(times) == len(amplitudes) == HUMPS[kind] + 2
    dimensionless = ImpulseShaper(tuple(t * OMEGA for t in times), tuple(amplitudes))
    return ei_constraint_residual(dimensionless, HUMPS[kind], zeta, vtol)


@pytest.mark.parametrize("kind, vtol, zeta", GRID)
def test_runtime_designs_meet_the_ei_definition_or_refuse_where_the_domain_ends(kind, vtol, zeta):
    end = BRANCH_ENDS.get((kind, vtol))
    if end is not None and zeta > end:
        with pytest.raises(ValueError) as refused:
            getattr(runtime_ei, kind)(OMEGA, zeta, vtol)
        assert f"ends at zeta = {end:.4f}" in str(refused.value)
        return
    assert _constraint_residual(kind, vtol, zeta) < 1e-12


def test_the_grid_reaches_every_zeta_where_the_domain_says_so():
    # Inside the measured domain (two-hump vtol <= 0.1396, three-hump vtol <= 0.0596) every
    # design of the grid exists: the check above is not a string of refusals.
    inside = [(k, v, z) for k, v, z in GRID if v <= {"ei": 0.25, "ei2": 0.1396, "ei3": 0.0596}[k]]
    for kind, vtol, zeta in inside:
        times, amplitudes = getattr(runtime_ei, kind)(OMEGA, zeta, vtol)
        assert min(amplitudes) > 0 and abs(sum(amplitudes) - 1.0) < 1e-12


@pytest.mark.parametrize("kind, vtol, zeta, end, below", REFUSED)
def test_beyond_the_domain_the_refusal_names_the_measured_end_of_the_branch(kind, vtol, zeta, end, below):
    with pytest.raises(ValueError) as refused:
        getattr(runtime_ei, kind)(OMEGA, zeta, vtol)
    message = str(refused.value)
    assert f"cannot be designed for zeta = {zeta:g}" in message
    assert f"ends at zeta = {end:.4f}" in message
    assert "measured domain" in message
    # The stated end is true: below it the design exists and meets the definition, just above it
    # is refused.
    assert _constraint_residual(kind, vtol, below) < 1e-12
    with pytest.raises(ValueError):
        getattr(runtime_ei, kind)(OMEGA, end + 0.002, vtol)


def test_the_three_hump_band_without_an_ei_shape_is_refused_and_its_neighbours_are_not():
    # Measured domain: for three-hump vtol 0.2 the zeta band 0.139-0.1405 has no EI shape (a
    # fourth peak rises through vtol); on either side of it the design meets the definition.
    with pytest.raises(ValueError) as refused:
        runtime_ei.ei3(OMEGA, 0.14, 0.2)
    message = str(refused.value)
    assert "the solution is no EI shape, its residual vibration rises to" in message
    assert float(message.split("rises to ")[1].split(" ")[0]) > 0.2
    for zeta in (0.1385, 0.141):
        assert _constraint_residual("ei3", 0.2, zeta) < 1e-12


def test_undamped_ei_is_the_closed_form():
    # Singhose's undamped EI: (1+V)/4, (1-V)/2, (1+V)/4 at 0, T/2, T.
    times, amplitudes = runtime_ei.ei(OMEGA, 0.0, 0.05)
    period = 2.0 * np.pi / OMEGA
    np.testing.assert_allclose(times, [0.0, period / 2, period], rtol=1e-15)
    np.testing.assert_allclose(amplitudes, [1.05 / 4, 0.95 / 2, 1.05 / 4], rtol=1e-15)


@pytest.mark.parametrize(
    "args, message",
    [
        ((OMEGA, 0.35, 0.05), "zeta must be in [0, 0.3] for EI shapers, got 0.35"),
        ((OMEGA, 1.0, 0.05), "zeta must be in [0, 1), got 1.0"),
        ((OMEGA, -0.1, 0.05), "zeta must be in [0, 1), got -0.1"),
        ((OMEGA, 0.1, 0.3), "vtol must be in [0.0001, 0.25] for EI shapers, got 0.3"),
        ((OMEGA, 0.1, 1e-5), "vtol must be in [0.0001, 0.25] for EI shapers, got 1e-05"),
        ((OMEGA, 0.1, 0.0), "vtol must be in (0, 1), got 0.0"),
        ((-5.0, 0.1, 0.05), "omega must be > 0, got -5.0"),
        ((float("nan"), 0.1, 0.05), "omega must be a finite real number, got nan"),
    ],
)
@pytest.mark.parametrize("kind", KINDS)
def test_bad_input_is_refused_with_the_design_layers_message(kind, args, message):
    for module in (design_ei, runtime_ei):
        with pytest.raises(ValueError) as failure:
            getattr(module, kind)(*args)
        assert str(failure.value) == message
