"""Model descriptions: one ``ModelDescription`` of a built FMU (``model``) and one writer per FMI
version (``fmi2``, ``fmi3``), as FMPy reads and writes them; the units with their SI base units
(``units``) and the check that every string fits in XML (``xml_text``)."""

from shapefmu.fmi.description import fmi2, fmi3
from shapefmu.fmi.description.model import ModelDescription, now
from shapefmu.fmi.description.xml_text import XML_MAX_TEXT_LENGTH, check_xml_string

WRITERS = {"2.0": fmi2.write, "3.0": fmi3.write}


def write(md: ModelDescription, fmi_version: str) -> str:
    """The ``modelDescription.xml`` text of ``md`` in FMI ``fmi_version`` ("2.0" or "3.0")."""
    if fmi_version not in WRITERS:
        raise ValueError(f"fmi_version must be one of {', '.join(WRITERS)}, got {fmi_version!r}")
    return WRITERS[fmi_version](md)


__all__ = ["XML_MAX_TEXT_LENGTH", "ModelDescription", "check_xml_string", "now", "write"]
