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

import copy
import dataclasses
import functools
import hashlib
import json
import math
from pathlib import Path

import numpy as np

from shapefmu.files import save_figure, write_text
from shapefmu.runtime.checks import check_finite, check_positive, check_size

CANDIDATES = ("bang-bang", "convolution", "simultaneous", "stos-convolution", "stos-simultaneous", "ekf-tuned",
              "time-optimal")
# Shaper FMU kind per shaper method: "zv" given several modes convolves one ZV per mode.
_SHAPER_KINDS = {"convolution": "zv", "simultaneous": "simultaneous"}
_SETTLE_KEYS = ("kp", "kd", "ki", "x_enter", "v_enter", "x_exit", "v_exit")


# ---------------------------------------------------------------------------------------------
# The plant FMU with a velocity output


def measured_plant(plant):
    """A plant of paper 002's eq. (1) form as a native plant model whose outputs are ``position``,
    ``velocity`` (the rigid-body x_r', which a STOS controller measures) and ``deflection_i``.

    The plant's own model file exposes no velocity, and a ``Plant`` with an extra row in C becomes
    the plant generator's generic state-space kind, whose tunable D makes every output depend on the input
    (an algebraic loop with a feed-through controller). This model is written symbolically in the
    physical parameters instead (``b2``, ``rigid_damping``, ``f[i]`` in Hz, ``zeta[i]``, ``b4[i]``,
    the names the model files give), so its outputs depend on the states only; it is linear, and
    the generated plant steps it by the exact zero-order hold.
    """
    import casadi as ca

    from shapefmu.fmi.native import Output, Variable
    from shapefmu.plants import as_plant
    from shapefmu.stos import rigid_body

    plant = as_plant(plant)
    b, damping = rigid_body(plant)
    x_r, v_r, voltage = ca.SX.sym("x_r"), ca.SX.sym("v_r"), ca.SX.sym(plant.inputs[0])
    b2, d = ca.SX.sym("b2"), ca.SX.sym("rigid_damping")
    states = [Variable("x_r", x_r), Variable("v_r", v_r)]
    derivatives = [v_r, -d * v_r + b2 * voltage]
    parameters = [Variable("b2", b2, b, "1/(V*s^2)", "nonzero", "rigid-body input gain"),
                  Variable("rigid_damping", d, damping, "1/s", "nonnegative", "rigid-body velocity damping")]
    outputs = [Output("position", x_r), Output("velocity", v_r)]
    for i, k in enumerate(range(2, plant.n_states, 2), start=1):
        omega = math.sqrt(-plant.A[k + 1, k])
        x, v = ca.SX.sym(f"x_f{i}"), ca.SX.sym(f"v_f{i}")
        f, zeta, b4 = ca.SX.sym(f"f[{i}]"), ca.SX.sym(f"zeta[{i}]"), ca.SX.sym(f"b4[{i}]")
        w = 2.0 * math.pi * f
        states += [Variable(f"x_f{i}", x), Variable(f"v_f{i}", v)]
        derivatives += [v, -w * w * x - 2.0 * zeta * w * v + b4 * voltage]
        parameters += [Variable(f"f[{i}]", f, omega / (2.0 * math.pi), "Hz", "positive", f"frequency of mode {i}"),
                       Variable(f"zeta[{i}]", zeta, -plant.A[k + 1, k + 1] / (2.0 * omega), "1", "damping_ratio",
                                f"damping ratio of mode {i}"),
                       Variable(f"b4[{i}]", b4, float(plant.B[k + 1, 0]), "1/(V*s^2)", "any", f"modal gain of mode {i}")]
        outputs.append(Output(f"deflection_{i}", x))
    return _linear_symbolic_plant(name=f"{plant.name}_measured", description=f"{plant.name} with its rigid-body velocity measured",
                                  states=tuple(states), derivatives=tuple(derivatives),
                                  inputs=(Variable(plant.inputs[0], voltage),), parameters=tuple(parameters),
                                  outputs=tuple(outputs))


def _linear_symbolic_plant(**fields):
    """A plant-generator ``NonlinearPlant`` whose equations are linear in x and u, built with the exact
    zero-order-hold step (and no RK4 substep parameter) like the linear model files."""
    from shapefmu.fmi.native import NonlinearPlant

    class LinearSymbolicPlant(NonlinearPlant):
        def model_part(self):
            part = super().model_part()
            return dataclasses.replace(part, linear=True, substep_parameter=None,
                                       parameters=tuple(p for p in part.parameters if p.name != "substep"))

    return LinearSymbolicPlant(**fields)


# ---------------------------------------------------------------------------------------------
# FMU cache


