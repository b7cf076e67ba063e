"""FMI 3.0 components of the master: the FMI 2.0 units of :mod:`.units` over fmpy's FMI 3 API.

The master treats both versions alike (batched value arrays per family, the same step loop); what
differs is said here: instantiation (``fmi3InstantiateCoSimulation`` without event mode, early
return or intermediate updates; ``fmi3InstantiateModelExchange``), initialisation
(``fmi3EnterInitializationMode`` takes the start time), the step (``fmi3DoStep`` reports a request
to end the simulation in ``terminateSimulation``, and the time reached in ``lastSuccessfulTime``),
``fmi3UpdateDiscreteStates`` in Model Exchange event iterations, and FMU states.

A Co-Simulation FMU that needs event mode (``hasEventMode`` with clocks or events it must be
told of) is run without it: the master does not handle ``eventHandlingNeeded``, and refuses an FMU
that reports it with an error naming the capability.
"""

from __future__ import annotations

import collections
from ctypes import byref, c_bool, c_double, c_uint, c_void_p
from pathlib import Path

from fmpy.fmi3 import FMU3Model, FMU3Slave, fmi3IntermediateUpdateCallback, fmi3LogMessageCallback

from shapefmu.cosim.types import FAMILIES_3
from shapefmu.cosim.units import STATUS_NAMES, FMUFailure, ModelExchangeUnit, Unit, _raw

# As for FMI 2.0 (see units.py): one process-wide logger, finding the unit's queue by its
# instance environment, so no callback dies before an FMU that may still log through it.
_QUEUES: dict[int, collections.deque] = {}


def _log_to_queue(environment, status, category, message):
    queue = _QUEUES.get(environment or 0)
    text = f"[{STATUS_NAMES.get(status, status).replace('fmi2', 'fmi3')}] {(message or b'').decode(errors='replace')}"
    if queue is None:
        print(text)
    else:
        queue.append(text)


_LOGGER = fmi3LogMessageCallback(_log_to_queue)
_NO_INTERMEDIATE_UPDATE = fmi3IntermediateUpdateCallback()


class Unit3(Unit):
    """An FMI 3.0 Co-Simulation FMU instance."""

    fmi3 = True
    prefix = "fmi3"
    real = "Float64"
    family_table = FAMILIES_3
    state_calls = ("fmi3GetFMUState", "fmi3SetFMUState", "fmi3FreeFMUState")
    queues = _QUEUES

    def __init__(self, name: str, fmu_path: Path, unzip_directory: str, description):
        self.name = name
        self.fmu_path = Path(fmu_path)
        self.description = description
        self.variables = {v.name: v for v in description.modelVariables}
        self.messages: collections.deque[str] = collections.deque(maxlen=20)
        _QUEUES[id(self.messages)] = self.messages
        self.fmu = self._make_fmu(unzip_directory)
        self.fmu.component = self._instantiate()
        if not self.fmu.component:
            _QUEUES.pop(id(self.messages), None)
            raise ValueError(f"component {name!r}: {self.fmu_path.name} could not be instantiated"
                             + (f"; FMU log: {' | '.join(self.messages)}" if self.messages else ""))
        self.c = c_void_p(self.fmu.component)
        self.do_step = _raw(self.fmu.dll, "fmi3DoStep")
        self.time_arg, self.step_arg = c_double(), c_double()
        self._flags = (c_bool(), c_bool(), c_bool(), c_double())  # eventHandlingNeeded, terminate, earlyReturn, last
        # fmpy reads FMI 3.0's canGetAndSetFMUState into the FMI 2.0 spelling of the attribute
        self.can_roll_back = bool(self._capabilities().canGetAndSetFMUstate)
        self._state = c_void_p()
        self._start_time = 0.0
        self.configure([], [])

    def _make_fmu(self, unzip_directory):
        return FMU3Slave(guid=self.description.guid, unzipDirectory=unzip_directory,
                         modelIdentifier=self.description.coSimulation.modelIdentifier, instanceName=self.name)

    def _instantiate(self):
        resources = str(Path(self.fmu.unzipDirectory) / "resources") + "/"  # FMI 3.0: a path, not a URI
        return self.fmu.fmi3InstantiateCoSimulation(
            self.name.encode(), self.description.guid.encode(), resources.encode(), False, False,
            False, False, (c_uint * 0)(), 0, id(self.messages), _LOGGER, _NO_INTERMEDIATE_UPDATE)

    def setup(self, start_time: float) -> None:
        self._start_time = start_time  # FMI 3.0 passes it to fmi3EnterInitializationMode

    def enter_initialization(self) -> None:
        self._call("fmi3EnterInitializationMode", self.fmu.enterInitializationMode, startTime=self._start_time)

    def step(self, t: float, h: float, final: bool = True) -> bool:
        """One fmi3DoStep; True when the FMU asked to end the simulation (``terminated_at``);
        ``final``: noSetFMUStatePriorToCurrentPoint (see :meth:`Unit.step`)."""
        event, terminate, early, last = self._flags
        status = self.do_step(self.c, c_double(t), c_double(h), c_bool(final), byref(event), byref(terminate),
                              byref(early), byref(last))
        if status > 1 and not (status == 2 and terminate.value):
            raise FMUFailure(self, "fmi3DoStep", status, time=t)
        if event.value and not terminate.value:
            raise FMUFailure(self, "fmi3DoStep", "eventHandlingNeeded (the master runs FMI 3.0 Co-Simulation FMUs "
                             "without event mode)", time=t)
        if terminate.value:
            self.terminated_at = last.value if t <= last.value <= t + h else t + h
            self.termination_call = "fmi3DoStep set terminateSimulation"
            return True
        return False

    def stop_or_fail(self, t: float, h: float, status: int) -> bool:
        raise FMUFailure(self, "fmi3DoStep", status, time=t)


class ModelExchangeUnit3(ModelExchangeUnit, Unit3):
    """An FMI 3.0 Model Exchange FMU, integrated by the master as an FMI 2.0 one is."""

    interface = "ModelExchange"

    def _make_fmu(self, unzip_directory):
        return FMU3Model(guid=self.description.guid, unzipDirectory=unzip_directory,
                         modelIdentifier=self.description.modelExchange.modelIdentifier, instanceName=self.name)

    def _capabilities(self):
        return self.description.modelExchange

    def _instantiate(self):
        resources = str(Path(self.fmu.unzipDirectory) / "resources") + "/"  # FMI 3.0: a path, not a URI
        return self.fmu.fmi3InstantiateModelExchange(self.name.encode(), self.description.guid.encode(),
                                                     resources.encode(), False, False, id(self.messages), _LOGGER)

    def _derivatives_function(self):
        return self.fmu.getContinuousStateDerivatives

    def _discrete_states(self):
        return "fmi3UpdateDiscreteStates", self.fmu.updateDiscreteStates
