"""No native build links an object file another user could have written (issue 23).

The object cache of ``shapefmu.fmi.native.compile`` holds compiled parts of the generic FMI layer,
linked into every native FMU. A hostile neighbour who creates the cache folder first, opens it to
everyone, or points it elsewhere by a link would have their object run wherever the FMU is loaded.
The tests plant garbage objects under the names the build would use: a build that linked one fails.
"""

from __future__ import annotations

import os
import stat
import tempfile
from pathlib import Path

import pytest

from shapefmu.fmi.native import build_plant_fmu
from shapefmu.fmi.native.compile import object_cache

ROOT = Path(__file__).resolve().parent.parent
MODEL = ROOT / "models" / "mass_spring_chain.toml"
ROOT_ONLY = pytest.mark.skipif(os.getuid() != 0, reason="creating another user's folder needs root")


@pytest.fixture
def temporary(tmp_path, monkeypatch):
    """A temporary directory of the test's own as the system's, and no cache home: the cache
    candidate is <tmp>/shapefmu-objects-<uid>, the one a neighbour can reach."""
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    monkeypatch.delenv("XDG_CACHE_HOME", raising=False)
    monkeypatch.delenv("HOME", raising=False)
    return tmp_path


def object_names() -> list[str]:
    """The file names the build gives its objects (learned from a build with a private cache)."""
    with tempfile.TemporaryDirectory() as home:
        os.environ["XDG_CACHE_HOME"] = home
        try:
            build_plant_fmu(MODEL, Path(home) / "P.fmu")
            return sorted(p.name for p in (Path(home) / "shapefmu" / "objects").glob("*.o"))
        finally:
            del os.environ["XDG_CACHE_HOME"]


def plant(folder: Path, names: list[str]) -> None:
    for name in names:
        (folder / name).write_bytes(b"\x7fELF planted by a neighbour")


def test_the_cache_is_private_to_the_user(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    folder = object_cache()
    status = os.lstat(folder)
    assert folder == tmp_path / "cache" / "shapefmu" / "objects"
    assert status.st_uid == os.getuid() and stat.S_IMODE(status.st_mode) & 0o077 == 0


def test_a_cache_folder_open_to_others_is_not_used(temporary):
    names = object_names()
    folder = temporary / f"shapefmu-objects-{os.getuid()}"
    folder.mkdir()
    folder.chmod(0o777)
    plant(folder, names)
    assert object_cache() is None
    build_plant_fmu(MODEL, temporary / "P.fmu")  # links only what it compiled itself
    assert sorted(p.name for p in folder.iterdir()) == names  # and left the folder alone


def test_a_link_in_the_cache_folder_s_place_is_not_followed(temporary):
    names = object_names()
    elsewhere = temporary / "elsewhere"
    elsewhere.mkdir(mode=0o700)
    plant(elsewhere, names)
    (temporary / f"shapefmu-objects-{os.getuid()}").symlink_to(elsewhere)
    assert object_cache() is None
    build_plant_fmu(MODEL, temporary / "P.fmu")


@ROOT_ONLY
def test_a_cache_folder_another_user_created_first_is_not_used(temporary):
    names = object_names()
    folder = temporary / f"shapefmu-objects-{os.getuid()}"
    folder.mkdir(mode=0o700)
    plant(folder, names)
    os.chown(folder, 65534, 65534)  # nobody's
    assert object_cache() is None
    build_plant_fmu(MODEL, temporary / "P.fmu")


def test_a_uid_without_a_passwd_entry_builds(temporary, monkeypatch):
    # What a container's arbitrary uid sees: no passwd entry (getpwuid raises KeyError, so
    # getpass.getuser() fails), no HOME, USER or LOGNAME. The uid alone names the cache.
    import getpass
    import pwd

    def no_entry(uid):
        raise KeyError(f"getpwuid(): uid not found: {uid}")

    monkeypatch.setattr(pwd, "getpwuid", no_entry)
    for name in ("USER", "LOGNAME", "LNAME", "USERNAME"):
        monkeypatch.delenv(name, raising=False)
    with pytest.raises((KeyError, OSError)):
        getpass.getuser()
    build_plant_fmu(MODEL, temporary / "P.fmu")
    assert any((temporary / f"shapefmu-objects-{os.getuid()}").glob("*.o"))
