"""Shaped moves beside the time-optimal one (``compare_moves``): the rigid-body bang-bang of paper
002, eq. (2), and the bang-bang convolved with impulse shapers (paper 002, eqs. 4 and 21), all
simulated exactly; their plot, and the report of ``shapefmu optimal`` (``optimal_report``)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from shapefmu.files import save_figure, write_text
from shapefmu.optimal.moves import Command, _u_max, residual_after_move
from shapefmu.optimal.solution import TimeOptimalSolution, time_optimal
from shapefmu.plants import as_plant, rigid_part


# ---------------------------------------------------------------------------------------------
# Comparison of moves


@dataclass(frozen=True)
class Move:
    """One move of a comparison: its command, length, residual vibration and peak input.

    Examples
    --------
    >>> from shapefmu.optimal.moves import Command
    >>> move = Move("rigid bang-bang", Command((0.0, 1.0, 2.0), (1.0, -1.0)), 2.0, 0.09, 1.0)
    >>> move.duration / move.command.duration
    1.0
    """

    name: str
    command: Command
    duration: float
    residual: float
    peak: float


@dataclass(frozen=True)
class MoveComparison:
    """Every move of ``compare_moves`` beside the time-optimal one, printed by ``table``.

    Examples
    --------
    >>> import math
    >>> from shapefmu.plants.library import rigid_flexible
    >>> plant = rigid_flexible(1.0, [(2 * math.pi * 0.75, 0.0, -1.0)], u_max=1.0)  # a rigid body and a 0.75 Hz mode
    >>> comparison = compare_moves(plant, 1.0)
    >>> [(move.name, round(move.duration, 6)) for move in comparison.moves]
    [('rigid bang-bang', 2.0), ('bang-bang * convolution (ZV per mode)', 2.666667), ('bang-bang * simultaneous', 2.666667), ('time-optimal', 2.077786)]
    >>> print(comparison.table().splitlines()[2])
    rigid bang-bang                                    2     0.96256   9.006e-02          1
    """

    plant: str
    distance: float
    u_max: float
    moves: tuple[Move, ...]
    optimal: TimeOptimalSolution

    def table(self) -> str:
        width = max(len(move.name) for move in self.moves)
        lines = [f"plant {self.plant}: move of {self.distance:g} with |u| <= {self.u_max:g}",
                 f"{'move':<{width}} {'time [s]':>14} {'vs optimal':>11} {'residual':>11} {'peak |u|':>10}"]
        for move in self.moves:
            lines.append(f"{move.name:<{width}} {move.duration:14.8g} {move.duration / self.optimal.T:11.5f} "
                         f"{move.residual:11.3e} {move.peak:10.4g}")
        return "\n".join(lines)


def rigid_bang_bang(plant, distance: float, u_max: float | None = None, output=0) -> Command:
    """The time-optimal bang-bang of the plant's rigid part alone (paper 002, eq. 2 for b2/s^2):
    the unshaped command that the shapers are convolved with.

    Examples
    --------
    >>> from shapefmu.plants.library import rigid_flexible
    >>> plant = rigid_flexible(1.0, u_max=1.0)  # x'' = u, |u| <= 1: T = 2 sqrt(X / (b U)) = 2 for X = 1
    >>> rigid_bang_bang(plant, 1.0)
    Command(breaks=(0.0, 1.0, 2.0), levels=(1.0, -1.0), final=0.0)
    """
    plant = as_plant(plant)
    rigid = time_optimal(rigid_part(plant), distance, _u_max(plant, u_max), output, n_intervals=40, n_samples=2)
    return rigid.command


def compare_moves(plant, distance: float, u_max: float | None = None, shapers=None, output=0,
                  progress=None) -> MoveComparison:
    """Move time and residual vibration of the rigid bang-bang, of it convolved with each shaper,
    and of the time-optimal move, all simulated exactly on the full plant.

    ``shapers`` maps a name to an ``ImpulseShaper``; by default the convolution (ZV per mode) and
    simultaneous shapers of paper 002 (Sec. II) for the plant's oscillatory modes. ``progress``, a
    function of one line of text, is told as each phase begins.

    Examples
    --------
    >>> import math
    >>> from shapefmu.plants.library import rigid_flexible
    >>> plant = rigid_flexible(1.0, [(2 * math.pi * 0.75, 0.0, -1.0)], u_max=1.0)  # a rigid body and a 0.75 Hz mode
    >>> comparison = compare_moves(plant, 1.0)  # the shaped moves rest, the rigid bang-bang does not
    >>> [move.residual < 1e-12 for move in comparison.moves], round(comparison.optimal.T, 7)
    ([False, True, True, True], 2.0777864)
    """
    from shapefmu.shapers import convolve_modes, simultaneous

    plant = as_plant(plant)
    u_max = _u_max(plant, u_max)
    if shapers is None:
        modes = plant.flexible_modes()
        shapers = {"convolution (ZV per mode)": convolve_modes(modes), "simultaneous": simultaneous(modes)}
    say = progress or (lambda text: None)
    say("rigid bang-bang of the plant's rigid part")
    rigid = rigid_bang_bang(plant, distance, u_max, output)
    optimal = time_optimal(plant, distance, u_max, output, progress=progress)
    say(f"simulating {len(shapers) + 2} moves on the full plant")
    candidates = [("rigid bang-bang", rigid)]
    candidates += [(f"bang-bang * {name}", rigid.shaped(shaper)) for name, shaper in shapers.items()]
    candidates.append(("time-optimal", optimal.command))
    moves = tuple(
        Move(name, command, command.duration, residual_after_move(plant, command, distance, output), command.peak)
        for name, command in candidates
    )
    return MoveComparison(plant.name, distance, u_max, moves, optimal)


def plot_comparison(comparison: MoveComparison, plant, path) -> None:
    """Save u(t) of every move (top), the moved output (middle) and the other outputs, the modal
    deflections for the plants of paper 002 (bottom), under the time-optimal move, to ``path``.

    Examples
    --------
    >>> import math
    >>> from shapefmu.plants.library import rigid_flexible
    >>> plant = rigid_flexible(1.0, [(2 * math.pi * 0.75, 0.0, -1.0)], u_max=1.0)  # a rigid body and a 0.75 Hz mode
    >>> import os, tempfile
    >>> path = os.path.join(tempfile.mkdtemp(), "moves.png")
    >>> plot_comparison(compare_moves(plant, 1.0), plant, path)
    >>> os.path.getsize(path) > 0
    True
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    plant = as_plant(plant)
    panels = 3 if len(plant.outputs) > 1 else 2
    fig, axes = plt.subplots(panels, 1, sharex=True, figsize=(8, 2.6 * panels))
    for move in comparison.moves:
        t = np.array(move.command.breaks)
        axes[0].step(t, np.append(move.command.levels, move.command.final), where="post", label=move.name)
    axes[0].set_ylabel(f"input {plant.inputs[0]}")
    axes[0].legend(fontsize="small")
    optimal = comparison.optimal
    y = optimal.x @ plant.C.T + np.outer(optimal.u, plant.D[:, 0])
    axes[1].plot(optimal.t, y[:, 0], label=f"{plant.outputs[0]} (time-optimal)")
    axes[1].set_ylabel(plant.outputs[0])
    axes[1].legend(fontsize="small")
    if panels == 3:
        for j, name in enumerate(plant.outputs[1:], start=1):
            axes[2].plot(optimal.t, y[:, j], label=name)
        axes[2].set_ylabel("other outputs (time-optimal)")
        axes[2].legend(fontsize="small")
    axes[-1].set_xlabel("time [s]")
    fig.tight_layout()
    try:
        save_figure(fig, path)
    finally:
        plt.close(fig)


