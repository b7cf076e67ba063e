"""The native C twins of the pythonfmu FMUs, as the twin contract (tests/test_native_twin_contract.py)
runs them: a kind joins the contract by one line in its TWINS once it is declared here.

A Twin says how its FMUs are built (the model name both share, one set of start values per case),
what drives them, how close the native FMU's outputs must stay to the twin's, and for each item of
the contract which runs it makes and what shows that a run exercised the FMU (``check`` on the
twin's rows: it converged, banged, switched, came to rest):

    steps_of_ts   runs in fmpy with steps of Ts: the native rows equal the twin's
    hosts         one run in fmpy, libcosim and ecos with steps of ``host_step``: equal to the twin's in fmpy
    random        runs with random steps and slivers of steps, the FMU state saved two fifths in and
                  restored after the run: equal to the twin's; the replay equals the native run
    changes       runs with parameters set before initialisation: as on the twin
    c_host        both FMUs side by side in hosts_c/fmi2_host.c (t += h, exit-handler teardown)
    platforms     hosts_c/plan_host.c on linux64, on win64 (Wine) and on aarch64 (qemu): the same numbers
    valgrind      (case, hosts_c driver) run under memcheck

"Equal" is bit for bit where ``exact`` (the native code computes as the twin's Python does), else to
1e-12 of ``scale`` per output; foreign hosts (libcosim's integer-nanosecond time, other platforms'
libm) are always held to the scale.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
import pytest

from shapefmu.fmi.kinds.impulse_train import train_start_values
from support.fixtures_fmi import EKF_STARTS, SCHEDULED_STARTS, STOS_STARTS, time_optimal_solution
from support.fmpy_slaves import initialised, run_points
from support.scenarios import EKF_OUTPUTS, OMEGA, SETTLE, TARGET, TS, U, ekf_signals, plant_step, recorded_measurements


def no_inputs(pair, times) -> list[dict]:
    return [{}] * (len(times) - 1)


def nothing(rows) -> None:
    """A check for runs whose comparison is the whole point."""


@dataclass(frozen=True)
class Run:
    """One run: the case's FMUs over the communication points ``times()`` (step k from times[k] to
    times[k + 1]), ``inputs(pair, times)`` set before each step, ``parameters`` before initialisation;
    ``check(twin_rows)`` asserts that it exercised the FMU."""

    case: str
    times: Callable[[], np.ndarray]
    inputs: Callable | None = no_inputs  # None: the kind's closed loop
    parameters: dict = field(default_factory=dict)
    check: Callable = nothing


@dataclass(frozen=True)
class Platforms:
    """plan_host's run of the case's native FMU: ``plan(vr)`` the plan's lines after its fmu line
    (``vr``: {name: value reference}); ``check(rows)`` on the linux64 rows (one per step)."""

    case: str
    plan: Callable[[dict], str]
    check: Callable


@dataclass(frozen=True)
class CHost:
    """fmi2_host's run of the case's twin and native FMU with ``options``; ``check(twin_rows)``."""

    case: str
    options: tuple
    check: Callable = nothing


def steps_of(h: float, count: int) -> Callable[[], np.ndarray]:
    return lambda: h * np.arange(count + 1)


def random_times(seed: int, count: int, draw: Callable, every: int, sliver: float) -> Callable[[], np.ndarray]:
    """Communication points of ``count`` steps ``draw(rng, count)``, every ``every``-th of ``sliver`` s."""
    def times():
        steps = draw(np.random.default_rng(seed), count)
        steps[::every] = sliver
        return np.concatenate([[0.0], np.cumsum(steps)])

    return times


class Twin:
    """A kind of native FMU beside its pythonfmu twin (see the module docstring)."""

    model: str
    outputs: tuple[str, ...]
    exact: bool = True
    units: bool = True  # the declared variables compare with their units
    read_before: bool = False  # rows also read right after the inputs are set (feed-through), before each step
    host_step: float
    steps_of_ts: tuple[Run, ...]
    hosts: Run
    random: tuple[Run, ...]
    changes: tuple[Run, ...] = ()
    c_host: CHost
    platforms: tuple[Platforms, ...]
    valgrind: tuple[str, str]

    def starts(self, case: str) -> dict:
        raise NotImplementedError

    @property
    def cases(self) -> list[str]:
        return [run.case for run in self.steps_of_ts]

    def pair(self, builds, case: str) -> tuple:
        """(native FMU, pythonfmu twin) of ``case``, built once per session."""
        starts = self.starts(case)
        return builds.native(self.model, **starts), builds.pythonfmu(self.model, **starts)

    def run(self, fmu, run: Run, pair) -> list[list[float]]:
        times = run.times()
        return run_points(fmu, times, run.inputs(pair, times), self.outputs, parameters=run.parameters,
                          read_before=self.read_before)

    def scale(self, rows) -> np.ndarray:
        """Per output: the magnitude the 1e-12 tolerance is relative to (at least 1)."""
        return np.maximum(np.max(np.abs(np.asarray(rows, dtype=float)), axis=0), 1.0)

    def assert_same(self, native_rows, twin_rows, exact: bool) -> None:
        if exact:
            assert native_rows == twin_rows if isinstance(native_rows, list) else np.array_equal(native_rows, twin_rows)
            return
        native, twin = np.asarray(native_rows, dtype=float), np.asarray(twin_rows, dtype=float)
        assert native.shape == twin.shape
        np.testing.assert_allclose(native / self.scale(twin), twin / self.scale(twin), rtol=0, atol=1e-12)

    def __repr__(self) -> str:
        return self.model


# ----------------------------------------------------------------------------------------- EKFTuner

def _ekf_inputs(seed: int):
    return lambda pair, times: ekf_signals(len(times) - 1, seed)


def _converged(rows) -> None:
    assert rows[-1][3] == 1.0


def _tuned(rows) -> None:
    assert rows[-1][3] == 1.0 and rows[-1][1] == pytest.approx(OMEGA, rel=0.01)  # it converged and tuned


def _tuned_to_20_hz(host_rows) -> None:
    """fmi2_host's rows (t, u, vibration, y, omega_est, zeta_est, converged)."""
    assert host_rows[-1, -1] == 1.0 and host_rows[-1, 4] == pytest.approx(2 * math.pi * 20.0, rel=1e-3)


