"""Compile and package a native FMU: its C sources into ``binaries/linux64``, ``binaries/win64``
and ``binaries/aarch64-linux``, then the FMU archive.

Every native FMU (plants, native shapers) is the one generic FMI 2.0 layer (``c/fmi2_layer*.c``)
plus a model part. The linux64 binary is compiled with the system C compiler (``$CC``, default
``gcc``); the win64 DLL with the mingw-w64 cross compiler (Debian ``gcc-mingw-w64-x86-64``, found
as ``$MINGW_CC`` or ``x86_64-w64-mingw32-gcc``); the library for 64-bit ARM Linux (a Raspberry Pi,
the boards that run printers) with Debian's ``gcc-aarch64-linux-gnu`` (``$AARCH64_CC`` or
``aarch64-linux-gnu-gcc``). One ``.fmu`` serves all three. FMI 2.0 names folders for x86 only;
for any other platform FMI 2.0.4 (section 2.3) asks for FMI 3.0's platform tuple, so the ARM
library is in ``binaries/aarch64-linux`` in both versions. Where a cross compiler is absent the
FMU is built without that platform and ``build_binaries`` says so in the note it returns; its
``sources/`` let any tool compile it later.

Object files are cached by the hash of the compiler, its flags and the sources, so the generic layer
is compiled once per user rather than once per FMU. An object in the cache is linked into FMUs that
run when a host loads them, so the cache is a folder only this user can write (``object_cache``):
one another local user created first, or opened to others, is never used.

The DLL links libgcc statically and needs only the Windows C runtime (msvcrt.dll), which every
Windows has.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import stat
import tempfile
import threading
import zipfile
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

from shapefmu.fmi.compiler import run_compiler

# The generic FMI layers, one of them shipped in every native FMU's sources/: the version-neutral core
# and the API of FMI 2.0 or 3.0 over it (layer_files).
_CORE_SOURCES = ("layer_core.c", "layer_state.c", "fmu_liveness.c")
_CORE_HEADERS = ("fmi2_model.h", "model_status.h", "layer_core.h", "fmu_liveness.h")
LAYER_SOURCES = ("fmi2_layer.c", "fmi2_layer_me.c", *_CORE_SOURCES)
LAYER_HEADERS = ("fmi2_layer.h", *_CORE_HEADERS)
FMI_VERSIONS = ("2.0", "3.0")


def layer_files(fmi_version: str) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """The C sources and headers of the generic layer of ``fmi_version`` ("2.0" or "3.0")."""
    if fmi_version not in FMI_VERSIONS:
        raise ValueError(f"fmi_version must be one of {', '.join(FMI_VERSIONS)}, got {fmi_version!r}")
    if fmi_version == "2.0":
        return LAYER_SOURCES, LAYER_HEADERS
    return ("fmi3_layer.c", "fmi3_layer_me.c", *_CORE_SOURCES), ("fmi3_layer.h", *_CORE_HEADERS)
# The standard's own headers: compiled against, never shipped in sources/ (the importing tool has
# them, and the FMI standard asks for them to be left out).
STANDARD_HEADERS = ("fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h",
                    "fmi3Functions.h", "fmi3FunctionTypes.h", "fmi3PlatformTypes.h")
MINGW = "x86_64-w64-mingw32-gcc"
AARCH64 = "aarch64-linux-gnu-gcc"


@dataclass(frozen=True)
class Platform:
    """One FMI platform: its binaries/ folder, the compiler command, flags and library suffix."""

    name: str
    compiler: str
    flags: tuple[str, ...]
    suffix: str


def linux64() -> Platform:
    return Platform("linux64", os.environ.get("CC", "gcc"),
                    ("-O2", "-shared", "-fPIC", "-std=c99", "-fvisibility=hidden"), ".so")


def win64() -> Platform | None:
    """The mingw-w64 cross compiler, or None where it is not installed."""
    compiler = os.environ.get("MINGW_CC") or shutil.which(MINGW)
    if not compiler:
        return None
    return Platform("win64", compiler, ("-O2", "-shared", "-std=c99", "-static-libgcc", "-s"), ".dll")


def copy_c_files(sources: Path, names) -> None:
    """Copy package files of ``shapefmu.fmi.native/c`` into ``sources``."""
    package = resources.files("shapefmu.fmi.native") / "c"
    for name in names:
        if name in STANDARD_HEADERS:
            raise ValueError(f"{name} is one of the FMI standard's headers, which sources/ leaves out")
        (sources / name).write_bytes((package / name).read_bytes())


def standard_headers(folder: Path) -> Path:
    """``folder`` holding the FMI standard's headers (STANDARD_HEADERS) only, for ``-I``."""
    folder.mkdir(parents=True, exist_ok=True)
    package = resources.files("shapefmu.fmi.native") / "c"
    for name in STANDARD_HEADERS:
        (folder / name).write_bytes((package / name).read_bytes())
    return folder


def _run(command: list[str], compiler: str, what: str, platform: str) -> None:
    try:
        completed = run_compiler(command)
    except FileNotFoundError:
        raise ValueError(f"C compiler {compiler!r} not found: set CC or install gcc") from None
    if completed.returncode != 0:
        raise ValueError(f"compiling the {what} FMU for {platform} failed ({' '.join(command)}):\n{completed.stderr}")


