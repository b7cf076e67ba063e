"""The FMU slaves: one module per FMU class, registered here by model name.

``SLAVES`` maps the FMU's model name (its modelIdentifier) to the module under this package that
defines the slave class of that name. Adding an FMU is one module and one line here; see the
docstring of ``shapefmu.fmi.python.slave_base`` for the steps.
"""

SLAVES = {
    "Shaper": "shaper",
    "ShapeFilter": "shape_filter",
    "ReferencePlayer": "reference_player",
    "ProfileGenerator": "profile_generator",
    "EKFTuner": "ekf_tuner",
    "STOSController": "stos_controller",
}
