"""The papers' plant models and SSP systems that ship with shapefmu, found by name.

They live in the repository's top-level ``models/`` folder; a wheel carries a copy of it as package
data, ``shapefmu/plants/models`` (setup.py's build step writes it), so an installed shapefmu finds
``disk_drive`` or ``ten_pendula`` from any folder. A path that exists always wins over a name.
"""

from __future__ import annotations

import ast
import os
import tomllib
from pathlib import Path
from xml.etree import ElementTree as ET

MODEL_SUFFIXES = (".toml", ".py")  # plant models: declarative files, and Python files defining plant()
SYSTEM_SUFFIXES = (".ssd",)  # SSP systems of the papers' examples


def models_folder() -> Path:
    """The folder of the shipped models: the wheel's package data, else the checkout's ``models/``.

    Examples
    --------
    >>> (models_folder() / "disk_drive.toml").is_file()
    True
    """
    packaged = Path(__file__).resolve().parent / "models"
    if packaged.is_dir():
        return packaged
    return Path(__file__).resolve().parents[3] / "models"  # src/shapefmu/plants/shipped.py -> the checkout


def shipped(suffixes: tuple[str, ...] = MODEL_SUFFIXES + SYSTEM_SUFFIXES) -> list[Path]:
    """The shipped files with those suffixes, by name.

    Examples
    --------
    >>> [path.name for path in shipped((".ssd",))]  # the papers' SSP systems
    ['disk_drive_shaped.ssd', 'disk_drive_stos.ssd']
    """
    folder = models_folder()
    if not folder.is_dir():
        return []
    return sorted((p for p in folder.iterdir() if p.suffix in suffixes and not p.name.startswith("_")), key=lambda p: p.name)


def find(name_or_path, suffixes: tuple[str, ...] = MODEL_SUFFIXES, what: str = "plant model") -> Path:
    """``name_or_path`` as an existing file, or the shipped file of that name (``disk_drive`` or
    ``disk_drive.toml``); a ValueError names what ships when neither exists.

    Examples
    --------
    >>> find("disk_drive").name, find("pendulum").name
    ('disk_drive.toml', 'pendulum.py')
    """
    text = os.fspath(name_or_path)
    path = Path(text)
    if path.exists() or "/" in text or os.sep in text:
        return path  # a path: given as it is (a missing one is reported by whoever opens it)
    candidates = [path] if path.suffix in suffixes else [path.with_name(path.name + suffix) for suffix in suffixes]
    for candidate in candidates:
        found = models_folder() / candidate.name
        if found.is_file():
            return found
    names = ", ".join(p.stem for p in shipped(suffixes)) or "none"
    raise ValueError(f"{name_or_path}: no such file, and no shipped {what} of that name (shipped: {names}; "
                     f"see shapefmu plant list)")


def describe() -> str:
    """The text of ``shapefmu plant list``: each shipped model and system with what it is.

    Examples
    --------
    >>> print(describe().splitlines()[1])
      disk_drive                   rigid_flexible: voice-coil disk drive, rigid body + 2.0 kHz and 3.0 kHz modes
    """
    lines = ["plant models (shapefmu plant show|build NAME, optimal NAME, stos NAME, compare NAME):"]
    for path in shipped(MODEL_SUFFIXES):
        lines.append(f"  {path.stem:28s} {_summary(path)}")
    lines.append("SSP systems (shapefmu simulate NAME, with the FMUs that shapefmu build writes to ./fmus):")
    for path in shipped(SYSTEM_SUFFIXES):
        lines.append(f"  {path.stem:28s} {_summary(path)}")
    lines.append(f"shipped in {models_folder()}")
    return "\n".join(lines)


def _summary(path: Path) -> str:
    """One line on a shipped file: a model's kind and description, a system's components."""
    try:
        if path.suffix == ".toml":
            data = tomllib.loads(path.read_text(encoding="utf-8"))
            return f"{data.get('kind', '?')}: {data.get('description', '')}"
        if path.suffix == ".py":
            docstring = ast.get_docstring(ast.parse(path.read_text(encoding="utf-8"))) or ""
            return f"Python plant(): {docstring.splitlines()[0] if docstring else ''}"
        root = ET.parse(path).getroot()
        components = [f"{c.get('name')} ({Path(c.get('source', '')).name})" for c in root.iter()
                      if c.tag.endswith("}Component")]
        return "components " + ", ".join(components)
    except (OSError, ValueError, SyntaxError, ET.ParseError) as error:
        return f"unreadable: {error}"
