"""The planner's residual checked through a plant FMU of the mode, run in our master.

A sprung mass on the moving axis (models' ``sprung_masses`` kind: 1 kg on a spring and damper tuned
to the 40 Hz, zeta 0.05 mode of issue 36's example; carriage acceleration in, the mass's deflection
out) is generated as a native FMU and driven, in ``shapefmu.cosim.master``, by a ReferencePlayer FMU
playing the planned acceleration (piecewise linear: its values at the phase ends, interpolated
linearly, exact). After the move the deflection is a free damped oscillation; its amplitude is
fitted on it (known frequency and damping, least squares). References: the same plant driven by
Ruckig's rigid move (its ringing: the issue's 78 um) and the closed form of the mode
(support.motion_cases.mode_amplitude, matrix exponentials).
"""

import json
import math

import numpy as np
import pytest

from shapefmu.compare.cache import FMUCache
from shapefmu.cosim.master import Master
from shapefmu.fmi.native import build_plant_fmu, model_from_file
from shapefmu.fmi.ssp import System
from support.motion_cases import example_plan, example_ruckig, mode_amplitude, ruckig_phases

HZ, ZETA = 40.0, 0.05
STEP = 1e-5
SPRUNG_MASS = f"""
name = "sprung_mass_40hz"
kind = "sprung_masses"
description = "1 kg on a spring and damper: a 40 Hz mode with zeta 0.05"

[parameters]
masses = {{ value = [1.0], unit = "kg" }}
stiffnesses = {{ value = [{(2 * math.pi * HZ) ** 2!r}], unit = "N/m" }}
dampers = {{ value = [{2 * ZETA * 2 * math.pi * HZ!r}], unit = "N*s/m" }}

[inputs]
acceleration = {{ unit = "m/s^2" }}

[outputs]
carriage_position = {{ unit = "m" }}
deflection = {{ unit = "m" }}
mass_acceleration = {{ unit = "m/s^2" }}
"""


def _acceleration_table(durations, jerks):
    """A ReferencePlayer table of the acceleration: its value at every phase end, linear between."""
    times, values, t, a = [0.0], [0.0], 0.0, 0.0
    for d, j in zip(durations, jerks):
        t, a = t + d, a + j * d
        times.append(t)
        values.append(a)
    return json.dumps({"kind": "signal_table", "interpolation": "linear", "time": times, "value": values})


def _residual_in_the_master(fmus, plant, durations, jerks):
    """Amplitude of the mass's free oscillation after the move, fitted on the plant FMU's output."""
    T = sum(durations)
    player = fmus.slave("ReferencePlayer", table=_acceleration_table(durations, jerks))
    system = (System("motion").add("plant", plant).add("player", player)
              .connect("player.y_mean", "plant.acceleration"))
    stop = T + 3.0 / HZ
    with Master(system, STEP, record=["plant.deflection"]) as master:
        results = master.run(stop)
    t, y = np.asarray(results["time"]), np.asarray(results["plant.deflection"])
    after = t >= T + 0.25 / HZ  # a few steps clear of the move's end
    w = 2 * math.pi * HZ
    wd, s = w * math.sqrt(1 - ZETA**2), t[after] - T
    basis = np.column_stack([np.exp(-ZETA * w * s) * np.cos(wd * s), np.exp(-ZETA * w * s) * np.sin(wd * s)])
    (c, d), *_ = np.linalg.lstsq(basis, y[after], rcond=None)
    return math.hypot(c, d)


def test_the_40_hz_move_leaves_the_plant_fmu_ringing_less_than_1_percent_of_ruckigs(tmp_path):
    fmus = FMUCache(tmp_path / "fmus", native=True)
    model = tmp_path / "sprung_mass_40hz.toml"
    model.write_text(SPRUNG_MASS)
    plant = build_plant_fmu(model_from_file(str(model)), tmp_path / "sprung_mass_40hz.fmu")
    rigid_durations, rigid_jerks = ruckig_phases(example_ruckig(), 0)
    rigid = _residual_in_the_master(fmus, plant, rigid_durations, rigid_jerks)
    assert rigid == pytest.approx(mode_amplitude((0, 0, 0), rigid_durations, rigid_jerks, HZ, ZETA, 0.0), rel=1e-5)
    assert rigid == pytest.approx(78e-6, rel=0.01)  # the "full ringing (78 um)"
    (_, durations, jerks), = example_plan(0.0).phases
    ours = _residual_in_the_master(fmus, plant, durations, jerks)
    assert ours <= 0.01 * rigid
    assert ours == pytest.approx(mode_amplitude((0, 0, 0), durations, jerks, HZ, ZETA, 0.0), abs=1e-6 * rigid)
