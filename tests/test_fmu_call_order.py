"""The pythonfmu FMUs' C front end keeps the FMI 2.0 state machine and refuses calls out of order.

OMSimulator 3.0 crashed (SIGSEGV, exit 139) on an SSP whose Shaper got zeta[1] = 1.5. After the
failed fmi2ExitInitializationMode it terminates its system: fmi2Terminate on the Shaper, which the
front end forwarded and the slave accepted, so OMSimulator freed the instance; then the plant
refused fmi2Terminate in Initialization Mode, the round failed, and OMSimulator terminated again
with the handles it kept: fmi2Terminate on the freed Shaper read its freed memory and jumped
through a garbage pointer in pythonfmu's export library. The front end now tracks the instance's
state (shim/fmi2_shim.c, 6.): after a failed initialisation only the getters, fmi2SetFMUstate,
fmi2Reset and fmi2FreeInstance are accepted, so fmi2Terminate is refused and OMSimulator never frees
the instance early; and a freed instance leaves a small handle behind, so a host's call on it is
refused instead of reaching freed memory. Our C host (hosts_c/fmi2_host.c) replays OMSimulator's
teardown (``--on-error omsimulator``) and arbitrary call lists (``--calls``). The reference for
every refusal is the FMI 2.0 state machine as the native plant FMUs implement it (plant_part.c): in
the same states they answer the same calls with the same status and message.
"""

from __future__ import annotations

import pytest
from support.c_hosts import fmu_arguments, run_host
from fmpy import read_model_description
from fmpy.fmi1 import FMICallException

RUN = ["--stop", 0.004, "--step", 1e-3]
AFTER_AN_ERROR = "not allowed after an error (only the getters, fmi2SetFMUstate, fmi2Reset and fmi2FreeInstance are)"


def _vr(fmu, name):
    return next(v.valueReference for v in read_model_description(str(fmu)).modelVariables if v.name == name)


@pytest.fixture(scope="module")
def extracted(shaper_fmu, shape_filter_fmu, plant_fmus, tmp_path_factory):
    """``--fmu`` arguments of the Shaper, a ShapeFilter and the disk-drive plant, extracted once."""
    folder = tmp_path_factory.mktemp("call_order")
    fmus = {"Shaper": shaper_fmu, "ShapeFilter": shape_filter_fmu, "plant": plant_fmus["disk_drive"]}
    return {name: fmu_arguments(fmu, folder / name) for name, fmu in fmus.items()}


@pytest.fixture(scope="module")
def bad_zeta(shaper_fmu):
    """``--set-real`` giving the Shaper zeta[1] = 1.5, outside [0, 1)."""
    return ["--set-real", f"{_vr(shaper_fmu, 'zeta[1]')}=1.5"]


def _calls(c_host, arguments, calls, *options):
    """Run ``calls`` on one instance; the statuses printed by the host and its stderr."""
    result = run_host(c_host, [arguments + list(options)], "--calls", ",".join(calls))
    assert result.returncode == 0, result.stdout + result.stderr[-3000:]
    statuses = [line.split()[1] for line in result.stdout.splitlines()]
    return [int(s) if s != "-" else s for s in statuses], result.stderr


def test_omsimulators_teardown_after_a_failed_initialisation_refuses_terminate_and_exits_0(
    c_host, extracted, bad_zeta
):
    result = run_host(c_host, [extracted["Shaper"] + bad_zeta, extracted["plant"]], *RUN, "--on-error", "omsimulator")
    assert result.returncode == 0, result.stdout + result.stderr[-3000:]  # was -11 (SIGSEGV): 139 in a shell
    assert result.stdout.splitlines() == [
        "failed fmi2ExitInitializationMode 3",
        "terminate Shaper_0 3",  # refused: the instance is in the error state, so OMSimulator does not free it
        "terminate Shaper_0 3",  # oms_terminate's second round: the instance is alive and refuses again
        "free Shaper_0",  # deleting the model frees both, once
        "free disk_drive_0",
        "done",
    ]
    assert "Shaper_0: Shaper Shaper_0: invalid parameters: zeta[1] must be in [0, 1), got 1.5" in result.stderr
    assert result.stderr.count(f"Shaper_0: fmi2Terminate: {AFTER_AN_ERROR}") == 2


