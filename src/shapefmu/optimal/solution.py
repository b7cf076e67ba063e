"""The time-optimal move (``time_optimal``) and its result (``TimeOptimalSolution``): a grid
transcription for the structure, then exact switch times.

``time_optimal`` finds the bang-bang input in three steps:

1. a feasible start: the shortest time, to a factor of 2, at which a linear program on a coarse
   grid of piecewise-constant inputs reaches the target (exact discretisation, scipy's HiGHS);
2. the structure: the shortest T on a fine uniform grid (``lp_transcription``: bisection on T of
   the least-peak LP, with the equality rows orthonormalised so that the ten pendula's nearly
   dependent modes are met too), whose grid input shows the sequence of bang levels and roughly
   where they switch. ``transcribe`` is the free-final-time alternative (CasADi + IPOPT), slower
   and, for the ten pendula, not converging; ``refine_transcription`` accepts either;
3. exact switch times: Newton / Levenberg-Marquardt on the switch instants and T, with the final
   state computed exactly for piecewise-constant input from matrix exponentials of the augmented
   matrix [[A, B], [0, 0]], expm of which holds e^{A t} and its integral times B. Where that
   Jacobian is nearly singular (closely spaced modes: the ten pendula, relative singular value
   ~1e-14) double precision fixes the switch times only to ~1e-4 and the fit slides to a longer
   move; ``refine_exact`` then solves the extremal's equations (rest at T, Pontryagin's switching
   function zero at every switch) for the switch times, T and the costate in 40-digit arithmetic.
"""

from __future__ import annotations

import io
import json
import warnings
from dataclasses import dataclass

import numpy as np

from shapefmu.optimal.moves import Command, rest_state, simulate
from shapefmu.optimal.refinement import _final_state, refine, refine_exact
from shapefmu.optimal.transcription import Transcription, _structure, lp_transcription
from shapefmu.plants import as_plant


# ---------------------------------------------------------------------------------------------
# The solution object


@dataclass(frozen=True)
class TimeOptimalSolution:
    """A time-optimal rest-to-rest move.

    ``levels[k]`` is the input on [switch_k, switch_{k+1}) with switch_0 = 0 and switch_last = T;
    after T the input is ``u_final``. ``t``, ``u``, ``x`` sample the exact solution (with every
    switch instant in ``t``). ``final_error`` is x(T) - x_f from the exact propagation of the
    refined switch times; ``residual`` is max_i |final_error_i| / peak_i, the peak of |x_i| over
    the move. ``transcription_T`` is the move time of the grid transcription that found the
    structure.

    Examples
    --------
    >>> from shapefmu.plants.library import rigid_flexible
    >>> plant = rigid_flexible(1.0, u_max=1.0)  # x'' = u, |u| <= 1: T = 2 sqrt(X / (b U)) = 2 for X = 1
    >>> solution = time_optimal(plant, 1.0)
    >>> solution.T, solution.switch_times, solution.levels
    (2.0, (1.0,), (1.0, -1.0))
    >>> print(solution.to_csv(), end="")
    time,u
    0,1
    1,-1
    2,0
    """

    T: float
    switch_times: tuple[float, ...]
    levels: tuple[float, ...]
    t: np.ndarray
    u: np.ndarray
    x: np.ndarray
    distance: float
    u_max: float
    u_final: float
    final_error: tuple[float, ...]
    residual: float
    states: tuple[str, ...]
    transcription_T: float

    @property
    def command(self) -> Command:
        return Command((0.0, *self.switch_times, self.T), self.levels, self.u_final)

    def to_dict(self) -> dict:
        return {
            "kind": "time_optimal",
            "T": self.T,
            "switch_times": list(self.switch_times),
            "levels": list(self.levels),
            "u_final": self.u_final,
            "distance": self.distance,
            "u_max": self.u_max,
            "final_error": list(self.final_error),
            "residual": self.residual,
            "states": list(self.states),
            "transcription_T": self.transcription_T,
        }

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), indent=2)

    def to_csv(self) -> str:
        """Signal table ``time,u`` of the piecewise-constant input: each row's value holds from its
        time until the next row's (zero-order hold), rows at 0, each exact switch instant and T
        (where the input becomes ``u_final``). Times are printed with 17 significant digits."""
        out = io.StringIO()
        out.write("time,u\n")
        for time, level in zip((0.0, *self.switch_times, self.T), (*self.levels, self.u_final)):
            out.write(f"{time:.17g},{level:.17g}\n")
        return out.getvalue()


def _peak_scale(x, x_f, distance):
    peak = np.maximum(np.max(np.abs(x), axis=0), np.abs(x_f))
    return np.maximum(peak, 1e-12 * abs(distance))


