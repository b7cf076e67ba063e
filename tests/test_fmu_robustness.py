"""No call order or value crashes or hangs a host: random FMI call sequences through fmpy, on every FMU.

Every FMU kind of ``shapefmu.fmi.kinds.KINDS`` gets the same random sequences (setters and
getters on any value reference, steps of any size, initialisation, reset, state save, restore and
serialisation in any order), built with its session fixture. The sequences run in a subprocess
with a timeout, so a crash (a signal) or a hang fails the test instead of killing pytest. A call
may fail with fmi2Error, never with fmi2Fatal (or any other status); the process must survive.
"""

import subprocess
import sys
import textwrap

import pytest

from shapefmu.fmi.kinds import KINDS as SLAVES

# The session fixture (tests/fixtures_fmi.py) that builds each registered FMU.
FIXTURES = {
    "Shaper": "shaper_fmu",
    "ShapeFilter": "shape_filter_fmu",
    "ReferencePlayer": "reference_fmu",
    "ProfileGenerator": "profile_fmu",
    "EKFTuner": "ekf_fmu",
    "STOSController": "stos_fmu",
}
# Random sequences per FMU: enough to reach every phase, few enough to keep all FMUs within seconds.
EXAMPLES = 25

SCRIPT = textwrap.dedent(
    """
    import math, sys
    from hypothesis import given, settings, strategies as st, HealthCheck
    from fmpy import extract, read_model_description
    from fmpy.fmi1 import FMICallException
    from fmpy.fmi2 import FMU2Slave

    path, examples = sys.argv[1], int(sys.argv[2])
    md = read_model_description(path)
    unzipped = extract(path)
    vrs = [v.valueReference for v in md.modelVariables] + [999]
    reals = st.floats(allow_nan=True, allow_infinity=True) | st.sampled_from([0.0, 1e-3, 0.5e-3, -1.0, 2.0])
    ops = st.one_of(
        st.tuples(st.just("setReal"), st.sampled_from(vrs), reals),
        st.tuples(st.just("setInteger"), st.sampled_from(vrs), st.integers(-5, 10)),
        st.tuples(st.just("setString"), st.sampled_from(vrs), st.sampled_from(["zv", "bogus", "simultaneous", ""])),
        st.tuples(st.just("getReal"), st.sampled_from(vrs), st.just(0)),
        st.tuples(st.just("getString"), st.sampled_from(vrs), st.just(0)),
        st.tuples(st.just("doStep"), reals, reals),
        st.tuples(st.sampled_from(["enter", "exit", "terminate", "reset", "getState", "setState", "serialize"]),
                  st.just(0), st.just(0)),
    )

    @settings(max_examples=examples, deadline=None, derandomize=True, suppress_health_check=list(HealthCheck))
    @given(st.lists(ops, max_size=25))
    def run(sequence):
        fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier,
                        instanceName="r")
        fmu.instantiate(loggingOn=False)
        fmu.setupExperiment(startTime=0.0)
        states = []
        for name, a, b in sequence:
            try:
                if name == "setReal": fmu.setReal([a], [b])
                elif name == "setInteger": fmu.setInteger([a], [b])
                elif name == "setString": fmu.setString([a], [b])
                elif name == "getReal": fmu.getReal([a])
                elif name == "getString": fmu.getString([a])
                elif name == "doStep": fmu.doStep(a, b)
                elif name == "enter": fmu.enterInitializationMode()
                elif name == "exit": fmu.exitInitializationMode()
                elif name == "terminate": fmu.terminate()
                elif name == "reset": fmu.reset()
                elif name == "getState": states.append(fmu.getFMUstate())
                elif name == "setState" and states: fmu.setFMUstate(states[-1])
                elif name == "serialize" and states:
                    fmu.setFMUstate(fmu.deSerializeFMUstate(fmu.serializeFMUstate(states[-1])))
            except FMICallException as error:
                assert error.status in (3,), error.status  # fmi2Error, never fmi2Fatal
        for state in states:
            fmu.freeFMUstate(state)
        fmu.freeInstance()

    run()
    print("survived")
    """
)


def test_every_registered_fmu_has_a_fixture_here():
    assert set(FIXTURES) == set(SLAVES)


@pytest.mark.parametrize("model_name", sorted(SLAVES))
def test_random_call_sequences_never_crash_or_hang(model_name, request, tmp_path):
    fmu = request.getfixturevalue(FIXTURES[model_name])
    script = tmp_path / "random_calls.py"
    script.write_text(SCRIPT)
    result = subprocess.run([sys.executable, str(script), str(fmu), str(EXAMPLES)], capture_output=True, text=True,
                            timeout=240)
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
    assert "survived" in result.stdout
