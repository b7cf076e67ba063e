"""``shapefmu compare``: one plant, every candidate command, run as SSP systems of FMUs by the master.

``compare(plant_model, distance, candidates=..., step=...)`` builds (or finds in a cache folder) the
FMUs, composes one SSP system per candidate with the :class:`~shapefmu.fmi.ssp.System` API, runs
each with :class:`~shapefmu.cosim.Master` (Gauss-Seidel, macro step ``step``) and measures the
recorded runs with one rule for all (:func:`move_metrics`). The candidates:

* ``bang-bang``: the rigid-body time-optimal bang-bang (paper 002, eq. 2; ``optimal.rigid_bang_bang``)
  played by a ReferencePlayer FMU straight into the plant;
* ``convolution`` / ``simultaneous``: the same bang-bang through a Shaper FMU, ZV per mode convolved
  (paper 002, Sec. II-A) or all modes at once (eq. 20);
* ``stos-convolution`` / ``stos-simultaneous``: the STOSController FMU in closed loop with the plant
  (paper 002, eqs. 7-22), its law built from the convolution or the simultaneous shaper, with the
  settle controller of ``stos.stos_law`` for the sampling period ``step``;
* ``ekf-tuned``: an EKFTuner FMU (paper 001) watches the first deflection during an identification
  move (the same bang-bang, unshaped), designs a ZVD shaper for the mode it estimates and shapes the
  next move, which is the one measured (its results hold that move alone: the identification
  move's response, run separately, is subtracted, which superposition allows on a linear plant);
* ``time-optimal``: the CasADi time-optimal input of the full plant (``optimal.time_optimal``)
  played by a ReferencePlayer FMU with its exact switch instants.

Sampling. Every FMU steps by ``step``. The players hand the plant ``y_mean``, the exact mean of the
command over the step: the plant's zero-order hold then receives the same impulse as under the
exact command, so an off-grid switch costs O(step^2), not O(step). In the Gauss-Seidel order
(player, shaper or controller, plant) each consumer sees its producer's value for the step it is
about to take; the shaper's and the controller's feed-through outputs are passed on as read at the
communication point (see :mod:`shapefmu.cosim.master`), so the shaped command is exactly the design
layer's ``ImpulseShaper.on_grid(step)`` filter and the STOS loop is ``stos.simulate_stos``'s.

The plant FMU is the plant with its rigid-body velocity as an extra output (:func:`measured_plant`),
which STOS needs; the same FMU drives every candidate, so they all meet the same plant.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np

from shapefmu.compare.cache import FMUCache
from shapefmu.compare.metrics import MoveMetrics, move_metrics
from shapefmu.compare.plot import plot_compare
from shapefmu.compare.systems import (SHAPER_KINDS, baked_in, ekf_tuned_moves, ekf_tuned_system, mode_arrays, modes_hz,
                                      signal_table, stos_system)
from shapefmu.runtime.checks import check_finite, check_positive, check_size

CANDIDATES = ("bang-bang", "convolution", "simultaneous", "stos-convolution", "stos-simultaneous", "ekf-tuned",
              "time-optimal")


@dataclasses.dataclass(frozen=True)
class CandidateRun:
    """One candidate: its metrics, the ratio of its move time to the time-optimal one, the recorded
    run (``results``, a structured array with the time, the plant's input as the plant held it over
    the step just taken, ``Comparison.command``, and the plant's outputs; the EKF-tuned run also
    ``tuner.omega_est``, ``tuner.zeta_est`` and ``tuner.converged``), and when the measured move
    starts (``start``; the EKF-tuned move follows its identification move)."""

    name: str
    metrics: MoveMetrics
    ratio: float
    results: np.ndarray
    start: float


@dataclasses.dataclass(frozen=True)
class Comparison:
    plant: str
    distance: float
    u_max: float
    step: float
    optimal_time: float
    runs: tuple[CandidateRun, ...]
    command: str  # the plant input recorded in every run
    written: tuple[Path, ...] = ()  # each candidate's system, where compare(write_ssp=...) wrote it

    def run(self, name: str) -> CandidateRun:
        for run in self.runs:
            if run.name == name:
                return run
        raise ValueError(f"name must be one of {[r.name for r in self.runs]}, got {name!r}")

    def table(self) -> str:
        width = max(len(r.name) for r in self.runs)
        lines = [f"plant {self.plant}: move of {self.distance:g} with |u| <= {self.u_max:g}, FMUs stepped by {self.step:g} s "
                 f"(time-optimal T = {self.optimal_time:.8g} s)",
                 f"{'candidate':<{width}} {'move time [s]':>14} {'residual':>11} {'peak |u|':>10} {'vs optimal':>11}"]
        for r in self.runs:
            m = r.metrics
            lines.append(f"{r.name:<{width}} {m.move_time:14.8g} {m.residual:11.3e} {m.peak:10.4g} {r.ratio:11.5f}")
        return "\n".join(lines)


def compare(plant_model, distance: float, candidates=CANDIDATES, step: float = 1e-6, *, cache="fmus",
            u_max: float | None = None, tolerance: float = 1e-3, stop_time: float | None = None,
            plot=None, write_ssp=None, target: str | None = None, native: bool = False,
            fmi_version: str = "2.0", progress=None) -> Comparison:
    """Run the plant with each candidate command as an SSP system of FMUs; see the module docstring.

    ``plant_model``: a model file or Plant of paper 002's eq. (1) form (a rigid body and 1-4 modes).
    ``distance``: the move X of the rigid body. ``step``: macro step and every FMU's sampling period.
    ``cache``: folder of the FMUs (``FMUCache``). ``tolerance``: the settling band of the move time,
    relative to |X| and U. ``stop_time``: length of each run (default: the slowest open-loop move,
    a quarter more, and two periods of the slowest mode). ``plot``: a PNG path for u(t), x_r(t) and
    the deflections of every candidate. ``write_ssp``: a path ``dir/name.ssp`` (or ``.ssd``); each
    candidate's system, with its experiment, is written to ``dir/name_<candidate>.ssp`` for
    ``target`` (None, "libcosim" or "omsimulator", with the macro step ``step``; see
    :func:`shapefmu.fmi.ssp.write_system`), and ``Comparison.written`` lists the files. ``native``:
    every slave is its native C twin, built with the system's parameters baked in (a twin designs
    at build time). ``fmi_version`` "3.0" (with ``native``): every FMU, plant included, is FMI 3.0,
    and the shaper's mode frequencies and dampings are bound as the array parameters f and zeta.
    ``progress``: a function of a line of text (or None), told as each phase and candidate begins.

    Every ratio is against the co-simulated time-optimal move, which is run even when it is not
    among ``candidates`` (then it is not in the table), so a candidate's ratio does not depend on
    what else was asked for.
    """
    from shapefmu.cosim.master import Master
    from shapefmu.fmi.ssp import System, write_system
    from shapefmu.optimal import rigid_bang_bang, time_optimal
    from shapefmu.plants import as_plant
    from shapefmu.stos import rigid_body, shaper_for

    plant = as_plant(plant_model)
    rigid_body(plant)  # eq. (1) form, or ValueError
    distance = check_finite(distance, "distance")
    if distance == 0.0:
        raise ValueError("distance must be non-zero: a move of 0 has no move time")
    step = check_positive(step, "step")
    tolerance = check_positive(tolerance, "tolerance")
    candidates = CANDIDATES if candidates is None else tuple(candidates)
    unknown = [c for c in candidates if c not in CANDIDATES]
    if unknown or not candidates:
        raise ValueError(f"candidates must be a non-empty selection of {CANDIDATES}, got {list(candidates)}")
    if u_max is None:
        if plant.inputs[0] not in plant.limits:
            raise ValueError(f"u_max not given and plant {plant.name!r} declares no limit for {plant.inputs[0]!r}")
        u_max = plant.limits[plant.inputs[0]]
    u_max = check_positive(u_max, "u_max")
    modes = modes_hz(plant)
    window = 2.0 * math.pi / min(omega for omega, _ in plant.flexible_modes())
    # the master's bound on the run's steps, before the designs (the run lasts at least two periods)
    check_size((2.0 * window if stop_time is None else check_positive(stop_time, "stop_time")) / step, "MAX_MACRO_STEPS",
               f"a run by steps of {step!r} s takes at least", "macro steps", "take a longer step")
    say = progress or (lambda text: None)
    fmus = FMUCache(cache, native=native, fmi_version=fmi_version)
    say(f"building or reusing the plant FMU in {cache}")
    plant_fmu = fmus.plant(plant)
    rigid = rigid_bang_bang(plant, distance, u_max)
    say("solving the time-optimal move (CasADi, then exact switch times)")
    optimal = time_optimal(plant, distance, u_max)
    longest_shaper = max(shaper_for(plant, kind).duration for kind in ("convolution", "simultaneous"))
    if stop_time is None:
        stop_time = 1.25 * (rigid.duration + longest_shaper) + 2.0 * window
    # A whole number of steps: the sampled FMUs refuse a shortened last step.
    stop_time = step * math.ceil(check_positive(stop_time, "stop_time") / step - 1e-9)
    outputs = ["plant.position"] + [f"plant.deflection_{i}" for i in range(1, modes["n_modes"] + 1)]
    command = f"plant.{plant.inputs[0]}"
    player = fmus.slave("ReferencePlayer")

    def system(name):
        return System(name.replace("-", "_")).add("plant", plant_fmu)

    def run_system(sys_, start=0.0, extra=()):
        with Master(sys_, step, record=[command, *outputs, *extra]) as master:
            return master.run(start + stop_time)

    runs, written = [], []
    to_run = tuple(dict.fromkeys((*candidates, "time-optimal")))  # the ratios' reference always runs
    for number, name in enumerate(to_run, start=1):
        say(f"candidate {name} ({number} of {len(to_run)}): building or reusing its FMUs, then running it")
        start, extra = 0.0, ()
        if name in ("bang-bang", "time-optimal"):
            table = signal_table(rigid if name == "bang-bang" else optimal.command)
            sys_ = system(name).add("player", player, {"table": table}).connect("player.y_mean", command)
        elif name in SHAPER_KINDS:
            shaper_fmu = fmus.slave("Shaper")
            bound = mode_arrays(modes, shaper_fmu) if fmi_version == "3.0" else modes
            sys_ = (system(name).add("player", player, {"table": signal_table(rigid)})
                    .add("shaper", shaper_fmu, {"kind": SHAPER_KINDS[name], "Ts": step, **bound})
                    .connect("player.y_mean", "shaper.u").connect("shaper.y", command))
        elif name.startswith("stos-"):
            sys_ = stos_system(plant, distance, step, fmus, u_max, shaper=name.removeprefix("stos-"))
        else:  # ekf-tuned; its estimate is recorded, so the design it shaped with can be checked
            start, both = ekf_tuned_moves(rigid, window, step)
            sys_ = ekf_tuned_system(system(name), fmus, both, distance, step, modes, command)
            extra = ("tuner.omega_est", "tuner.zeta_est", "tuner.converged")
        if native:
            sys_ = baked_in(sys_, fmus, strings_only=False)
        results = run_system(sys_, start, extra)
        if write_ssp is not None and name in candidates:
            path = Path(write_ssp)
            if target == "omsimulator":
                sys_ = baked_in(sys_, fmus, strings_only=True)
            # one system per candidate beside the name given: files the user did not name, never replaced
            written.append(write_system(sys_.for_experiment(start + stop_time), path.with_stem(f"{path.stem}_{name.replace('-', '_')}"),
                                        target, step if target else None, named=False))
        if start > 0.0:
            # The plant is linear: remove what is left of the identification move's ring-down
            # (that move alone through the same tuner, which passes it unshaped and one step late
            # before it converges), so that the measured move is judged by its own vibration.
            alone = ekf_tuned_system(system("identification"), fmus, rigid, distance, step, modes, command)
            first = run_system(baked_in(alone, fmus, strings_only=False) if native else alone, start)
            for output in outputs:
                results[output] -= first[output]
        runs.append((name, results, start))

    measured = []
    for name, results, start in runs:
        # The plant's input recorded at t_k+1 is the one it held over [t_k, t_k+1]: shift it so
        # that u[k] is the input from t_k on, as move_metrics reads it.
        applied = np.append(results[command][1:], results[command][-1])
        moving = results["time"] >= start - 1e-9 * step
        position = results["plant.position"][moving]
        metrics = move_metrics(results["time"][moving], applied[moving], position,
                               [results[o][moving] for o in outputs[1:]], distance, u_max, window, tolerance)
        measured.append((name, metrics, results, start))
    reference = next(m.move_time for name, m, *_ in measured if name == "time-optimal")
    comparison = Comparison(plant.name, distance, u_max, step, optimal.T,
                            tuple(CandidateRun(name, m, m.move_time / reference, r, s) for name, m, r, s in measured
                                  if name in candidates),
                            command, tuple(written))
    if plot is not None:
        plot_compare(comparison, plot)
    return comparison
