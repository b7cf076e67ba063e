"""The TrackedShaper FMU (fmi/kinds/tracked_shaper.py) in fmpy: its FMU state restores the run exactly,
and a measurement that is not a number is refused naming it. Its closed loop is tests/test_tracked_cosim.py."""

import math

import numpy as np
import pytest
from support.fmpy_slaves import initialised

TS = 5e-4


def feed(slave, vr, k0, commands, measurements):
    """y at each sample k0, k0 + 1, ...: both inputs set, y read, the step taken."""
    y = []
    for k, (u, m) in enumerate(zip(commands, measurements), start=k0):
        slave.setReal([vr["u"], vr["measurement"]], [float(u), float(m)])
        y.append(slave.getReal([vr["y"]])[0])
        slave.doStep(k * TS, TS)
    return y


def test_a_restored_state_gives_the_same_run_again(tracked_fmu):
    """The command rests before the first sample (the kernel counts that as rested for ever): the state
    holds no inf, and restoring it replays the moves and the rings the EKF watches bit for bit."""
    t = np.arange(1200) * TS
    commands = np.where((t > 0.01) & (t < 0.03) | (t > 0.3) & (t < 0.32), 5.0, 0.0)
    measurements = 0.3 * np.exp(-5.0 * t) * np.sin(2.0 * math.pi * 30.0 * t)
    slave, vr = initialised(tracked_fmu)
    feed(slave, vr, 0, commands[:10], measurements[:10])  # taken while the command still rests since before t0
    state = slave.deSerializeFMUstate(slave.serializeFMUstate(slave.getFMUstate()))
    first = feed(slave, vr, 10, commands[10:], measurements[10:])
    slave.setFMUstate(state)
    again = feed(slave, vr, 10, commands[10:], measurements[10:])
    slave.freeInstance()
    assert again == first and np.ptp(first) > 0


def test_a_measurement_that_is_not_a_number_is_refused(tracked_fmu):
    from fmpy.fmi1 import FMICallException

    slave, vr = initialised(tracked_fmu)
    with pytest.raises(FMICallException):
        slave.setReal([vr["measurement"]], [float("nan")])
    slave.freeInstance()
