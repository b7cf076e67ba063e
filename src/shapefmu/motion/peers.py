"""Ruckig (pip ``ruckig``, MIT) beside the planner: a test and benchmark peer, never a dependency.

``ruckig_move`` plans the same rigid move with Ruckig's own code, so that a command, a test or a
benchmark can set both side by side; without ``ruckig`` installed it returns (None, 0.0).
"""

from __future__ import annotations

import time


def ruckig_move(states, targets, limits, straight=False):
    """(Ruckig's trajectory or None where it reports an error, seconds its ``calculate`` took) from
    ``states`` to ``targets`` [(p, v, a)] within ``limits`` (``AxisLimits`` or runtime ``Limits``)."""
    try:
        from ruckig import InputParameter, Result, Ruckig, Synchronization, Trajectory
    except ImportError:
        return None, 0.0
    n = len(states)
    generator, request, trajectory = Ruckig(n), InputParameter(n), Trajectory(n)
    request.current_position = [s[0] for s in states]
    request.current_velocity = [s[1] for s in states]
    request.current_acceleration = [s[2] for s in states]
    request.target_position = [t[0] for t in targets]
    request.target_velocity = [t[1] for t in targets]
    request.target_acceleration = [t[2] for t in targets]
    request.max_velocity = [lim.v_max for lim in limits]
    request.max_acceleration = [lim.a_max for lim in limits]
    request.max_jerk = [lim.j_max for lim in limits]
    request.min_velocity = [-lim.v_max if lim.v_min is None else lim.v_min for lim in limits]
    request.min_acceleration = [-lim.a_max if lim.a_min is None else lim.a_min for lim in limits]
    if straight:
        request.synchronization = Synchronization.Phase
    started = time.perf_counter()
    result = generator.calculate(request, trajectory)
    elapsed = time.perf_counter() - started
    return (trajectory if result in (Result.Working, Result.Finished) else None), elapsed


def ruckig_duration(states, targets, limits, straight=False):
    """Ruckig's synchronised duration, or None (no ``ruckig``, or an error it reports)."""
    trajectory, _ = ruckig_move(states, targets, limits, straight)
    return None if trajectory is None else trajectory.duration