NOT_LIVE = "shapefmu FMU: {} called on an instance that is not live (already freed?)"


# The first FMU initialises, so OMSimulator's first round terminates and frees it before the
# Shaper refuses; the second round then calls fmi2Terminate on the freed instance, and deleting the
# model frees it a second time. The pythonfmu front end leaves a handle behind on free; the native
# plant (generic C layer) keeps a registry of live instances. With the plant first (the "zplant"
# system of README.md) this crashed: use after free in the plant (-11 or -6).
@pytest.mark.parametrize("first, instance, refusal", [
    ("ShapeFilter", "ShapeFilter_0", "fmi2Terminate: not allowed after fmi2FreeInstance"),
    ("plant", "disk_drive_0", NOT_LIVE.format("fmi2Terminate")),
])
def test_a_call_on_an_instance_the_host_freed_is_refused_not_a_use_after_free(
    c_host, extracted, bad_zeta, first, instance, refusal
):
    fmus = [extracted[first], extracted["Shaper"] + bad_zeta]
    result = run_host(c_host, fmus, *RUN, "--on-error", "omsimulator")
    assert result.returncode == 0, result.stdout + result.stderr[-3000:]
    assert result.stdout.splitlines() == [
        "failed fmi2ExitInitializationMode 3",
        f"terminate {instance} 0",
        f"free {instance}",
        "terminate Shaper_0 3",
        f"terminate {instance} 3",  # on the freed instance: refused
        f"free {instance}",  # a second fmi2FreeInstance: nothing left to free
        "free Shaper_0",
        "done",
    ]
    assert result.stderr.count(refusal) == 1


@pytest.fixture(scope="module")
def native_shaper(tmp_path_factory):
    """``--fmu`` arguments of a native (C) ZVD Shaper."""
    from shapefmu.fmi.native.sampled import build_native_fmu

    folder = tmp_path_factory.mktemp("native_order")
    fmu = build_native_fmu("Shaper", folder / "NativeShaper.fmu", kind="zvd", **{"f[1]": 10.0, "zeta[1]": 0.05})
    return fmu_arguments(fmu, folder / "NativeShaper")


@pytest.mark.parametrize("which", ["plant", "native Shaper"])
def test_calls_on_a_freed_native_instance_are_refused_and_a_second_free_does_nothing(
    c_host, extracted, native_shaper, which
):
    arguments = extracted["plant"] if which == "plant" else native_shaper
    calls = ["setup", "enter", "exit", "step", "free", "terminate", "step", "get", "reset", "free", "setup"]
    statuses, stderr = _calls(c_host, arguments, calls)  # exits 0: no use after free
    assert statuses == [0, 0, 0, 0, "-", 3, 3, 3, 3, "-", 3]
    for function in ("fmi2Terminate", "fmi2DoStep", "fmi2GetReal", "fmi2Reset", "fmi2SetupExperiment"):
        assert stderr.count(NOT_LIVE.format(function)) == 1, stderr


def test_terminate_after_a_failed_exit_initialization_is_refused_and_free_instance_works(c_host, extracted, bad_zeta):
    calls = ["setup", "enter", "set", "exit", "terminate", "free"]
    statuses, stderr = _calls(c_host, extracted["Shaper"], calls, *bad_zeta)
    assert statuses == [0, 0, 0, 3, 3, "-"]
    assert f"Shaper: fmi2Terminate: {AFTER_AN_ERROR}" in stderr


# Calls out of order: every call before the last is allowed; the last is refused with this message.
OUT_OF_ORDER = {
    "doStep before initialisation": (["setup", "step"], "fmi2DoStep: not allowed in Instantiated"),
    "doStep in initialization mode": (["setup", "enter", "step"], "fmi2DoStep: not allowed in Initialization Mode"),
    "terminate before initialisation": (["setup", "terminate"], "fmi2Terminate: not allowed in Instantiated"),
    "terminate twice": (["setup", "enter", "exit", "step", "terminate", "terminate"],
                        "fmi2Terminate: not allowed in Terminated"),
    "doStep after terminate": (["setup", "enter", "exit", "terminate", "step"], "fmi2DoStep: not allowed in Terminated"),
    "exitInitializationMode twice": (["setup", "enter", "exit", "exit"],
                                     "fmi2ExitInitializationMode: not allowed in Step Complete"),
    "enterInitializationMode twice": (["setup", "enter", "enter"],
                                      "fmi2EnterInitializationMode: not allowed in Initialization Mode"),
    "setupExperiment after initialisation": (["setup", "enter", "exit", "setup"],
                                             "fmi2SetupExperiment: not allowed in Step Complete"),
    "setReal after terminate": (["setup", "enter", "exit", "terminate", "set"], "fmi2SetReal: not allowed in Terminated"),
}


