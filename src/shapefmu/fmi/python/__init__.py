"""pythonfmu FMUs: slave classes that run ``runtime/`` code, the builder that bundles them, the C shim.

Modules here import the standard library, ``runtime/`` and each other (``slaves/`` and
``slave_base``/``state_codec`` are copied into every FMU, so they import nothing else); the
builder may also import the design layer.
"""
