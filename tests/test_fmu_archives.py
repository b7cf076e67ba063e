"""Every FMU archive is complete as the FMI standard's distribution section describes it: sources/
with buildDescription.xml and without the standard's own headers (and complete: compiled from
sources/ and the standard's headers alone, the library gives the shipped one's numbers),
documentation/index.html with every variable, the icon, and a pythonfmu FMU's
externalDependencies.txt naming the CPython library it needs."""

import io
import shutil
import subprocess
import xml.etree.ElementTree as ET
import zipfile
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from shapefmu.fmi.native.compile import STANDARD_HEADERS, standard_headers


class _Cells(HTMLParser):
    """The text of every table cell of a page, row by row, and its title."""

    def __init__(self):
        super().__init__()
        self.rows, self.title, self._where = [], "", None

    def handle_starttag(self, tag, attrs):
        if tag == "tr":
            self.rows.append([])
        if tag in ("td", "title"):
            self._where = tag
            if tag == "td":
                self.rows[-1].append("")

    def handle_endtag(self, tag):
        self._where = None

    def handle_data(self, data):
        if self._where == "td":
            self.rows[-1][-1] += data
        elif self._where == "title":
            self.title += data


def _variable_names(description: bytes) -> list[str]:
    return [v.get("name") for v in ET.fromstring(description).find("ModelVariables")]


def assert_complete(fmu: Path, fmi3: bool = False, python: bool = False):
    with zipfile.ZipFile(fmu) as archive:
        names = set(archive.namelist())
        description = archive.read("modelDescription.xml")
        page = archive.read("documentation/index.html").decode()
        icon = archive.read("terminalsAndIcons/icon.png" if fmi3 else "model.png")
        if python:
            dependencies = archive.read("documentation/externalDependencies.txt").decode()
            assert "libpython3." in dependencies and "CPython" in dependencies
        else:
            assert "sources/buildDescription.xml" in names
        shipped_headers = {Path(n).name for n in names if n.startswith(("sources/", "resources/shim/"))}
    assert not shipped_headers & set(STANDARD_HEADERS), shipped_headers & set(STANDARD_HEADERS)
    cells = _Cells()
    cells.feed(page)
    root = ET.fromstring(description)
    assert cells.title == root.get("modelName")
    listed = [row[0] for row in cells.rows if row]
    assert listed == _variable_names(description)
    with Image.open(io.BytesIO(icon)) as image:
        assert image.size == (64, 64) and image.format == "PNG"


def test_native_shaper_and_filter_archives(native_shapers, native_filters):
    for fmu, _ in [*native_shapers.values(), *native_filters.values()]:
        assert_complete(fmu)


@pytest.mark.parametrize("version", ["2.0", "3.0"])
def test_every_native_twin_archive(tmp_path, version):
    from shapefmu.fmi.native.twins import build_all_native

    for fmu in build_all_native(tmp_path, version):
        assert_complete(fmu, fmi3=version == "3.0")


def test_plant_archives_fmi2_and_fmi3(plant_fmus, tmp_path):
    from shapefmu.fmi.native import build_plant_fmu

    for fmu in plant_fmus.values():
        assert_complete(fmu)
    assert_complete(build_plant_fmu("disk_drive", tmp_path / "DiskDrive3.fmu", fmi_version="3.0"), fmi3=True)


def test_pythonfmu_archives(all_fmus):
    for fmu in all_fmus:
        assert_complete(fmu, python=True)


def test_a_plant_description_is_escaped_on_its_page(tmp_path):
    from shapefmu.fmi.native import build_plant_fmu

    model = tmp_path / "odd.toml"
    model.write_text((Path(__file__).parents[1] / "models" / "disk_drive.toml").read_text().replace(
        'description = "voice-coil disk drive, rigid body + 2.0 kHz and 3.0 kHz modes"',
        'description = "<script>alert(1)</script> & \\"quoted\\""'))
    fmu = build_plant_fmu(model, tmp_path / "Odd.fmu")
    page = zipfile.ZipFile(fmu).read("documentation/index.html").decode()
    assert "<script>" not in page and "&lt;script&gt;alert(1)&lt;/script&gt; &amp; &quot;quoted&quot;" in page


def _fmi3_shaper(native_shapers, tmp_path):
    from shapefmu.fmi.native.twins import build_native

    starts = next(iter(native_shapers.values()))[1]
    return build_native("Shaper", tmp_path / "Shaper3.fmu", fmi_version="3.0", **starts)


@pytest.mark.parametrize("which", ["Shaper", "plant", "Shaper FMI 3.0"])
def test_sources_compile_alone_with_the_standard_headers(which, native_shapers, plant_fmus, tmp_path):
    """sources/ and the standard's headers are all a tool needs: the library compiled from them,
    put in place of the shipped one, gives the same numbers in fmpy. An FMI 3.0 FMU's sources need
    FMI 3.0's headers only (a tool importing FMI 3.0 sources has no FMI 2.0 ones)."""
    from fmpy import simulate_fmu

    fmi3 = which.endswith("3.0")
    fmu = {"Shaper": lambda: next(iter(native_shapers.values()))[0], "plant": lambda: plant_fmus["disk_drive"],
           "Shaper FMI 3.0": lambda: _fmi3_shaper(native_shapers, tmp_path)}[which]()
    folder = tmp_path / "unpacked"
    with zipfile.ZipFile(fmu) as archive:
        archive.extractall(folder)
    build = ET.parse(folder / "sources" / "buildDescription.xml").getroot()
    identifier = build.find("BuildConfiguration").get("modelIdentifier")
    c_files = [f.get("name") for f in build.iter("SourceFile")]
    include = standard_headers(tmp_path / "standard")
    if fmi3:  # FMI 3.0's headers only
        for header in include.glob("fmi2*.h"):
            header.unlink()
    library = tmp_path / f"{identifier}.so"
    compiler = shutil.which("gcc") or shutil.which("cc")
    subprocess.run([compiler, "-shared", "-fPIC", "-O2", "-std=c99", "-I", str(include), "-o", str(library),
                    *(str(folder / "sources" / f) for f in c_files), "-lm"], check=True, capture_output=True)
    rebuilt = tmp_path / "Rebuilt.fmu"
    with zipfile.ZipFile(fmu) as old, zipfile.ZipFile(rebuilt, "w") as new:
        for item in old.infolist():
            shipped = f"binaries/{'x86_64-linux' if fmi3 else 'linux64'}/{identifier}.so"
            data = library.read_bytes() if item.filename == shipped else old.read(item)
            new.writestr(item, data)
    inputs = {"Shaper": ("u", 1.0), "plant": ("voltage", 1.0), "Shaper FMI 3.0": ("u", 1.0)}[which]
    runs = [simulate_fmu(str(path), stop_time=0.01, step_size=1e-4, output_interval=1e-4,
                         start_values={inputs[0]: inputs[1]}) for path in (fmu, rebuilt)]
    for name in runs[0].dtype.names:
        assert np.array_equal(runs[0][name], runs[1][name]), name