def _omega_moved(rows) -> None:
    assert np.ptp(rows[:, 1]) > 0


class EKFTunerTwin(Twin):
    """Paper 001's EKF-tuned shaper: a noisy 10 Hz ring-down watched at 1 kHz from a 60 rad/s guess.
    Held to 1e-12 of each output's range (not bit for bit), as its tests always held it."""

    model = "EKFTuner"
    outputs = tuple(EKF_OUTPUTS)
    exact = False
    host_step = EKF_STARTS["Ts"]
    H = EKF_STARTS["Ts"]
    steps_of_ts = (Run("tuner", steps_of(H, 2500), _ekf_inputs(0), check=_tuned),)
    hosts = Run("tuner", steps_of(H, 800), _ekf_inputs(1))
    random = (Run("tuner", random_times(7, 1500, lambda rng, n: rng.choice([0.3, 0.5, 1.0, 1.7, 2.5], size=n) * 1e-3,
                                        13, 1e-12), _ekf_inputs(5), check=_converged),)  # steps of 0.3 to 2.5 Ts
    changes = (Run("tuner", steps_of(2e-3, 1200), _ekf_inputs(3), check=_converged,
                   parameters={"kind": "mzv", "omega0": 2 * math.pi * 8.0, "Ts": 2e-3, "retune_fraction": 0.02}),)
    # random steps (a third onto the grid), a 20 Hz vibration the EKF locks on to (the host's inputs)
    c_host = CHost("tuner", ("--random", 11, 1e-9 * H, 7.3 * H, 8000, H, "--period", 50 * H, "--square", 0.0),
                   _tuned_to_20_hz)
    # the host drives the vibration with its own sequence (u left at 0)
    platforms = (Platforms("tuner", lambda vr: f"input {vr['vibration']} 0.5\n"
                           + "".join(f"output {vr[name]}\n" for name in EKF_OUTPUTS) + "run 600 0.001\n",
                           _omega_moved),)
    valgrind = ("tuner", "valgrind_ekf_tuner")

    def starts(self, case):
        return EKF_STARTS

    def scale(self, rows):
        return np.maximum(np.ptp(np.asarray(rows, dtype=float), axis=0), 1.0)


