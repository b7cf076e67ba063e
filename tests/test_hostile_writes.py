"""Every file a command writes goes through one checked, atomic writer (issue 34, item 2).

``ln -s victim.txt out.ssv; shapefmu recommend --mode 40:0.05 --build out.fmu`` wrote the .ssv XML
into victim.txt, and an existing out.ssv was overwritten though the user named only out.fmu. Now
every writer (``shapefmu.files``) refuses a link, a folder or a FIFO, refuses to replace a file the
user did not name, and writes a new file beside the target (created exclusively) that it renames
over it: the victim of a planted link keeps its bytes, and a writer that fails leaves the old file.

The writers are driven as the commands drive them: the CLI for recommend's .ssv, the library
functions the other commands call for plots, FMUs, systems, parameter sets, solutions and results,
and the lock and journal a run keeps beside its output.
"""

from __future__ import annotations

import os
import zipfile

import numpy as np
import pytest
from hostile_support import guarded

VICTIM = b"the user's own file, which no shapefmu command may touch\n"


@pytest.fixture
def victim(tmp_path):
    path = tmp_path / "victim.txt"
    path.write_bytes(VICTIM)
    return path


def _link(path, target):
    os.symlink(target, path)
    return path


def test_recommend_build_refuses_an_ssv_planted_as_a_link_and_leaves_its_target_alone(tmp_path, victim, monkeypatch):
    monkeypatch.chdir(tmp_path)
    _link(tmp_path / "out.ssv", victim)
    code, out, err = guarded(["recommend", "--mode", "40:0.05", "--build", "out.fmu"], seconds=600)
    assert code == 2 and "out.ssv" in err and "symbolic link" in err, err
    assert victim.read_bytes() == VICTIM and not (tmp_path / "out.fmu").exists()


def test_recommend_build_refuses_to_overwrite_an_ssv_the_user_did_not_name(tmp_path, victim, monkeypatch):
    monkeypatch.chdir(tmp_path)
    os.replace(victim, tmp_path / "out.ssv")
    code, out, err = guarded(["recommend", "--mode", "40:0.05", "--build", "out.fmu"], seconds=600)
    assert code == 2 and "out.ssv" in err and "not a file you named" in err, err
    assert (tmp_path / "out.ssv").read_bytes() == VICTIM


def test_recommend_build_writes_the_fmu_and_the_ssv_beside_it(tmp_path, monkeypatch):
    from shapefmu.fmi.ssp import read_ssv

    monkeypatch.chdir(tmp_path)
    code, out, err = guarded(["recommend", "--mode", "40:0.05", "--build", "out.fmu"], seconds=600)
    assert code == 0, err
    assert zipfile.is_zipfile(tmp_path / "out.fmu") and read_ssv(tmp_path / "out.ssv")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.fmu", "out.ssv"]  # no temporary left behind


# The file each writer writes, by what it is (and the commands that write it).
WRITERS = {"plot (every --plot)": "out.png", "FMU (build, plant, recommend --build)": "out.fmu",
           "parameter set (.ssv)": "out.ssv", "system (.ssd, simulate --write-ssp)": "out.ssd",
           "system archive (.ssp)": "out.ssp", "results (simulate --out)": "out.csv",
           "solution (optimal --json)": "out.json", "signal table (optimal --csv)": "out.csv"}


