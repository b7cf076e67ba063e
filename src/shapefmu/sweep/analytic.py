"""The analytic path of a sweep: closed forms of the design layer, vectorised over all points.

Each factory returns ``func({parameter: array}) -> {metric: array}`` for
``sweep(func, points, vectorized=True)``, the counterpart of a co-simulation sweep of the same
system where a closed form exists.
"""

from __future__ import annotations

import numpy as np

from shapefmu.analysis import residual_vibration
from shapefmu.runtime.checks import check_positive

# Points per chunk: bounds the (points x pendula x window) complex array to ~50 MB.
_CHUNK = 256


def shaper_residual(shaper, *, omega: str = "plant.wn", zeta: str = "plant.zeta", definition: str = "percent",
                    name: str = "residual"):
    """Residual vibration of ``shaper`` on a mode (omega, zeta) taken from the sweep's parameters
    (paper 000, eq. 4 / 5 via ``analysis.residual_vibration``, vectorised over omega for each zeta)."""

    def evaluate(parameters):
        w = np.asarray(parameters[omega], dtype=float)
        z = np.asarray(parameters[zeta], dtype=float)
        result = np.empty_like(w)
        for value in np.unique(z):
            chosen = z == value
            result[chosen] = residual_vibration(shaper, w[chosen], float(value), definition)
        return {name: result}

    return evaluate


def pendula_swing(acceleration, ts: float, lengths, stop_time: float, *, g: str = "plant.g",
                  zeta: str = "plant.zeta", name: str = "residual"):
    """Largest swing |theta_j(t)| of pendula on a cart after a sampled move, for every (g, zeta).

    The cart acceleration ``a[k]`` is held on [k ts, (k+1) ts); each pendulum of length L obeys
    L theta'' + 2 zeta omega L theta' + g theta = -a with omega^2 = g / L (``plants.pendula``).
    With the pole p = -zeta omega + j omega sqrt(1 - zeta^2) and its modal coordinate z
    (theta = 2 Re z), the exact zero-order-hold response after the last non-zero sample N - 1 is

        z(N ts) = (e^{p ts} - 1) / p * 1 / (L (p* - p)) * sum_k a[k] e^{p (N - 1 - k) ts},
        theta(N ts + tau) = 2 Re(z(N ts) e^{p tau}),

    evaluated at the sample times N ts, (N + 1) ts, ... up to ``stop_time``: the window in which a
    co-simulation recording every ``ts`` finds its residual (``sweep.residual(command=...)``).
    """
    ts = check_positive(ts, "ts")
    a = np.asarray(acceleration, dtype=float).ravel()
    moving = np.flatnonzero(a)
    if moving.size == 0:
        raise ValueError("acceleration must have a non-zero sample: there is no move")
    a = a[: moving[-1] + 1]
    n_move = a.size
    n_stop = int(round(check_positive(stop_time, "stop_time") / ts))
    if n_stop <= n_move:
        raise ValueError(f"stop_time must be after the move's end {n_move * ts:g} s, got {stop_time!r}")
    tau = np.arange(n_stop - n_move + 1) * ts
    lengths = np.array([check_positive(length, f"lengths[{i}]") for i, length in enumerate(lengths)])

    def evaluate(parameters):
        gravity = np.asarray(parameters[g], dtype=float)
        damping = np.asarray(parameters[zeta], dtype=float)
        if np.any(gravity <= 0) or np.any(damping < 0) or np.any(damping >= 1):
            raise ValueError(f"{g} must be > 0 and {zeta} in [0, 1) at every point")
        swing = np.empty(gravity.shape)
        for start in range(0, gravity.size, _CHUNK):
            part = slice(start, start + _CHUNK)
            omega = np.sqrt(gravity[part, None] / lengths)
            z = damping[part, None]
            p = omega * (-z + 1j * np.sqrt(1.0 - z * z))
            decay = np.exp(p * ts)
            total = np.zeros_like(p)
            for value in a:  # Horner: sum_k a[k] decay^(N-1-k), |decay| <= 1 keeps it stable
                total = total * decay + value
            modal = (decay - 1.0) / p / (lengths * (np.conj(p) - p)) * total
            theta = 2.0 * np.real(modal[..., None] * np.exp(p[..., None] * tau))
            swing[part] = np.max(np.abs(theta), axis=(1, 2))
        return {name: swing}

    return evaluate
