"""Plots people look at: sensitivity curves and shaped commands (matplotlib, Agg backend)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (the backend must be chosen first)
import numpy as np  # noqa: E402

from shapefmu import files  # noqa: E402

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
    """Write ``fig`` to ``path`` (``shapefmu.files``: checked, whole), close it, and return the path."""
    fig.tight_layout()
    try:
        return files.save_figure(fig, path, dpi=120)
    finally:
        plt.close(fig)


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


def plot_identified(found, path) -> Path:
    """The spectrum of each identified recording with its modes marked."""
    fig, ax = plt.subplots(figsize=(9, 5))
    for item in found:
        s = item.spectrum
        line, = ax.semilogy(s.freq, s.psd, lw=1, label=f"{Path(s.source).name} ({s.axis})")
        for mode in item.modes.modes:
            ax.axvline(mode.frequency, color=line.get_color(), ls=":", lw=1)
            ax.annotate(f"{mode.frequency:.1f} Hz\nzeta {mode.zeta:.3f}", (mode.frequency, mode.peak), fontsize=8,
                        xytext=(4, 0), textcoords="offset points")
    top = max(max((m.frequency for m in i.modes.modes), default=i.spectrum.freq[-1] / 3) for i in found)
    ax.set_xlim(0, min(3 * top, max(i.spectrum.freq[-1] for i in found)))
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel("power spectral density")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    return save_figure(fig, path)


def plot_recommendation(spectra, advice, path) -> Path:
    """The measured spectra (left axis) and every candidate's remaining-vibration curve V(f) (right
    axis, worst over the damping range): the pick and the best of Klipper's six drawn bold."""
    from shapefmu.identification.recommend import remaining_curve

    fig, ax = plt.subplots(figsize=(10, 6))
    top = 2.5 * max(m.frequency for m in advice.modes) if advice.modes else spectra[0].freq[-1]
    for s in spectra:
        keep = s.freq <= top
        ax.plot(s.freq[keep], s.psd[keep], color="k", lw=1.2, label=f"spectrum {Path(s.source).name} ({s.axis})")
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel("power spectral density")
    ax.set_xlim(0, top)
    right = ax.twinx()
    freq = np.linspace(0.5, top, 2000)
    for c in advice.candidates:
        bold = c is advice.pick or c is advice.baseline
        label = f"{c.label} {'/'.join(f'{f:.1f}' for f in c.frequencies)} Hz: {100 * c.vibration:.1f} %, " \
                f"{c.max_accel:.0f} mm/s^2" + (" (pick)" if c is advice.pick else "") + \
                (" (best of Klipper's six)" if c is advice.baseline else "")
        right.plot(freq, remaining_curve(c, freq, advice.dampings), lw=2.2 if bold else 0.7,
                   alpha=1.0 if bold else 0.5, label=label)
    right.set_ylabel("vibration left by the shaper (worst over damping)")
    right.set_ylim(0, 1.05)
    lines = ax.get_legend_handles_labels()
    more = right.get_legend_handles_labels()
    right.legend(lines[0] + more[0], lines[1] + more[1], fontsize=6, loc="upper right", ncol=2)
    ax.set_title(f"pick: {advice.pick.label}; vibration bound {100 * advice.bound:.2f} %")
    return save_figure(fig, path)
