"""Build shapefmu slaves into FMI 2.0 co-simulation FMUs (linux64).

An FMU holds

- ``binaries/linux64/<Model>.so``: the C front end (``shim/fmi2_shim.c``, ``shim/fmu_states.c``
  and ``shim/python_runtime.c``, compiled here with the system C compiler), which makes libpython
  global, starts the interpreter, keeps the FMI 2.0 state machine and forwards to
- ``binaries/linux64/<Model>_pythonfmu.so``: pythonfmu's export library, which embeds Python;
- ``resources/<package>/``: the slave, its base and ``runtime/``, under a package name made of the
  shapefmu version and a hash of exactly these sources, so FMUs built from different code never
  share a module in one interpreter, and FMUs built from the same code share it harmlessly;
- ``resources/<package>_<Model>.py`` and ``resources/slavemodule.txt``: the entry module the export
  library imports;
- ``resources/shapefmu_build.json``: the start values baked in, the GUID and the declared
  dependencies, read by every instance (so two builds of one slave differ only here);
- ``resources/shim/`` (the front end's sources, for the record) and ``modelDescription.xml``.

Start values are checked at build time by running the slave's own design (``initialize``), so a
bad parameter fails the build with the slave's ValueError.
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
from shapefmu.fmi.python.model_description import model_description
from shapefmu.fmi.python.slaves import SLAVES

PYTHON_FMI_DIR = Path(__file__).parent
PACKAGE_DIR = PYTHON_FMI_DIR.parent.parent
SHIM_DIR = PYTHON_FMI_DIR / "shim"
SHIM_SOURCES = (SHIM_DIR / "fmi2_shim.c", SHIM_DIR / "fmu_states.c", SHIM_DIR / "python_runtime.c")
# The FMI 2.0 standard headers, shared with the native FMUs.
FMI_HEADERS_DIR = PYTHON_FMI_DIR.parent / "native" / "c"
SHIM_FILES = (*SHIM_SOURCES, SHIM_DIR / "fmi2_shim.h")  # the standard's headers left out
BUILD_FILE = "shapefmu_build.json"
ENTRY_MODULE = '''"""Entry module of the {name} FMU, imported by pythonfmu's export library."""

from {package}.fmi.python import slave_base as _slave_base
from {package}.fmi.python.slaves.{module} import {name}  # noqa: F401