class FMUCache:
    """A folder of FMUs built on demand: the slaves with default start values (parameters are bound
    per system) and measured plants. A file is rebuilt when its fingerprint (the slave's bundled
    sources, or the plant's matrices) differs from the one recorded in ``fingerprints.json``.
    With ``native`` the slaves are their native C twins (``shapefmu.fmi.native.twins``), in the
    subfolder ``native/``; with ``fmi_version`` "3.0" the twins and the plants are FMI 3.0 FMUs, in
    ``native3/``."""

    def __init__(self, directory, native: bool = False, fmi_version: str = "2.0"):
        if fmi_version != "2.0" and not native:
            raise ValueError(f"fmi_version {fmi_version} needs native: the pythonfmu FMUs are FMI 2.0 only")
        self.native, self.fmi_version = native, fmi_version
        # the slaves' subfolder; FMI 3.0 plants go with the FMI 3.0 slaves, FMI 2.0 ones at the top
        self.folder = "native3/" if fmi_version == "3.0" else "native/" if native else ""
        self.plant_folder = "native3/" if fmi_version == "3.0" else ""
        self.directory = Path(directory)
        self.directory.mkdir(parents=True, exist_ok=True)
        self._names: dict[Path, str] = {}  # slave FMU -> the model it is
        self._stamps_path = self.directory / "fingerprints.json"
        try:
            self._stamps = json.loads(self._stamps_path.read_text())
        except (OSError, ValueError):
            self._stamps = {}

    def _cached(self, file_name: str, fingerprint: str, build) -> Path:
        path = self.directory / file_name
        if not (path.is_file() and self._stamps.get(file_name) == fingerprint):
            path.parent.mkdir(exist_ok=True)
            build(path)
            self._stamps[file_name] = fingerprint
            write_text(self._stamps_path, json.dumps(self._stamps, indent=1, sort_keys=True), "FMU cache stamps")
        return path

    def slave(self, name: str, **start_values) -> Path:
        """``<name>.fmu`` for a slave of ``shapefmu.fmi.python.slaves`` (e.g. "Shaper", "STOSController");
        with ``start_values``, a copy with those baked in, ``<name>_<digest>.fmu``."""
        from shapefmu.fmi.python.builder import build_fmu, bundled_sources, package_name

        fingerprint = package_name(bundled_sources(name))
        build = build_fmu
        if self.native:
            from shapefmu.fmi.native.twins import build_native, fingerprint as native_fingerprint

            fingerprint += native_fingerprint(name)
            build = functools.partial(build_native, fmi_version=self.fmi_version)
        file_name = f"{self.folder}{name}.fmu"
        if start_values:
            baked = json.dumps(start_values, sort_keys=True)
            file_name = file_name.replace(".fmu", f"_{hashlib.sha256(baked.encode()).hexdigest()[:12]}.fmu")
            fingerprint += baked
        path = self._cached(file_name, fingerprint, lambda path: build(name, path, **elements(start_values)))
        self._names[path.resolve()] = name
        return path

    def model_of(self, fmu: Path) -> str | None:
        """The model name of a slave FMU this cache built, None for any other FMU (a plant)."""
        return self._names.get(Path(fmu).resolve())

    def plant(self, plant) -> Path:
        """The measured plant FMU (``measured_plant``) of a Plant or model file, e.g. DiskDriveMeasured.fmu."""
        from shapefmu.fmi.native import build_plant_fmu, fmu_file_name
        from shapefmu.plants import as_plant

        plant = as_plant(plant)
        digest = hashlib.sha256(b"".join(np.ascontiguousarray(m).tobytes() for m in (plant.A, plant.B)))
        digest.update(repr((plant.name, plant.inputs)).encode())
        model = measured_plant(plant)
        return self._cached(self.plant_folder + fmu_file_name(model.name), digest.hexdigest(),
                            lambda path: build_plant_fmu(model, path, fmi_version=self.fmi_version))


def elements(values: dict) -> dict:
    """``values`` with each array value (an FMI 3.0 array parameter, a list) as its elements
    ``name[1]``, ``name[2]``, ...: the start values a twin is built from name elements."""
    flat = {}
    for name, value in values.items():
        if isinstance(value, (list, tuple)):
            flat.update({f"{name}[{i}]": item for i, item in enumerate(value, start=1)})
        else:
            flat[name] = value
    return flat


# ---------------------------------------------------------------------------------------------
# Metrics


