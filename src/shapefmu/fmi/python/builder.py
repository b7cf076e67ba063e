"""Build shapefmu slaves into FMI 2.0 co-simulation FMUs (linux64).

An FMU holds

- ``binaries/linux64/<Model>.so``: the C front end (``shim/fmi2_shim.c``, ``shim/fmu_states.c``
  and ``shim/python_runtime.c``, compiled here with the system C compiler), which makes libpython
  global, starts the interpreter, keeps the FMI 2.0 state machine and forwards to
- ``binaries/linux64/<Model>_pythonfmu.so``: pythonfmu's export library, which embeds Python;
- ``resources/<package>/``: the kind (its interface and model, ``fmi/kinds``), the slave and
  ``runtime/``, under a package name made of the shapefmu version and a hash of exactly these
  sources, so FMUs built from different code never share a module in one interpreter, and FMUs
  built from the same code share it harmlessly;
- ``resources/<package>_<Model>.py`` and ``resources/slavemodule.txt``: the entry module the export
  library imports;
- ``resources/shapefmu_build.json``: the start values baked in, the GUID and the declared
  dependencies, read by every instance (so two builds of one slave differ only here);
- ``resources/shim/`` (the front end's sources, for the record) and ``modelDescription.xml``.

Start values are checked at build time by running the kind's own design (``Model.initialize``), so
a bad parameter fails the build with its ValueError.
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.util
import json
import os
import shutil
import sys
import sysconfig
import tempfile
import uuid
import zipfile
from pathlib import Path

from shapefmu import __version__
from shapefmu.files import check_output, write_file
from shapefmu.fmi.compiler import run_compiler
from shapefmu.fmi.description import ModelDescription, fmi2, now
from shapefmu.fmi.kinds import KINDS, designed, kind

PYTHON_FMI_DIR = Path(__file__).parent
PACKAGE_DIR = PYTHON_FMI_DIR.parent.parent
KINDS_DIR = PYTHON_FMI_DIR.parent / "kinds"
SHIM_DIR = PYTHON_FMI_DIR / "shim"
SHIM_SOURCES = (SHIM_DIR / "fmi2_shim.c", SHIM_DIR / "fmu_states.c", SHIM_DIR / "python_runtime.c")
# The FMI 2.0 standard headers, shared with the native FMUs.
FMI_HEADERS_DIR = PYTHON_FMI_DIR.parent / "native" / "c"
SHIM_FILES = (*SHIM_SOURCES, SHIM_DIR / "fmi2_shim.h")  # the standard's headers left out
BUILD_FILE = "shapefmu_build.json"
ENTRY_MODULE = '''"""Entry module of the {name} FMU, imported by pythonfmu's export library."""

from {package}.fmi.kinds.{module} import Model as _Model
from {package}.fmi.python import slave_base as _slave_base


class {name}(_slave_base.Fmi2Slave):
    model_class = _Model


