"""The zip archives users hand us, opened without trusting them: ``.ssp`` systems and ``.fmu`` files.

An archive is the user's file, and may be anything: not a zip at all, corrupt, a "zip bomb" (a
1.3 MB archive declaring a 1 GB member), or a system whose FMU ``source`` climbs out of the
archive (``../x.fmu``). What is refused here is refused with one line naming the file, the member
and what is wrong, before anything is written:

- ``extract_system(archive, folder)`` extracts only the members the system uses (its
  SystemStructure.ssd, the FMUs its components name, the .ssv files its bindings name), each
  within ``runtime.limits.MAX_ARCHIVE_MEMBER_BYTES`` and all within ``MAX_ARCHIVE_BYTES``, checked
  on the sizes the archive declares before anything is written (zipfile writes no more than that);
- ``read_description(fmu)`` reads an FMU's modelDescription.xml (fmpy's reader) after checking that
  the file is a zip archive holding one, whose content extracts within the member limit.
"""

from __future__ import annotations

import posixpath
import shutil
import zipfile
import zlib
from pathlib import Path
from xml.etree import ElementTree as ET

from shapefmu.runtime import limits
from shapefmu.runtime.checks import check_size

SSD_MEMBER = "SystemStructure.ssd"
_CHUNK = 1 << 20
# Elements of an .ssd whose ``source`` names a file the system needs (SSP 1.0: ssd:Component,
# ssd:ParameterBinding).
_SOURCED = ("Component", "ParameterBinding")
# What a damaged archive raises while a member is read: a bad header or CRC, a deflate stream that
# does not decode, data that ends early.
_CORRUPT = (zipfile.BadZipFile, zlib.error, EOFError)


def _open(path: Path, what: str) -> zipfile.ZipFile:
    try:
        return zipfile.ZipFile(path)
    except zipfile.BadZipFile:
        raise ValueError(f"{path}: not {what} (not a zip archive)") from None


def _member_name(source: str, archive: Path, where: str) -> str:
    """The archive member a ``source`` attribute names, refusing one that leaves the archive."""
    name = posixpath.normpath(source.replace("\\", "/"))
    if (":" in source.split("/")[0] or name.startswith("/") or name == ".." or name.startswith("../")
            or source.startswith(("/", "\\"))):
        raise ValueError(f"{archive}: {where}: source {source!r} points outside the archive; "
                         f"an .ssp must carry the files its system uses (e.g. resources/x.fmu)")
    return name


def _extract(archive: zipfile.ZipFile, info: zipfile.ZipInfo, target: Path, path: Path, budget: int) -> int:
    """Copy one member to ``target`` if its declared size fits the member limit and ``budget`` (what
    is left of MAX_ARCHIVE_BYTES); returns that size. A refused or corrupt member leaves no file.

    The declared size bounds what is written: zipfile stops reading a member at its declared size
    (and reports a CRC mismatch if the data goes on), however large the compressed stream inflates.
    """
    where = f"{path}!{info.filename}"
    check_size(info.file_size, "MAX_ARCHIVE_MEMBER_BYTES", f"{where} declares", "bytes", "it is not extracted")
    if info.file_size > budget:
        raise ValueError(f"{where}: the members the system uses declare more than the {limits.MAX_ARCHIVE_BYTES:,} "
                         f"bytes allowed in all (shapefmu.runtime.limits.MAX_ARCHIVE_BYTES)")
    target.parent.mkdir(parents=True, exist_ok=True)
    try:
        with archive.open(info) as source, open(target, "wb") as out:
            shutil.copyfileobj(source, out, _CHUNK)
    except _CORRUPT as error:
        target.unlink(missing_ok=True)
        raise ValueError(f"{where}: the archive is corrupt ({type(error).__name__}: {error})") from None
    return info.file_size


def extract_system(path, folder) -> Path:
    """Extract what the system in the .ssp archive ``path`` uses into ``folder``; returns the .ssd.

    Raises ValueError for a file that is not a zip archive, has no SystemStructure.ssd, names a
    source outside the archive or missing from it, is corrupt, or extracts past the limits.
    """
    path, folder = Path(path), Path(folder)
    with _open(path, "an .ssp archive") as archive:
        members = {info.filename: info for info in archive.infolist()}
        if SSD_MEMBER not in members:
            raise ValueError(f"{path}: the archive holds no {SSD_MEMBER}")
        budget = limits.MAX_ARCHIVE_BYTES
        ssd = folder / SSD_MEMBER
        budget -= _extract(archive, members[SSD_MEMBER], ssd, path, budget)
        for source, where in _sources(ssd, path):
            name = _member_name(source, path, where)
            info = members.get(name)
            if info is None:
                raise ValueError(f"{path}: {where}: source {source!r} is not in the archive")
            target = folder / name
            if not target.exists():
                budget -= _extract(archive, info, target, path, budget)
    return ssd


def _sources(ssd: Path, archive: Path) -> list[tuple[str, str]]:
    """(source, element description) of every element of the .ssd that names a file."""
    try:
        root = ET.parse(ssd).getroot()
    except ET.ParseError as error:
        raise ValueError(f"{archive}!{SSD_MEMBER}: not valid XML: {error}") from None
    found = []
    for node in root.iter():
        kind = node.tag.rpartition("}")[2]
        source = node.get("source")
        if kind in _SOURCED and source is not None:
            name = node.get("name")
            found.append((source, f"{kind} {name!r}" if name else kind))
    return found


def read_description(fmu):
    """fmpy's ModelDescription of the FMU file ``fmu``, or ValueError naming the file and the fault."""
    from fmpy import read_model_description
    from lxml import etree

    fmu = Path(fmu)
    if fmu.is_dir():
        raise ValueError(f"{fmu}: is a directory, not an FMU file")
    with _open(fmu, "an FMU") as archive:
        infos = archive.infolist()
        if "modelDescription.xml" not in {info.filename for info in infos}:
            raise ValueError(f"{fmu}: not an FMU (the archive holds no modelDescription.xml)")
        check_size(sum(info.file_size for info in infos), "MAX_ARCHIVE_MEMBER_BYTES", f"{fmu} declares",
                   "bytes of content", "this FMU is not extracted")
    try:
        return read_model_description(str(fmu), validate=False)
    except etree.XMLSyntaxError as error:
        raise ValueError(f"{fmu}!modelDescription.xml: malformed XML: {error}") from None
    except _CORRUPT as error:
        raise ValueError(f"{fmu}: the archive is corrupt ({type(error).__name__}: {error})") from None
    except Exception as error:  # noqa: BLE001 - fmpy raises bare Exception (and AttributeError, ValueError,
        # KeyError...) for a well-formed file it cannot read, e.g. an unsupported fmiVersion: the file's fault
        raise ValueError(f"{fmu}!modelDescription.xml: cannot be read as an FMI model description "
                         f"({type(error).__name__}: {error})") from None