def object_cache() -> Path | None:
    """The folder of cached object files: ``$XDG_CACHE_HOME/shapefmu/objects`` (default
    ``~/.cache``), else ``<tmp>/shapefmu-objects-<uid>``; the first that is a real folder (not a
    link) owned by this process's uid that no one else may write, created with mode 0700 if absent.
    None if neither is: objects are then compiled for each FMU. The uid, not ``$USER`` or the
    password database, names the user, so a uid without a passwd entry builds too."""
    candidates = []
    home = os.environ.get("XDG_CACHE_HOME") or (os.path.join(os.environ["HOME"], ".cache") if os.environ.get("HOME") else None)
    if home and os.path.isabs(home):
        candidates.append(Path(home) / "shapefmu" / "objects")
    candidates.append(Path(tempfile.gettempdir()) / f"shapefmu-objects-{os.getuid()}")
    for folder in candidates:
        try:
            folder.parent.mkdir(mode=0o700, parents=True, exist_ok=True)
            try:
                folder.mkdir(mode=0o700)
            except FileExistsError:
                pass
            status = os.lstat(folder)
        except OSError:
            continue
        if stat.S_ISDIR(status.st_mode) and status.st_uid == os.getuid() and not status.st_mode & 0o022:
            return folder
    return None


def _object(platform: Platform, sources: Path, include: Path, c_file: str, headers: bytes, what: str,
            cache: Path) -> Path:
    """The object file of ``c_file`` in ``cache``, keyed by the compiler, its flags and the bytes of the
    file and of every header it may include: the generic layer is compiled once, not per FMU."""
    digest = hashlib.sha256(repr((platform.compiler, platform.flags)).encode() + headers)
    digest.update((sources / c_file).read_bytes())
    target = cache / f"{digest.hexdigest()}.o"
    if not target.is_file():
        partial = cache / f"{digest.hexdigest()}.{os.getpid()}.{threading.get_ident()}.partial.o"
        flags = [f for f in platform.flags if f not in ("-shared", "-s")]
        _run([platform.compiler, *flags, "-c", "-I", str(sources), "-I", str(include), str(sources / c_file), "-o",
              str(partial)],
             platform.compiler, what, platform.name)
        os.replace(partial, target)
    return target


def compile_binary(platform: Platform, sources: Path, c_files, binary: Path, what: str) -> None:
    """Compile ``c_files`` (in ``sources``, with the FMI standard's headers beside) into the shared
    library ``binary``."""
    binary.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="shapefmu-objects-") as scratch:  # where no cache may be used
        include = standard_headers(Path(scratch) / "fmi-headers")
        headers = b"".join(path.name.encode() + path.read_bytes()
                           for path in sorted([*sources.glob("*.h"), *include.glob("*.h")]))
        cache = object_cache() or Path(scratch)
        objects = [str(_object(platform, sources, include, f, headers, what, cache)) for f in c_files]
        _run([platform.compiler, *platform.flags, *objects, "-o", str(binary), "-lm"], platform.compiler, what,
             platform.name)


def aarch64_linux() -> Platform | None:
    """The aarch64 Linux cross compiler, or None where it is not installed."""
    compiler = os.environ.get("AARCH64_CC") or shutil.which(AARCH64)
    if not compiler:
        return None
    return Platform("aarch64-linux", compiler, ("-O2", "-shared", "-fPIC", "-std=c99", "-fvisibility=hidden"), ".so")


# binaries/ folder names per FMI version (linux, windows, arm): FMI 2.0's names, else platform tuples.
BINARY_FOLDERS = {"2.0": ("linux64", "win64", "aarch64-linux"), "3.0": ("x86_64-linux", "x86_64-windows", "aarch64-linux")}


def build_binaries(root: Path, identifier: str, c_files, what: str, fmi_version: str = "2.0") -> str:
    """``root/binaries/<platform>/<identifier>.<so|dll>`` for Linux and, where the cross compilers
    are installed, Windows and ARM Linux (folders named as ``fmi_version`` names them); returns ""
    or a note saying which platforms were left out and why."""
    sources = root / "sources"
    linux_folder, *cross_folders = BINARY_FOLDERS[fmi_version]
    compile_binary(linux64(), sources, c_files, root / "binaries" / linux_folder / f"{identifier}.so", what)
    missing = []
    cross = ((win64, MINGW, "gcc-mingw-w64-x86-64"), (aarch64_linux, AARCH64, "gcc-aarch64-linux-gnu"))
    for folder, (find, command, package) in zip(cross_folders, cross):
        platform = find()
        if platform is None:
            missing.append(f"binaries/{folder} ({command}, Debian package {package}, is not installed)")
            continue
        compile_binary(platform, sources, c_files, root / "binaries" / folder / f"{identifier}{platform.suffix}", what)
    if missing:
        return f"note: {what} FMU built without {' and '.join(missing)}; its sources/ are inside"
    return ""


def zip_fmu(root: Path, out_path: Path) -> Path:
    """Zip the FMU folder ``root`` into ``out_path`` (written beside and moved, never half-written)."""
    out_path.parent.mkdir(parents=True, exist_ok=True)
    partial = out_path.with_name(out_path.name + ".partial")
    with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as archive:
        for path in sorted(root.rglob("*")):
            if path.is_file():
                archive.write(path, path.relative_to(root).as_posix())
    shutil.move(partial, out_path)
    return out_path


def build_description(identifier: str, source_files) -> str:
    """sources/buildDescription.xml (FMI 2.0.4 / 3.0 build description) listing the C sources."""
    files = "\n".join(f'      <SourceFile name="{name}"/>' for name in source_files)
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<fmiBuildDescription fmiVersion="3.0">
  <BuildConfiguration modelIdentifier="{identifier}">
    <SourceFileSet language="C99">
{files}
    </SourceFileSet>
  </BuildConfiguration>
</fmiBuildDescription>
"""
