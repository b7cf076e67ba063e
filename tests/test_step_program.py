"""The master's per-step program (src/shapefmu/cosim/step_program.py): the plan of FMI calls for one
macro step, rendered as a Python function and as a compiled C loop.

Second opinions: the closed form of a Gauss-Seidel chain of the master tests' small FMUs (a ramp,
a feed-through gain, a forward-Euler integrator: tests/support/cosim_fmus.py), worked out by hand
from the order the plan must follow (master module docstring: each component takes the latest
outputs; a feed-through output is passed on as read right after its inputs are set); exact rational
arithmetic for how a linear transformation x * f + o must round (as Python rounds it: a product,
then a sum, never one fused multiply-add); the FMI 3.0 standard's widths of its types for the
record's columns; and the Python loop itself wherever the C loop cannot be had.
"""

from fractions import Fraction

import numpy as np
import pytest

from support.c_fmus import WIDE_TYPES, build_typed_stair, build_typed_stair3
from support.cosim_fmus import build_test_fmu

from shapefmu.cosim import Master, step_program
from shapefmu.fmi.ssp import System

H = 0.01


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    folder = tmp_path_factory.mktemp("step_program")
    built = {name: build_test_fmu(name, folder) for name in ("CosimRamp", "CosimGain", "CosimIntegrator")}
    return {**built, "stair": build_typed_stair(folder), "stair3": build_typed_stair3(folder)}


def chain(fmus, factor=2.0, offset=1.0) -> System:
    """ramp (3 t + 0.25) -> factor * y + offset -> gain (2 u + 0.5) -> integrator (x0 = 1.5)."""
    return (System("chain")
            .add("ramp", fmus["CosimRamp"], {"slope": 3.0, "bias": 0.25})
            .add("gain", fmus["CosimGain"], {"k": 2.0, "c": 0.5})
            .add("integrator", fmus["CosimIntegrator"], {"x0": 1.5})
            .connect("ramp.y", "gain.u", factor=factor, offset=offset)
            .connect("gain.y", "integrator.u"))


def runs(system, stop, **options) -> dict:
    """{loop kind: results} of the system run by the compiled and by the Python loop."""
    out = {}
    for native in (True, False):
        with Master(system, H, native=native, **options) as master:
            out[master.loop_kind] = master.run(stop)
    assert set(out) == {"C", "Python"}
    return out


@pytest.mark.parametrize("every", [1, 7])
def test_gauss_seidel_passes_each_output_on_as_soon_as_it_is_read(fmus, every):
    """The ramp steps first; the gain takes the ramp's new value and its feed-through output goes
    on as read right after that input is set, before its own step; the integrator steps last with
    it. A record every ``every``-th step and the last, cut at the stop time."""
    n = 53
    results = runs(chain(fmus), n * H + 0.004, output_interval=every * H)
    t = np.append(H * np.arange(n + 1), n * H + 0.004)
    ramp = 3.0 * t + 0.25
    gain = 2.0 * (2.0 * ramp + 1.0) + 0.5
    steps = np.diff(t)
    integrator = 1.5 + np.concatenate([[0.0], np.cumsum(gain[1:] * steps)])  # each step's input: the gain after the ramp stepped
    kept = [k for k in range(n + 2) if k % every == 0 or k == n + 1]
    for kind, result in results.items():
        np.testing.assert_allclose(result["time"], t[kept], rtol=0, atol=1e-12, err_msg=kind)
        np.testing.assert_allclose(result["ramp.y"], ramp[kept], rtol=0, atol=1e-12, err_msg=kind)
        np.testing.assert_allclose(result["gain.y"], gain[kept], rtol=0, atol=1e-12, err_msg=kind)
        np.testing.assert_allclose(result["integrator.y"], integrator[kept], rtol=0, atol=1e-12, err_msg=kind)


