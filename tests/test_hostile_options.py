"""Options whose values were silently changed or overflowed: one line naming the value and the valid
range instead (issue 34, Low items not about recordings).

``--filter-ts 1`` became 0.007 s (a window filter's adjusted period: the design layer adjusted ts far
past a rounding of the window's length, whoever asked), ``--set x=1e400`` became inf,
and a denormal ``--step`` reached ``compare`` as "cannot convert float infinity to integer" and a
sweep as a failure of every run, after they were sent out.
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from hostile_support import guarded

from shapefmu.fmi.ssp import System

MODELS = Path(__file__).resolve().parent.parent / "models"


def one_line(code, err):
    assert code == 2 and len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
    return err


def test_a_filter_period_too_long_is_refused_naming_the_option_and_its_range():
    # recommend bounds it itself (identification/recommend.py's TS_RANGE); the design layer below refuses too
    err = one_line(*guarded(["recommend", "--mode", "40:0.05", "--filter-ts", "1"], seconds=600)[::2])
    assert "--filter-ts" in err and "got 1.0" in err and "0.01]" in err


@pytest.mark.parametrize("adjust", [[], ["--adjust-ts"]], ids=["", "--adjust-ts"])
def test_a_window_period_too_long_is_refused_even_when_adjusting_it(adjust):
    code, out, err = guarded(["design", "hanning", "--mode", "40:0.05", "--ts", "1", *adjust])
    one_line(code, err)
    omega_d = 2 * math.pi * 40 * math.sqrt(1 - 0.05**2)
    assert f"ts must be at most {math.pi / omega_d:.6g} s" in err  # Hanning: M = 4 pi / (omega_d ts) >= 4


def test_a_window_period_a_rounding_of_m_away_is_still_adjusted():
    omega_d = 2 * math.pi * 40 * math.sqrt(1 - 0.05**2)
    ts = 4 * math.pi / (omega_d * 40.4)  # M = 40.4: adjusted to M = 40
    code, out, err = guarded(["design", "hanning", "--mode", "40:0.05", "--ts", repr(ts), "--adjust-ts"])
    assert code == 0 and f"at ts = {4 * math.pi / (omega_d * 40):.10g} s" in out, err


@pytest.fixture(scope="module")
def plant_ssp(plant_fmus, tmp_path_factory):
    return System("plant").add("plant", plant_fmus["disk_drive"]).write_ssp(tmp_path_factory.mktemp("o") / "p.ssp")


@pytest.mark.parametrize("value", ["1e400", "-1e400", "1" + "0" * 400])
def test_a_number_beyond_a_double_is_refused_not_made_infinite(plant_ssp, value):
    err = one_line(*guarded(["simulate", plant_ssp, "--stop", "1e-3", "--step", "1e-3", "--set",
                             f"plant.voltage={value}"])[::2])
    assert "plant.voltage" in err and value[:20] in err and "1.8e308" in err


def test_compare_refuses_a_denormal_step_before_any_design():
    err = one_line(*guarded(["compare", MODELS / "disk_drive.toml", "--distance", "0.05", "--step", "1e-320"])[::2])
    assert "steps of 1e-320 s takes at least inf macro steps" in err and "MAX_MACRO_STEPS" in err


def test_a_sweep_refuses_a_denormal_step_before_sending_out_any_run(plant_ssp, tmp_path):
    err = one_line(*guarded(["sweep", plant_ssp, "--metric", "peak", "--command", "plant.position", "--stop-time",
                             "0.01", "--step", "1e-320", "--vary", "plant.voltage=1,2", "--workers", "1", "--out",
                             tmp_path / "rows.csv"], seconds=600)[::2])
    assert "steps of 1e-320 s takes inf macro steps" in err and "none of the" not in err
    assert not (tmp_path / "rows.csv").exists()
