"""The ReferencePlayer FMU: plays a signal table, e.g. the CasADi time-optimal input, with exact switches.

Parameter ``table``: the table as JSON text, either a ``TimeOptimalSolution.to_dict()`` object
(``"kind": "time_optimal"``, played as a zero-order hold with its exact switch instants) or a
``"signal_table"`` object (``time``, ``value``, ``interpolation`` "hold" or "linear", ``before``);
``shapefmu build reference solution.json -o fmus/TimeOptimal.fmu`` bakes a file in as its start value.

Outputs (FMI 2.0 co-simulation: after ``fmi2DoStep(t, h)`` they are the values at t + h):

- ``y``: the signal at the communication point, right-continuous, so a step that straddles or ends
  on a switch returns the new level (``runtime.reference_player``);
- ``y_mean``: the exact mean of the signal over the step just taken, the zero-order-hold
  equivalent for a consumer that holds its input over its own step (at initialisation, the value).

No inputs, so no output depends on one; the table is fixed at initialisation.
"""

import json

from ...runtime.reference_player import SignalTable, from_dict
from .interface import Interface, output, parameter
from .model import Model as _Model

# A rigid-body bang-bang of unit level and length, so that a default build plays something sensible.
DEFAULT_TABLE = json.dumps({"kind": "signal_table", "interpolation": "hold", "time": [0.0, 0.5, 1.0],
                            "value": [1.0, -1.0, 0.0]})


def parse_table(text):
    """The SignalTable described by the JSON ``text`` (ValueError naming the parameter otherwise)."""
    try:
        data = json.loads(text)
    except (TypeError, json.JSONDecodeError) as error:
        raise ValueError(f"table must be JSON text of a signal_table or time_optimal object: {error}") from None
    return from_dict(data)


INTERFACE = Interface(
    "ReferencePlayer",
    "Plays a signal table (e.g. a time-optimal input) with exact discontinuities",
    (
        parameter("table", DEFAULT_TABLE, "signal table as JSON: a time_optimal solution or a signal_table"),
        output("y", "table value at the communication point (right-continuous at switches)"),
        output("y_mean", "exact mean of the table value over the last communication step"),
    ),
    command_in=None,
    command_out="y",
)


class Model(_Model):
    interface = INTERFACE
    kernels = (SignalTable,)
    state_attributes = ("table",)

    def initialize(self):
        self.table = parse_table(self.values["table"])
        self.values["y"] = self.values["y_mean"] = self.table.value(self.time)

    def experiment(self):
        """DefaultExperiment: the table and a tenth more, in 1000 steps."""
        end = max(self.table.times[-1], 0.0)
        stop = 1.1 * end if end > 0.0 else 1.0
        return 0.0, stop, stop / 1000.0

    def picture(self):
        """The table over its span and a tenth more."""
        start, stop, _ = self.experiment()
        times = [start + (stop - start) * k / 96 for k in range(97)]
        return [("line", [(t, self.table.value(t)) for t in times])]

    def step(self, t, h):
        self.values["y"] = self.table.value(t + h)
        self.values["y_mean"] = self.table.average(t, t + h)
