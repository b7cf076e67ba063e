"""The native C twins of the pythonfmu FMUs, by the model name they share: one registry for
``shapefmu build <target> --native``, ``shapefmu build --native`` (every twin) and
``shapefmu compare --native``.

A twin has the pythonfmu FMU's variables, units, start values and sampled semantics, so an SSP may
bind either; ``build_native(name, out_path, **start_values)`` builds one.
"""

from __future__ import annotations

import hashlib
import importlib
from importlib import resources
from pathlib import Path

# model name -> (module, builder(out_path, **start_values) -> Path)
TWINS = {
    "Shaper": ("shapefmu.fmi.native.sampled", "build_native_shaper"),
    "ImpulseTrain": ("shapefmu.fmi.native.sampled", "build_native_impulse_train"),
    "ShapeFilter": ("shapefmu.fmi.native.sampled", "build_native_shape_filter"),
    "EKFTuner": ("shapefmu.fmi.native.ekf_tuner", "build_native_ekf_tuner"),
    "TrackedShaper": ("shapefmu.fmi.native.tracked_shaper", "build_native_tracked_shaper"),
    "ScheduledShaper": ("shapefmu.fmi.native.scheduled_shaper", "build_native_scheduled_shaper"),
    "STOSController": ("shapefmu.fmi.native.stos", "build_native_stos"),
    "ReferencePlayer": ("shapefmu.fmi.native.reference", "build_native_reference"),
    "ProfileGenerator": ("shapefmu.fmi.native.profiles", "build_native_profile"),
}


def build_native(name: str, out_path, *, fmi_version: str = "2.0", clock: bool = False, **start_values) -> Path:
    """The native twin of the pythonfmu FMU ``name`` with ``start_values``, written to ``out_path`` as
    an FMI ``fmi_version`` ("2.0" or "3.0") FMU; ``clock``: with the periodic input clock of its sample
    period (FMI 3.0, sampled FMUs)."""
    if name not in TWINS:
        raise ValueError(f"name must be one of {', '.join(TWINS)} (the FMUs with a native C twin), got {name!r}")
    module, builder = TWINS[name]
    return getattr(importlib.import_module(module), builder)(out_path, fmi_version=fmi_version, clock=clock,
                                                                 **start_values)


def build_all_native(out_dir, fmi_version: str = "2.0", progress=None) -> list[Path]:
    """Every native twin with its default start values into ``out_dir``, named as the pythonfmu FMUs;
    ``progress`` (a function of a line of text, or None) is told as each FMU begins."""
    out_dir = Path(out_dir)
    built = []
    for name in TWINS:
        if progress is not None:
            progress(f"building {name}.fmu (native)")
        built.append(build_native(name, out_dir / f"{name}.fmu", fmi_version=fmi_version))
    return built


def fingerprint(name: str) -> str:
    """A digest of what the twin ``name`` is built from (its builder module and the C files), so a
    cache of built twins knows when to rebuild."""
    module, _ = TWINS[name]
    digest = hashlib.sha256(Path(importlib.import_module(module).__file__).read_bytes())
    folder = resources.files("shapefmu.fmi.native") / "c"
    for path in sorted(folder.iterdir(), key=lambda p: p.name):
        digest.update(path.name.encode() + path.read_bytes())
    return digest.hexdigest()[:16]