# Balances the export library's extra release of this module's globals (slave_base.ENTRY_MODULE_REFERENCES).
_slave_base.ENTRY_MODULE_REFERENCES.append(globals())
'''
# Minor versions of Python 3 the front end looks for when the recorded libpython is missing.
FALLBACK_MINORS = (13, 12, 11, 10, 9, 8)


def slave_class(name: str):
    """The slave class registered as ``name`` in ``shapefmu.fmi.python.slaves.SLAVES``."""
    if name not in SLAVES:
        raise ValueError(f"name must be one of {', '.join(SLAVES)}, got {name!r}")
    module = importlib.import_module(f"shapefmu.fmi.python.slaves.{SLAVES[name]}")
    return getattr(module, name)


def bundled_sources(name: str) -> dict[str, bytes]:
    """Files of the bundled package, relative to it: runtime/, the slave base and the slave."""
    files = {
        "__init__.py": b'"""shapefmu code bundled into one FMU."""\n',
        "fmi/__init__.py": b"",
        "fmi/python/__init__.py": b"",
        "fmi/python/slaves/__init__.py": b"",
    }
    for path in sorted((PACKAGE_DIR / "runtime").glob("*.py")):
        files[f"runtime/{path.name}"] = path.read_bytes()
    for module in ("slave_base.py", "state_codec.py"):
        files[f"fmi/python/{module}"] = (PYTHON_FMI_DIR / module).read_bytes()
    files[f"fmi/python/slaves/{SLAVES[name]}.py"] = (PYTHON_FMI_DIR / "slaves" / f"{SLAVES[name]}.py").read_bytes()
    return files


def package_name(files: dict[str, bytes]) -> str:
    """``shapefmu_<version>_<hash of the bundled sources>``: unique to the code, not to the build."""
    digest = hashlib.sha256()
    for relative in sorted(files):
        digest.update(relative.encode() + b"\0" + files[relative] + b"\0")
    return f"shapefmu_{__version__.replace('.', '_')}_{digest.hexdigest()[:16]}"


def _coerce(var, value):
    """A start value converted to the variable's type, or ValueError naming it."""
    if var.type == "Real":
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ValueError(f"{var.name} must be a real number, got {value!r}")
        return float(value)
    if var.type == "Integer":
        if isinstance(value, bool) or not (isinstance(value, int) or (isinstance(value, float) and value.is_integer())):
            raise ValueError(f"{var.name} must be an integer, got {value!r}")
        return int(value)
    if var.type == "Boolean":
        if not isinstance(value, bool):
            raise ValueError(f"{var.name} must be true or false, got {value!r}")
        return value
    if not isinstance(value, str):
        raise ValueError(f"{var.name} must be a string, got {value!r}")
    return value


def designed_slave(name: str, start_values: dict):
    """An instance of slave ``name`` with ``start_values`` applied and its design run."""
    slave = slave_class(name)(instance_name="build")
    for key, value in start_values.items():
        var = slave.by_name.get(key)
        if var is None or var.causality not in ("parameter", "input"):
            settable = ", ".join(v.name for v in slave.variables if v.causality in ("parameter", "input"))
            raise ValueError(f"{name} has no parameter or input {key!r}; settable: {settable}")
        slave.values[key] = _coerce(var, value)
    slave.phase = "initialization"
    slave.initialize()
    return slave


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
    """Build FMU ``name`` (a key of ``SLAVES``) to ``out_path`` with ``start_values`` baked in.

    Structured variable names are passed as a mapping: ``build_fmu("Shaper", p, **{"f[1]": 2000.0})``.
    Returns the path of the written .fmu.
    """
    if not sys.platform.startswith("linux"):
        raise RuntimeError(f"FMUs are built for linux64 only (the front end is ELF), not for {sys.platform}")
    out_path = Path(out_path)
    slave = designed_slave(name, start_values)
    dependencies = slave.output_dependencies()
    files = bundled_sources(name)
    package = package_name(files)
    baked = {key: slave.values[key] for key in start_values}
    identity = json.dumps({"package": package, "model": name, "start": baked}, sort_keys=True)
    guid = "{" + str(uuid.uuid5(uuid.NAMESPACE_URL, "shapefmu:" + identity)) + "}"
    export_library, pythonfmu_version = _export_library()
    xml = model_description(slave, guid, dependencies, slave.experiment(), pythonfmu_version)
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
                fmu.writestr(f"resources/{entry}.py", ENTRY_MODULE.format(name=name, package=package, module=SLAVES[name]))
                fmu.writestr(f"resources/{BUILD_FILE}", json.dumps(build, indent=2))
                for relative, content in files.items():
                    fmu.writestr(f"resources/{package}/{relative}", content)
                for relative, content in _documentation(xml, name).items():
                    fmu.writestr(relative, content)

        return write_file(out_path, write, "FMU")  # no half-written FMU is ever left under the final name


def _documentation(xml: str, name: str) -> dict[str, bytes]:
    """documentation/index.html, externalDependencies.txt and model.png of the pythonfmu FMU ``name``."""
    from shapefmu.fmi.documentation import icon_png, index_html

    about = importlib.import_module(f"shapefmu.fmi.python.slaves.{SLAVES[name]}").__doc__
    # The library's file name only: the build machine's folders say nothing about the user's machine.
    soname = Path(_libpython()).name or f"libpython3.{sys.version_info.minor}.so.1.0"
    dependencies = (f"The {name} FMU runs its model in CPython, embedded through pythonfmu's export library.\n"
                    f"It needs the CPython 3 shared library: built with CPython 3.{sys.version_info.minor} ({soname}); "
                    f"where the build's copy is missing it looks for "
                    f"libpython3.{{{','.join(str(m) for m in dict.fromkeys((sys.version_info.minor, *FALLBACK_MINORS)))}}}.so.1.0 on "
                    f"the library path.\nIt needs no Python package: its code is inside, under resources/.\n")
    return {"documentation/index.html": index_html(xml.encode(), about, ["linux64"]).encode(),
            "documentation/externalDependencies.txt": dependencies.encode(),
            "model.png": icon_png()}


def build_all(out_dir, progress=None) -> list[Path]:
    """Build every registered FMU with its default start values into ``out_dir``; ``progress``
    (a function of a line of text, or None) is told as each FMU begins."""
    out_dir = Path(out_dir)
    built = []
    for name in SLAVES:
        if progress is not None:
            progress(f"building {name}.fmu")
        built.append(build_fmu(name, out_dir / f"{name}.fmu"))
    return built
