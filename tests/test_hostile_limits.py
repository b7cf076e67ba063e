"""Inputs that used to run for minutes, exhaust memory or pass silently: each is refused (or warned
about) with its size estimate against the documented limit of shapefmu.runtime.limits."""

import math

import pytest
from hostile_support import guarded, time_limit

from shapefmu.analysis import residual_vibration
from shapefmu.cosim import Master
from shapefmu.fmi.ssp import System
from shapefmu.fmi.variable_types import typed_value
from shapefmu.runtime import shaper_designs
from shapefmu.shapers import check_sampling, design, zv

TWENTY_MODES = [(2 * math.pi * 10 * (i + 1), 0.0) for i in range(20)]


@pytest.fixture(autouse=True)
def bounded_time():
    with time_limit(60):
        yield


@pytest.fixture(scope="module")
def shaper_ssp(tmp_path_factory, shaper_fmu):
    """The ZV Shaper FMU of fixtures_fmi (10 Hz, Ts = 1 ms) alone in a system."""
    return System("alone").add("shaper", shaper_fmu).write_ssp(tmp_path_factory.mktemp("alone") / "alone.ssp")


# --- the design layer ------------------------------------------------------------------------------


def test_zvd_over_twenty_modes_is_refused_with_its_impulse_count():
    # 3^20 impulses: the convolution took minutes and gigabytes before it was estimated first.
    message = r"zvd convolved over 20 modes \(3 x 3 x .* x 3\) would have 3,486,784,401 impulses, more than the " \
              r"limit of 10,000 \(shapefmu.runtime.limits.MAX_IMPULSES\)"
    with pytest.raises(ValueError, match=message):
        design("zvd", TWENTY_MODES)
    with pytest.raises(ValueError, match=message):
        shaper_designs.design_impulses("zvd", TWENTY_MODES)  # what a Shaper FMU runs


def test_zvd_over_four_modes_stays_within_the_limit_and_is_exact():
    shaper = design("zvd", TWENTY_MODES[:4])
    assert len(shaper) <= 3**4
    assert max(residual_vibration(shaper, w, z) for w, z in TWENTY_MODES[:4]) < 1e-12


@pytest.mark.parametrize("argv, words", [
    (["design", "zvd", *[a for i in range(20) for a in ("--mode", str(10 * (i + 1)))]], "3,486,784,401 impulses"),
    (["design", "zv_dn", "--mode", "10", "--n", "2000"], "n must be in [0, 100]"),
    (["design", "hanning", "--mode", "10:0.05", "--ts", "1e-9"], "2.003e+08 samples, more than the limit of 1,000,000"),
    (["design", "hanning", "--mode", "10:0.05", "--ts", "1e-9", "--adjust-ts"], "MAX_SAMPLED_LENGTH"),
    (["design", "hanning", "--mode", "10", "--order", "1000"], "80,320,099,500 multiply-adds"),
    (["profile", "TP", "--mode", "1", "--distance", "1", "--speed", "1", "--ts", "1e-12"], "5e+11 samples"),
    (["stos", "models/disk_drive.toml", "--distance", "0.05", "--t-end", "1e9"], "MAX_RESULT_BYTES"),
])
def test_a_design_past_a_limit_is_one_line_with_its_estimate(argv, words):
    code, _, err = guarded(argv)
    assert code == 2 and err.count("\n") == 1 and err.startswith(f"shapefmu {argv[0]}: error: ") and words in err


# --- FMUs at initialisation --------------------------------------------------------------------------


def test_a_shaper_fmu_with_a_picosecond_period_fails_initialisation_with_its_delay_line(shaper_ssp):
    code, _, err = guarded(["simulate", str(shaper_ssp), "--stop", "0.01", "--step", "1e-3",
                            "--set", "shaper.Ts=1e-12"])
    assert code == 1 and err.count("\n") == 1
    assert "fmi2ExitInitializationMode returned" in err and "(error)" in err
    assert "sampled at Ts = 1e-12 s has a delay line of 5e+10 samples, more than the limit of 1,000,000" in err


def test_a_shape_filter_fmu_of_order_1000_fails_initialisation_with_its_cost(shape_filter_fmu, tmp_path):
    ssp = System("filter").add("filter", shape_filter_fmu).write_ssp(tmp_path / "filter.ssp")
    code, _, err = guarded(["simulate", str(ssp), "--stop", "0.01", "--step", "1e-3", "--set", "filter.order=1000"])
    assert code == 1 and err.count("\n") == 1
    assert "order 1000 of a " in err and "multiply-adds, more than the limit of 50,000,000" in err


