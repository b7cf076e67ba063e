"""shapefmu installed from its wheel and from its sdist, used from an empty folder outside the
repository, does what README.md says.

The wheel and the sdist are built from this checkout and installed without dependencies into new
virtual environments; the dependencies come from the test environment's site-packages through a
.pth line (whose own .pth files, the editable install of this checkout among them, Python does not
run), so the shapefmu imported there is the installed one. Then, in an empty folder:

- every ``shapefmu`` command line of README.md (the ``sh`` blocks, and the ``$ `` lines of the
  transcripts), read out of the README and run as written, in order, exits 0 or prints the one-line
  error the README shows after it (the wheel: all of them; the sdist: the first-hour path, build
  then the shipped systems);
- a command whose extra is missing (its package made unimportable) prints one line naming the
  extra, and a build with no C compiler on PATH one line saying to install one;
- the wheel's metadata holds LICENSE, py.typed, and extras that match ``shapefmu.cli.extras``.
"""

from __future__ import annotations

import email
import os
import re
import subprocess
import sys
import sysconfig
import tarfile
import venv
import zipfile
from pathlib import Path

import pytest

from shapefmu.cli.extras import EXTRAS
from shapefmu.fmi.kinds import KINDS

ROOT = Path(__file__).resolve().parent.parent
PLANT_MODELS = [p for p in (ROOT / "models").iterdir() if p.suffix in (".toml", ".py")]


