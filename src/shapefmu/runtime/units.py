"""The units frequencies cross shapefmu's public boundaries in, so that a signature says them.

One convention: a frequency's name carries its unit. ``omega`` (``omega_n``, ``omega0``, ``omega_d``,
``omega_model``, ``delta_omega``, ``first_resonance``) is an angular frequency in rad/s, the papers'
symbol and the unit of python-control and scipy.signal, annotated ``RadPerSecond``; ``f`` (an FMU's
``f[i]``, ``frequencies_hz``) is a frequency in Hz, annotated ``Hz``, as the command line, the FMU
parameters named f, the recordings' spectra and the recommendations give them. Nothing converts
silently: ``shapefmu.cli.arguments.parse_mode`` turns the command line's Hz into the Python API's
rad/s, and an FMU parameter keeps the unit its name says.
"""

RadPerSecond = float
Hz = float
