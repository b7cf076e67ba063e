"""The SSP systems of the candidates: a player, a shaper, a STOS controller or an EKF tuner before the
measured plant, composed with :class:`~shapefmu.fmi.ssp.System` from the FMUs of an ``FMUCache``."""

from __future__ import annotations

import copy
import dataclasses
import json
import math

from shapefmu.compare.cache import FMUCache

# Shaper FMU kind per shaper method: "zv" given several modes convolves one ZV per mode.
SHAPER_KINDS = {"convolution": "zv", "simultaneous": "simultaneous"}
SETTLE_KEYS = ("kp", "kd", "ki", "x_enter", "v_enter", "x_exit", "v_exit")


def signal_table(command) -> str:
    """ReferencePlayer ``table`` of an ``optimal.Command`` (zero-order hold, exact breaks)."""
    return json.dumps({"kind": "signal_table", "interpolation": "hold", "time": list(command.breaks),
                       "value": [*command.levels, command.final]})


def modes_hz(plant) -> dict:
    """The Shaper's and the STOS controller's start values for the plant's flexible modes."""
    from shapefmu.fmi.kinds.shaper import MAX_MODES, mode_start_values

    modes = plant.flexible_modes()
    if not 1 <= len(modes) <= MAX_MODES:
        raise ValueError(f"plant {plant.name!r} must have 1 to {MAX_MODES} flexible modes for the shaper FMUs, "
                         f"got {len(modes)}")
    return mode_start_values([(omega / (2.0 * math.pi), zeta) for omega, zeta in modes])


def mode_arrays(modes: dict, fmu) -> dict:
    """The shaper's modes (``modes_hz``) as the FMI 3.0 array parameters f and zeta of ``fmu``, whole:
    the modes first, the FMU's own start values after them (unused: n_modes says how many count)."""
    from fmpy import read_model_description

    declared = {v.name: str(v.start).split() for v in read_model_description(str(fmu)).modelVariables}
    arrays = {"n_modes": modes["n_modes"]}
    for name in ("f", "zeta"):
        given = [modes[f"{name}[{i}]"] for i in range(1, modes["n_modes"] + 1)]
        arrays[name] = given + [float(v) for v in declared[name][len(given):]]
    return arrays


def baked_in(system, fmus: FMUCache, strings_only: bool):
    """``system`` with each slave's bindings baked into a copy of its FMU as start values: the
    String ones, removed from the bindings, for OMSimulator, which imports no String binding (see
    :mod:`shapefmu.fmi.ssp.targets`); every one, the bindings kept, for a native twin, which
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
    if shaper not in SHAPER_KINDS:
        raise ValueError(f"shaper must be one of {', '.join(SHAPER_KINDS)}, got {shaper!r}")
    law = stos_law(plant, shaper, Ts, u_max)
    controller = {"b": b, "U": law.U, "damping": damping, "kind": SHAPER_KINDS[shaper], "Ts": Ts, "settle": True,
                  **modes_hz(plant), **{key: law.settle[key] for key in SETTLE_KEYS}, "target": distance}
    return (System("stos").add("controller", fmus.slave("STOSController"), controller)
            .add("plant", fmus.plant(plant))
            .connect("plant.position", "controller.x_r").connect("plant.velocity", "controller.x_r_dot")
            .connect("controller.u", f"plant.{plant.inputs[0]}"))


def ekf_tuned_moves(rigid, window: float, step: float):
    """(start, command): the identification move, a rest while the EKF converges, then the measured
    move, the same bang-bang again from X to 2X, starting at ``start``."""
    from shapefmu.optimal import Command

    rest = 10.0 * window  # the EKF converges within about five periods of the ring-down (paper 001)
    start = step * math.ceil((rigid.duration + rest) / step)  # on the grid: the run ends a whole number of steps later
    return start, Command((*rigid.breaks, *(start + b for b in rigid.breaks)), (*rigid.levels, 0.0, *rigid.levels))


def ekf_tuned_system(sys_, fmus, moves, distance, step, modes, command):
    """A ReferencePlayer playing ``moves`` into an EKFTuner that drives the plant's input.

    The EKF (paper 001) watches deflection_1 from a guess 10 % below the first mode and designs a
    ZVD shaper for its estimate; the tuner switches the shaper in while the command rests."""
    tuner = {"kind": "zvd", "Ts": step, "omega0": 0.9 * 2.0 * math.pi * modes["f[1]"], "amplitude": 1e-2 * distance}
    return (sys_.add("player", fmus.slave("ReferencePlayer"), {"table": signal_table(moves)})
            .add("tuner", fmus.slave("EKFTuner"), tuner)
            .connect("player.y_mean", "tuner.u").connect("plant.deflection_1", "tuner.vibration")
            .connect("tuner.y", command))
