"""The closed-form shaper kinds are listed once, in runtime.shaper_designs.CLOSED_FORM, with their
impulses per mode; the C that re-designs them in a native FMU (c/shaper_designs.c) knows the same
kinds with the same counts, and the design layer's catalog the same kinds as the runtime."""

import re
import subprocess
from importlib import resources

from shapefmu.runtime import ekf_tuner, shaper_designs
from shapefmu.shapers import catalog

C_FOLDER = resources.files("shapefmu.fmi.native") / "c"
PROGRAM = r"""
#include <stdio.h>
#include "shaper_designs.h"
int main(int argc, char **argv) {
    for (int i = 1; i < argc; i++)
        for (int n = 0; n <= 5; n++) printf("%s %d %d\n", argv[i], n, impulses_per_mode(closed_form_kind(argv[i]), n));
    return 0;
}
"""


def test_the_c_names_the_closed_form_kinds_of_the_runtime_in_its_order():
    text = (C_FOLDER / "shaper_designs.c").read_text(encoding="utf-8")
    names = re.search(r"static const char \*const names\[\] = \{([^}]*)\}", text).group(1)
    assert re.findall(r'"(\w+)"', names) == list(shaper_designs.CLOSED_FORM)


def test_the_c_counts_the_impulses_per_mode_as_the_runtime(tmp_path):
    (tmp_path / "main.c").write_text(PROGRAM)
    program = tmp_path / "counts"
    subprocess.run(["gcc", "-std=c99", "-I", str(C_FOLDER), str(tmp_path / "main.c"), str(C_FOLDER / "shaper_designs.c"),
                    "-o", str(program), "-lm"], check=True)
    rows = subprocess.run([str(program), *shaper_designs.CLOSED_FORM], capture_output=True, text=True,
                          check=True).stdout.split("\n")
    counts = {(kind, int(n)): int(count) for kind, n, count in (row.split() for row in rows if row)}
    assert counts == {(kind, n): per_mode(n) for kind, per_mode in shaper_designs.CLOSED_FORM.items() for n in range(6)}


def test_the_tuner_the_catalog_and_the_runtime_list_the_same_kinds():
    assert ekf_tuner.KINDS == tuple(shaper_designs.CLOSED_FORM)
    assert catalog.KINDS == shaper_designs.KINDS
    assert set(catalog.SINGLE_MODE) | {"zv_dn", "simultaneous"} == set(shaper_designs.KINDS)
