"""The figure of a comparison: every candidate's command, position error and deflection."""

from __future__ import annotations

from pathlib import Path

from shapefmu.files import save_figure


def plot_compare(comparison, path) -> Path:
    """u(t), the position error and the deflections of every candidate of ``comparison`` (a
    :class:`~shapefmu.compare.Comparison`), from its move's start, as a PNG at ``path``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, axes = plt.subplots(3, 1, sharex=True, figsize=(9, 8))
    for run in comparison.runs:
        r = run.results
        moving = r["time"] >= run.start - 1e-12
        ms = 1e3 * (r["time"][moving] - run.start)
        axes[0].step(ms, r[comparison.command][moving], where="pre", lw=0.8, label=run.name)
        axes[1].plot(ms, r["plant.position"][moving] - comparison.distance, lw=0.8, label=run.name)
        axes[2].plot(ms, r["plant.deflection_1"][moving], lw=0.8, label=run.name)
    axes[0].set_ylabel("command u")
    axes[1].set_ylabel("position - target")
    axes[2].set_ylabel("deflection_1")
    axes[2].set_xlabel("time from the move's start [ms]")
    axes[0].legend(fontsize="small", ncol=3)
    axes[0].set_title(f"{comparison.plant}: move of {comparison.distance:g}, FMUs at {comparison.step:g} s")
    figure.tight_layout()
    try:
        return save_figure(figure, path)
    finally:
        plt.close(figure)
