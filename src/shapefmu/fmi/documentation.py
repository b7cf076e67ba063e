"""What every FMU archive carries besides its model: ``documentation/index.html`` and an icon.

The FMI standard's distribution section (FMI 2.0.4 section 2.3, FMI 3.0 section 2.5) names the
optional parts of an archive a user meets first: ``documentation/index.html``, the entry point of
the FMU's documentation, and the icon, ``model.png`` at the root in FMI 2.0 and
``terminalsAndIcons/icon.png`` in FMI 3.0. ``add_documentation(root, about, picture)`` writes both
into an unpacked FMU whose ``modelDescription.xml`` is already there: the page says what the FMU does
(``about``: the model's own docstring, with the sampled semantics and the paper and equation it
implements), what its inputs and outputs mean, lists every variable with causality, variability,
type, start, unit and description as the model description declares them, names the interfaces and
platforms inside and gives the full reference of every paper ``about`` cites; the icon draws
``picture``, what the FMU is (``shapefmu.fmi.icon``).

Every string that reaches the page comes from a model description or a docstring, and a plant's
description comes from a user's model file: all of it is escaped.
"""

from __future__ import annotations

import html
import re
import xml.etree.ElementTree as ET
from pathlib import Path

from shapefmu.fmi.icon import icon_png

_TYPES = ("Real", "Integer", "Boolean", "String", "Enumeration",
          "Float64", "Float32", "Int8", "UInt8", "Int16", "UInt16", "Int32", "UInt32", "Int64", "UInt64", "Binary")
# The papers shapefmu implements (README "References"), by the number the docstrings cite them with.
PAPERS = {
    "000": "L. Zhou, E. A. Misawa, Vibration suppression shape filter generation from window functions, IFAC 2005",
    "001": "Y.-C. Huang, Y.-L. Lee, M.-Y. Ma, Numerical simulation and experimental validation of the vibration "
           "suppression control by using input shaping technique with extended Kalman filter, Journal of Marine "
           "Science and Technology 26(5), 2018",
    "002": "C. La-orpacharapan, L. Y. Pao, Nonlinear control for maneuvering multiple flexible mode systems",
    "003": "D. Bowling, G. Starr, J. Wood, R. Lumia, Expanding the twin pulse swing free profile",
    "004": "L. Zhou, E. A. Misawa, Robust vibration suppression control profile generation based on "
           "time-frequency uncertainty",
}


def _paragraphs(text: str) -> str:
    """Plain text (a docstring) as HTML: blank lines part paragraphs, indented blocks stay preformatted."""
    blocks, out = [b for b in text.strip("\n").split("\n\n") if b.strip()], []
    for block in blocks:
        lines = block.split("\n")
        if all(line.startswith("    ") or not line.strip() for line in lines[1:]) and lines[0].startswith("    "):
            out.append(f"<pre>{html.escape(chr(10).join(line[4:] for line in lines))}</pre>")
        else:
            out.append(f"<p>{html.escape(' '.join(line.strip() for line in lines if line.strip()))}</p>")
    return "\n".join(out)


def _variables(root: ET.Element) -> list[dict]:
    """Every variable of an FMI 2.0 or 3.0 model description, as the strings the page shows."""
    rows = []
    if root.get("fmiVersion", "").startswith("2"):
        container = root.find("ModelVariables")
        for var in (container if container is not None else []):
            typed = next((child for child in var if child.tag in _TYPES), None)
            rows.append({"name": var.get("name", ""), "causality": var.get("causality", "local"),
                         "variability": var.get("variability", "continuous"),
                         "type": typed.tag if typed is not None else "",
                         "start": typed.get("start", "") if typed is not None else "",
                         "unit": typed.get("unit", "") if typed is not None else "",
                         "description": var.get("description", "")})
    else:
        container = root.find("ModelVariables")
        for var in (container if container is not None else []):
            rows.append({"name": var.get("name", ""), "causality": var.get("causality", "local"),
                         "variability": var.get("variability", "continuous"), "type": var.tag,
                         "start": var.get("start", ""), "unit": var.get("unit", ""),
                         "description": var.get("description", "")})
    return rows


def index_html(model_description: bytes, about: str, platforms) -> str:
    """The page of one FMU: ``about`` (plain text), its variables, interfaces and ``platforms``."""
    root = ET.fromstring(model_description)
    name = root.get("modelName", "")
    interfaces = [tag for tag in ("CoSimulation", "ModelExchange", "ScheduledExecution") if root.find(tag) is not None]
    rows = "\n".join(
        "<tr>" + "".join(f"<td>{html.escape(row[key])}</td>" for key in
                         ("name", "causality", "variability", "type", "start", "unit", "description")) + "</tr>"
        for row in _variables(root))
    escape = html.escape
    signals = "\n".join(f"<li><b>{escape(row['name'])}</b> ({escape(row['causality'])}"
                        f"{', ' + escape(row['unit']) if row['unit'] else ''}): {escape(row['description'])}</li>"
                        for row in _variables(root) if row["causality"] in ("input", "output"))
    papers = "\n".join(f"<li>paper {number}: {escape(PAPERS[number])}</li>"
                       for number in sorted(set(re.findall(r"paper (\d{3})", about)) & set(PAPERS)))
    return f"""<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<title>{escape(name)}</title>
<style>
body {{ font-family: sans-serif; max-width: 60em; margin: 2em auto; line-height: 1.4; }}
table {{ border-collapse: collapse; }} td, th {{ border: 1px solid #ccc; padding: 0.2em 0.5em; text-align: left; }}
pre {{ background: #f4f4f4; padding: 0.5em; }}
</style>
</head>
<body>
<h1>{escape(name)}</h1>
<p>{escape(root.get("description", ""))}</p>
<p>FMI {escape(root.get("fmiVersion", ""))}, {escape(", ".join(interfaces))}; binaries for
{escape(", ".join(platforms) or "no platform")}. Generated by {escape(root.get("generationTool", ""))}.</p>
<h2>What it does</h2>
{_paragraphs(about)}
<h2>Inputs and outputs</h2>
<ul>
{signals or "<li>none</li>"}
</ul>
<h2>Variables</h2>
<table>
<tr><th>name</th><th>causality</th><th>variability</th><th>type</th><th>start</th><th>unit</th><th>description</th></tr>
{rows}
</table>
<h2>References</h2>
<ul>
{papers or "<li>shapefmu's own model</li>"}
</ul>
</body>
</html>
"""


def add_documentation(root: Path, about: str, picture) -> None:
    """Write ``documentation/index.html`` and the icon of ``picture`` into the unpacked FMU at ``root``."""
    description = (root / "modelDescription.xml").read_bytes()
    fmi3 = not ET.fromstring(description).get("fmiVersion", "").startswith("2")
    binaries = root / "binaries"
    platforms = sorted(p.name for p in binaries.iterdir() if p.is_dir()) if binaries.is_dir() else []
    (root / "documentation").mkdir(exist_ok=True)
    (root / "documentation" / "index.html").write_text(index_html(description, about, platforms), encoding="utf-8")
    icon = root / "terminalsAndIcons" / "icon.png" if fmi3 else root / "model.png"
    icon.parent.mkdir(exist_ok=True)
    icon.write_bytes(icon_png(picture))