def time_optimal(plant, distance: float, u_max: float | None = None, output=0, n_intervals: int = 100,
                 n_samples: int = 2001, tolerance: float = 1e-9, progress=None) -> TimeOptimalSolution:
    """The minimum-time rest-to-rest move of ``output`` by ``distance`` with |u| <= u_max.

    ``plant`` is a ``Plant``, a python-control LTI or a model file with one input; ``u_max``
    defaults to the plant's declared input limit. Every mode ends at rest: x(T) = x_f with
    (x_f, u_f) the rest state of ``rest_state``. The grid transcription (``lp_transcription``, at
    least ``n_intervals`` steps) finds the bang-bang structure; ``refine`` makes the switch times
    exact; ``check_optimality`` verifies the result. ``progress``, a function of one line of text, is
    told as each of the two solver phases begins.

    Raises ValueError for u_max <= 0, a plant that is not controllable from its input, or a
    target that has no rest state within the limit. Warns (RuntimeWarning) if the refined move
    misses the rest state by more than ``tolerance`` (relative to each state's peak), or is longer
    than the grid's move (then it rests but is not the optimum: the structure was wrong).

    Examples
    --------
    >>> import math
    >>> from shapefmu.plants.library import rigid_flexible
    >>> plant = rigid_flexible(1.0, [(2 * math.pi * 0.75, 0.0, -1.0)], u_max=1.0)  # a rigid body and a 0.75 Hz mode
    >>> solution = time_optimal(plant, 1.0)  # longer than the rigid body's 2 s: the mode rests too
    >>> round(solution.T, 7), len(solution.switch_times), solution.residual < 1e-9
    (2.0777864, 3, True)
    """
    plant = as_plant(plant)
    if progress is not None:
        progress(f"time-optimal move: bisecting the move time by linear programs on {n_intervals} intervals")
    grid = lp_transcription(plant, distance, u_max, n_intervals, output)
    if progress is not None:
        progress(f"time-optimal move: refining the switch times of the grid's {grid.T:.6g} s move")
    return refine_transcription(plant, grid, n_samples, tolerance)


def _ill_conditioned(plant, levels, switches, T, scale, threshold: float = 1e-8) -> bool:
    """True if the final state's Jacobian in (switches, T), dimensionless, has a singular value
    below ``threshold`` of its largest: double precision then leaves the switch times uncertain
    by ~1e-16 / threshold (closely spaced modes)."""
    J = _final_state(plant.A, plant.B[:, :1], np.asarray(switches, dtype=float), T, levels)[1] * T / scale[:, None]
    s = np.linalg.svd(J, compute_uv=False)
    return bool(s[-1] < threshold * s[0])


def refine_transcription(plant, grid: Transcription, n_samples: int = 2001,
                         tolerance: float = 1e-9) -> TimeOptimalSolution:
    """The exact time-optimal move from the bang-bang structure of a transcription (``refine``,
    and ``refine_exact`` where the double-precision fit is ill-conditioned).

    Examples
    --------
    >>> from shapefmu.plants.library import rigid_flexible
    >>> plant = rigid_flexible(1.0, u_max=1.0)  # x'' = u, |u| <= 1: T = 2 sqrt(X / (b U)) = 2 for X = 1
    >>> from shapefmu.optimal.transcription import lp_transcription
    >>> refine_transcription(plant, lp_transcription(plant, 1.0)).switch_times
    (1.0,)
    """
    plant = as_plant(plant)
    distance, u_max, output = grid.distance, grid.u_max, grid.output
    x_f, u_f = rest_state(plant, distance, output)
    try:
        levels, switches = _structure(grid.u, grid.T, u_max)
    except ValueError as error:
        raise ValueError(f"no time-optimal move found for distance = {distance!r} with u_max = {u_max!r} on "
                         f"plant {plant.name!r} ({error}); a move that lasts many thousand or a tiny fraction "
                         f"of the plant's mode periods is out of the transcription's numerical range") from None
    command = Command((0.0, *switches, grid.T), tuple(levels), u_f)
    _, states = simulate(plant, command, np.linspace(0.0, grid.T, 201))
    scale = _peak_scale(states, x_f, distance)
    start = (list(switches), grid.T)
    switches, T = refine(plant, x_f, levels, switches, grid.T, scale)
    if _ill_conditioned(plant, levels, switches, T, scale):
        # The double-precision fit has only ~1e-4 of the switch times right; redo it in extended
        # precision from the transcription's estimate, else from that fit. An extremal that
        # reaches x_f is the optimum (``check_optimality`` verifies it), so the first one is kept.
        for guess in (start, (switches, T)):
            exact = refine_exact(plant, distance, output, levels, *guess)
            if exact is not None:
                switches, T = exact
                break
    edges = np.concatenate([[0.0], switches, [T]])
    if np.any(np.diff(edges) < -1e-12 * T):
        raise ValueError(f"switch-time refinement of the move of {distance:g} on plant {plant.name!r} reordered the "
                         f"switches ({edges}); the transcription's structure is wrong: raise n_intervals")
    command = Command(tuple(map(float, edges)), tuple(levels), u_f)
    t = np.union1d(np.linspace(0.0, T, n_samples), edges)
    at_breaks, x = simulate(plant, command, t)
    error = at_breaks[-1] - x_f
    residual = float(np.max(np.abs(error) / _peak_scale(x, x_f, distance)))
    if T > grid.T * (1.0 + 1e-9):
        # The grid's move is feasible, so the optimum is no longer than grid.T: the refinement has
        # slid along a nearly singular direction (closely spaced modes) to a longer extremal.
        warnings.warn(f"time_optimal: the refined move ({T:.10g} s) is longer than the grid transcription's "
                      f"({grid.T:.10g} s) on plant {plant.name!r}; it rests but is not time-optimal to "
                      f"{T / grid.T - 1:.2g}", RuntimeWarning, stacklevel=3)
    if residual > tolerance:
        # Closely spaced modes (the ten pendula) can call for pulses shorter than the grid resolves;
        # the refined move then misses the target by ``residual``, which the solution reports.
        warnings.warn(f"time_optimal: the {len(switches)}-switch structure found by the transcription leaves a "
                      f"final-state residual of {residual:.3g} > {tolerance:g} on plant {plant.name!r}; "
                      "the move is not exactly rest-to-rest", RuntimeWarning, stacklevel=3)
    return TimeOptimalSolution(
        T=float(T), switch_times=tuple(map(float, switches)), levels=tuple(map(float, levels)), t=t, u=command(t),
        x=x, distance=distance, u_max=u_max, u_final=u_f, final_error=tuple(map(float, error)), residual=residual,
        states=plant.states, transcription_T=grid.T,
    )