def _install(folder: Path, artifact: Path) -> Path:
    """The python of a new venv in ``folder`` holding ``artifact`` (a wheel or an sdist)."""
    venv.create(folder / "venv", with_pip=False)
    python = folder / "venv" / "bin" / "python"
    site = Path(subprocess.run([python, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                               check=True, capture_output=True, text=True).stdout.strip())
    (site / "test_dependencies.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    # An sdist is built in pip's isolated build environment (setuptools >= 77, as pyproject.toml asks).
    subprocess.run([sys.executable, "-m", "pip", "--python", str(python), "install", "--no-deps", "--quiet",
                    str(artifact)], check=True, capture_output=True, text=True)
    return python


@pytest.fixture(scope="module")
def artifacts(tmp_path_factory) -> dict[str, Path]:
    """{"wheel": ..., "sdist": ...} built from this checkout."""
    dist = tmp_path_factory.mktemp("dist")
    subprocess.run([sys.executable, "-m", "build", "--sdist", "--wheel", "--outdir", str(dist), str(ROOT)], check=True,
                   capture_output=True, text=True)
    return {"wheel": next(dist.glob("shapefmu-*.whl")), "sdist": next(dist.glob("shapefmu-*.tar.gz"))}


@pytest.fixture(scope="module")
def installed(artifacts, tmp_path_factory) -> Path:
    """The python of a new venv holding shapefmu from its wheel."""
    return _install(tmp_path_factory.mktemp("wheel"), artifacts["wheel"])


def _environment(**changes) -> dict:
    environment = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
    return {**environment, **changes}


def shapefmu(python, *arguments, cwd) -> str:
    done = subprocess.run([python, "-m", "shapefmu", *arguments], cwd=cwd, capture_output=True, text=True,
                          env=_environment(), timeout=600)
    assert done.returncode == 0, done.stderr
    return done.stdout


def readme_commands() -> list[tuple[str, str | None]]:
    """Every ``shapefmu`` command line of README.md, in order, with the error line the README shows
    after it (None where it shows none): the lines of ``sh`` blocks (continuations joined) and the
    ``$ `` lines of any block, a transcript; each ``python`` block, as a bash here-document, in its
    place (a later command line may run what it wrote)."""
    commands = []
    for language, lines in _blocks((ROOT / "README.md").read_text(encoding="utf-8")):
        if language == "python":
            commands.append(["python - <<'README'\n" + "\n".join(lines) + "\nREADME", None])
            continue
        transcript = any(line.startswith("$ ") for line in lines)
        for line in _joined(lines):
            if transcript and line.startswith("$ "):
                commands.append([line[2:], None])
            elif transcript and commands and re.match(r"shapefmu [\w-]+: error: ", line):
                commands[-1][1] = line
            elif language == "sh" and not transcript and line.strip():
                commands.append([line, None])
    return [(command, error) for command, error in commands if command.startswith(("shapefmu ", "python - <<"))]


def _blocks(text: str):
    """(language, lines) of each fenced block of a Markdown text."""
    language, lines = None, None
    for line in text.splitlines():
        if line.startswith("```"):
            if lines is None:
                language, lines = line[3:].strip(), []
            else:
                yield language, lines
                lines = None
        elif lines is not None:
            lines.append(line)


def _joined(lines):
    """The lines with each ``\\`` continuation joined to the line it continues."""
    joined = []
    for line in lines:
        if joined and joined[-1].endswith("\\"):
            joined[-1] = joined[-1][:-1] + " " + line.strip()
        else:
            joined.append(line)
    return joined


def test_the_readme_has_its_command_lines_and_names_no_checkout_path():
    commands = readme_commands()
    assert len(commands) >= 30 and sum(error is not None for _, error in commands) >= 3
    assert sum(command.startswith("python - <<") for command, _ in commands) >= 3
    assert not [c for c, _ in commands if "models/" in c or "../shared" in c]
    assert "../shared" not in (ROOT / "README.md").read_text(encoding="utf-8")


def _run_readme(python: Path, folder: Path, commands) -> None:
    """Run ``commands`` as README.md writes them (bash, the venv's shapefmu first on PATH) in
    ``folder``; each exits 0, or with the README's one-line error."""
    environment = _environment(PATH=f"{python.parent}{os.pathsep}{os.environ['PATH']}")
    for command, error in commands:
        done = subprocess.run(["bash", "-c", command], cwd=folder, capture_output=True, text=True, env=environment,
                              timeout=900)
        if error is None:
            assert done.returncode == 0, f"{command}\n{done.stderr[-2000:]}"
        else:
            assert done.returncode != 0 and done.stderr.strip() == error, f"{command}\n{done.stderr[-2000:]}"


def test_every_command_line_of_the_readme_runs_from_the_wheel_in_an_empty_folder(installed, tmp_path):
    _run_readme(installed, tmp_path, readme_commands())


def test_the_sdist_installs_and_runs_the_shipped_systems_after_build(artifacts, tmp_path):
    python = _install(tmp_path / "sdist", artifacts["sdist"])
    here = tmp_path / "empty"
    here.mkdir()
    where = subprocess.run([python, "-c", "import shapefmu; print(shapefmu.__file__)"], cwd=here, check=True,
                           capture_output=True, text=True).stdout
    assert str(ROOT) not in where and "site-packages" in where
    words = {c: c.partition("#")[0].split() for c, _ in readme_commands()}
    first_hour = [(c, None) for c, w in words.items()
                  if w == ["shapefmu", "build"] or w[:2] == ["shapefmu", "simulate"] and len(w) == 3]
    assert [w for c, w in words.items() if (c, None) in first_hour] == [
        ["shapefmu", "build"], ["shapefmu", "simulate", "disk_drive_shaped"], ["shapefmu", "simulate", "disk_drive_stos"]]
    _run_readme(python, here, first_hour)


def test_the_wheel_carries_the_papers_models_and_runs_its_own_code(installed, tmp_path):
    where = subprocess.run([installed, "-c", "import shapefmu, shapefmu.plants.shipped as s; "
                            "print(shapefmu.__file__); print(s.models_folder())"],
                           cwd=tmp_path, check=True, capture_output=True, text=True).stdout.split()
    assert str(ROOT) not in where[0] and "site-packages" in where[0]
    assert where[1].endswith("shapefmu/plants/models")

    def models(folder):
        return sorted(p.name for p in Path(folder).iterdir() if p.suffix in (".toml", ".py", ".ssd"))

    assert models(where[1]) == models(ROOT / "models") and len(models(where[1])) == 10
    listing = shapefmu(installed, "plant", "list", cwd=tmp_path)
    assert "disk_drive " in listing and "ten_pendula " in listing and "disk_drive_shaped " in listing


def test_build_plant_show_and_compare_from_an_empty_folder_print_what_the_checkout_prints(installed, tmp_path):
    here, there = tmp_path / "checkout", tmp_path / "empty"
    here.mkdir()
    there.mkdir()
    for folder, python in ((here, sys.executable), (there, installed)):
        built = shapefmu(python, "build", cwd=folder)
        # every FMU kind, every plant model shipped in models/, and the measured disk drive a shipped system runs
        assert len(re.findall(r"^built fmus/\w+\.fmu$", built, re.M)) == len(KINDS) + len(PLANT_MODELS) + 1, built
    assert sorted(p.name for p in (there / "fmus").iterdir()) == sorted(p.name for p in (here / "fmus").iterdir())
    for arguments in (("plant", "show", "disk_drive"), ("compare", "disk_drive", "--distance", "0.05")):
        assert shapefmu(installed, *arguments, cwd=there) == shapefmu(sys.executable, *arguments, cwd=here)
    dependencies = zipfile.ZipFile(there / "fmus" / "Shaper.fmu").read("documentation/externalDependencies.txt")
    assert sys.base_prefix.encode() not in dependencies and b"libpython3." in dependencies


def _without(python, modules, arguments, cwd, path=None):
    """Run shapefmu with ``modules`` unimportable (as when their extra is not installed)."""
    blocked = "".join(f"sys.modules[{m!r}] = None; " for m in modules)
    code = f"import sys; {blocked}from shapefmu.cli import main; sys.exit(main({list(arguments)!r}))"
    environment = _environment(**({"PATH": path} if path is not None else {}))
    environment.pop("CC", None)
    return subprocess.run([python, "-c", code], cwd=cwd, capture_output=True, text=True, env=environment, timeout=600)


@pytest.mark.parametrize("modules, arguments, extra", [
    (("distributed", "dask"), ["sweep", "disk_drive_shaped", "--vary", "plant.b2=1:2:2", "--metric", "peak",
                               "--command", "shaper.y"], "dask"),
    (("casadi",), ["optimal", "disk_drive", "--distance", "0.05"], "optimal"),
    (("fmpy",), ["simulate", "disk_drive_shaped"], "cosim"),
])
def test_a_command_without_its_extra_says_which_in_one_line(installed, tmp_path, modules, arguments, extra):
    done = _without(installed, modules, arguments, tmp_path)
    assert done.returncode == 1 and len(done.stderr.splitlines()) == 1, done.stderr
    assert f"pip install 'shapefmu[{extra}]'" in done.stderr and "Traceback" not in done.stderr


def test_a_pythonfmu_build_without_a_c_compiler_is_one_line(installed, tmp_path):
    empty = tmp_path / "bin"
    empty.mkdir()  # a PATH with no cc, gcc or anything else
    done = _without(installed, (), ["build", "shaper", "--kind", "zvd", "--mode", "40:0.05", "-o", "S.fmu"], tmp_path,
                    path=str(empty))
    assert done.returncode == 2 and len(done.stderr.splitlines()) == 1, done.stderr
    assert "no C compiler" in done.stderr and "apt install gcc" in done.stderr and not (tmp_path / "S.fmu").exists()


def test_the_wheel_has_its_license_types_and_the_extras_the_commands_name(artifacts):
    with zipfile.ZipFile(artifacts["wheel"]) as wheel:
        names = wheel.namelist()
        metadata = email.message_from_bytes(wheel.read(next(n for n in names if n.endswith(".dist-info/METADATA"))))
    assert any(n.endswith(".dist-info/licenses/LICENSE") for n in names) and "shapefmu/py.typed" in names
    assert metadata["License-Expression"] == "MIT" and metadata.get_all("Classifier")
    requires = metadata.get_all("Requires-Dist")
    core = {re.split(r"[<>=\[; ]", r)[0].lower() for r in requires if "extra ==" not in r}
    assert core == {"numpy", "scipy", "control", "matplotlib", "pythonfmu"}
    for module, (extra, _) in EXTRAS.items():
        provided = {re.split(r"[<>=\[; ]", r)[0].lower() for r in requires if f'extra == "{extra}"' in r}
        assert module in provided or (module == "distributed" and "dask" in provided), (module, extra, provided)
    with tarfile.open(artifacts["sdist"]) as sdist:
        assert any(n.endswith("/LICENSE") for n in sdist.getnames())
