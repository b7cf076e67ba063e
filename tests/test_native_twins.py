"""``shapefmu build <target> --native`` and ``shapefmu build --native``: every native twin from
the command line, with its parameters baked in (shapefmu.fmi.native.twins)."""

import zipfile


def test_the_command_line_builds_the_ekf_tuner_and_every_twin(tmp_path, monkeypatch):
    from fmpy import read_model_description
    from hostile_support import guarded

    from shapefmu.fmi import native
    from shapefmu.fmi.native.twins import TWINS

    out = tmp_path / "Tuner.fmu"
    code, text, err = guarded(["build", "ekf-tuner", "--native", "--kind", "mzv", "--omega0", "50", "--ts", "2e-3",
                               "-o", out], seconds=120)
    assert code == 0, err
    starts = {v.name: v.start for v in read_model_description(str(out)).modelVariables}
    assert (starts["kind"], float(starts["omega0"]), float(starts["Ts"])) == ("mzv", 50.0, 2e-3)
    assert "sources/ekf_tuner_part.c" in zipfile.ZipFile(out).namelist()
    code, _, err = guarded(["build", "ekf-tuner", "--native", "--omega0", "-5", "-o", out])
    assert code == 2 and err.count("\n") == 1 and "omega0 must be > 0" in err, err
    monkeypatch.setattr(native, "build_all", lambda models, folder, fmi_version, progress=None: [])  # the plants have their own tests
    code, text, err = guarded(["build", "--native", "-o", tmp_path / "all"], seconds=300)
    assert code == 0, err
    for name in TWINS:
        names = zipfile.ZipFile(tmp_path / "all" / f"{name}.fmu").namelist()
        assert any(n.startswith("sources/") for n in names) and not any("pythonfmu" in n for n in names), name


def test_the_command_line_builds_the_other_twins_from_parameters(tmp_path, time_optimal_solution):
    from fmpy import read_model_description
    from hostile_support import guarded

    out = tmp_path / "Stos.fmu"
    code, _, err = guarded(["build", "stos-controller", "--native", "--param", "kind=zvd", "--param", "n_modes=1",
                            "--param", "f[1]=40", "--param", "damping=10", "--param", "Ts=1e-4", "-o", out], seconds=120)
    assert code == 0, err
    starts = {v.name: v.start for v in read_model_description(str(out)).modelVariables}
    assert (starts["kind"], float(starts["f[1]"]), float(starts["damping"]), float(starts["Ts"])) == ("zvd", 40.0, 10.0, 1e-4)
    assert "sources/stos_law.c" in zipfile.ZipFile(out).namelist()
    code, _, err = guarded(["build", "profile", "--native", "--param", "profile=TP", "-o", tmp_path / "P.fmu"])
    assert code == 0, err
    (tmp_path / "solution.json").write_text(time_optimal_solution.to_json())
    code, _, err = guarded(["build", "reference", tmp_path / "solution.json", "--native", "-o", tmp_path / "R.fmu"])
    assert code == 0 and "sources/table_part.c" in zipfile.ZipFile(tmp_path / "R.fmu").namelist(), err
    code, _, err = guarded(["build", "profile", "--param", "null=two", "-o", tmp_path / "P2.fmu"])
    assert code == 2 and "--param null is an Integer parameter of ProfileGenerator, got 'two'" in err