def _write(name, path):
    """Write ``path`` (named WRITERS[name]) with the writer ``name``, as the commands call it."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from shapefmu.cosim.output_files import save_results
    from shapefmu.fmi.native.compile import zip_fmu
    from shapefmu.fmi.ssp import System, write_ssv
    from shapefmu.optimal.comparison import optimal_report
    from shapefmu.plots import save_figure

    model = os.path.join(os.path.dirname(__file__), "..", "models", "disk_drive.toml")
    if name.startswith("plot"):
        save_figure(plt.figure(), path)
    elif name.startswith("FMU"):
        root = path.parent / "fmu_folder"
        root.mkdir()
        (root / "modelDescription.xml").write_text("<fmiModelDescription/>")
        zip_fmu(root, path)
    elif name.startswith("parameter set"):
        write_ssv(path, {"k": 1.0})
    elif name.startswith("system"):
        (System("s").write_ssd if path.suffix == ".ssd" else System("s").write_ssp)(path)
    elif name.startswith("results"):
        save_results(np.zeros(3, dtype=[("time", "f8"), ("x", "f8")]), path)
    else:
        optimal_report(model, 0.05, **{"json_path" if path.suffix == ".json" else "csv_path": path})


@pytest.mark.parametrize("name", WRITERS)
def test_a_writer_refuses_a_link_in_place_of_its_file(tmp_path, victim, name):
    path = _link(tmp_path / WRITERS[name], victim)
    with pytest.raises(ValueError, match="symbolic link"):
        _write(name, path)
    assert victim.read_bytes() == VICTIM and os.path.islink(path)


@pytest.mark.parametrize("name", WRITERS)
def test_a_writer_never_writes_through_a_link_planted_beside_its_file(tmp_path, victim, name):
    """The names a writer of old used for its half-written file (``out.fmu.partial``), planted as links."""
    path = tmp_path / WRITERS[name]
    for planted in (f"{path.name}.partial", f".{path.name}.tmp", f"{path.name}.tmp"):
        _link(tmp_path / planted, victim)
    _write(name, path)
    assert victim.read_bytes() == VICTIM and path.is_file() and not path.is_symlink()


@pytest.mark.parametrize("name", WRITERS)
def test_a_writer_replaces_the_file_it_was_named_whole(tmp_path, name):
    path = tmp_path / WRITERS[name]
    path.write_bytes(b"old")
    _write(name, path)
    assert path.read_bytes() != b"old"
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []  # no temporary left behind


def test_a_link_planted_while_the_file_is_written_is_replaced_not_followed(tmp_path, victim):
    from shapefmu import files

    path = tmp_path / "out.txt"

    def write(temporary):
        _link(path, victim)  # the race: after the checks, before the rename
        temporary.write_text("new")

    files.write_file(path, write)
    assert victim.read_bytes() == VICTIM and not path.is_symlink() and path.read_text() == "new"


def test_a_writer_that_fails_leaves_the_old_file_and_no_temporary(tmp_path):
    from shapefmu import files

    path = tmp_path / "out.txt"
    path.write_text("old")

    def write(temporary):
        temporary.write_text("half")
        raise OSError("disk full")

    with pytest.raises(OSError, match="disk full"):
        files.write_file(path, write)
    assert path.read_text() == "old" and sorted(p.name for p in tmp_path.iterdir()) == ["out.txt"]


@pytest.mark.parametrize("kind", ["folder", "FIFO"])
def test_a_folder_or_a_fifo_in_place_of_the_file_is_refused(tmp_path, kind):
    from shapefmu import files

    path = tmp_path / "out.txt"
    path.mkdir() if kind == "folder" else os.mkfifo(path)
    with pytest.raises(ValueError, match=f"is a {kind}"):
        files.write_text(path, "x")


def test_the_lock_beside_a_run_s_output_is_never_opened_through_a_link(tmp_path, victim):
    from shapefmu.cosim.output_files import output_lock

    _link(tmp_path / ".out.csv.lock", victim)
    with pytest.raises(ValueError, match="symbolic link"):
        with output_lock(tmp_path / "out.csv"):
            pass
    assert victim.read_bytes() == VICTIM


def test_a_sweep_journal_planted_as_a_link_is_refused(tmp_path, victim):
    from shapefmu.sweep.store import Store

    _link(tmp_path / "out.parquet.partial.csv", victim)
    with pytest.raises(ValueError, match="symbolic link"):
        Store(tmp_path / "out.parquet", ["a"], resume=False).open()
    assert victim.read_bytes() == VICTIM
