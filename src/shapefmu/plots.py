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
    """What a person reads off a recommendation: the spectrum Klipper judges (left axis) with the
    identified modes marked and what the pick and Klipper's pick leave of it, and on the right axis the
    share each leaves at every frequency (worst over the test dampings) with at most three other
    candidates; the legend sits below the axes, off the data."""
    from shapefmu.identification.recommend import remaining_curve

    pick, klipper = advice.pick, advice.klipper_pick
    others = [c for c in advice.candidates if not (c.same(pick) or c.same(klipper))][:3]
    top = min(advice.max_freq, max(s.freq[-1] for s in spectra))
    fig, ax = plt.subplots(figsize=(10, 7))
    worst = None
    for s in spectra:
        keep = s.freq <= top
        ax.plot(s.freq[keep], s.psd[keep], color="k", lw=1.4, label=f"spectrum {Path(s.source).name} ({s.axis})")
        worst = s if worst is None or s.psd.max() > worst.psd.max() else worst
    keep = worst.freq <= top
    for c, style in ((klipper, dict(color="tab:blue", ls="--")), (pick, dict(color="tab:red", ls="-"))):
        after = worst.psd[keep] * remaining_curve(c, worst.freq[keep], advice.dampings)
        ax.plot(worst.freq[keep], after, lw=1.2, alpha=0.8, **style, label=f"left by {_name(c)}")
    for m in advice.modes:
        ax.axvline(m.frequency, color="0.5", ls=":", lw=1)
        ax.annotate(f"{m.frequency:.1f} Hz", (m.frequency, 1.0), xycoords=("data", "axes fraction"), fontsize=8,
                    rotation=90, va="top", ha="right", color="0.3")
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel("power spectral density (as Klipper judges it)")
    ax.set_xlim(0, top)
    ax.set_ylim(bottom=0)
    right = ax.twinx()
    freq = np.linspace(0.5, top, 2000)
    for c in others:
        right.plot(freq, remaining_curve(c, freq, advice.dampings), lw=0.8, alpha=0.6, label=_described(c))
    right.plot(freq, remaining_curve(klipper, freq, advice.dampings), color="tab:blue", ls="--", lw=2,
               label=_described(klipper) + " (Klipper's pick)")
    right.plot(freq, remaining_curve(pick, freq, advice.dampings), color="tab:red", lw=2.4,
               label=_described(pick) + f" (pick, {advice.firmware})")
    right.set_ylabel("share of the vibration left (worst over damping)")
    right.set_ylim(0, 1.05)
    handles = [h for a in (ax, right) for h in a.get_legend_handles_labels()[0]]
    labels = [t for a in (ax, right) for t in a.get_legend_handles_labels()[1]]
    # below the x axis: tight_layout makes room for it, and no curve runs under it
    right.legend(handles, labels, loc="upper center", bbox_to_anchor=(0.5, -0.09), ncol=2, fontsize=8, frameon=False)
    ax.set_title(f"{advice.firmware} pick: {_name(pick)}; {advice.verdict}")
    return save_figure(fig, path)


def _name(candidate) -> str:
    freqs = "/".join(f"{f:.1f}" for f in candidate.frequencies)
    return f"{candidate.label} {freqs} Hz" if freqs else f"{candidate.label} ({len(candidate.times)} impulses)"


def _described(candidate) -> str:
    return (f"{_name(candidate)}: vibration {100 * candidate.vibration:.2f} %, max accel {candidate.max_accel:.0f}, "
            f"score {candidate.score:.2e}")
