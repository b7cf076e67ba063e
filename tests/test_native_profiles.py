"""The native C ProfileGenerator FMU beyond the twin contract (tests/test_native_twin_contract.py:
equal to its pythonfmu twin bit for bit with steps that divide the breaks and with random steps, with
the start input, with a bang-bang re-designed in C, in every host, on three platforms, under
valgrind): a restored FMU state (before and after the start latched) replays as the twin runs;
design parameters refuse another value; a move larger than the FMU holds is refused at build time."""

import numpy as np
import pytest

from support.fmpy_slaves import refused_start_values, replayed_run, run_points
from support.twins import PROFILE_GENERATOR

from shapefmu.fmi.native import profiles
from shapefmu.fmi.native.profiles import build_native_profile

OUTPUTS = PROFILE_GENERATOR.outputs


@pytest.mark.parametrize(("save_at", "replay_start"), [(200, 500), (400, 300)])
def test_a_restored_fmu_state_replays_as_the_twin_runs(builds, save_at, replay_start):
    """The state is taken before the start input rises at step 300 (the replay starts the move at
    step 500 instead) or in the middle of the move (the replay runs it on): the replayed rows are
    the native FMU's own and the twin's uninterrupted run with the replay's start."""
    native, twin = PROFILE_GENERATOR.pair(builds, "twin-pulse")
    rng = np.random.default_rng(3)
    times = np.concatenate([[0.0], np.cumsum(rng.uniform(1e-6, 3e-3, 1500))])
    starting = lambda at: [{"start": float(k >= at)} for k in range(len(times) - 1)]  # noqa: E731
    waiting = {"t_start": -1.0}
    rows, replayed = replayed_run(native, times, starting(300), OUTPUTS, save_at, starting(replay_start),
                                  parameters=waiting)
    twin_rows = run_points(twin, times, starting(300), OUTPUTS, parameters=waiting)
    twin_replay = run_points(twin, times, starting(replay_start), OUTPUTS, parameters=waiting)
    assert rows == twin_rows and replayed == twin_replay[save_at:]
    assert replayed[0] == twin_rows[save_at] and (replayed != rows[save_at:]) == (replay_start != 300)
    assert twin_replay[replay_start - 1][0] == 0.0 and twin_replay[replay_start][2] != 0.0  # the latch moved


@pytest.mark.parametrize(("starts", "words"), [
    ({"distance": 2.0}, "distance is 1.7 in this native FMU, whose move is designed at build time; got 2"),
    ({"profile": "TP"}, "profile is BC:TZ in this native FMU"),
    ({"null": 3}, "null is 2 in this native FMU"),
    ({"t_start": float("inf")}, "t_start must be finite, got inf"),
    ({"speed": -1.0}, "speed is 0.69999999999999996 in this native FMU"),  # a twin-pulse build: its design stays
])
def test_design_parameters_of_a_twin_pulse_keep_their_build_values(builds, capfd, starts, words):
    native, _ = PROFILE_GENERATOR.pair(builds, "twin-pulse")
    assert refused_start_values(native, starts, when_set=True).status == 3 and words in capfd.readouterr().out


@pytest.mark.parametrize(("starts", "words"), [
    ({"speed": -1.0}, "speed must be >= 0 (0: no speed limit), got -1"),
    ({"shaper": "ei"}, "shaper must be none or a kind this FMU designs in C (zv, zvd, zvdd, zv_dn, mzv), got ei"),
    ({"profile": "TP"}, "profile is bang-bang in this native FMU"),
])
def test_a_bang_bang_refuses_what_it_cannot_re_design(builds, capfd, starts, words):
    native, _ = PROFILE_GENERATOR.pair(builds, "shaped bang-bang")
    refused_start_values(native, starts, when_set=True)
    assert words in capfd.readouterr().out


def test_a_move_larger_than_the_bound_is_refused_before_any_c_is_written(tmp_path, monkeypatch):
    monkeypatch.setattr(profiles, "MAX_LEVELS", 2)
    with pytest.raises(ValueError, match=r"the move has \d+ pieces, more than the 2 a native ProfileGenerator holds"):
        build_native_profile(tmp_path / "Big.fmu")
    assert not (tmp_path / "Big.fmu").exists()
