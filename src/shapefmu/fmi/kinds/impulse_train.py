"""The ImpulseTrain FMU: a shaper given by its impulses, times and amplitudes, rather than designed.

What ``shapefmu recommend`` designs for a measured spectrum (``identification.trains``), Klipper's
and RepRapFirmware's shapers and any other train arrive as explicit impulses; this kind runs them.
Parameters: ``n_impulses`` (1..32) and, for i = 1..n_impulses, ``impulse_time[i]`` (s, >= 0,
strictly increasing in i) and ``impulse_amplitude[i]`` (finite, summing to 1 within 1e-9, so a
constant command passes unchanged); the entries after ``n_impulses`` are unused and must stay 0.
``Ts`` is the sampling period of the filter, ``u0`` the command before the start time. Input ``u``,
output ``y``. The FMU checks the sum, it does not normalise: a train that does not sum to 1 is
refused with its sum (``shapefmu build shaper --impulses`` normalises what a user types, and says so).

Sampled semantics, as the Shaper FMU (``runtime.sample_clock``): the command is sampled at
t0 + k Ts; an impulse off the grid, t = (d + alpha) Ts, is split onto it
(``runtime.shaper_filter.grid_impulses``: 1 - alpha at delay d, alpha at d + 1), so y[k] =
sum_i a_i ((1 - alpha_i) u[k - d_i] + alpha_i u[k - d_i - 1]), the sum of the amplitudes times the
command linearly interpolated between its samples at t_k - t_i: exactly sum_i a_i u(t_k - t_i) for
a command that is linear between the samples (a ramp, a trapezoidal velocity with corners on the
grid). Any step h > 0 is accepted, outputs are held between samples, a step over more than 10^7
samples is refused.

Feed-through: y is declared to depend on u whatever the train (an impulse at t = 0 passes u at
once); a train whose first impulse comes later gives that dependency a zero weight, which FMI allows.
"""

import math

from ...runtime.checks import check_count, check_finite, check_positive
from .interface import Interface, Variable, impulse_shaping, parameter, sampled_description
from .model import ImpulseFIRModel

MAX_IMPULSES = 32  # entries declared: 64 parameters of an FMI 2.0 FMU; Klipper's and RRF's shapers hold 2-5
SUM_TOLERANCE = 1e-9


def _entries(base, unit, description, minimum, first):
    """``base[1..MAX_IMPULSES]``, starting at ``first``, then 0: the default train is one impulse of
    amplitude 1 at t = 0, which passes the command unchanged, so a build sets only the entries it uses."""
    return tuple(Variable(f"{base}[{i}]", "Real", "parameter", "fixed", first if i == 1 else 0.0, unit,
                          description.format(i=i), minimum, None, "exact") for i in range(1, MAX_IMPULSES + 1))


INTERFACE = Interface(
    "ImpulseTrain",
    sampled_description("Impulse shaper given by its impulses (times and amplitudes, summing to 1)", "u"),
    (
        parameter("n_impulses", 1, f"number of impulses used, 1..{MAX_IMPULSES}: entries 1..n_impulses "
                  "of impulse_time and impulse_amplitude (the others stay 0)", minimum=1, maximum=MAX_IMPULSES),
        *_entries("impulse_time", "s", "time of impulse {i} (>= 0, increasing with the index)", 0.0, 0.0),
        *_entries("impulse_amplitude", "1", "amplitude of impulse {i} (the amplitudes of the impulses used sum to 1)", None,
                   1.0),
        *impulse_shaping(1e-4),
    ),
    command_in="u",
    command_out="y",
)


def train_start_values(times, amplitudes):
    """The start values of an ImpulseTrain running the impulses ``times`` (s), ``amplitudes``, checked
    as the FMU checks them (``check_train``): ``n_impulses``, ``impulse_time[i]``, ``impulse_amplitude[i]``.

    >>> train_start_values([0.0, 0.01], [0.5, 0.5])["impulse_time[2]"]
    0.01
    """
    times, amplitudes = list(times), list(amplitudes)
    if len(times) != len(amplitudes):
        raise ValueError(f"times and amplitudes must be as many, got {len(times)} times and {len(amplitudes)} amplitudes")
    if not 1 <= len(times) <= MAX_IMPULSES:
        raise ValueError(f"the number of impulses must be in [1, {MAX_IMPULSES}], got {len(times)}")
    values = {"n_impulses": len(times)}
    for i, (t, a) in enumerate(zip(times, amplitudes), 1):
        values[f"impulse_time[{i}]"] = float(t)
        values[f"impulse_amplitude[{i}]"] = float(a)
    check_train({**dict.fromkeys(_unused(len(times)), 0.0), **values})
    return values


def _unused(n):
    """The names of the entries after the first ``n``."""
    return [f"{base}[{i}]" for i in range(n + 1, MAX_IMPULSES + 1) for base in ("impulse_time", "impulse_amplitude")]


def check_train(values):
    """(times, amplitudes) of the train the parameters ``values`` hold, or ValueError naming the
    parameter, its value and the valid range."""
    n = check_count(values["n_impulses"], "n_impulses", 1)
    if n > MAX_IMPULSES:
        raise ValueError(f"n_impulses must be in [1, {MAX_IMPULSES}], got {n}")
    times, amplitudes = [], []
    for i in range(1, n + 1):
        t = check_finite(values[f"impulse_time[{i}]"], f"impulse_time[{i}]")
        if t < 0.0 or (times and t <= times[-1]):
            floor = f"> impulse_time[{i - 1}] = {times[-1]!r} s" if times else ">= 0 s"
            raise ValueError(f"impulse_time[{i}] must be {floor} (times increase with the index), got {t!r}")
        times.append(t)
        amplitudes.append(check_finite(values[f"impulse_amplitude[{i}]"], f"impulse_amplitude[{i}]"))
    for name in _unused(n):
        if values[name] != 0.0:
            raise ValueError(f"{name} must be 0 since n_impulses = {n} uses impulses 1..{n} only, got {values[name]!r}; "
                             f"raise n_impulses to use it")
    total = math.fsum(amplitudes)
    if not abs(total - 1.0) <= SUM_TOLERANCE:
        raise ValueError(f"impulse_amplitude[1..{n}] must sum to 1 within {SUM_TOLERANCE:g}, got the sum {total!r}")
    return times, amplitudes


class Model(ImpulseFIRModel):
    interface = INTERFACE

    def initialize(self):
        times, amplitudes = check_train(self.values)
        ts = check_positive(self.values["Ts"], "Ts")
        self.start_impulses(times, amplitudes, ts, check_finite(self.values["u0"], "u0"), "the impulse train")

    def output_dependencies(self):
        return {"y": ["u"]}  # whatever the train: module docstring
