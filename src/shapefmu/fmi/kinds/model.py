"""What an FMU kind computes, apart from FMI: the base of every kind's ``Model``.

A ``Model`` holds the values of its FMU's variables (a dict ``name -> value`` shared with whoever
runs it: the pythonfmu slave, or the native build that designs with it) and the runtime kernels it
designs from them. The pythonfmu slave (``shapefmu.fmi.python.slave_base``) owns the FMI state
machine and calls the hooks below; the native build calls ``initialize`` once, at build time, and
writes what it designed into the C twin's ``model.c``.

Bundled into every pythonfmu FMU: standard library only.
"""

OK, WARNING, ERROR = 0, 1, 3  # the FMI status of a logged message


class Model:
    """Base of the kinds' models: the hooks, with what a kind that needs nothing more does."""

    interface = None          # the kind's Interface
    kernels = ()              # runtime classes that may appear in a saved FMU state
    state_attributes = ()     # attributes holding the kernels, saved and restored with the state

    def __init__(self, values, owner="", log=None):
        self.values = values
        self.owner = owner    # "<model name> <instance name>", heading logged messages
        self._log = log
        self.time = 0.0       # the FMU's time: the start time at ``initialize``, then each step's end
        self.running = False  # initialised and stepping (the pythonfmu slave's "step" phase)
        for name in self.state_attributes:
            setattr(self, name, None)

    def log(self, message, status=OK):
        if self._log is not None:
            self._log(message, status)

    def initialize(self):
        """Validate the parameters (ValueError naming the parameter, its value and the valid range)
        and design the kernels, at ``self.time``: the exit of initialisation."""

    def step(self, t, h):
        """Advance the kernels over (t, t + h] and set the outputs. Any h > 0 is honoured (hosts trim
        their last step to 1e-16 s): a sampled model takes its samples on the grid t0 + k Ts with
        ``runtime.sample_clock.SampleClock`` (made in ``initialize``, listed in ``kernels`` and
        ``state_attributes``), which counts them from the steps, never from the host's t."""
        raise NotImplementedError

    def input_changed(self, name):
        """Called after input ``name`` is set: recompute the outputs that feed through from it."""

    def output_dependencies(self):
        """``{output: [inputs it depends on at the same instant]}``, after ``initialize``."""
        return {v.name: [] for v in self.interface.variables if v.causality == "output"}

    def experiment(self):
        """The DefaultExperiment (start, stop, step) in s, after ``initialize``."""
        return 0.0, 1.0, 1e-3

    def picture(self):
        """What the FMU's icon shows of the design, after ``initialize``: strokes ``(kind, points)``
        (``shapefmu.fmi.icon``); the base draws a step."""
        return [("line", [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (3.0, 1.0)])]
