"""Every FMU kind shapefmu makes, declared once: its interface (``interface.Interface``: variables,
causality, variability, units, descriptions, start values) and its model (``model.Model``: what it
computes, with the runtime's kernels), one module per kind.

``KINDS`` maps each FMU's model name to its module here. The pythonfmu FMU runs the model inside
(``shapefmu.fmi.python``), the native C twin lists the interface in its generated ``model.c`` and
designs with the model at build time (``shapefmu.fmi.native``), and both model descriptions are
written from the interface (``shapefmu.fmi.description``). Adding a kind is one module here (its
``INTERFACE`` and ``Model``) and one line in ``KINDS``; its native twin, one C model part.

Bundled into every pythonfmu FMU (with the kind's own module): standard library only.
"""

import importlib

KINDS = {
    "Shaper": "shaper",
    "ShapeFilter": "shape_filter",
    "ReferencePlayer": "reference_player",
    "ProfileGenerator": "profile_generator",
    "EKFTuner": "ekf_tuner",
    "STOSController": "stos_controller",
}


def kind(name):
    """The module of the kind ``name`` (a key of ``KINDS``)."""
    if name not in KINDS:
        raise ValueError(f"name must be one of {', '.join(KINDS)}, got {name!r}")
    return importlib.import_module(f"{__name__}.{KINDS[name]}")


def designed(name, start_values):
    """The model of kind ``name`` with ``start_values`` (name -> value, converted to the variables'
    types) applied and its design run, as at the exit of initialisation at t = 0."""
    model_class = kind(name).Model
    interface = model_class.interface
    values = {v.name: (0.0 if v.start is None else v.start) for v in interface.variables}
    for key, value in start_values.items():
        values[key] = interface.typed_start(key, value)
    model = model_class(values, f"{name} build")
    model.initialize()
    return model
