"""One FMU instance inside the master (src/shapefmu/cosim/units.py, units3.py), driven here directly:
batched value arrays per FMI type, FMI 3.0 arrays and their nValues, values set by name, an FMU
asking to end the simulation, and a Model Exchange FMU integrated over a step.

The FMUs are the tests' own C FMUs, whose behaviour their sources state in closed form
(tests/fmus_c/array_gain3.c: y = k .* u, total = s + sum(y), m2 = 2 m, x += h y; typed_stair.c:
der(level) = x_in, counter = increment * floor(t / period), a stop at stop_at); the standards say
what a call must carry (FMI 3.0: nValues counts the values of every array element, an array
variable is named name[i] from 1; FMI 2.0 sec. 4.2.3: a step that ends the simulation returns
fmi2Discard, with fmi2Terminated true and fmi2LastSuccessfulTime the time reached).
"""

import shutil

import numpy as np
import pytest

from support.c_fmus import build_array_gain3, build_typed_stair

from shapefmu.cosim.loading import load_units
from shapefmu.cosim.units import FMUFailure, ModelExchangeUnit


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    folder = tmp_path_factory.mktemp("units")
    return {"arrays": build_array_gain3(folder), "stair": build_typed_stair(folder)}


@pytest.fixture
def unit_of(fmus):
    """unit_of(name, model_exchange=False): a unit of one of ``fmus``, freed after the test."""
    loaded = []

    def load(name, model_exchange=False):
        units, folders = load_units([(name, fmus[name])], {name} if model_exchange else set())
        loaded.append((units, folders))
        return units[0]

    yield load
    for units, folders in loaded:
        for unit in units:
            unit.free()
        for folder in folders:
            shutil.rmtree(folder, ignore_errors=True)


def initialised(unit, inputs, reads, values=None, given=None):
    """``unit`` configured to set ``inputs`` and read ``reads``, ``values`` set by name, the input
    arrays filled from ``given`` ({family: values}) and set in initialisation."""
    unit.configure(inputs, reads)
    unit.setup(0.0)
    unit.apply_values(values or {})
    unit.enter_initialization()
    for family, items in (given or {}).items():
        unit.channels[family].in_val[0:len(items)] = items
    unit.set_inputs()
    unit.exit_initialization(0.0, 1e-10)
    return unit


def test_an_fmi3_array_travels_whole_and_nvalues_counts_its_elements(unit_of):
    u, s, m = [0.5, -1.0, 2.5], 10.0, [3, -7]
    unit = initialised(unit_of("arrays"), ["u", "s", "m"], ["y", "total", "m2", "x"], {"k": [2.0, 3.0, 4.0]},
                       {"Float64": [*u, s], "Int32": m})
    floats, ints = unit.channels["Float64"], unit.channels["Int32"]
    assert (floats.nvr_in, floats.n_in, floats.nvr_out, floats.n_out) == (2, 4, 3, 7)
    assert (ints.nvr_in, ints.n_in, ints.nvr_out, ints.n_out) == (1, 2, 1, 2)
    unit.step(0.0, 0.25)
    unit.read()
    y = [2.0 * 0.5, 3.0 * -1.0, 4.0 * 2.5]
    assert list(floats.out_val[0:3]) == y and floats.out_val[3] == s + sum(y)
    assert list(floats.out_val[4:7]) == [0.25 * v for v in y]  # x += h y, from the step's start
    assert list(ints.out_val[0:2]) == [2 * v for v in m]


def test_an_array_is_named_by_its_elements_from_one(unit_of):
    unit = initialised(unit_of("arrays"), ["u"], ["y"])
    assert unit.elements("y") == ("y", [0, 1, 2])
    assert unit.elements("y[2]") == ("y", [1])
    assert unit.slots("u[3]", inputs=True) == ("Float64", [2])
    with pytest.raises(ValueError, match=r"y\[4\]: index 4 is beyond the 3 elements of arrays.y"):
        unit.elements("y[4]")
    with pytest.raises(ValueError, match=r"component 'arrays' \(ArrayGain3.fmu\) has no variable 'w'"):
        unit.elements("w")