# ----------------------------------------------------------------------------------- STOSController

def _banged_and_arrived(rows) -> None:
    controls = [u for u, _ in rows]
    assert max(map(abs, controls)) > 0.9 * U and len(set(controls)) > 5  # it banged and switched
    assert abs(rows[-1][1] - TARGET) < 2e-2 * TARGET


def _switched_in_the_host(host_rows) -> None:
    """fmi2_host's rows (t, target, x_r, x_r_dot, u)."""
    assert np.ptp(host_rows[:, 4]) > U


def _switched_on_the_platform(rows) -> None:
    assert rows.shape == (800, 1) and np.ptp(rows) > 0.5 * U and len(set(rows[:, 0])) > 3


def _recorded_loop(pair, times) -> list[dict]:
    """The measurements of the twin's closed loop at steps of Ts, replayed open loop."""
    return recorded_measurements(pair[1], len(times) - 1)


class STOSControllerTwin(Twin):
    """Paper 002's STOS law around the disk drive's rigid body (modes at 2 and 3 kHz). In a closed
    loop (``inputs=None``) the rows are (u, x): u read after the measurement is set, x the body's
    position after the step; open loop, u read before and after each step."""

    model = "STOSController"
    outputs = ("u",)
    read_before = True
    host_step = TS
    CASES = {"simultaneous": STOS_STARTS, "settle": {**STOS_STARTS, "settle": True, **SETTLE},
             "back EMF": {**STOS_STARTS, "damping": 650.0}, "zv convolved": {**STOS_STARTS, "kind": "zv"}}
    steps_of_ts = tuple(Run(case, steps_of(TS, 520), None, check=_banged_and_arrived) for case in CASES)
    hosts = Run("simultaneous", steps_of(TS, 300), _recorded_loop)
    random = (Run("settle", random_times(3, 600, lambda rng, n: rng.choice([0.25, 0.5, 1.0, 1.5, 3.0], size=n) * TS,
                                         11, 1e-13), _recorded_loop),)
    changes = tuple(Run(case, steps_of(TS, 400), None, parameters=changed,
                        check=lambda rows: len({u for u, _ in rows}) > 3) for case, changed in (
        ("simultaneous", {"Ts": 2e-5, "settle": True, **SETTLE}),
        ("simultaneous", {"b": 3.1e3, "U": 9.0, "damping": 300.0}),  # the curves redesigned in C for this body
        ("zv convolved", {"kind": "mzv", "n_modes": 1, "f[1]": 1500.0, "zeta[1]": 0.05, "U": 12.0}),  # and this shaper
        ("zv convolved", {"kind": "zv_dn", "n": 2, "f[2]": 3500.0}),
    ))
    c_host = CHost("simultaneous", ("--random", 5, 1e-9 * TS, 7.3 * TS, 3000, TS, "--amplitude", 1e-3,
                                    "--period", 200 * TS), _switched_in_the_host)
    # back EMF: the law's log1p and expm1 from each platform's own libm; settle: the sub-sample blend
    # (bisection on the predicted flow) every sample. The host drives the position error (+-1 mm).
    platforms = tuple(Platforms(case, lambda vr: f"input {vr['x_r']} 1e-3\noutput {vr['u']}\nrun 800 {TS!r}\n",
                                _switched_on_the_platform) for case in ("back EMF", "settle"))
    valgrind = ("settle", "valgrind_stos")

    def starts(self, case):
        return self.CASES[case]

    def run(self, fmu, run, pair):
        if run.inputs is not None:
            return super().run(fmu, run, pair)
        times = run.times()
        slave, vr = initialised(fmu, run.parameters)
        x = v = 0.0
        rows = []
        for t, t_next in zip(times[:-1], times[1:]):
            slave.setReal([vr["target"], vr["x_r"], vr["x_r_dot"]], [TARGET, x, v])
            (u,) = slave.getReal([vr["u"]])
            slave.doStep(t, t_next - t)
            x, v = plant_step(x, v, u, t_next - t)
            rows.append([u, x])
        slave.freeInstance()
        return rows

    def scale(self, rows):
        return np.full(np.shape(rows)[1], U)