def test_the_c_loop_rounds_a_linear_transformation_as_python_does_not_as_a_fused_multiply_add(fmus):
    factor, offset = 0.1, -0.3  # y * 0.1 - 0.3 rounds twice, a fused multiply-add once
    results = runs(chain(fmus, factor, offset), 40 * H, algorithm="jacobi")
    ramp = results["Python"]["ramp.y"][:-1]
    unfused = ramp * factor + offset
    fused = np.array([float(Fraction(y) * Fraction(factor) + Fraction(offset)) for y in ramp])
    assert np.any(unfused != fused)  # the values tell the two roundings apart
    for kind, result in results.items():
        inputs = (result["gain.y"][1:] - 0.5) / 2.0  # the gain's input, exactly (k = 2, c = 0.5: exact in binary)
        assert np.array_equal(inputs, unfused), kind


def test_each_reason_for_the_python_loop_is_named_and_the_python_loop_runs(fmus, monkeypatch):
    ring = (System("ring").add("g1", fmus["CosimGain"], {"k": 0.5}).add("g2", fmus["CosimGain"], {"k": -0.8, "c": 1.0})
            .connect("g1.y", "g2.u").connect("g2.y", "g1.u"))
    stair = System("stair").add("stair", fmus["stair"])
    with Master(ring, H) as master:
        assert master.loop_kind == "Python"
        assert master.loop_reason.startswith("the algebraic loop through") and master.loop_reason.endswith("is solved in Python")
    with Master(stair, H, model_exchange=["stair"]) as master:
        assert (master.loop_kind, master.loop_reason) == ("Python", "component 'stair' runs as Model Exchange (integrated in Python)")
    monkeypatch.setattr(step_program, "MAX_COMPILED_COMPONENTS", 2)
    with Master(chain(fmus), H) as master:
        assert master.loop_reason == ("the system has 3 components, more than the 2 whose step loop compiles in about "
                                      "a second")
        master.run(0.1)
    monkeypatch.undo()
    monkeypatch.setenv("CC", "")
    monkeypatch.setenv("PATH", "/nonexistent")
    with Master(chain(fmus), H) as master:
        assert master.loop_reason == "no C compiler (set CC or install gcc)"


def test_a_loop_that_fails_to_compile_falls_back_to_python_with_the_same_results(fmus, monkeypatch):
    system = chain(fmus, factor=1.2345678912, offset=-0.987654321)  # a program no earlier test compiled
    with Master(system, H, native=False) as master:
        expected = master.run(0.3)
    monkeypatch.setenv("CC", "false")  # a compiler that always fails
    with Master(system, H) as master:
        assert (master.loop_kind, master.loop_reason) == ("Python", "compiling the step loop failed")
        assert master.run(0.3).tobytes() == expected.tobytes()


def test_the_record_has_one_packed_column_per_variable_in_its_fmi3_type(fmus):
    """FMI 3.0 sec. 2.4.7: IntN and UIntN are N-bit integers, Float64 a double, Boolean one value,
    Enumeration an Int64; the row is packed (no padding between columns)."""
    widths = {"Int8": "i1", "UInt8": "u1", "Int16": "i2", "UInt16": "u2", "UInt32": "u4", "Int64": "i8", "UInt64": "u8"}
    record = ["s.x_out", "s.counter", "s.b_out", "s.e_out", *(f"s.{t.lower()}_out" for t in WIDE_TYPES)]
    with Master(System("s").add("s", fmus["stair3"]), H, record=record) as master:
        dtype = step_program.buffer_dtype(master)
        result = master.run(0.05)
    expected = [("time", "f8"), ("s.x_out", "f8"), ("s.counter", "i4"), ("s.b_out", "?"), ("s.e_out", "i8"),
                *((f"s.{t.lower()}_out", widths[t]) for t in WIDE_TYPES)]
    assert [(name, dtype.fields[name][0].str[1:] if dtype.fields[name][0].char != "?" else "?") for name in dtype.names] \
        == expected
    assert dtype.itemsize == sum(np.dtype(code).itemsize for _, code in expected)
    assert result.dtype == dtype and len(result) == 6
