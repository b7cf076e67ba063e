"""What XML 1.0 can hold: every string a model description carries comes from a declaration or a
user's file (a plant's description, a signal table's JSON text) and is checked before it is written."""

import re
from xml.etree.ElementTree import Element

# Characters outside XML 1.0's Char production (section 2.2): no reference can write them either.
_NOT_XML = re.compile("[^\t\n\r\x20-\ud7ff\ue000-\ufffd\U00010000-\U0010ffff]")
# libxml2's XML_MAX_TEXT_LENGTH: the longest attribute value it reads without XML_PARSE_HUGE, which fmpy
# (through lxml) and most FMI hosts do not set; a longer String start value makes an FMU they cannot open.
XML_MAX_TEXT_LENGTH = 10_000_000
# What ElementTree writes for each character that an attribute value cannot hold as itself.
_ESCAPED = {"&": 5, "<": 4, ">": 4, '"': 6, "\n": 5, "\r": 5, "\t": 5}


def check_xml_string(value: str, owner: str, what: str = "value") -> None:
    """Refuse a string XML 1.0 cannot hold (a String start value from a user's file), naming ``owner``."""
    bad = _NOT_XML.search(value)
    if bad:
        raise ValueError(f"{owner}: its {what} holds the character U+{ord(bad.group()):04X} at position {bad.start()}, "
                         f"which XML 1.0 (modelDescription.xml) cannot hold")
    written = len(value.encode("utf-8", "surrogatepass")) + sum((n - 1) * value.count(c) for c, n in _ESCAPED.items())
    if written >= XML_MAX_TEXT_LENGTH:
        raise ValueError(f"{owner}: its {what} is {written:,} bytes in modelDescription.xml, more than the "
                         f"{XML_MAX_TEXT_LENGTH:,} that fmpy and other hosts' XML parsers (libxml2) read")


def check_attributes(root: Element, owner_of) -> None:
    """Every attribute value under ``root``, each named by ``owner_of(node)`` in a refusal."""
    for node in root.iter():
        for name, value in node.attrib.items():
            check_xml_string(value, owner_of(node), f"{name} value")
