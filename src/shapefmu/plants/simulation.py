"""Running a plant whose scheduling input moves, sample by sample, with a per-sample kernel in the loop.

The plant's state advances over each sample period by the exact zero-order-hold step of the model
at the scheduling value in force, x[k+1] = Ad x[k] + Bd u[k] with
[[Ad, Bd], [0, I]] = expm([[A, B], [0, 0]] ts) (Van Loan). A kernel (a shaper, an EKF-tracked shaper)
reads the measured output at t_k, before its command for the sample acts, and returns the input held
over [t_k, t_k + ts): the sampled semantics of the FMUs (DESIGN.md), so this is the Python stand-in for
a plant FMU with a scheduling input and a shaper FMU in the co-simulation master.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.linalg import expm

from shapefmu.plants.model import Plant
from shapefmu.plants.scheduling import ScheduledPlant
from shapefmu.runtime.checks import check_positive, check_size


def zero_order_hold(plant: Plant, ts: float) -> tuple[np.ndarray, np.ndarray]:
    """``(Ad, Bd)`` of ``plant`` for an input held over each period ``ts``.

    Examples
    --------
    >>> import control
    >>> from shapefmu.plants import as_plant
    >>> Ad, Bd = zero_order_hold(as_plant(control.ss(-2.0, 1.0, 1.0, 0.0)), 0.1)  # x' = -2 x + u
    >>> round(float(Ad[0, 0]), 9), round(float(Bd[0, 0]), 9)  # e^{-0.2}, (1 - e^{-0.2}) / 2
    (0.818730753, 0.090634623)
    """
    ts = check_positive(ts, "ts")
    n, m = plant.B.shape
    block = np.zeros((n + m, n + m))
    block[:n, :n] = plant.A
    block[:n, n:] = plant.B
    step = expm(block * ts)
    return step[:n, :n], step[:n, n:]


@dataclass(frozen=True)
class LoopRun:
    """What a run gives: ``inputs`` the plant received at each sample (the kernel's outputs),
    ``outputs`` (samples x outputs) the plant's outputs at each sample instant, without noise,
    ``measured`` what the kernel read (the measured output with its noise; empty without a kernel).

    Examples
    --------
    >>> import numpy as np
    >>> from shapefmu.plants import load_scheduled
    >>> run = run_loop(load_scheduled("printer_bed"), np.ones(11), 0.0, 0.01)  # 1 m/s^2 held, no kernel
    >>> run.inputs.shape, run.outputs.shape, run.measured.shape
    ((11,), (11, 3), (0,))
    """

    inputs: np.ndarray
    outputs: np.ndarray
    measured: np.ndarray


def run_loop(plant: ScheduledPlant, commands, values, ts: float,
             kernel: Callable[[int, float, float], float] | None = None, measure: str | None = None,
             noise: float = 0.0, seed: int = 0) -> LoopRun:
    """Run ``plant`` from rest through ``commands`` (one per sample), the scheduling input at ``values``
    (one per sample, or one value for the whole run).

    ``kernel(k, command, measurement) -> input`` closes the loop: it reads output ``measure`` at sample
    k plus normal noise of standard deviation ``noise`` (seeded by ``seed``); without a kernel the
    plant takes the commands as they are.

    Examples
    --------
    >>> import numpy as np
    >>> from shapefmu.plants import load_scheduled
    >>> run = run_loop(load_scheduled("printer_bed"), np.ones(11), 0.0, 0.01)  # 1 m/s^2 from rest
    >>> round(float(run.outputs[-1, 0]), 12)  # the carriage at 0.1 s: a t^2 / 2, exact under a held input
    0.005
    """
    commands = np.asarray(commands, dtype=float).ravel()
    values = np.broadcast_to(np.asarray(values, dtype=float), commands.shape)
    check_size(8 * commands.size * (len(plant.plant.outputs) + 2), "MAX_RESULT_BYTES", "a run would record",
               "bytes", "run fewer samples")
    if not (np.all(np.isfinite(commands)) and np.all(np.isfinite(values))):
        raise ValueError("commands and values must be finite")
    row = None
    if kernel is not None:
        if measure not in plant.plant.outputs:
            raise ValueError(f"measure must name an output of {plant.plant.name} ({', '.join(plant.plant.outputs)}), "
                             f"got {measure!r}")
        row = plant.plant.outputs.index(measure)
        if np.any(plant.plant.D[row]):
            raise ValueError(f"output {measure!r} feeds the input through: its value at a sample depends on the "
                             f"command of that sample, which the kernel has not yet given")
    noise = np.random.default_rng(seed).normal(0.0, noise, commands.size) if noise > 0 else np.zeros(commands.size)
    steps = {}
    x = np.zeros(plant.plant.n_states)
    inputs = np.empty(commands.size)
    outputs = np.empty((commands.size, len(plant.plant.outputs)))
    measured = np.empty(commands.size if kernel is not None else 0)
    for k, (command, value) in enumerate(zip(commands.tolist(), values.tolist())):
        if value not in steps:
            model = plant.at(value)
            steps[value] = (*zero_order_hold(model, ts), model.C, model.D)
        Ad, Bd, C, D = steps[value]
        outputs[k] = C @ x
        u = command
        if kernel is not None:
            measured[k] = outputs[k, row] + noise[k]
            u = kernel(k, command, float(measured[k]))
        outputs[k] += D[:, 0] * u
        inputs[k] = u
        x = Ad @ x + Bd[:, 0] * u
    return LoopRun(inputs, outputs, measured)
