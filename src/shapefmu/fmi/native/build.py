"""Assemble and compile a plant FMU: sources, buildDescription.xml, modelDescription.xml, binary."""

from __future__ import annotations

import dataclasses
import hashlib
import importlib.util
import os
import re
import sys
import tempfile
import tomllib
import uuid
from pathlib import Path

from shapefmu import __version__
from shapefmu.fmi.description import ModelDescription, fmi2, fmi3, now, write
from shapefmu.fmi.documentation import add_documentation
from shapefmu.fmi.native import linear
from shapefmu.fmi.native.codegen import write_sources
from shapefmu.fmi.native.compile import build_binaries, build_description, copy_c_files, write_layer, zip_fmu
from shapefmu.fmi.native.model_part import ModelPart, check_name
from shapefmu.fmi.native.nonlinear import NonlinearPlant
from shapefmu.plants import as_plant
from shapefmu.runtime.checks import check_size, read_text_file

# The hand-written C shipped with every plant FMU (package data in fmi/native/c/) besides the generic
# layer of its FMI version: the plants' model part.
PLANT_SOURCES = ("plant_part.c", "plant_expm.c")
PLANT_HEADERS = ("plant_model.h", "plant_expm.h")


def _check_states(count: int, what: str) -> None:
    check_size(count, "MAX_PLANT_STATES", f"{what} has", "states", "a plant FMU of that order takes too long to generate")


def _from_model_file(path: Path, name: str | None) -> ModelPart:
    plant = as_plant(path)
    _check_states(plant.n_states, f"plant model {path}")
    data = tomllib.loads(read_text_file(path, "plant model"))  # as_plant read and checked it just now
    signals = {signal: fields for key in ("inputs", "outputs") for signal, fields in data[key].items()}
    descriptions = {key: raw.get("description", "") for key, raw in data["parameters"].items()}
    part = linear.model_part(plant, name=name, signals=signals, descriptions=descriptions,
                             description=data.get("description", ""))
    return dataclasses.replace(part, source=data.get("source", ""))


def to_model_part(model, name: str | None = None) -> ModelPart:
    """The model part of a model file path (or the name of a shipped model), a ``Plant``, a
    python-control LTI or a ``NonlinearPlant``."""
    if name is not None:
        check_name(name, "name")
    if isinstance(model, NonlinearPlant):
        _check_states(len(model.states), f"nonlinear plant {model.name!r}")
        part = model.model_part()
        if name is not None:
            part = dataclasses.replace(part, name=name)
        return part
    if isinstance(model, (str, os.PathLike)):
        from shapefmu.plants.shipped import find

        return _from_model_file(find(model, (".toml",)), name)
    plant = as_plant(model)
    _check_states(plant.n_states, f"plant {plant.name!r}")
    return linear.model_part(plant, name=name)


def _about(part: ModelPart) -> str:
    """What a plant FMU's documentation says it does (its description comes from the model)."""
    step = ("the exact zero-order-hold step of the linear system (its matrix exponential), so any "
            "communication step gives the sampled solution to rounding" if part.linear else
            f"fixed-substep RK4, the substep being the parameter {part.substep_parameter}")
    return (f"{part.description or part.name}{' (' + part.source + ')' if part.source else ''}\n\n"
            f"A plant model of shapefmu as a native C FMU: {len(part.states)} continuous states, inputs "
            f"{', '.join(s.name for s in part.inputs) or 'none'}, outputs {', '.join(s.name for s in part.outputs)}. "
            f"Model Exchange gives the host the state derivatives; Co-Simulation steps with {step}. "
            f"The inputs are held over a communication step. sources/ holds its C code (the generated model and "
            f"shapefmu's FMI layer).")


def build_plant_fmu(model, out_path, *, name: str | None = None, fmi_version: str = "2.0") -> Path:
    """Generate, compile and zip a plant FMU (Model Exchange + Co-Simulation); returns its path.

    ``model`` is a model file (``models/*.toml``), a ``Plant``, a python-control LTI or a
    ``NonlinearPlant``; ``name`` replaces the model's name (and the FMU's model identifier);
    ``fmi_version`` is "2.0" (default) or "3.0" (the same variables as Float64, the same
    Co-Simulation step: the two give identical numbers).
    """
    out_path = Path(out_path)
    if out_path.is_dir():
        raise ValueError(f"out_path {str(out_path)!r} is a folder; give the FMU file to write, e.g. {out_path / 'Plant.fmu'}")
    part = to_model_part(model, name)
    identifier = part.identifier
    with tempfile.TemporaryDirectory(prefix="shapefmu_plant_") as tmp:
        root = Path(tmp)
        sources = root / "sources"
        sources.mkdir()
        copy_c_files(sources, PLANT_SOURCES + PLANT_HEADERS)
        wrapper_sources = [*write_layer(sources, fmi_version), *PLANT_SOURCES]
        # The GUID hashes the sources, which include the GUID: generate with a placeholder first.
        generated = write_sources(part, "", sources)
        c_files = [*wrapper_sources, *generated]
        guid = _guid(part, {f: (sources / f).read_text(encoding="utf-8") for f in c_files})
        write_sources(part, guid, sources)
        (sources / "buildDescription.xml").write_text(build_description(identifier, c_files), encoding="utf-8")
        note = build_binaries(root, identifier, c_files, f"plant {part.name}", fmi_version)
        if note:
            print(note, file=sys.stderr)
        description = _description(part, guid, tuple(c_files) if fmi_version == "2.0" else (), now())
        (root / "modelDescription.xml").write_text(write(description, fmi_version), encoding="utf-8")
        if fmi_version == "3.0":
            interface = part.interface()
            (root / "terminalsAndIcons").mkdir()
            (root / "terminalsAndIcons" / "terminalsAndIcons.xml").write_text(
                fmi3.terminals_and_icons(interface.command_in, interface.command_out), encoding="utf-8")
        add_documentation(root, _about(part), part.picture())
        zip_fmu(root, out_path)
    return out_path