@pytest.mark.parametrize("case", OUT_OF_ORDER)
def test_a_call_out_of_order_is_refused_with_a_message_as_the_native_plant_refuses_it(c_host, extracted, case):
    calls, message = OUT_OF_ORDER[case]
    u = ["--set-real", f"{extracted['Shaper'][4]}=0.5"]  # the Shaper's input: a setter call allowed while running
    statuses, stderr = _calls(c_host, extracted["Shaper"], calls, *u)
    assert statuses == [0] * (len(calls) - 1) + [3]
    assert f"Shaper: {message}" in stderr
    assert "allowed only" not in stderr and "is not allowed in phase" not in stderr  # never reached the slave
    plant_u = ["--set-real", f"{extracted['plant'][4]}=0.5"]
    plant_statuses, plant_stderr = _calls(c_host, extracted["plant"], calls, *plant_u)
    assert plant_statuses == statuses
    assert f"disk_drive: {message}" in plant_stderr


def test_after_a_failed_initialisation_only_getters_and_reset_are_accepted_and_reset_runs_again(
    c_host, extracted, bad_zeta
):
    calls = ["setup", "enter", "set", "exit", "get", "step", "terminate", "set", "exit", "reset",
             "setup", "enter", "exit", "step", "terminate", "free"]
    statuses, stderr = _calls(c_host, extracted["Shaper"], calls, *bad_zeta)
    # After fmi2Reset the parameters are the FMU's start values again: the second run is valid.
    assert statuses == [0, 0, 0, 3, 0, 3, 3, 3, 3, 0, 0, 0, 0, 0, 0, "-"]
    for call in ("fmi2DoStep", "fmi2Terminate", "fmi2SetReal", "fmi2ExitInitializationMode"):
        assert f"Shaper: {call}: {AFTER_AN_ERROR}" in stderr


def _slave(fmu, name="order"):
    from fmpy import extract
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(str(fmu))
    slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(fmu)), modelIdentifier=md.coSimulation.modelIdentifier,
                      instanceName=name)
    slave.instantiate(loggingOn=False)
    return slave


def test_a_restored_fmu_state_brings_back_the_state_machine_state_it_was_saved_in(shaper_fmu, capfd):
    slave = _slave(shaper_fmu)
    instantiated = slave.getFMUState()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    slave.doStep(0.0, 1e-3)
    stepping = slave.getFMUState()
    serialised = slave.serializeFMUState(stepping)
    slave.terminate()
    slave.setFMUState(stepping)  # back in Step Complete: the host may step again
    slave.doStep(1e-3, 1e-3)
    slave.setFMUState(instantiated)
    with pytest.raises(FMICallException) as refused:
        slave.doStep(2e-3, 1e-3)
    assert refused.value.status == 3
    assert "fmi2DoStep: not allowed in Instantiated" in capfd.readouterr().out
    slave.reset()
    slave.setFMUState(slave.deserializeFMUState(serialised))  # serialised with its state
    slave.doStep(1e-3, 1e-3)
    for state in (instantiated, stepping):
        slave.freeFMUState(state)
    slave.freeInstance()


def test_a_state_saved_before_a_failed_initialisation_restores_the_instance(shaper_fmu):
    # FMI 2.0: after fmi2Error the simulation may restart from a stored state with fmi2SetFMUstate.
    slave = _slave(shaper_fmu)
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    good = slave.getFMUState()
    slave.setReal([_vr(shaper_fmu, "zeta[1]")], [1.5])
    with pytest.raises(FMICallException):
        slave.exitInitializationMode()
    with pytest.raises(FMICallException):
        slave.getFMUState()  # not in the error state: there is nothing sound to save
    slave.setFMUState(good)
    slave.exitInitializationMode()
    slave.doStep(0.0, 1e-3)
    slave.terminate()
    slave.freeFMUState(good)
    slave.freeInstance()
