"""What XML 1.0 can hold: every string a model description carries comes from a declaration or a
user's file (a plant's description, a signal table's JSON text) and is checked before it is written."""

import re
from xml.etree.ElementTree import Element

# Characters outside XML 1.0's Char production (section 2.2): no reference can write them either.
_NOT_XML = re.compile("[^\t\n\r\x20-\ud7ff\ue000-\ufffd\U00010000-\U0010ffff]")


def check_xml_string(value: str, owner: str, what: str = "value") -> None:
    """Refuse a string XML 1.0 cannot hold (a String start value from a user's file), naming ``owner``."""
    bad = _NOT_XML.search(value)
    if bad:
        raise ValueError(f"{owner}: its {what} holds the character U+{ord(bad.group()):04X} at position {bad.start()}, "
                         f"which XML 1.0 (modelDescription.xml) cannot hold")


def check_attributes(root: Element, owner_of) -> None:
    """Every attribute value under ``root``, each named by ``owner_of(node)`` in a refusal."""
    for node in root.iter():
        for name, value in node.attrib.items():
            check_xml_string(value, owner_of(node), f"{name} value")
