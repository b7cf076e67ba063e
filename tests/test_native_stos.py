"""The native C STOSController FMU beyond the twin contract (tests/test_native_twin_contract.py:
equal to its pythonfmu twin in closed loop, with random steps, in every host, on three platforms,
under valgrind): its FMU state restores the settle law exactly, and the design parameters refuse
another value than their build value."""

import pytest

from support.fmpy_slaves import initialised, refused_start_values
from support.scenarios import SETTLE, stos_loop
from support.twins import STOS_CONTROLLER


def test_state_restores_the_settle_law_exactly(builds):
    native, _ = STOS_CONTROLLER.pair(builds, "settle")
    slave, vr = initialised(native)
    controls, plant = stos_loop(slave, vr, 320)
    state = slave.getFMUState()
    first, _ = stos_loop(slave, vr, 200, plant, 320)
    slave.setFMUState(state)
    again, _ = stos_loop(slave, vr, 200, plant, 320)
    raw = slave.serializeFMUState(state)
    slave.freeInstance()
    fresh, vr = initialised(native)
    fresh.setFMUState(fresh.deserializeFMUState(raw))
    restored, _ = stos_loop(fresh, vr, 200, plant, 320)
    fresh.freeInstance()
    assert again == first and restored == first


@pytest.mark.parametrize(("starts", "words"), [
    ({"f[1]": 2100.0}, "f[1] is 2000 in this native FMU, whose shaper is designed at build time; got 2100"),
    ({"b": -1.0}, "b must be > 0, got -1"),
    ({"zeta[2]": 1.0}, "zeta[2] must be in [0, 1), got 1"),
    ({"kind": "zvd"}, "kind is simultaneous in this native FMU"),
    ({"n_modes": 1}, "n_modes is 2 in this native FMU"),
    ({"Ts": 0.0}, "Ts must be > 0, got 0"),
    ({"settle": True, **SETTLE, "x_exit": 1e-7}, "with settle on, x_exit must be >= x_enter, got 1e-07"),
])
def test_bad_parameters_are_refused_with_a_logged_message(builds, capfd, starts, words):
    native, _ = STOS_CONTROLLER.pair(builds, "simultaneous")
    assert refused_start_values(native, starts).status == 3 and words in capfd.readouterr().out