@dataclasses.dataclass(frozen=True)
class MoveMetrics:
    """``move_time``: from the move's start until the position stays within ``tolerance`` |X| of
    the target and the command within ``tolerance`` U of its final value (for an open-loop command
    that is its end, at the grid); ``residual``: the largest |y_j - y_j,final| of the position and
    the deflections over one period of the slowest mode after the move time, divided by |X| (the
    definition of ``optimal.residual_after_move``, on the recorded samples); ``peak``: max |u|."""

    move_time: float
    residual: float
    peak: float


def move_metrics(t, u, position, deflections, distance: float, u_max: float, window: float,
                 tolerance: float = 1e-3, u_final: float = 0.0) -> MoveMetrics:
    """The metrics of :class:`MoveMetrics` from samples at ``t`` (the move starts at t[0])."""
    t, u, position = (np.asarray(a, dtype=float) for a in (t, u, position))
    deflections = np.atleast_2d(np.asarray(deflections, dtype=float))
    outside = (np.abs(position - distance) > tolerance * abs(distance)) | (np.abs(u - u_final) > tolerance * u_max)
    late = np.flatnonzero(outside)
    if late.size and late[-1] + 1 >= t.size:
        return MoveMetrics(math.inf, math.nan, float(np.max(np.abs(u))))
    first = late[-1] + 1 if late.size else 0
    span = (t >= t[first] - 1e-12 * window) & (t <= t[first] + window * (1 + 1e-9))
    errors = [np.abs(position[span] - distance)] + [np.abs(row[span]) for row in deflections]
    residual = max(float(np.max(e)) for e in errors) / abs(distance)
    return MoveMetrics(float(t[first] - t[0]), residual, float(np.max(np.abs(u))))


# ---------------------------------------------------------------------------------------------
# Systems and the comparison


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


def _signal_table(command) -> str:
    """ReferencePlayer ``table`` of an ``optimal.Command`` (zero-order hold, exact breaks)."""
    return json.dumps({"kind": "signal_table", "interpolation": "hold", "time": list(command.breaks),
                       "value": [*command.levels, command.final]})


def _modes_hz(plant) -> dict:
    modes = plant.flexible_modes()
    if not 1 <= len(modes) <= 4:
        raise ValueError(f"plant {plant.name!r} must have 1 to 4 flexible modes for the shaper FMUs, got {len(modes)}")
    values = {"n_modes": len(modes)}
    for i, (omega, zeta) in enumerate(modes, start=1):
        values[f"f[{i}]"] = omega / (2.0 * math.pi)
        values[f"zeta[{i}]"] = zeta
    return values


def _mode_arrays(modes: dict, fmu) -> dict:
    """The shaper's modes (``_modes_hz``) as the FMI 3.0 array parameters f and zeta of ``fmu``, whole:
    the modes first, the FMU's own start values after them (unused: n_modes says how many count)."""
    from fmpy import read_model_description

    declared = {v.name: str(v.start).split() for v in read_model_description(str(fmu)).modelVariables}
    arrays = {"n_modes": modes["n_modes"]}
    for name in ("f", "zeta"):
        given = [modes[f"{name}[{i}]"] for i in range(1, modes["n_modes"] + 1)]
        arrays[name] = given + [float(v) for v in declared[name][len(given):]]
    return arrays


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
    modes = _modes_hz(plant)
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
            table = _signal_table(rigid if name == "bang-bang" else optimal.command)
            sys_ = system(name).add("player", player, {"table": table}).connect("player.y_mean", command)
        elif name in _SHAPER_KINDS:
            shaper_fmu = fmus.slave("Shaper")
            bound = _mode_arrays(modes, shaper_fmu) if fmi_version == "3.0" else modes
            sys_ = (system(name).add("player", player, {"table": _signal_table(rigid)})
                    .add("shaper", shaper_fmu, {"kind": _SHAPER_KINDS[name], "Ts": step, **bound})
                    .connect("player.y_mean", "shaper.u").connect("shaper.y", command))
        elif name.startswith("stos-"):
            sys_ = stos_system(plant, distance, step, fmus, u_max, shaper=name.removeprefix("stos-"))
        else:  # ekf-tuned; its estimate is recorded, so the design it shaped with can be checked
            start, both = _ekf_tuned_moves(rigid, window, step)
            sys_ = _ekf_tuned_system(system(name), fmus, both, distance, step, modes, command)
            extra = ("tuner.omega_est", "tuner.zeta_est", "tuner.converged")
        if native:
            sys_ = _baked_in(sys_, fmus, strings_only=False)
        results = run_system(sys_, start, extra)
        if write_ssp is not None and name in candidates:
            path = Path(write_ssp)
            if target == "omsimulator":
                sys_ = _baked_in(sys_, fmus, strings_only=True)
            # one system per candidate beside the name given: files the user did not name, never replaced
            written.append(write_system(sys_.for_experiment(start + stop_time), path.with_stem(f"{path.stem}_{name.replace('-', '_')}"),
                                        target, step if target else None, named=False))
        if start > 0.0:
            # The plant is linear: remove what is left of the identification move's ring-down
            # (that move alone through the same tuner, which passes it unshaped and one step late
            # before it converges), so that the measured move is judged by its own vibration.
            alone = _ekf_tuned_system(system("identification"), fmus, rigid, distance, step, modes, command)
            first = run_system(_baked_in(alone, fmus, strings_only=False) if native else alone, start)
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