# --------------------------------------------------------------------------------- ProfileGenerator

def _starting_at(at: float):
    """The start input set to 1 at every communication point from ``at`` on (left at 0 before)."""
    return lambda pair, times: [{"start": 1.0} if t >= at else {} for t in times[:-1]]


def _moved_and_rests(rows) -> None:
    assert max(abs(row[2]) for row in rows) > 0 and rows[-1][1] == pytest.approx(0.0, abs=1e-9)


def _moved(rows) -> None:
    assert any(row[2] != 0.0 for row in rows)


def _moved_by(distance: float):
    def check(rows):
        assert rows[-1][0] == pytest.approx(distance, rel=1e-9)  # the move it was asked for
    return check


def _position_moved(host_rows) -> None:
    """fmi2_host's rows (t, start, position, velocity, acceleration)."""
    assert np.ptp(host_rows[:, 2]) > 0


def _moved_on_the_platform(rows) -> None:
    assert rows.shape == (300, 3) and np.ptp(rows) > 0


class ProfileGeneratorTwin(Twin):
    """Three families: a twin-pulse kind of paper 003 (BC:TZ, the defaults), time-frequency of paper
    004, a ZVD-shaped bang-bang of paper 002 starting at t_start. Rows are read before and after
    each step: the acceleration feeds through from the start input."""

    model = "ProfileGenerator"
    outputs = ("position", "velocity", "acceleration")
    read_before = True
    host_step = 1e-3
    CASES = {"twin-pulse": {},
             "time-frequency": {"profile": "time-frequency", "omega_n": 60.0, "Ts": 1e-3, "move_time": 0.2, "distance": 0.1},
             "shaped bang-bang": {"profile": "bang-bang", "shaper": "zvd", "omega[1]": 20.0, "distance": 0.5,
                                  "t_start": 0.05}}
    steps_of_ts = tuple(Run(case, steps_of(1e-3, 6000), check=_moved_and_rests) for case in CASES)
    hosts = Run("time-frequency", steps_of(1e-3, 300), _starting_at(0.02))
    random = tuple(Run(case, random_times(8, 1500, lambda rng, n: rng.uniform(1e-9, 3e-3, n), 9, 1e-15),
                       _starting_at(0.4), check=_moved) for case in CASES)
    changes = (*(Run("shaped bang-bang", steps_of(1e-3, 4000), parameters=changed,
                     check=_moved_by(changed.get("distance", 0.5))) for changed in (
        {"distance": 0.8, "acceleration_limit": 2.5, "speed": 0.3},            # bang-coast-bang
        {"shaper": "mzv", "n_modes": 2, "omega[2]": 55.0, "zeta[2]": 0.1},     # another closed-form shaper
        {"shaper": "zv_dn", "n": 3, "omega[1]": 12.0, "speed": 0.0},
        {"shaper": "none", "distance": 0.2},
    )), Run("shaped bang-bang", steps_of(1e-3, 2000), parameters={"t_start": 0.3},
            check=lambda rows: rows[2 * 250 + 1][0] == 0.0 and rows[2 * 400 + 1][0] > 0.0))
    c_host = CHost("twin-pulse", ("--stop", 4.0, "--steps", 500, "--period", 0.7), _position_moved)
    # the host's input sequence reaches 0.5 within a few steps: the start input starts the move
    platforms = (Platforms("time-frequency", lambda vr: f"input {vr['start']} 1\n"
                           + "".join(f"output {vr[n]}\n" for n in ProfileGeneratorTwin.outputs) + "run 300 0.001\n",
                           _moved_on_the_platform),)
    valgrind = ("twin-pulse", "valgrind_profile")

    def starts(self, case):
        return self.CASES[case]

    def scale(self, rows):
        return np.ones(np.shape(rows)[1])