def test_one_element_set_by_name_keeps_the_others_at_their_start_values(unit_of):
    unit = initialised(unit_of("arrays"), [], ["y"], {"k[2]": 5.0})
    unit.step(0.0, 0.1)
    unit.read()
    assert list(unit.channels["Float64"].out_val[0:3]) == [1.0 * 1.0, 5.0 * 2.0, 1.0 * 3.0]  # u starts at 1 2 3
    unit = unit_of("arrays")
    unit.configure([], [])
    with pytest.raises(ValueError, match=r"arrays.k has 3 elements, got 2 values"):
        unit.apply_values({"k": [1.0, 2.0]})


def test_values_of_every_fmi2_type_are_set_by_name_and_read_in_their_own_family(unit_of):
    values = {"increment": 3, "negate": True, "label": "up", "mode": 2, "period": 0.5}
    unit = initialised(unit_of("stair"), ["x_in", "n_in", "b_in", "s_in"], ["x_out", "counter", "n_out", "b_out", "s_out"],
                       values, {"Real": [0.25], "Integer": [4], "Boolean": [0], "String": [b"x"]})
    unit.step(0.0, 1.2)  # two period boundaries (0.5, 1.0): counter = sign(mode) * increment * 2
    unit.read()
    counter = -1 * 3 * 2  # mode 2: counting down
    assert unit.channels["Real"].out_val[0] == 0.25 + counter
    assert list(unit.channels["Integer"].out_val[0:2]) == [counter, 2 * 4 + counter]
    assert unit.channels["Boolean"].out_val[0] == 1  # b_in != negate
    assert unit.channels["String"].out_val[0] == b"up:x"


def test_a_step_that_ends_the_simulation_says_when_and_a_failed_call_names_itself(unit_of):
    unit = initialised(unit_of("stair"), [], ["x_out"], {"stop_at": 0.35})
    assert not unit.step(0.0, 0.2)
    assert unit.step(0.2, 0.2)  # fmi2Discard, fmi2Terminated: the run ends
    assert unit.terminated_at == 0.35 and "fmi2Terminated is true" in unit.termination_call
    with pytest.raises(FMUFailure) as failure:
        unit.step(0.4, 0.2)  # a terminated FMU refuses to step on: that is an error, not an end
    assert (failure.value.call, failure.value.status, failure.value.time) == ("fmi2DoStep", "fmi2Error", 0.4)


def test_an_fmi3_failure_names_the_fmi3_status(unit_of):
    unit = initialised(unit_of("arrays"), [], [])
    with pytest.raises(FMUFailure) as failure:
        unit.step(0.0, -1.0)
    assert failure.value.status == "fmi3Error"  # fmi3Status 3 (FMI 3.0 sec. 2.2.3)


def test_a_model_exchange_unit_integrates_its_derivative_over_the_step_with_the_input_held(unit_of):
    unit = initialised(unit_of("stair", model_exchange=True), ["x_in"], ["level", "counter"], {"period": 0.3},
                       {"Real": [2.0]})
    assert isinstance(unit, ModelExchangeUnit)
    levels = []
    for k in range(4):
        unit.set_inputs()
        unit.step(0.25 * k, 0.25)
        unit.read()
        levels.append((unit.channels["Real"].out_val[0], unit.channels["Integer"].out_val[0]))
    # level(t) = 2 t (der(level) = x_in held); counter = floor(t / 0.3) at the time events 0.3, 0.6, 0.9
    np.testing.assert_allclose([level for level, _ in levels], [0.5, 1.0, 1.5, 2.0], rtol=1e-8)
    assert [counter for _, counter in levels] == [0, 1, 2, 3]
