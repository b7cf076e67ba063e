"""Every SSP file the project writes is read by the SSP tools a user opens it in next.

Two independent readers: the SSP 1.0 XML schemas (the XSDs that pyssp-standard ships, with
xmlschema) and pyssp-standard itself, the Python SSP library, which reads the default experiment's
start and stop time. Then the files ``--write-ssp`` writes run in libcosim with our master's numbers.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pyssp_standard as pyssp
import pytest
import xmlschema
from support.c_fmus import build_typed_stair

from shapefmu.fmi.ssp import System, read_ssp, write_ssv
from shapefmu.plants.shipped import SYSTEM_SUFFIXES, shipped

RESOURCES = Path(pyssp.__file__).parent / "resources"


@pytest.fixture(scope="module")
def schemas():
    return {kind: xmlschema.XMLSchema10(str(RESOURCES / f"SystemStructure{name}.xsd"))
            for kind, name in (("ssd", "Description"), ("ssv", "ParameterValues"))}


def check_ssd(path: Path, schemas) -> None:
    """``path`` (.ssd, or the SystemStructure.ssd of an .ssp) is valid SSP 1.0 and pyssp reads it."""
    import zipfile

    from pyssp_standard.ssd import SSD

    if zipfile.is_zipfile(path):
        folder = path.parent / f"{path.stem}_unpacked"
        with zipfile.ZipFile(path) as archive:
            archive.extractall(folder)
        path = folder / "SystemStructure.ssd"
    errors = [f"{error.path}: {error.reason}" for error in schemas["ssd"].iter_errors(str(path))]
    assert errors == [], f"{path.name}: {errors}"
    with SSD(path) as ssd:  # reads DefaultExperiment's startTime and stopTime as numbers
        assert ssd.system is not None


@pytest.fixture(scope="module")
def stair(tmp_path_factory):
    return build_typed_stair(tmp_path_factory.mktemp("ssp_files"))


def typed_system(stair, ssv):
    return (System("typed").add("a", stair, {"mode": "down", "label": "x", "period": 0.5}, ssv=ssv).add("b", stair)
            .connect("a.x_out", "b.x_in", factor=2.0, offset=0.5).connect("a.counter", "b.n_in")
            .connect("a.e_out", "b.e_in").connect("a.b_out", "b.b_in"))


@pytest.mark.parametrize("suffix", [".ssd", ".ssp"])
@pytest.mark.parametrize("target, options", [(None, {}), ("libcosim", {"step": 0.1}),
                                             ("omsimulator", {"step": 0.1, "fold": {"a.x_out": []}})],
                         ids=["default", "libcosim", "omsimulator"])
def test_a_written_system_is_valid_ssp_and_pyssp_reads_it(stair, tmp_path, schemas, suffix, target, options):
    from shapefmu.fmi.ssp import write_system

    ssv = write_ssv(tmp_path / "a.ssv", {"increment": 3, "negate": True})
    system = typed_system(stair, ssv)
    if target == "omsimulator":
        system = System("typed").add("a", stair, {"period": 0.5}).add("b", stair).connect("a.x_out", "b.x_in")
    for experiment in (system, system.for_experiment(4.5)):
        path = write_system(experiment, tmp_path / f"{target}_{experiment.stop_time}{suffix}", target, **options)
        check_ssd(path, schemas)
        again = read_ssp(path)
        assert (again.start_time, again.stop_time) == (0.0, experiment.stop_time or 1.0)


def test_a_parameter_file_is_valid_ssv(tmp_path, schemas):
    ssv = write_ssv(tmp_path / "p.ssv", {"f[1]": 2000.0, "n": 3, "flag": True, "kind": "zvd"})
    assert [str(e.reason) for e in schemas["ssv"].iter_errors(str(ssv))] == []


@pytest.mark.parametrize("path", shipped(SYSTEM_SUFFIXES), ids=lambda p: p.name)
def test_the_shipped_systems_are_valid_ssp(path, schemas):
    check_ssd(path, schemas)


def test_the_libcosim_target_carries_its_step_and_runs_there_as_in_our_master(tmp_path, schemas):
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver

    from shapefmu.cli import main
    from shapefmu.cosim import Master

    out = tmp_path / "dd.ssp"
    assert main(["compare", "disk_drive", "--distance", "0.05", "--candidate", "convolution", "--step", "2e-6",
                 "--fmus", str(tmp_path / "fmus"), "--write-ssp", str(out), "--target", "libcosim"]) == 0
    written = tmp_path / "dd_convolution.ssp"
    check_ssd(written, schemas)
    system = read_ssp(written)
    with Master(system, 2e-6, algorithm="jacobi", record=["plant.position"]) as master:
        ours = master.run(system.stop_time)
    log_output_level(CosimLogLevel.ERROR)
    execution = CosimExecution.from_ssp_file(str(written))  # no step given: the file's annotation
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    plant = {info.name.decode(): info.index for info in execution.slave_infos()}["plant"]
    position = {v.name.decode(): v.reference for v in execution.slave_variables(plant)}["position"]
    theirs = []
    for _ in range(len(ours) - 1):
        execution.step(1)
        theirs.append(observer.last_real_values(plant, [position])[0])
    assert execution.status().current_time == round(system.stop_time * 1e9)
    np.testing.assert_allclose(theirs, ours["plant.position"][1:], rtol=0, atol=1e-15)


def test_simulate_writes_the_system_it_ran_with_its_set_values(stair, tmp_path, schemas, capsys):
    from shapefmu.cli import main
    from shapefmu.cosim import simulate

    ssd = typed_system(stair, None).write_ssd(tmp_path / "typed.ssd")
    out = tmp_path / "again.ssp"
    assert main(["simulate", str(ssd), "--stop", "2", "--step", "0.25", "--set", "a.increment=4",
                 "--record", "b.n_out", "--write-ssp", str(out)]) == 0
    assert f"system written to {out}" in capsys.readouterr().out
    check_ssd(out, schemas)
    again = read_ssp(out)
    assert again.stop_time == 2.0 and again.parameter_values("a")["increment"] == 4
    first = simulate(read_ssp(ssd), 2.0, 0.25, record=["b.n_out"], parameters={"a.increment": 4})
    second = simulate(again, again.stop_time, 0.25, record=["b.n_out"])
    assert first.tobytes() == second.tobytes()


@pytest.mark.parametrize("arguments, message", [
    (["--target", "libcosim"], "--target and --fold apply to --write-ssp FILE, which is not given"),
    (["--write-ssp", "x.txt"], "the SSP file name must end in .ssd, .ssp"),
])
def test_write_ssp_options_are_checked_before_the_run(stair, tmp_path, capsys, arguments, message):
    from shapefmu.cli import main

    ssd = System("one").add("a", stair).write_ssd(tmp_path / "one.ssd")
    with pytest.raises(SystemExit) as exit_:
        main(["simulate", str(ssd), "--stop", "1", "--step", "0.5", *arguments])
    assert exit_.value.code == 2 and message in capsys.readouterr().err