def test_a_shaper_fmu_above_nyquist_warns_through_its_logger(shaper_ssp):
    # 1 kHz sampled at 1 ms: the shaped command leaves the whole vibration (design layer, exactly 1).
    omega = 2 * math.pi * 1000.0
    assert residual_vibration(zv(omega).on_grid(1e-3), omega, 0.0) == pytest.approx(1.0, abs=1e-12)
    with Master(shaper_ssp, 1e-3) as master:
        master.run(0.01, parameters={"shaper.f[1]": 1000.0})
        logged = list(master.units[0].messages)
    assert any(m.startswith("[fmi2Warning] Shaper shaper: mode f[1] = 1000.0 Hz is at or above the Nyquist "
                            "frequency 1/(2 Ts) = 500 Hz of Ts = 0.001 s") for m in logged), logged
    code, _, err = guarded(["simulate", str(shaper_ssp), "--stop", "0.01", "--step", "1e-3",
                            "--set", "shaper.f[1]=1000"])
    assert code == 0 and "shapefmu simulate: warning: component 'shaper': Shaper shaper: mode f[1]" in err


def test_the_design_layer_refuses_a_mode_above_nyquist_unless_asked(tmp_path):
    with pytest.raises(ValueError, match=r"mode 1 \(1000 Hz\) is at or above the Nyquist frequency 500 Hz"):
        check_sampling([(2 * math.pi * 1000.0, 0.0)], 1e-3)
    assert check_sampling([(2 * math.pi * 1000.0, 0.0)], 1e-3, allow_aliasing=True) == 1e-3
    assert check_sampling([(2 * math.pi * 499.0, 0.0)], 1e-3) == 1e-3
    argv = ["build", "shaper", "--mode", "1000", "--ts", "1e-3", "-o", str(tmp_path / "S.fmu")]
    code, _, err = guarded(argv)
    assert code == 2 and "--allow-aliasing" in err and not (tmp_path / "S.fmu").exists()


# --- values for FMU variables -------------------------------------------------------------------------


def test_a_fractional_integer_parameter_is_refused_not_truncated(shaper_ssp, shaper_fmu):
    code, _, err = guarded(["simulate", str(shaper_ssp), "--stop", "0.01", "--step", "1e-3",
                            "--set", "shaper.n_modes=1.5"])
    assert code == 2 and err.count("\n") == 1
    assert "parameter shaper.n_modes must be an integer in [-2147483648, 2147483647] (Integer), got '1.5'" in err
    with pytest.raises(ValueError, match=r"n_modes' must be an integer in \[-2147483648, 2147483647\] \(Integer\), got 1.5"):
        System("s").add("shaper", shaper_fmu, {"n_modes": 1.5})


@pytest.mark.parametrize("kind, value, expected", [
    ("Integer", 2.0, 2), ("Integer", "3", 3), ("Integer", 1e30, None), ("Integer", True, None), ("Integer", "x", None),
    ("Integer", 2**31, None), ("Boolean", "false", False), ("Boolean", 2, None), ("Real", 10**400, None),
    ("Real", "1e-3", 1e-3), ("String", "zvd", "zvd"),
])
def test_fmi_values_keep_their_value_or_are_refused(kind, value, expected):
    if expected is None:
        with pytest.raises(ValueError, match=rf"x must be .* \({kind}\), got"):
            typed_value(value, kind, None, "x")
    else:
        assert typed_value(value, kind, None, "x") == expected


# --- the master's run -------------------------------------------------------------------------------------


def test_an_infinite_output_interval_is_one_line(shaper_ssp):
    code, _, err = guarded(["simulate", str(shaper_ssp), "--stop", "0.01", "--step", "1e-3",
                            "--output-interval", "inf"])
    assert code == 2 and err.count("\n") == 1 and "output_interval must be a finite whole multiple > 0" in err


def test_a_run_whose_results_need_petabytes_is_refused_before_the_first_step(shaper_ssp):
    # 1e12 s at 1 ms: 1e15 rows of time and y, 16 PB (14.2 PiB) of results.
    code, _, err = guarded(["simulate", str(shaper_ssp), "--stop", "1e12", "--step", "1e-3"])
    assert code == 2 and err.count("\n") == 1
    assert "(1e+15 rows) needs 1.6e+16 bytes, more than the limit of 2,147,483,648" in err
    assert "MAX_RESULT_BYTES" in err
