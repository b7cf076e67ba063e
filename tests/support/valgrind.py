"""valgrind memcheck on the tests' C programs: no invalid access, no definite, indirect or possible leak.

    requires_valgrind: a skip mark, saying why, where valgrind or gcc is missing
    MEMCHECK: the memcheck command in front of a program (any error or such leak: exit 99)
    assert_clean_under_memcheck(command, **run_options) -> the completed process, its report checked
    run_driver_under_valgrind(fmu, driver, folder): tests/hosts_c/<driver>.c compiled with the FMU's
        own sources (-g) and run under memcheck; it prints "ok ..." when every call did what it should

A driver knows the FMU through the FMI API and fmu_description.h, which ``description_header``
writes from the FMU's modelDescription.xml (hosts_c/driver.h says what it holds): what a host reads.
"""

from __future__ import annotations

import shutil
import subprocess
import zipfile
from pathlib import Path

import pytest
from fmpy import read_model_description

from support import FMI_HEADERS, HOSTS_C
requires_valgrind = pytest.mark.skipif(shutil.which("valgrind") is None or shutil.which("gcc") is None,
                                       reason="needs valgrind and gcc (bash .ci/system-packages)")
MEMCHECK = ["valgrind", "--tool=memcheck", "--leak-check=full", "--show-leak-kinds=definite,indirect,possible",
            "--errors-for-leak-kinds=definite,indirect,possible", "--error-exitcode=99"]


def assert_clean_under_memcheck(command: list, **options) -> subprocess.CompletedProcess:
    """``command`` run under MEMCHECK: exit 0 and memcheck's "0 errors"."""
    completed = subprocess.run([*MEMCHECK, *map(str, command)], capture_output=True, text=True, timeout=300, **options)
    assert completed.returncode == 0, completed.stderr[-3000:] + completed.stdout
    assert "ERROR SUMMARY: 0 errors" in completed.stderr
    return completed


def c_string(text: str) -> str:
    """``text`` as a C string literal: printable ASCII as it is, every other byte of its UTF-8 as an
    octal escape (three digits, so a following digit cannot join it)."""
    out = []
    for byte in text.encode():
        character = chr(byte)
        out.append(character if 32 <= byte < 127 and character not in '"\\?' else f"\\{byte:03o}")
    return '"' + "".join(out) + '"'


def description_header(fmu) -> str:
    """fmu_description.h of ``fmu`` (see hosts_c/driver.h)."""
    md = read_model_description(str(fmu))
    token = md.guid if md.fmiVersion.startswith("2") else md.instantiationToken
    rows = [f"    {{{c_string(v.name)}, {v.valueReference}u, {c_string(v.causality)}, "
            f"{c_string(v.start) if v.start is not None else 'NULL'}}},"
            for v in md.modelVariables]
    lines = ["/* Written by tests/support/valgrind.py from the FMU's modelDescription.xml. */",
             f"#define FMU_GUID {c_string(token)}",
             f"#define N_STATES {len(md.derivatives)}"]
    if md.derivatives:
        derivative = md.derivatives[0].variable
        lines += [f"#define FIRST_STATE_VR {derivative.derivative.valueReference}u",
                  f"#define FIRST_DERIVATIVE_VR {derivative.valueReference}u"]
    lines += ["typedef struct { const char *name; unsigned int vr; const char *causality; const char *start; } Variable;",
              "static const Variable VARIABLES[] = {", *rows, "};", ""]
    return "\n".join(lines)


def run_driver_under_valgrind(fmu, driver: str, folder: Path) -> None:
    """hosts_c/``driver``.c compiled with the FMU's sources and run under memcheck: no error, no leak."""
    folder.mkdir(parents=True, exist_ok=True)
    with zipfile.ZipFile(fmu) as archive:
        archive.extractall(folder)
    sources = folder / "sources"
    (folder / "fmu_description.h").write_text(description_header(fmu))
    program = folder / driver
    subprocess.run(["gcc", "-g", "-O1", "-std=c99", "-I", str(folder), "-I", str(HOSTS_C), "-I", str(sources),
                    "-I", str(FMI_HEADERS), str(HOSTS_C / f"{driver}.c"), *map(str, sorted(sources.glob("*.c"))),
                    "-o", str(program), "-lm"], check=True)
    completed = assert_clean_under_memcheck([program])
    assert completed.stdout.startswith("ok ")