# ---------------------------------------------------------------------------------- ReferencePlayer

LINEAR_TABLE = json.dumps({"kind": "signal_table", "interpolation": "linear", "before": -0.5,
                           "time": [0.1, 0.35, 0.35, 0.6, 0.8], "value": [0.0, 1.0, -2.0, 0.5, 0.5]})


def _table_end(case: str) -> float:
    return time_optimal_solution().T if case == "time-optimal" else 1.0


def _switched(rows) -> None:
    assert len({row[0] for row in rows}) > 2  # the table switched


def _switched_within_steps(rows) -> None:
    _switched(rows)
    assert any(row[0] != row[1] for row in rows)  # y_mean averages over steps that hold a switch


def _a_thousand_steps(host_rows) -> None:
    assert len(host_rows) >= 1000


def _switched_on_the_platform_table(rows) -> None:
    assert rows.shape == (1000, 2) and np.ptp(rows) > 2


class ReferencePlayerTwin(Twin):
    """The CasADi time-optimal input of the disk drive's move (a hold table with exact switch
    instants) and a linear table with a jump. Its variables carry no units on either side to compare."""

    model = "ReferencePlayer"
    outputs = ("y", "y_mean")
    units = False
    host_step = 1e-5
    # h = end / 400: t += h drifts onto and around the switches
    steps_of_ts = tuple(Run(case, lambda case=case: _table_end(case) / 400 * np.arange(481), check=_switched)
                        for case in ("time-optimal", "linear"))
    hosts = Run("time-optimal", steps_of(1e-5, 300))
    # random steps straddle and end near the switches, one in seven of 1e-15 s
    random = tuple(Run(case, lambda case=case: random_times(4, 300, lambda rng, n: rng.uniform(1e-9, _table_end(case) / 14, n),
                                                            7, 1e-15)(), check=_switched_within_steps)
                   for case in ("time-optimal", "linear"))
    c_host = CHost("linear", ("--stop", 1.0, "--step", 1e-3), _a_thousand_steps)
    platforms = (Platforms("linear", lambda vr: f"output {vr['y']}\noutput {vr['y_mean']}\nrun 1000 0.001\n",
                           _switched_on_the_platform_table),)
    valgrind = ("time-optimal", "valgrind_reference")

    def starts(self, case):
        return {"table": time_optimal_solution().to_json() if case == "time-optimal" else LINEAR_TABLE}


EKF_TUNER, STOS_CONTROLLER, PROFILE_GENERATOR, REFERENCE_PLAYER = (
    EKFTunerTwin(), STOSControllerTwin(), ProfileGeneratorTwin(), ReferencePlayerTwin())


# ------------------------------------------------------------------------------------- ImpulseTrain

TRAIN_TS = 2e-4
TRAINS = {  # (times s, amplitudes): off the grid of TRAIN_TS; the second starts late, with a negative impulse
    "five": ((0.0, 0.00317, 0.00742, 0.01105, 0.01533), (0.12, 0.27, 0.31, 0.21, 0.09)),
    "late": ((0.0021, 0.0049, 0.0093), (0.6, -0.2, 0.6)),
}


def _move(pair, times) -> list[dict]:
    """A command that ramps up over 10 ms, holds, and carries a 230 Hz ripple from 20 ms on."""
    t = np.asarray(times[:-1])
    u = np.clip(t / 0.01, 0.0, 1.0) + 0.1 * np.sin(2 * np.pi * 230.0 * t) * (t >= 0.02)
    return [{"u": float(value)} for value in u]


