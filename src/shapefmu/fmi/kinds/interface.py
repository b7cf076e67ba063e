"""The interface of an FMU kind as data: its variables, each with causality, variability, type, start
value, unit and description, and the kind's own flags.

One ``Interface`` per kind (``shapefmu.fmi.kinds``) is what the pythonfmu slave declares, what the
native C twin's generated ``model.c`` lists and what the model description writers
(``shapefmu.fmi.description``, one per FMI version) write; a plant's interface is made from its model
part the same way. As the FMI Reference FMUs keep ``config.h`` and ``FMI3.xml`` beside ``model.c``.

Arrays are named, not nested: the elements ``f[1]``, ``f[2]``, ... of a parameter are one array of
that many elements, which FMI 2.0 lists as scalars and FMI 3.0 declares as one array variable with a
``<Dimension>`` (``shapefmu.fmi.description.fmi3``).

Bundled into every pythonfmu FMU: standard library only.
"""

from dataclasses import dataclass, replace

TYPES = ("Real", "Integer", "Boolean", "String")
_TYPE_OF = {bool: "Boolean", int: "Integer", float: "Real", str: "String"}


@dataclass(frozen=True)
class Variable:
    """One value of an FMU: a scalar, or one element ``name[i]`` of an array parameter.

    ``start`` is None where the variable has no start value (outputs, calculated locals); ``unit``
    names a unit of ``shapefmu.fmi.description.units`` ("" for none, Real variables only);
    ``derivative_of`` names the state a derivative belongs to.
    """

    name: str
    type: str
    causality: str            # parameter, input, output, local, independent
    variability: str          # constant, fixed, tunable, discrete, continuous
    start: object = None
    unit: str = ""
    description: str = ""
    minimum: float | None = None
    maximum: float | None = None
    initial: str | None = None   # exact, calculated, approx; None: the standard's default
    nominal: float | None = None
    derivative_of: str | None = None

    def with_start(self, value):
        """This variable with another start value (a build's)."""
        return replace(self, start=value)


def parameter(name, start, description, unit="1", minimum=None, maximum=None, variability="fixed"):
    """A parameter set before the exit of initialisation; its type follows ``start``."""
    return Variable(name, _TYPE_OF[type(start)], "parameter", variability, start, unit, description, minimum, maximum,
                    "exact")


def input_(name, start, description, unit="1"):
    """A continuous Real input."""
    return Variable(name, "Real", "input", "continuous", float(start), unit, description)


def output(name, description, unit="1"):
    """A continuous Real output, computed by the FMU."""
    return Variable(name, "Real", "output", "continuous", None, unit, description, initial="calculated")


def mode_parameters(count, frequency, unit, frequency_start, zeta_start=0.0, mode="mode"):
    """The interleaved ``<frequency>[i]``, ``zeta[i]`` parameters of ``count`` modes, i = 1..count: the
    frequency in ``unit``, starting at ``frequency_start(i)``, and the damping ratio, at ``zeta_start``;
    ``mode`` names what they describe ("mode", "shaper mode")."""
    variables = []
    for i in range(1, count + 1):
        variables.append(parameter(f"{frequency}[{i}]", frequency_start(i), f"natural frequency of {mode} {i}", unit))
        variables.append(parameter(f"zeta[{i}]", zeta_start, f"damping ratio of {mode} {i}, in [0, 1)", minimum=0.0))
    return tuple(variables)


def sampled_description(summary, inputs, period="Ts"):
    """A sampled FMU's description: ``summary`` and the semantics of its clock."""
    return (
        f"{summary}. Samples {inputs} at startTime + k*{period} whatever the communication steps, each sample "
        f"taking the value set at the last communication point at or before its instant; between samples the "
        f"outputs hold the newest sample's, and inputs set there are used from the next sample on"
    )


@dataclass(frozen=True)
class Interface:
    """An FMU kind: its model name (the model identifier too), description and variables in the order
    of their declaration, and the command it takes and gives (FMI 3.0 terminals; None: none)."""

    name: str
    description: str
    variables: tuple
    command_in: str | None = None
    command_out: str | None = None

    def __post_init__(self):
        names = [v.name for v in self.variables]
        repeated = sorted({n for n in names if names.count(n) > 1})
        if repeated:
            raise ValueError(f"{self.name}: variables declared twice: {repeated}")
        for v in self.variables:
            if v.type not in TYPES:
                raise ValueError(f"{self.name}: variable {v.name} has type {v.type!r}, not one of {TYPES}")
            if not v.description and v.causality != "independent":
                raise ValueError(f"{self.name}: variable {v.name!r} needs a description")

    def variable(self, name):
        """The variable called ``name`` (KeyError if there is none)."""
        for v in self.variables:
            if v.name == name:
                return v
        raise KeyError(name)

    def start_values(self):
        """``{name: start}`` of every variable with a start value."""
        return {v.name: v.start for v in self.variables if v.start is not None}

    def settable(self):
        """The names a build may give start values to: parameters and inputs."""
        return [v.name for v in self.variables if v.causality in ("parameter", "input")]

    def typed_start(self, name, value):
        """``value`` as the start value of the parameter or input ``name``, converted to its type, or
        ValueError naming it."""
        v = next((v for v in self.variables if v.name == name and v.causality in ("parameter", "input")), None)
        if v is None:
            raise ValueError(f"{self.name} has no parameter or input {name!r}; settable: {', '.join(self.settable())}")
        return _coerce(v, value)


def _coerce(var, value):
    """A start value converted to the variable's type, or ValueError naming it."""
    if var.type == "Real":
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ValueError(f"{var.name} must be a real number, got {value!r}")
        return float(value)
    if var.type == "Integer":
        if isinstance(value, bool) or not (isinstance(value, int) or (isinstance(value, float) and value.is_integer())):
            raise ValueError(f"{var.name} must be an integer, got {value!r}")
        return int(value)
    if var.type == "Boolean":
        if not isinstance(value, bool):
            raise ValueError(f"{var.name} must be true or false, got {value!r}")
        return value
    if not isinstance(value, str):
        raise ValueError(f"{var.name} must be a string, got {value!r}")
    return value