LOG_CATEGORIES = (("logStatusError", ""), ("logAll", ""))


def _description(part: ModelPart, guid: str, source_files: tuple[str, ...], date: str | None) -> ModelDescription:
    """The model description of the plant FMU of ``part``: Model Exchange (with directional
    derivatives from the Jacobians) and Co-Simulation, on the host's memory functions."""
    interface = part.interface()
    return ModelDescription(
        model_name=part.name, identifier=part.identifier, guid=guid, description=part.description,
        generation_tool=f"shapefmu {__version__} plant generator", variables=interface.variables,
        dependencies=part.dependencies_by_name(), log_categories=LOG_CATEGORIES, generation_date=date,
        experiment=part.experiment(), model_exchange=True, directional_derivatives=True, source_files=source_files,
        designed=False)


def _guid(part: ModelPart, sources: dict[str, str]) -> str:
    """A GUID that changes whenever the model description (but its date) or any source changes."""
    digest = hashlib.md5(fmi2.write(_description(part, "", (), None)).encode())
    for name in sorted(sources):
        digest.update(name.encode())
        digest.update(sources[name].encode())
    return "{" + str(uuid.UUID(digest.hexdigest())) + "}"


def fmu_file_name(model_name: str) -> str:
    """``disk_drive`` -> ``DiskDrive.fmu`` (the file names of fmus/). Characters other than letters,
    digits and _ are dropped, so no name can climb out of the folder (``../x``) or name another."""
    words = re.sub(r"[^A-Za-z0-9_]", "", model_name).split("_")
    stem = "".join(word[:1].upper() + word[1:] for word in words)
    if not stem:
        raise ValueError(f"model name {model_name!r} has no letter or digit to name its FMU file by")
    return stem + ".fmu"


def model_from_file(path):
    """The model a file holds: a model file (*.toml) as its path, or ``plant()`` of a Python model
    file (*.py, e.g. models/pendulum.py), or the shipped model of that name (``pendulum``); None for a
    Python file that defines no ``plant()``."""
    from shapefmu.plants.shipped import find

    path = find(path)
    if not path.is_file():
        raise ValueError(f"model file {str(path)!r} does not exist or is not a regular file")
    if path.suffix == ".toml":
        return path
    if path.suffix != ".py":
        raise ValueError(f"a plant model file must be .toml or .py (defining plant()), got {str(path)!r}")
    spec = importlib.util.spec_from_file_location(f"shapefmu_models_{path.stem}", path)
    module = importlib.util.module_from_spec(spec)
    # The file is the user's program: whatever it raises, or a sys.exit in it, is their model's error.
    try:
        spec.loader.exec_module(module)
        factory = getattr(module, "plant", None)
        return factory() if callable(factory) else None
    except SystemExit as stop:
        raise ValueError(f"{path}: the model file called sys.exit({stop.code!r}) while shapefmu read it") from None
    except Exception as error:  # noqa: BLE001 - reported as the model's, in one line
        raise ValueError(f"{path}: the model file raised {type(error).__name__}: {error}") from None


def build_all(models_dir=None, out_dir="fmus", *, fmi_version: str = "2.0", progress=None) -> list[Path]:
    """Build one FMU per plant model in ``models_dir`` (every *.toml, and every *.py defining
    ``plant()``; default: the models that ship with shapefmu) into ``out_dir``, named by
    ``fmu_file_name``, as FMI ``fmi_version`` FMUs; returns the paths. ``progress`` (a function of
    a line of text, or None) is told as each model begins."""
    from shapefmu.plants.shipped import models_folder

    models_dir, out_dir = Path(models_dir) if models_dir is not None else models_folder(), Path(out_dir)
    if not models_dir.is_dir():
        raise ValueError(f"models_dir must be a directory, got {str(models_dir)!r}")
    built = []
    for path in sorted(models_dir.glob("*.toml")):
        if progress is not None:
            progress(f"building the plant FMU of {path.name}")
        part = to_model_part(path)
        built.append(build_plant_fmu(path, out_dir / fmu_file_name(part.name), fmi_version=fmi_version))
    for path in sorted(models_dir.glob("*.py")):
        model = model_from_file(path)
        if model is not None:
            if progress is not None:
                progress(f"building the plant FMU of {path.name}")
            built.append(build_plant_fmu(model, out_dir / fmu_file_name(to_model_part(model).name),
                                         fmi_version=fmi_version))
    return built
