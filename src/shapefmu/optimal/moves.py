"""Piecewise-constant commands, their exact simulation, the rest state a move ends in, and the
vibration left after a move."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.linalg import expm, matrix_balance

from shapefmu.plants import Plant, as_plant
from shapefmu.runtime.checks import check_positive


# ---------------------------------------------------------------------------------------------
# Piecewise-constant commands and their exact simulation


@dataclass(frozen=True)
class Command:
    """A piecewise-constant input: ``levels[k]`` on [breaks[k], breaks[k+1]), then ``final`` for
    t >= breaks[-1] (0 for a plant with a rigid body, the holding input otherwise).

    Examples
    --------
    >>> bang_bang = Command((0.0, 1.0, 2.0), (1.0, -1.0))
    >>> bang_bang.duration, bang_bang.peak, bang_bang([0.5, 1.0, 3.0]).tolist()  # right-continuous
    (2.0, 1.0, [1.0, -1.0, 0.0])
    """

    breaks: tuple[float, ...]
    levels: tuple[float, ...]
    final: float = 0.0

    def __post_init__(self):
        if len(self.breaks) != len(self.levels) + 1 or not self.levels:
            raise ValueError(f"a command needs len(breaks) == len(levels) + 1 >= 2, got {len(self.breaks)} "
                             f"and {len(self.levels)}")
        if any(b < a for a, b in zip(self.breaks, self.breaks[1:])):
            raise ValueError(f"breaks must be non-decreasing, got {self.breaks}")

    @property
    def duration(self) -> float:
        return self.breaks[-1] - self.breaks[0]

    @property
    def peak(self) -> float:
        return max(abs(v) for v in self.levels)

    def __call__(self, t) -> np.ndarray:
        """u(t), right-continuous at the breaks."""
        t = np.asarray(t, dtype=float)
        index = np.searchsorted(self.breaks, t, side="right") - 1
        values = np.append(self.levels, self.final)
        u = np.where(index < 0, 0.0, values[np.clip(index, 0, len(self.levels))])
        return u

    def shaped(self, shaper) -> Command:
        """The command convolved with impulses A_i at t_i: sum_i A_i u(t - t_i), exactly.

        The result is piecewise constant again with breaks at every break + t_i (paper 002,
        eq. 4 for the four-impulse convolution shaper and eq. 21 for the three-impulse one).
        """
        times = np.asarray(shaper.times, dtype=float)
        amplitudes = np.asarray(shaper.amplitudes, dtype=float)
        breaks = np.unique((np.asarray(self.breaks)[:, None] + times).ravel())
        # Merge breaks closer than 1e-12 of the duration: sums of delays coincide in exact arithmetic.
        tol = 1e-12 * max(breaks[-1] - breaks[0], 1e-300)
        merged = [breaks[0]]
        for b in breaks[1:]:
            if b - merged[-1] > tol:
                merged.append(b)
        merged = np.array(merged)
        mid = 0.5 * (merged[:-1] + merged[1:])
        levels = sum(a * self(mid - ti) for ti, a in zip(times, amplitudes))
        final = self.final * float(amplitudes.sum())
        return Command(tuple(map(float, merged)), tuple(map(float, levels)), final)


def _augmented_expm(A, B, tau):
    """(e^{A tau}, integral_0^tau e^{A s} ds B) from one expm of [[A, B], [0, 0]] tau."""
    n, m = B.shape
    M = np.zeros((n + m, n + m))
    M[:n, :n] = A
    M[:n, n:] = B
    E = expm(M * tau)
    return E[:n, :n], E[:n, n:]


def simulate(plant, command: Command, t=None, x0=None):
    """States of the plant under a piecewise-constant command, exact (no sampling of the input).

    Returns the states at the command's breaks (shape (len(breaks), n)), and, if ``t`` is given
    (sorted, >= the first break), also at the times ``t`` (shape (len(t), n)). The single input is
    the plant's first input; after the last break it is ``command.final``.

    Examples
    --------
    >>> from shapefmu.plants.library import rigid_flexible
    >>> plant = rigid_flexible(1.0, u_max=1.0)  # x'' = u, |u| <= 1: T = 2 sqrt(X / (b U)) = 2 for X = 1
    >>> simulate(plant, Command((0.0, 1.0, 2.0), (1.0, -1.0)))[-1].tolist()  # at rest at x = 1
    [1.0, 0.0]
    """
    plant = as_plant(plant)
    A, B = plant.A, plant.B[:, :1]
    x = np.zeros(plant.n_states) if x0 is None else np.asarray(x0, dtype=float)
    at_breaks = [x]
    for k, level in enumerate(command.levels):
        E, G = _augmented_expm(A, B, command.breaks[k + 1] - command.breaks[k])
        x = E @ x + G[:, 0] * level
        at_breaks.append(x)
    at_breaks = np.array(at_breaks)
    if t is None:
        return at_breaks
    t = np.asarray(t, dtype=float)
    if t.ndim != 1 or np.any(np.diff(t) < 0) or (t.size and t[0] < command.breaks[0]):
        raise ValueError(f"t must be a sorted 1-D array starting at or after {command.breaks[0]!r}")
    # Step through the union of t and the breaks, so that the input is constant on every step;
    # a uniform t repeats one step length, whose matrix exponential is computed once (the step
    # lengths are keyed to 12 significant digits, the accuracy of these sampled states).
    grid = np.union1d(t, command.breaks)
    values = command(grid[:-1])
    states = [at_breaks[0]]
    cache = {}
    for dt, level in zip(np.diff(grid), values):
        key = float(f"{dt:.12e}")
        if key not in cache:
            cache[key] = _augmented_expm(A, B, dt)
        E, G = cache[key]
        states.append(E @ states[-1] + G[:, 0] * level)
    return at_breaks, np.array(states)[np.searchsorted(grid, t)]

# ---------------------------------------------------------------------------------------------
# The problem: target rest state, checks, scaling


def _single_input(plant: Plant) -> None:
    if plant.B.shape[1] != 1:
        raise ValueError(f"plant {plant.name!r} has {plant.B.shape[1]} inputs; time_optimal needs exactly one")


def _u_max(plant: Plant, u_max) -> float:
    if u_max is None:
        if plant.inputs[0] not in plant.limits:
            raise ValueError(f"u_max not given and plant {plant.name!r} declares no limit for input {plant.inputs[0]!r}")
        u_max = plant.limits[plant.inputs[0]]
    return check_positive(u_max, "u_max")


def _output_index(plant: Plant, output) -> int:
    if isinstance(output, str):
        if output not in plant.outputs:
            raise ValueError(f"output must be one of {plant.outputs}, got {output!r}")
        return plant.outputs.index(output)
    if not (isinstance(output, int) and 0 <= output < len(plant.outputs)):
        raise ValueError(f"output must be an index in [0, {len(plant.outputs)}) or a name, got {output!r}")
    return output


def rest_state(plant: Plant, distance: float, output=0) -> tuple[np.ndarray, float]:
    """The equilibrium (x_f, u_f) with A x_f + B u_f = 0 and output y = distance.

    For a plant with a rigid body u_f = 0; for a plant without an integrator (the closed-loop LSM
    of paper 001, eq. 33) the input has to be held at u_f = distance / G(0) after the move.
    Raises ValueError if no such rest state exists or it is not unique.

    Examples
    --------
    >>> from shapefmu.plants.library import rigid_flexible
    >>> plant = rigid_flexible(1.0, u_max=1.0)  # x'' = u, |u| <= 1: T = 2 sqrt(X / (b U)) = 2 for X = 1
    >>> x_f, u_f = rest_state(plant, 1.0)
    >>> x_f.tolist(), u_f
    ([1.0, 0.0], 0.0)
    """
    j = _output_index(plant, output)
    n = plant.n_states
    M = np.block([[plant.A, plant.B[:, :1]], [plant.C[j : j + 1], plant.D[j : j + 1, :1]]])
    rhs = np.zeros(n + 1)
    rhs[-1] = distance
    if np.linalg.cond(M) > 1e12:
        raise ValueError(
            f"unreachable target: plant {plant.name!r} has no unique rest state with output {plant.outputs[j]!r} = "
            f"{distance:g} (the matrix [[A, B], [C, D]] is singular: a zero at s = 0, or an output that does not "
            "settle at rest)"
        )
    z = np.linalg.solve(M, rhs)
    return z[:n], float(z[n])


def check_controllable(plant: Plant) -> None:
    """PBH test: rank [A - lambda I, B] = n at every eigenvalue, else ValueError naming the mode.

    Examples
    --------
    >>> from shapefmu.plants.library import rigid_flexible
    >>> check_controllable(rigid_flexible(1.0, [(1.0, 0.0, 0.0)]))  # b4 = 0: the mode is not driven
    Traceback (most recent call last):
    ...
    ValueError: plant 'rigid_flexible' is not controllable: the mode at s = 0+1j cannot be moved by input 'u', so a rest-to-rest move cannot be planned
    """
    # Balance first (diagonal similarity): companion forms with entries from 1 to 1e8 would
    # otherwise make a controllable mode look uncontrollable at any fixed tolerance.
    _, (d, _) = matrix_balance(plant.A, permute=False, separate=True)
    A = plant.A * d[None, :] / d[:, None]
    B = plant.B[:, :1] / d[:, None]
    n = plant.n_states
    scale = max(np.linalg.norm(A, 2), np.linalg.norm(B), 1e-300)
    for lam in np.linalg.eigvals(A):
        s = np.linalg.svd(np.hstack([A - lam * np.eye(n), B]), compute_uv=False)
        if s[-1] <= 1e-10 * scale:
            raise ValueError(
                f"plant {plant.name!r} is not controllable: the mode at s = {lam:.6g} cannot be moved by input "
                f"{plant.inputs[0]!r}, so a rest-to-rest move cannot be planned"
            )


# ---------------------------------------------------------------------------------------------
# Vibration left after a move


def residual_after_move(plant, command: Command, distance: float, output=0) -> float:
    """Vibration left after a move, relative to the distance.

    The largest |y_j(t) - y_j,f| over every output j and t from the end of the command through one
    period of the slowest oscillatory mode (the free response from the exact final state is
    evaluated at 400 points of that window), divided by |distance|. A move that ends exactly at
    rest has residual 0.

    Examples
    --------
    >>> import math
    >>> from shapefmu.plants.library import rigid_flexible
    >>> plant = rigid_flexible(1.0, [(2 * math.pi * 0.75, 0.0, -1.0)], u_max=1.0)  # a rigid body and a 0.75 Hz mode
    >>> bang_bang = Command((0.0, 1.0, 2.0), (1.0, -1.0))  # the rigid body's own: 1.5 periods of the mode
    >>> f"{residual_after_move(plant, bang_bang, 1.0):.3e}"
    '9.006e-02'
    """
    plant = as_plant(plant)
    x_f, _ = rest_state(plant, distance, output)
    x_end = simulate(plant, command)[-1]
    oscillatory = [m.omega for m in plant.modes() if m.oscillatory]
    window = 2.0 * math.pi / min(oscillatory) if oscillatory else 0.0
    error = x_end - x_f
    step = expm(plant.A * (window / 399))
    peak = 0.0
    for _ in range(400):
        peak = max(peak, float(np.max(np.abs(plant.C @ error))))
        error = step @ error
    return peak / abs(distance)