def _baked_in(system, fmus: FMUCache, strings_only: bool):
    """``system`` with each slave's bindings baked into a copy of its FMU as start values: the
    String ones, removed from the bindings, for OMSimulator, which imports no String binding (see
    :mod:`shapefmu.fmi.ssp_targets`); every one, the bindings kept, for a native twin, which
    designs at build time and refuses another value than its build value."""
    result = copy.copy(system)
    result.components = {}
    for name, component in system.components.items():
        baked = {k: v for k, v in component.parameters.items()
                 if not strings_only or component.connectors[k].type == "String"}
        model = fmus.model_of(component.fmu)
        if baked and model is not None:
            component = copy.copy(component)
            component.fmu = fmus.slave(model, **baked)
            component.connectors = {k: dataclasses.replace(c, start=baked[k]) if k in baked else c
                                    for k, c in component.connectors.items()}
            if strings_only:
                component.parameters = {k: v for k, v in component.parameters.items() if k not in baked}
        result.components[name] = component
    return result


def stos_system(plant, distance: float, Ts: float, fmus: FMUCache, u_max: float | None = None,
                shaper: str = "simultaneous"):
    """The SSP system STOS <-> plant: the STOSController FMU, designed like ``stos.stos_law(plant,
    shaper, Ts)`` (``shaper``: "convolution" or "simultaneous"; settle controller included) with
    ``target`` = ``distance`` bound as a parameter, reading the measured plant's ``position`` and
    ``velocity`` and driving its input. Run it with the macro step ``Ts``."""
    from shapefmu.fmi.ssp import System
    from shapefmu.plants import as_plant
    from shapefmu.stos import rigid_body, stos_law

    plant = as_plant(plant)
    b, damping = rigid_body(plant)
    if shaper not in _SHAPER_KINDS:
        raise ValueError(f"shaper must be one of {', '.join(_SHAPER_KINDS)}, got {shaper!r}")
    law = stos_law(plant, shaper, Ts, u_max)
    controller = {"b": b, "U": law.U, "damping": damping, "kind": _SHAPER_KINDS[shaper], "Ts": Ts, "settle": True,
                  **_modes_hz(plant), **{key: law.settle[key] for key in _SETTLE_KEYS}, "target": distance}
    return (System("stos").add("controller", fmus.slave("STOSController"), controller)
            .add("plant", fmus.plant(plant))
            .connect("plant.position", "controller.x_r").connect("plant.velocity", "controller.x_r_dot")
            .connect("controller.u", f"plant.{plant.inputs[0]}"))


def _ekf_tuned_moves(rigid, window: float, step: float):
    """(start, command): the identification move, a rest while the EKF converges, then the measured
    move, the same bang-bang again from X to 2X, starting at ``start``."""
    from shapefmu.optimal import Command

    rest = 10.0 * window  # the EKF converges within about five periods of the ring-down (paper 001)
    start = step * math.ceil((rigid.duration + rest) / step)  # on the grid: the run ends a whole number of steps later
    return start, Command((*rigid.breaks, *(start + b for b in rigid.breaks)), (*rigid.levels, 0.0, *rigid.levels))


def _ekf_tuned_system(sys_, fmus, moves, distance, step, modes, command):
    """A ReferencePlayer playing ``moves`` into an EKFTuner that drives the plant's input.

    The EKF (paper 001) watches deflection_1 from a guess 10 % below the first mode and designs a
    ZVD shaper for its estimate; the tuner switches the shaper in while the command rests."""
    tuner = {"kind": "zvd", "Ts": step, "omega0": 0.9 * 2.0 * math.pi * modes["f[1]"], "amplitude": 1e-2 * distance}
    return (sys_.add("player", fmus.slave("ReferencePlayer"), {"table": _signal_table(moves)})
            .add("tuner", fmus.slave("EKFTuner"), tuner)
            .connect("player.y_mean", "tuner.u").connect("plant.deflection_1", "tuner.vibration")
            .connect("tuner.y", command))


def plot_compare(comparison: Comparison, path) -> Path:
    """u(t), the position error and the deflections of every candidate, from its move's start."""
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
