"""Robustness sweeps: one run per parameter point, mapped over a Dask cluster, one row per run.

The experiments layer: may import ``shapefmu.cosim``, ``shapefmu.fmi``, ``shapefmu.analysis``,
``shapefmu.runtime``, ``shapefmu.plots`` and the design layer; never ``shapefmu.cli``.
"""

# Each module imports only modules listed before it: store, analytic, points, metrics, target (the
# co-simulation target, its worker plugin and the masters a worker keeps open), runs (a batch of runs
# on a worker), driver (sweep() and its Dask client), report (the map and the summary).
from shapefmu.sweep.driver import SweepRows, check_workers, sweep
from shapefmu.sweep.metrics import NAMED_METRICS, Metric, move_end, move_time, named_metrics, peak, residual
from shapefmu.sweep.points import Points, grid, parse_range, parse_vary, random_samples
from shapefmu.sweep.report import plot_map, summary
from shapefmu.sweep.runs import RunTimeout
from shapefmu.sweep.store import FIXED_COLUMNS, STATUSES, Store, as_array, columns, metric_names_in_file, read_rows
from shapefmu.sweep.target import Cosim, cosim

__all__ = [
    "FIXED_COLUMNS", "NAMED_METRICS", "STATUSES", "Cosim", "Metric", "Points", "RunTimeout", "Store", "SweepRows",
    "as_array",
    "check_workers", "columns", "cosim", "grid", "metric_names_in_file", "move_end", "move_time", "named_metrics", "parse_range",
    "parse_vary", "peak", "plot_map", "random_samples", "read_rows", "residual", "summary", "sweep",
]
