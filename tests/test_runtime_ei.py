"""Standard-library EI family (runtime/ei.py) against the numpy design layer (shapers/ei.py)."""

import importlib

import numpy as np
import pytest

runtime_ei = importlib.import_module("shapefmu.runtime.ei")
design_ei = importlib.import_module("shapefmu.shapers.ei")

KINDS = ("ei", "ei2", "ei3")
OMEGA = 2.0 * np.pi * 7.0
# Every kind over zeta in [0, 0.3], vtol up to past the two-hump threshold (0.1396), and the
# three-hump fold region: the vtol = 0.05 branch turns back at zeta 0.2756 and forward at 0.2751.
GRID = [(k, v, z) for k in KINDS for v in (0.01, 0.05, 0.1, 0.14) for z in (0.0, 0.1, 0.2, 0.3)] + [
    ("ei3", v, z)
    for v in (0.03, 0.035, 0.04, 0.045, 0.05)
    for z in (0.26, 0.27, 0.275, 0.2752, 0.2755, 0.2758, 0.28, 0.29)
]
# Beyond the measured domain (shapers/ei.py): branch ends (two-hump vtol 0.2 at zeta 0.2424,
# three-hump vtol 0.1 at 0.2441, vtol 0.25 at 0.1228) and the three-hump vtol 0.2 band near zeta
# 0.14 where a fourth peak rises above vtol.
REFUSED = [("ei2", 0.2, 0.3), ("ei3", 0.1, 0.3), ("ei3", 0.25, 0.2), ("ei3", 0.2, 0.14)]


def _design_or_message(module, kind, vtol, zeta):
    try:
        return getattr(module, kind)(OMEGA, zeta, vtol)
    except ValueError as refused:
        return str(refused)


@pytest.mark.parametrize("kind, vtol, zeta", GRID)
def test_runtime_designs_or_refuses_exactly_as_the_design_layer(kind, vtol, zeta):
    got = _design_or_message(runtime_ei, kind, vtol, zeta)
    reference = _design_or_message(design_ei, kind, vtol, zeta)
    if isinstance(reference, str):
        assert got == reference
        return
    times, amplitudes = got
    assert len(times) == len(reference.times) == {"ei": 3, "ei2": 4, "ei3": 5}[kind]
    np.testing.assert_allclose(np.array(times) * OMEGA, np.array(reference.times) * OMEGA, rtol=0, atol=1e-10)
    np.testing.assert_allclose(amplitudes, reference.amplitudes, rtol=0, atol=1e-10)


def test_the_grid_reaches_every_zeta_where_the_domain_says_so():
    # Inside the measured domain (two-hump vtol <= 0.1396, three-hump vtol <= 0.0596) every
    # design of the grid exists: the comparison above is not between two refusals.
    inside = [(k, v, z) for k, v, z in GRID if v <= {"ei": 0.25, "ei2": 0.1396, "ei3": 0.0596}[k]]
    for kind, vtol, zeta in inside:
        times, amplitudes = getattr(runtime_ei, kind)(OMEGA, zeta, vtol)
        assert min(amplitudes) > 0 and abs(sum(amplitudes) - 1.0) < 1e-12


@pytest.mark.parametrize("kind, vtol, zeta", REFUSED)
def test_beyond_the_domain_both_refuse_with_the_same_message_naming_it(kind, vtol, zeta):
    with pytest.raises(ValueError) as expected:
        getattr(design_ei, kind)(OMEGA, zeta, vtol)
    with pytest.raises(ValueError) as got:
        getattr(runtime_ei, kind)(OMEGA, zeta, vtol)
    assert str(got.value) == str(expected.value)
    assert f"cannot be designed for zeta = {zeta:g}" in str(got.value)
    assert "measured domain" in str(got.value)


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
