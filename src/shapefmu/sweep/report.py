"""A sweep's rows reported: the robustness map (a PNG) and a text summary."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from shapefmu.sweep.store import FIXED_COLUMNS, STATUSES


def plot_map(rows: np.ndarray, metric: str, path, x: str, y: str | None = None) -> Path:
    """Plot ``metric`` against the parameter ``x`` (and ``y``) of a sweep's rows; save it as PNG.

    Points sharing (x, y) but differing in other parameters show their worst (largest) value: the
    map answers "how bad can it get here". Two parameters on a full grid give a colour map, scattered
    samples a coloured scatter; points with a run that is not "ok" are marked with a red x.
    """
    available = [n for n in rows.dtype.names if n not in FIXED_COLUMNS]
    for name, what in ((metric, "metric"), (x, "x"), (y, "y")):
        if name is not None and name not in available:
            raise ValueError(f"{what} must be one of the sweep's columns {available}, got {name!r}")
    from shapefmu.plots import plt, save_figure  # pyplot as shapefmu.plots set it up: the Agg backend

    axes = [a for a in (x, y) if a is not None]
    ok = rows["status"] == "ok"
    keys = np.stack([rows[a] for a in axes], axis=1)
    unique, inverse = np.unique(keys, axis=0, return_inverse=True)
    inverse = inverse.ravel()
    worst = np.full(len(unique), -np.inf)
    np.maximum.at(worst, inverse[ok], rows[metric][ok])
    worst[np.isinf(worst)] = np.nan
    failed = np.zeros(len(unique), dtype=bool)
    failed[inverse[~ok]] = True
    fig, ax = plt.subplots(figsize=(7, 4.6))
    if y is None:
        ax.plot(unique[:, 0], worst, marker=".")
        ax.set_ylabel(metric)
        marks = np.zeros(int(failed.sum()))
    else:
        xs, ys = np.unique(unique[:, 0]), np.unique(unique[:, 1])
        if xs.size * ys.size == len(unique) and xs.size > 1 and ys.size > 1:
            image = ax.pcolormesh(xs, ys, worst.reshape(xs.size, ys.size).T, shading="nearest")
        else:
            image = ax.scatter(unique[:, 0], unique[:, 1], c=worst, s=16)
        fig.colorbar(image, ax=ax, label=metric)
        ax.set_ylabel(y)
        marks = unique[failed, 1]
    if np.any(failed):
        ax.plot(unique[failed, 0], marks, "rx", label="run not ok")
        ax.legend()
    ax.set_xlabel(x)
    ax.set_title(f"{metric}: worst over {len(rows)} runs")
    return save_figure(fig, path)


def summary(rows: np.ndarray, metrics: Sequence[str]) -> str:
    """Counts per status and the range of each metric over the "ok" runs."""
    counts = ", ".join(f"{int(np.sum(rows['status'] == s))} {s}" for s in STATUSES if np.any(rows["status"] == s))
    lines = [f"{len(rows)} runs: {counts}"]
    resumed = getattr(rows, "resumed", 0)  # a SweepRows from sweep(); a plain array has no such count
    if resumed:
        failed = getattr(rows, "resumed_failed", 0)
        retry = f"; {failed} of those are errors or timeouts: --retry-failed runs them again" if failed else ""
        lines.append(f"{resumed} of them resumed from the output file, not run again{retry}")
    ok = rows[rows["status"] == "ok"]
    for name in metrics:
        if ok.size:
            worst = ok[np.argmax(ok[name])]
            at = ", ".join(f"{n} = {worst[n]:.6g}" for n in rows.dtype.names
                           if n not in FIXED_COLUMNS and n not in metrics)
            lines.append(f"{name}: min {ok[name].min():.6g}, max {ok[name].max():.6g} (at {at})")
    failed = rows[rows["status"] != "ok"]
    for row in failed[:5]:
        lines.append(f"run {row['run']}: {row['status']}: {row['error']}")
    if failed.size > 5:
        lines.append(f"... and {failed.size - 5} more runs not ok")
    return "\n".join(lines)