def optimal_report(path, distance: float, u_max: float | None = None, plot=None, json_path=None,
                   csv_path=None, progress=None) -> str:
    """The text of ``shapefmu optimal FILE --distance X [--u-max U] [--plot out.png] [--json s.json]
    [--csv u.csv]``; the JSON and CSV files are the solution's ``to_json`` and ``to_csv``, which
    ``shapefmu build reference`` plays back; ``progress`` as in :func:`compare_moves`.

    Examples
    --------
    >>> import math
    >>> from shapefmu.plants.library import rigid_flexible
    >>> plant = rigid_flexible(1.0, [(2 * math.pi * 0.75, 0.0, -1.0)], u_max=1.0)  # a rigid body and a 0.75 Hz mode
    >>> print(optimal_report(plant, 1.0).splitlines()[0])
    plant rigid_flexible: move of 1 with |u| <= 1
    """
    plant = as_plant(path)
    comparison = compare_moves(plant, distance, u_max, progress=progress)
    optimal = comparison.optimal
    lines = [comparison.table(), "",
             f"time-optimal: T = {optimal.T:.12g} s, {len(optimal.switch_times)} switches at "
             + ", ".join(f"{s:.10g}" for s in optimal.switch_times),
             f"refined final-state residual {optimal.residual:.3e} (transcription T = {optimal.transcription_T:.10g} s)"]
    for target, text, what in ((json_path, optimal.to_json, "solution"), (csv_path, optimal.to_csv, "signal table")):
        if target is not None:
            write_text(target, text(), what)
            lines.append(f"{what} written to {target}")
    if plot is not None:
        if progress is not None:
            progress(f"plotting to {plot}")
        plot_comparison(comparison, plant, plot)
        lines.append(f"plot written to {plot}")
    return "\n".join(lines)
