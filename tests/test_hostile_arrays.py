"""The master bounds the arrays of the FMUs it loads before any work (issue 34, item 8).

``--set g.k=[1,2,3]`` on an FMI 3.0 array declared with 10^8 elements took 2.9 GB and two minutes
before the size error (10^18: a MemoryError traceback), and an output array of 10^5 elements made
5.3 MB of generated C that gcc had not finished after seven minutes. Now an array of more than
MAX_ARRAY_ELEMENTS elements is refused when the model description is read, naming the limit, and a
system moving or recording more than MAX_COMPILED_VALUES values a step runs the Python step loop,
saying why, without compiling.

The FMUs are ArrayGain3 (tests/fmus_c/array_gain3.c) with one array's declared size changed in its
modelDescription.xml: the master must decide from the declaration alone.
"""

from __future__ import annotations

import tracemalloc
import zipfile

import pytest
from support.c_fmus import build_array_gain3
from hostile_support import guarded

from shapefmu.cosim import Master
from shapefmu.fmi.ssp import System
from shapefmu.runtime import limits


@pytest.fixture(scope="module")
def gain(tmp_path_factory):
    return build_array_gain3(tmp_path_factory.mktemp("arrays"))


def declared(gain, folder, sizes, name):
    """ArrayGain3 with its Float64 arrays declared of ``sizes`` (variable -> elements) in ``folder/name.fmu``;
    its binary keeps 3 elements each."""
    out = folder / f"{name}.fmu"
    with zipfile.ZipFile(gain) as source, zipfile.ZipFile(out, "w") as target:
        for item in source.infolist():
            data = source.read(item)
            if item.filename == "modelDescription.xml":
                text = data.decode()
                for variable, size in sizes.items():
                    at = text.index('<Dimension start="3"/>', text.index(f'<Float64 name="{variable}" '))
                    text = text[:at] + f'<Dimension start="{size}"/>' + text[at + len('<Dimension start="3"/>'):]
                data = text.encode()
            target.writestr(item, data)
    return out


@pytest.mark.parametrize("size", [10**8, 10**18, limits.MAX_ARRAY_ELEMENTS + 1])
def test_an_array_past_the_bound_is_refused_when_read_in_one_line_before_any_allocation(gain, tmp_path, size):
    ssp = System("s").add("g", declared(gain, tmp_path, {"k": size}, "k")).write_ssp(tmp_path / "s.ssp")
    tracemalloc.start()
    code, out, err = guarded(["simulate", ssp, "--stop", "1", "--step", "0.25", "--set", "g.k=[1,2,3]"], seconds=600)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert f"declares k an array of {size:,} elements, more than the {limits.MAX_ARRAY_ELEMENTS:,}" in err
    assert peak < 50e6  # bytes the refusal needed: not the 2.9 GB of a 10^8-element buffer


def test_an_array_at_the_bound_is_taken(gain, tmp_path):
    with Master(System("s").add("g", declared(gain, tmp_path, {"k": limits.MAX_ARRAY_ELEMENTS}, "k")), 0.25) as master:
        assert master.units[0].elements("k")[1][-1] == limits.MAX_ARRAY_ELEMENTS - 1


def test_recording_more_values_than_the_compiled_loop_takes_runs_the_python_loop_uncompiled(gain, tmp_path,
                                                                                          monkeypatch):
    from shapefmu.cosim import step_program

    compiled = []
    monkeypatch.setattr(step_program, "_compile", lambda *args: compiled.append(args))
    system = System("s").add("g", declared(gain, tmp_path, {"y": 10**5}, "y"))
    with Master(system, 0.25, record=["g.y"]) as master:
        assert master.loop_kind == "Python" and compiled == []
        assert "moves and records 100,000 values a step, more than the 2,000" in master.loop_reason


def test_a_system_within_the_compiled_loop_s_bound_still_compiles(gain):
    with Master(System("s").add("g", gain), 0.25, record=["g.y", "g.x", "g.total"]) as master:
        assert master.loop_kind == "C"