def _shaped(rows) -> None:
    assert len({row[0] for row in rows}) > 50 and np.ptp(np.asarray(rows)) > 0.9  # it moved, smoothly


def _shaped_in_the_host(host_rows) -> None:
    """fmi2_host's rows (t, u, y)."""
    assert np.ptp(host_rows[:, 2]) > 1


class ImpulseTrainTwin(Twin):
    """Explicit impulses off the sample grid (split onto it), one train starting at t = 0 and one
    starting late with a negative impulse and a command resting at u0 = 0.4 before the start."""

    model = "ImpulseTrain"
    outputs = ("y",)
    read_before = True
    host_step = TRAIN_TS
    steps_of_ts = tuple(Run(case, steps_of(TRAIN_TS, 400), _move, check=_shaped) for case in TRAINS)
    hosts = Run("five", steps_of(TRAIN_TS, 300), _move)
    random = tuple(Run(case, random_times(6, 600, lambda rng, n: rng.choice([0.3, 0.5, 1.0, 1.7, 4.0], size=n) * TRAIN_TS,
                                          9, 1e-13), _move, check=_shaped) for case in TRAINS)
    changes = (Run("five", steps_of(TRAIN_TS, 400), _move, check=_shaped, parameters={"Ts": 1e-4, "u0": -0.3}),
               Run("five", steps_of(TRAIN_TS, 400), _move, check=_shaped, parameters={  # another train of three
                   "n_impulses": 3, "impulse_time[2]": 0.004, "impulse_time[3]": 0.0081, "impulse_time[4]": 0.0,
                   "impulse_time[5]": 0.0, "impulse_amplitude[1]": 0.25, "impulse_amplitude[2]": 0.5,
                   "impulse_amplitude[3]": 0.25, "impulse_amplitude[4]": 0.0, "impulse_amplitude[5]": 0.0}))
    c_host = CHost("five", ("--stop", 0.2, "--step", 1e-3, "--amplitude", 2.0), _shaped_in_the_host)
    platforms = (Platforms("late", lambda vr: f"input {vr['u']} 1\noutput {vr['y']}\nrun 300 0.0002\n",
                           lambda rows: np.ptp(rows) > 0.5),)
    valgrind = ("five", "valgrind_sampled")

    def starts(self, case):
        return {**train_start_values(*TRAINS[case]), "Ts": TRAIN_TS, "u0": 0.4 if case == "late" else 0.0}


IMPULSE_TRAIN = ImpulseTrainTwin()


# ---------------------------------------------------------------------------------- ScheduledShaper

SCHEDULED_TS = 5e-4
SCHEDULED_CASES = {
    # the bed of models/printer_bed.toml gaining 300 g (30 -> 26.3 Hz), re-designed at every change
    "bed zv": SCHEDULED_STARTS | {"kind": "zv"},
    # a mode that moves with position over [-1, 1]: three rows, re-designed past 0.1 %, from rest at 0.3
    "position mzv": {"kind": "mzv", "n_rows": 3, "values[1]": -1.0, "values[2]": 0.0, "values[3]": 1.0,
                     "f[1]": 12.0, "f[2]": 15.0, "f[3]": 20.0, "zeta[1]": 0.02, "zeta[2]": 0.05, "zeta[3]": 0.1,
                     "resolution": 1e-3, "Ts": 1e-3, "u0": 0.3},
    # Marlin's linear law f = 30 - 12 value (two rows, extrapolated), three ZVs convolved (zv_dn, n = 2)
    "law zv_dn": {"kind": "zv_dn", "n": 2, "n_rows": 2, "values[1]": 0.0, "values[2]": 1.0, "f[1]": 30.0,
                  "f[2]": 18.0, "zeta[1]": 0.03, "zeta[2]": 0.03, "extrapolate": True, "Ts": SCHEDULED_TS},
}
SCHEDULING_SPAN = {"bed zv": (0.0, 300.0), "position mzv": (-1.2, 1.2), "law zv_dn": (-0.2, 1.3)}