# Balances the export library's extra release of this module's globals (slave_base.ENTRY_MODULE_REFERENCES).
_slave_base.ENTRY_MODULE_REFERENCES.append(globals())
'''
# Minor versions of Python 3 the front end looks for when the recorded libpython is missing.
FALLBACK_MINORS = (13, 12, 11, 10, 9, 8)


def bundled_sources(name: str) -> dict[str, bytes]:
    """Files of the bundled package, relative to it: runtime/, the kind and the slave."""
    kind(name)  # a known kind, or ValueError
    files = {
        "__init__.py": b'"""shapefmu code bundled into one FMU."""\n',
        "fmi/__init__.py": b"",
        "fmi/python/__init__.py": b"",
    }
    for path in sorted((PACKAGE_DIR / "runtime").glob("*.py")):
        files[f"runtime/{path.name}"] = path.read_bytes()
    for module in ("slave_base.py", "state_codec.py"):
        files[f"fmi/python/{module}"] = (PYTHON_FMI_DIR / module).read_bytes()
    for module in ("__init__.py", "interface.py", "model.py", f"{KINDS[name]}.py"):
        files[f"fmi/kinds/{module}"] = (KINDS_DIR / module).read_bytes()
    return files


def package_name(files: dict[str, bytes]) -> str:
    """``shapefmu_<version>_<hash of the bundled sources>``: unique to the code, not to the build."""
    digest = hashlib.sha256()
    for relative in sorted(files):
        digest.update(relative.encode() + b"\0" + files[relative] + b"\0")
    return f"shapefmu_{__version__.replace('.', '_')}_{digest.hexdigest()[:16]}"


def _libpython() -> str:
    """The build interpreter's shared libpython, recorded in the front end ('' if Python is static)."""
    if not sysconfig.get_config_var("Py_ENABLE_SHARED"):
        return ""
    path = Path(sysconfig.get_config_var("LIBDIR") or "") / (sysconfig.get_config_var("INSTSONAME") or "")
    return str(path) if path.is_file() else ""


def compile_shim(out: Path, model_identifier: str, guid: str, libpython: str | None = None, minors=None) -> Path:
    """Compile the C front end for one FMU with the system C compiler.

    ``libpython`` (default: the build interpreter's) and ``minors`` (default: the build's minor
    version, then ``FALLBACK_MINORS``) are where the front end looks for Python at run time.
    """
    compiler = os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc")
    if not compiler:
        raise ValueError("no C compiler: a pythonfmu FMU's front end is compiled when it is built, with $CC, cc or "
                         "gcc, and none is on PATH; install one (Debian/Ubuntu: apt install gcc) or set CC")
    libpython = _libpython() if libpython is None else libpython
    if minors is None:
        minors = [sys.version_info.minor] + [m for m in FALLBACK_MINORS if m != sys.version_info.minor]
    command = [
        compiler, "-shared", "-fPIC", "-O2", "-fvisibility=hidden", "-Wall",
        f'-DSHIM_GUID="{guid}"',
        f'-DSHIM_LIBPYTHON="{libpython}"',
        f'-DSHIM_PYTHONHOME="{sys.base_prefix if libpython else ""}"',
        f'-DSHIM_INNER_NAME="{model_identifier}_pythonfmu.so"',
        f"-DSHIM_FALLBACK_MINORS={','.join(map(str, minors))}",
        "-I", str(FMI_HEADERS_DIR), "-o", str(out), *map(str, SHIM_SOURCES), "-ldl", "-lpthread",
    ]
    result = run_compiler(command)
    if result.returncode != 0:
        raise RuntimeError(f"compiling the FMU front end failed:\n{' '.join(command)}\n{result.stderr}")
    return out


def _export_library() -> tuple[Path, str]:
    spec = importlib.util.find_spec("pythonfmu")
    if spec is None or not spec.submodule_search_locations:
        raise RuntimeError("pythonfmu is needed at build time for its export library")
    root = Path(spec.submodule_search_locations[0])
    library = root / "resources" / "binaries" / "linux64" / "libpythonfmu-export.so"
    if not library.is_file():
        raise RuntimeError(f"pythonfmu's linux64 export library is missing: {library}")
    version = (root / "_version.py").read_text().split("=")[-1].strip().strip("'\"")
    return library, version


def build_fmu(name: str, out_path, **start_values) -> Path:
    """Build FMU ``name`` (a key of ``shapefmu.fmi.kinds.KINDS``) to ``out_path`` with ``start_values`` baked in.

    Structured variable names are passed as a mapping: ``build_fmu("Shaper", p, **{"f[1]": 2000.0})``.
    Returns the path of the written .fmu.
    """
    if not sys.platform.startswith("linux"):
        raise RuntimeError(f"FMUs are built for linux64 only (the front end is ELF), not for {sys.platform}")
    out_path = Path(out_path)
    model = designed(name, start_values)
    dependencies = model.output_dependencies()
    files = bundled_sources(name)
    package = package_name(files)
    baked = {key: model.values[key] for key in start_values}
    identity = json.dumps({"package": package, "model": name, "start": baked}, sort_keys=True)
    guid = "{" + str(uuid.uuid5(uuid.NAMESPACE_URL, "shapefmu:" + identity)) + "}"
    export_library, pythonfmu_version = _export_library()
    xml = fmi2.write(_description(model, guid, dependencies, pythonfmu_version))
    documentation = _documentation(xml, name, model.picture())
    entry = f"{package}_{name}"
    build = {"guid": guid, "package": package, "start_values": baked, "dependencies": dependencies}
    check_output(out_path, "FMU")
    with tempfile.TemporaryDirectory(prefix="shapefmu_build_") as temp:
        shim = compile_shim(Path(temp) / f"{name}.so", name, guid)

        def write(partial):
            with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as fmu:
                fmu.writestr("modelDescription.xml", xml)
                fmu.write(shim, f"binaries/linux64/{name}.so")
                fmu.write(export_library, f"binaries/linux64/{name}_pythonfmu.so")
                for source in SHIM_FILES:  # the record; hosts do not build it
                    fmu.write(source, f"resources/shim/{source.name}")
                fmu.writestr("resources/slavemodule.txt", entry)
                fmu.writestr(f"resources/{entry}.py", ENTRY_MODULE.format(name=name, package=package, module=KINDS[name]))
                fmu.writestr(f"resources/{BUILD_FILE}", json.dumps(build, indent=2))
                for relative, content in files.items():
                    fmu.writestr(f"resources/{package}/{relative}", content)
                for relative, content in documentation.items():
                    fmu.writestr(relative, content)

        return write_file(out_path, write, "FMU")  # no half-written FMU is ever left under the final name


# The log categories of a pythonfmu FMU: (name, description).
LOG_CATEGORIES = (
    ("logStatusWarning", "Warnings"),
    ("logStatusError", "Errors: bad parameters, non-finite inputs, calls out of order"),
    ("logStatusFatal", "Failures of the embedded Python runtime"),
    ("logAll", "Everything else (debug logging)"),
)


def _description(model, guid: str, dependencies: dict, pythonfmu_version: str) -> ModelDescription:
    """The model description of the designed ``model``'s FMU: its kind's variables with the build's
    start values; no external tool, state get/set and serialisation, Python's own memory."""
    interface = model.interface
    variables = tuple(v.with_start(None if v.causality == "output" else model.values[v.name])
                      for v in interface.variables)
    return ModelDescription(
        model_name=interface.name, identifier=interface.name, guid=guid, description=interface.description,
        generation_tool=f"shapefmu {__version__} (pythonfmu {pythonfmu_version} export library)",
        variables=variables, dependencies=dependencies, log_categories=LOG_CATEGORIES, generation_date=now(),
        experiment=model.experiment(), host_memory=False)


def _documentation(xml: str, name: str, picture) -> dict[str, bytes]:
    """documentation/index.html, externalDependencies.txt and model.png (``picture``) of the pythonfmu FMU ``name``."""
    from shapefmu.fmi.documentation import index_html
    from shapefmu.fmi.icon import icon_png

    about = kind(name).__doc__
    # The library's file name only: the build machine's folders say nothing about the user's machine.
    soname = Path(_libpython()).name or f"libpython3.{sys.version_info.minor}.so.1.0"
    dependencies = (f"The {name} FMU runs its model in CPython, embedded through pythonfmu's export library.\n"
                    f"It needs the CPython 3 shared library: built with CPython 3.{sys.version_info.minor} ({soname}); "
                    f"where the build's copy is missing it looks for "
                    f"libpython3.{{{','.join(str(m) for m in dict.fromkeys((sys.version_info.minor, *FALLBACK_MINORS)))}}}.so.1.0 on "
                    f"the library path.\nIt needs no Python package: its code is inside, under resources/.\n")
    return {"documentation/index.html": index_html(xml.encode(), about, ["linux64"]).encode(),
            "documentation/externalDependencies.txt": dependencies.encode(),
            "model.png": icon_png(picture)}


def build_all(out_dir, progress=None) -> list[Path]:
    """Build every kind's FMU with its default start values into ``out_dir``; ``progress``
    (a function of a line of text, or None) is told as each FMU begins."""
    out_dir = Path(out_dir)
    built = []
    for name in KINDS:
        if progress is not None:
            progress(f"building {name}.fmu")
        built.append(build_fmu(name, out_dir / f"{name}.fmu"))
    return built
