"""pythonfmu FMUs: the slave that runs a kind's model (``shapefmu.fmi.kinds``) inside the FMU, the
builder that bundles them, the C shim.

``slave_base`` and ``state_codec`` are copied into every FMU with the kind's module and ``runtime/``,
so they import the standard library and each other only; the builder may also import the design layer.
"""