def _moves_through_a_drift(case: str):
    """Moves of the command (a 2.5 Hz sine clipped at +-1: moves and rests; a 90 Hz ripple from 0.3 s) while
    the scheduling input drifts across the case's span and back, with a jump at 0.55 s: both inputs as
    functions of the time, so any steps sample them."""
    low, high = SCHEDULING_SPAN[case]

    def inputs(pair, times):
        t = np.asarray(times[:-1])
        u = np.clip(np.sin(2 * np.pi * 2.5 * t) * 1.5, -1.0, 1.0) + 0.05 * np.sin(2 * np.pi * 90.0 * t) * (t > 0.3)
        drift = low + (high - low) * (0.5 - 0.5 * np.cos(2 * np.pi * 0.8 * t)) + (high - low) * 0.2 * (t > 0.55)
        return [{"u": float(a), "scheduling": float(s)} for a, s in zip(u, np.minimum(drift, high))]

    return inputs


def _moved_and_shaped(rows) -> None:
    assert np.ptp(np.asarray(rows)) > 1.0 and len({row[0] for row in rows}) > 100  # it moved, and shaped


def _shaped_on_the_platform(rows) -> None:
    assert rows.shape == (400, 1) and np.ptp(rows) > 0.5 and len(np.unique(rows)) > 150


class ScheduledShaperTwin(Twin):
    """Issue 37's ScheduledShaper: a closed-form shaper re-designed for the mode its scheduling input puts in
    force, each change of the command shaped by the design in force when it was commanded. The C does the
    Python's arithmetic operation for operation: bit for bit. Rows are read before and after each step
    (y feeds through from both inputs)."""

    model = "ScheduledShaper"
    outputs = ("y",)
    read_before = True
    host_step = SCHEDULED_TS
    steps_of_ts = tuple(Run(case, steps_of(SCHEDULED_CASES[case]["Ts"], 1000), _moves_through_a_drift(case),
                            check=_moved_and_shaped) for case in SCHEDULED_CASES)
    hosts = Run("bed zv", steps_of(SCHEDULED_TS, 600), _moves_through_a_drift("bed zv"))
    random = tuple(Run(case, random_times(12, 1200, lambda rng, n: rng.choice([0.3, 0.5, 1.0, 1.7, 4.0], size=n) * 5e-4,
                                          9, 1e-13), _moves_through_a_drift(case), check=_moved_and_shaped)
                   for case in ("bed zv", "position mzv"))
    changes = (Run("bed zv", steps_of(1e-3, 700), _moves_through_a_drift("bed zv"), check=_moved_and_shaped,
                   parameters={"kind": "zvd", "Ts": 1e-3, "f[2]": 24.0, "resolution": 1e-3, "u0": 0.2}),
               Run("law zv_dn", steps_of(SCHEDULED_TS, 700), _moves_through_a_drift("law zv_dn"),
                   check=_moved_and_shaped, parameters={"kind": "mzv", "f[2]": 22.0, "zeta[2]": 0.05}))
    # the host's two inputs (sines a radian apart, a square on top): both the command and the position move
    c_host = CHost("position mzv", ("--random", 4, 1e-9, 2.5e-3, 3000, 1e-3, "--period", 0.35, "--square", 0.5),
                   lambda rows: np.ptp(rows[:, 3]) > 1.0)
    # the position held between rows (libm's sqrt, exp and pow of each platform), the command driven
    platforms = (Platforms("position mzv", lambda vr: f"real {vr['scheduling']} 0.37\ninput {vr['u']} 1\n"
                           f"output {vr['y']}\nrun 400 0.001\n", _shaped_on_the_platform),)
    valgrind = ("bed zv", "valgrind_scheduled")

    def starts(self, case):
        return SCHEDULED_CASES[case]


SCHEDULED_SHAPER = ScheduledShaperTwin()
