"""Plots people look at: sensitivity curves and shaped commands (matplotlib, Agg backend)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (the backend must be chosen first)
import numpy as np  # noqa: E402

from shapefmu.analysis import SensitivityCurve  # noqa: E402


def plot_sensitivity(curves: Sequence[tuple[str, SensitivityCurve]], path, vtol: float | None = None) -> Path:
    """Residual vibration against q = omega_actual/omega_model, one line per labelled curve."""
    fig, ax = plt.subplots(figsize=(7, 4.2))
    for label, curve in curves:
        scale = 100.0 if curve.definition == "percent" else 1.0
        ax.plot(curve.q, scale * curve.residual, label=label)
    if vtol is not None:
        ax.axhline(100.0 * vtol, color="0.4", lw=0.8, ls="--", label=f"vtol = {100 * vtol:g} %")
    ax.set_xlabel(r"$q = \omega_{actual} / \omega_{model}$")
    definition = curves[0][1].definition if curves else "percent"
    ax.set_ylabel("residual vibration [%]" if definition == "percent" else "residual vibration amplitude")
    ax.set_ylim(bottom=0.0)
    ax.grid(alpha=0.3)
    ax.legend()
    return save_figure(fig, path)


def plot_shaped_command(t, u, shaped: dict[str, np.ndarray], path, ylabel: str = "command") -> Path:
    """An unshaped command and its shaped versions on one time axis."""
    fig, ax = plt.subplots(figsize=(7, 4.2))
    ax.plot(t, u, color="0.5", lw=1.0, label="unshaped")
    for label, y in shaped.items():
        ax.plot(t, y, label=label)
    ax.set_xlabel("time [s]")
    ax.set_ylabel(ylabel)
    ax.grid(alpha=0.3)
    ax.legend()
    return save_figure(fig, path)


def save_figure(fig, path) -> Path:
    """Write ``fig`` to ``path`` (its folder created), close it, and return the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def plot_motion_profile(profile, path, title: str = "") -> Path:
    """Acceleration, velocity and position of a rest-to-rest profile on a shared time axis."""
    fig, axes = plt.subplots(3, 1, figsize=(7, 6), sharex=True)
    for ax, values, label in zip(
        axes,
        (profile.acceleration, profile.velocity, profile.position),
        ("acceleration", "velocity", "position"),
    ):
        ax.plot(profile.t[: len(values)], values)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[0].set_title(title)
    axes[-1].set_xlabel("time [s]")
    return save_figure(fig, path)
