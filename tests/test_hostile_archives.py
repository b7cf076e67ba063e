"""Hostile archives: zip bombs, .ssp files whose FMU climbs out of the archive, files that are not
FMUs, malformed model descriptions, corrupt archives. Each is one line naming the file and the
member, written before anything is extracted, and a bomb writes less than it declares."""

import shutil
import struct
import zipfile
from pathlib import Path

import pytest
from hostile_support import guarded

from shapefmu.fmi.archives import extract_system, read_description
from shapefmu.fmi.ssp import System, read_ssp
from shapefmu.runtime import limits

MIB = 2**20


def simulate(system):
    """(exit code, stderr) of a short run of ``system``."""
    code, _, err = guarded(["simulate", system, "--stop", "0.01", "--step", "1e-3"])
    return code, err


@pytest.fixture
def shaper_system(shaper_fmu, tmp_path):
    """An .ssp holding one Shaper FMU (fixtures_fmi.shaper_fmu) under resources/, as Shaper.fmu."""
    fmu = tmp_path / "Shaper.fmu"
    shutil.copy(shaper_fmu, fmu)  # the session's build has a file name of its own
    return System("alone").add("shaper", fmu).write_ssp(tmp_path / "alone.ssp")


def add_zeros(ssp: Path, member: str, size: int) -> None:
    """Append a member of ``size`` zero bytes, deflated to about a thousandth of that: a zip bomb."""
    with zipfile.ZipFile(ssp, "a", zipfile.ZIP_DEFLATED, compresslevel=9) as archive:
        with archive.open(member, "w", force_zip64=True) as out:
            for _ in range(size // MIB):
                out.write(bytes(MIB))


def declare_size(ssp: Path, member: str, size: int) -> None:
    """Make the archive declare ``size`` bytes for ``member`` (local header and central directory)."""
    data = bytearray(ssp.read_bytes())
    with zipfile.ZipFile(ssp) as archive:
        info = archive.getinfo(member)
    struct.pack_into("<I", data, info.header_offset + 22, size)
    entry = data.find(b"PK\x01\x02")
    while entry != -1:
        length = struct.unpack_from("<H", data, entry + 28)[0]
        if data[entry + 46:entry + 46 + length] == member.encode():
            struct.pack_into("<I", data, entry + 24, size)
        entry = data.find(b"PK\x01\x02", entry + 1)
    ssp.write_bytes(bytes(data))


def written(folder: Path) -> int:
    return sum(p.stat().st_size for p in folder.rglob("*") if p.is_file())


def test_an_unused_bomb_member_is_never_extracted(shaper_system, tmp_path):
    add_zeros(shaper_system, "resources/bomb.bin", 64 * MIB)
    assert shaper_system.stat().st_size < 2 * MIB  # 64 MiB declared in well under 2 MB
    folder = tmp_path / "extracted"
    extract_system(shaper_system, folder)
    assert not (folder / "resources" / "bomb.bin").exists()
    with zipfile.ZipFile(shaper_system) as archive:
        used = archive.getinfo("SystemStructure.ssd").file_size + archive.getinfo("resources/Shaper.fmu").file_size
        declared = sum(info.file_size for info in archive.infolist())
    assert written(folder) == used < declared - 64 * MIB + MIB
    code, err = simulate(shaper_system)
    assert code == 0, err


def test_a_used_member_declaring_more_than_the_limit_is_refused_before_writing(shaper_system, tmp_path):
    declare_size(shaper_system, "resources/Shaper.fmu", 0xF000_0000)  # 3.75 GiB declared
    folder = tmp_path / "extracted"
    with pytest.raises(ValueError, match=r"alone.ssp!resources/Shaper.fmu declares 4,026,531,840 bytes, more than "
                                         r"the limit of 1,073,741,824 \(shapefmu.runtime.limits.MAX_ARCHIVE_MEMBER"):
        extract_system(shaper_system, folder)
    assert not (folder / "resources").exists()  # only the .ssd was written
    code, err = simulate(shaper_system)
    assert code == 2 and err.count("\n") == 1 and "resources/Shaper.fmu declares" in err


def test_a_used_bomb_past_a_lowered_limit_writes_nothing_of_it(shaper_system, tmp_path, monkeypatch):
    # The limit is read at each check, so a program may lower (or raise) it: here 16 MiB.
    monkeypatch.setattr(limits, "MAX_ARCHIVE_MEMBER_BYTES", 16 * MIB)
    with zipfile.ZipFile(shaper_system) as archive:
        ssd = archive.read("SystemStructure.ssd")
    bomb = tmp_path / "bomb.ssp"
    with zipfile.ZipFile(bomb, "w") as archive:
        archive.writestr("SystemStructure.ssd", ssd)
    add_zeros(bomb, "resources/Shaper.fmu", 64 * MIB)
    folder = tmp_path / "extracted"
    with pytest.raises(ValueError, match="declares 67,108,864 bytes, more than the limit of 16,777,216"):
        extract_system(bomb, folder)
    assert written(folder) == len(ssd)


@pytest.mark.parametrize("source", ["../Shaper.fmu", "/tmp/Shaper.fmu", "resources/../../Shaper.fmu",
                                    "file:///tmp/Shaper.fmu"])
def test_an_fmu_source_outside_the_archive_is_refused(shaper_system, shaper_fmu, tmp_path, source):
    shutil.copy(shaper_fmu, tmp_path / "Shaper.fmu")  # a real FMU where the source points
    with zipfile.ZipFile(shaper_system) as archive:
        ssd = archive.read("SystemStructure.ssd").decode()
        fmu = archive.read("resources/Shaper.fmu")
    escaping = tmp_path / "escaping.ssp"
    with zipfile.ZipFile(escaping, "w") as archive:
        archive.writestr("SystemStructure.ssd", ssd.replace('source="resources/Shaper.fmu"', f'source="{source}"'))
        archive.writestr("resources/Shaper.fmu", fmu)
    code, err = simulate(escaping)
    assert code == 2 and err.count("\n") == 1
    assert f"escaping.ssp: Component 'shaper': source {source!r} points outside the archive" in err


def test_a_source_missing_from_the_archive_is_named(shaper_system, tmp_path):
    with zipfile.ZipFile(shaper_system) as archive:
        ssd = archive.read("SystemStructure.ssd").decode()
    lacking = tmp_path / "lacking.ssp"
    with zipfile.ZipFile(lacking, "w") as archive:
        archive.writestr("SystemStructure.ssd", ssd)
    code, err = simulate(lacking)
    assert code == 2 and "source 'resources/Shaper.fmu' is not in the archive" in err


def test_a_corrupt_archive_names_the_member(shaper_system, tmp_path):
    data = bytearray(shaper_system.read_bytes())
    with zipfile.ZipFile(shaper_system) as archive:
        info = archive.getinfo("resources/Shaper.fmu")
    start = info.header_offset + 30 + len(info.filename) + 1000
    data[start:start + 200] = bytes(b ^ 0x5A for b in data[start:start + 200])
    corrupt = tmp_path / "corrupt.ssp"
    corrupt.write_bytes(bytes(data))
    code, err = simulate(corrupt)
    assert code == 2 and err.count("\n") == 1
    assert "corrupt.ssp!resources/Shaper.fmu: the archive is corrupt" in err


def system_folder(tmp_path, fmu_bytes):
    """A folder holding SystemStructure.ssd whose one component is x.fmu with the given bytes."""
    folder = tmp_path / "system"
    folder.mkdir()
    (folder / "x.fmu").write_bytes(fmu_bytes)
    (folder / "SystemStructure.ssd").write_text(
        '<?xml version="1.0"?>\n<ssd:SystemStructureDescription xmlns:ssd="http://ssp-standard.org/SSP1/'
        'SystemStructureDescription" version="1.0" name="s"><ssd:System name="s"><ssd:Elements>'
        '<ssd:Component name="x" source="x.fmu"/></ssd:Elements></ssd:System></ssd:SystemStructureDescription>')
    return folder


def test_a_file_that_is_not_an_fmu_is_named(tmp_path):
    folder = system_folder(tmp_path, b"hello, not a zip")
    code, err = simulate(folder)
    assert code == 2 and err.count("\n") == 1 and "system/x.fmu: not an FMU (not a zip archive)" in err
    with pytest.raises(ValueError, match="not an FMU"):
        System("s").add("x", folder / "x.fmu")


def test_a_malformed_model_description_is_named_with_its_line(shaper_fmu, tmp_path):
    fmu = tmp_path / "cut.fmu"
    with zipfile.ZipFile(shaper_fmu) as source, zipfile.ZipFile(fmu, "w") as out:
        for info in source.infolist():
            data = source.read(info)
            out.writestr(info, data[: len(data) // 2] if info.filename == "modelDescription.xml" else data)
    with pytest.raises(ValueError, match=r"cut.fmu!modelDescription.xml: malformed XML: .*line \d+"):
        read_description(fmu)
    code, err = simulate(system_folder(tmp_path, fmu.read_bytes()))
    assert code == 2 and err.count("\n") == 1 and "x.fmu!modelDescription.xml: malformed XML" in err


def test_a_zip_without_a_model_description_is_not_an_fmu(tmp_path):
    fmu = tmp_path / "empty.fmu"
    with zipfile.ZipFile(fmu, "w") as archive:
        archive.writestr("readme.txt", "no model here")
    with pytest.raises(ValueError, match="empty.fmu: not an FMU .the archive holds no modelDescription.xml"):
        read_description(fmu)


def test_a_directory_given_as_the_system_is_named(tmp_path):
    code, err = simulate(tmp_path)
    assert code == 2 and err.count("\n") == 1
    assert f"{tmp_path} is a directory without a SystemStructure.ssd; give an .ssp or .ssd file" in err
    with pytest.raises(ValueError, match="without a SystemStructure.ssd"):
        read_ssp(tmp_path)
