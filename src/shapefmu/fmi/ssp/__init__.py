"""SSP 1.0 system descriptions (``.ssd``, ``.ssp``, ``.ssv``), as FMPy keeps them in ``fmpy.ssp``:

- :mod:`.system`: the :class:`System` of FMU components, connections and parameter bindings, and its
  writer (``write_system``, ``System.write_ssd`` / ``write_ssp``);
- :mod:`.reading`: ``read_ssp`` (an .ssp archive, an .ssd file or a folder);
- :mod:`.values`: parameter values and ``.ssv`` files (``read_ssv``, ``write_ssv``);
- :mod:`.connectors`: an FMU's connectors, FMI 3.0 arrays and their elements;
- :mod:`.targets`: the variants other tools read (OMSimulator, libcosim).
"""

from shapefmu.fmi.ssp.reading import read_ssp
from shapefmu.fmi.ssp.system import Component, Connection, System, check_component_name, write_system
from shapefmu.fmi.ssp.values import PARAMETER_SET, read_ssv, write_ssv

__all__ = ["PARAMETER_SET", "Component", "Connection", "System", "check_component_name", "read_ssp", "read_ssv",
           "write_ssv", "write_system"]
