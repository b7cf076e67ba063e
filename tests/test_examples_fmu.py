"""The papers end to end through FMUs (examples/paper00*_fmu.py) agree with the design layer.

Each example's ``run()`` drives FMUs with the co-simulation master; the FMUs come from the session
fixtures (tests/support/fixtures_fmi.py, fixtures_plants.py) where one fits, parameter bindings setting what
their start values do not. Every tolerance below is derived in the test's comment or in the
example's docstring; none is a measured difference widened.
"""

from __future__ import annotations

import math
import shutil
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
sys.path.insert(0, str(EXAMPLES))

import paper000_window_filters_fmu as paper000  # noqa: E402
import paper001_ekf_fmu as paper001  # noqa: E402
import paper002_stos_fmu as paper002  # noqa: E402
import paper003_ten_pendula_fmu as paper003  # noqa: E402
import paper004_time_frequency_fmu as paper004  # noqa: E402

from shapefmu.analysis import residual_vibration  # noqa: E402
from shapefmu.plants import library  # noqa: E402
from shapefmu.stos import stos_law  # noqa: E402


# --- paper 000: window filters' sensitivity -------------------------------------------------------

@pytest.fixture(scope="module")
def paper000_result(feedthrough_filter_fmu):
    return paper000.run({"filter": feedthrough_filter_fmu})


def test_window_filter_sensitivity_through_fmus_equals_eq_4_and_5(paper000_result):
    # Exact by construction (the staircase of a shaped step is the impulses convolved with a step,
    # and the plant FMU's zero-order hold is exact): only rounding separates the two, ~1e-14 of
    # values of order 0.1-1; 1e-10 leaves room for the C matrix exponential and nothing else.
    for (kind, zeta), curve in paper000_result["curves"].items():
        for definition in ("percent", "absolute"):
            np.testing.assert_allclose(curve["fmu"][definition], curve["design"][definition], rtol=0, atol=1e-10,
                                       err_msg=f"{kind}, zeta = {zeta}, {definition}")


def test_window_filter_headline_band_and_tail_match_the_design_layer(paper000_result):
    for kind, h in paper000_result["headline"].items():
        shaper = paper000.DESIGNS[kind](1.0, paper000.HEADLINE_ZETA, paper000.paper_ts(paper000.HEADLINE_ZETA))
        # Band edges: both found by Brent's method (xtol 1e-10 on FMU runs, 1e-12 in the design
        # layer) on curves equal to 1e-10, whose slope at the edges is > 0.1 per unit q.
        assert h["fmu_band"][0] == pytest.approx(h["design_band"][0], abs=1e-8)
        assert h["fmu_band"][1] == pytest.approx(h["design_band"][1], abs=1e-8)
        # The tail maximum: the FMU path refines its grid maximum; the reference is the design
        # layer's curve maximised the same way (bounded Brent, xatol 1e-7: V is flat at a peak, so
        # the value is good to ~V'' 1e-14).
        grid = paper000.TAIL_Q
        k = int(np.argmax(residual_vibration(shaper, grid, paper000.HEADLINE_ZETA)))
        peak = minimize_scalar(lambda q: -residual_vibration(shaper, q, paper000.HEADLINE_ZETA),
                               bounds=(grid[max(k - 1, 0)], grid[min(k + 1, grid.size - 1)]), method="bounded",
                               options={"xatol": 1e-7})
        assert h["fmu_tail"] == pytest.approx(max(-peak.fun, residual_vibration(shaper, grid[k], 0.05)), rel=1e-8)
    # Paper 000's claim (Fig. 2-3): the Hanning filter is more robust near and far above the design.
    rectangle, hanning = paper000_result["headline"]["rectangle"], paper000_result["headline"]["hanning"]
    assert hanning["fmu_band"][0] < rectangle["fmu_band"][0] and hanning["fmu_band"][1] > rectangle["fmu_band"][1]
    assert hanning["fmu_tail"] < 0.1 * rectangle["fmu_tail"]


# --- paper 001: EKF-tuned shaping ---------------------------------------------------------------

@pytest.fixture(scope="module")
def paper001_result(ekf_fmu, reference_fmu):
    return paper001.run({"tuner": ekf_fmu, "player": reference_fmu})


def test_ekf_tuned_cosimulation_equals_the_design_layer_on_the_recorded_signals(paper001_result):
    # Second method: estimation.EKFTunedShaper on the samples the tuner FMU consumed, convolved with
    # the rig FMU's pulse response; the same arithmetic in another order, on responses of 0.1.
    assert paper001_result["second_method_deviation"] <= 1e-14


def test_ekf_tuned_table_matches_the_design_example(paper001_result):
    rows, design = paper001_result["rows"], paper001_result["design"]
    for key in ["none"] + [(g, k) for g in paper001.GUESSES for k in paper001.SHAPERS]:
        fmu, ref = rows[key], design[key]
        # Largest amplitude: the FMU path's impulse is a 1 ms pulse through a zero-order hold, whose
        # response lags the sampled one by half a sample: a sampled peak moves by at most
        # 1 - cos(omega_d Ts / 2) = 5e-4 of itself; the noise-free watch changes the EKF's estimate
        # by ~1e-4 of omega, which moves a ZV's 0.05 peak by less than that. 1 % covers both.
        assert fmu[0] == pytest.approx(ref[0], rel=1e-2), key
        # Settling time to 3 %: counted in whole samples, with the half-sample lag: 2 samples.
        assert abs(fmu[1] - ref[1]) <= 2 / paper001.FS + 1e-9, key
    # Paper 001's conclusions (Table 1): more impulses, smaller peak; ZVDD damps the most.
    for guess in paper001.GUESSES:
        zv, zvd, zvdd = (rows[guess, k] for k in paper001.SHAPERS)
        assert zv[0] > zvd[0] > zvdd[0] and zv[2] < zvd[2] < zvdd[2], guess


# --- paper 002: STOS on the disk drive ------------------------------------------------------------

@pytest.fixture(scope="module")
def paper002_result(stos_fmu, tmp_path_factory):
    """The project's models/disk_drive_stos.ssd, its FMUs where its sources point (../fmus/)."""
    from shapefmu.compare import measured_plant
    from shapefmu.fmi.native import build_plant_fmu

    root = tmp_path_factory.mktemp("paper002")
    (root / "models").mkdir()
    (root / "fmus").mkdir()
    ssd = shutil.copy(paper002.SYSTEM, root / "models" / paper002.SYSTEM.name)
    shutil.copy(stos_fmu, root / "fmus" / "STOSController.fmu")
    build_plant_fmu(measured_plant(library.disk_drive()), root / "fmus" / "DiskDriveMeasured.fmu")
    return paper002.run(ssd)


def test_stos_through_fmus_reproduces_the_design_layer_seek(paper002_result):
    for kind, r in paper002_result["runs"].items():
        # Gauss-Seidel hands the plant the law evaluated at the same samples as simulate_stos, on
        # the exact zero-order hold: the same trajectory up to rounding (x_r ~ 0.1 rad).
        assert r["largest_state_difference"] <= 1e-12, kind
        assert r["largest_u_difference"] <= 1e-5 * library.DISK_DRIVE_U, kind
        # So the move ends on the same sample, and the vibration left is the same.
        assert r["fmu_move_time"] == pytest.approx(r["design_move_time"], abs=paper002.TS / 2), kind
        np.testing.assert_allclose(r["fmu_residual"], r["design_residual"], rtol=1e-6, err_msg=kind)
        # Slower than the CasADi time-optimal move of the full plant, faster than the rigid
        # bang-bang stretched by the shaper's length (the bound examples/stos_disk_drive.py prints).
        shaper = stos_law(library.disk_drive(), kind, Ts=paper002.TS).shaper
        assert paper002_result["optimal_T"] < r["fmu_move_time"], kind
        assert r["fmu_move_time"] <= paper002_result["rigid_T"] + shaper.duration + 2 * paper002.TS, kind
    runs = paper002_result["runs"]
    # Paper 002: the simultaneous shaper's STOS is faster (12.08 us there, with its shaper times).
    assert runs["simultaneous"]["fmu_move_time"] < runs["convolution"]["fmu_move_time"]


# --- paper 003: ten pendula as a sweep -------------------------------------------------------------

@pytest.fixture(scope="module")
def paper003_result(profile_fmu, plant_fmus):
    return paper003.run({"profile": profile_fmu, "plant": plant_fmus["ten_pendula"]})


def test_ten_pendula_sweep_matches_the_design_layer_within_the_sampling_bound(paper003_result):
    for name, r in paper003_result.items():
        assert np.all(r["rows"]["status"] == "ok") and r["rows"].size == 10, name
        # The FMU path holds the move's point values over 0.25 ms steps: within sampling_bound of
        # the continuous move (example docstring), which the design example's 1 ms sampled
        # profile matches to |design - continuous|.
        allowed = r["bound_deg"] + np.abs(r["design_deg"] - r["continuous_deg"])
        assert np.all(np.abs(r["fmu_deg"] - r["design_deg"]) <= allowed), name
    classic, expanded = (paper003_result[n]["fmu_deg"].max() for n in ("classic twin pulse", "M-BC:TZ:TP"))
    # Paper 003's headline: M-BC:TZ:TP leaves at most 3 % of the classic twin pulse's swing (97 %).
    assert expanded <= 0.03 * classic


# --- paper 004: time-frequency seek ------------------------------------------------------------------

@pytest.fixture(scope="module")
def paper004_result(profile_fmu, plant_fmus):
    return paper004.run({"profile": profile_fmu, "plant": plant_fmus["disk_drive"]})


def test_time_frequency_seek_through_fmus_has_the_design_scale_and_leakage(paper004_result):
    r = paper004_result
    # n from a log-linear fit of the FMU's exact samples (rounding ~1e-15 relative in the logs),
    # against the design layer's bounded minimisation (xatol 1e-6).
    assert r["fmu_n"] == pytest.approx(r["design_n"], abs=2e-6)
    assert r["fmu_n"] == pytest.approx(11.41, abs=0.005)  # the paper, to its two decimals
    # 1 - J by Simpson quadrature of |G|^2 on 40001 points (error ~h^4 of a smooth integrand),
    # against the closed form; the energy above omega_0 is 2e-5 of the total, so 1e-4 relative.
    assert r["fmu_leakage"] == pytest.approx(r["design_leakage"], rel=1e-4)


def test_time_frequency_seek_leaves_the_design_layers_vibration(paper004_result):
    r = paper004_result
    # The plant FMU's zero-order hold against optimal.simulate on the design's samples: both exact,
    # on deflections of ~1 track during the move.
    assert r["deflection_deviation"] <= 1e-9
    assert r["seek"]["residual"] == pytest.approx(r["design_seek"]["residual"], rel=1e-8)
    # Paper 004: the seek settles within +-5 % track right after the move (2.6 ms for 2.5 ms
    # there); a bang-bang of the same length leaves far more than that.
    assert r["seek"]["residual"] < paper004.BAND and r["seek"]["settle"] <= r["move_end"] + 0.1e-3
    assert r["bang_bang"]["residual"] > 10 * r["seek"]["residual"]
    assert math.isclose(r["bang_bang_final_position"], paper004.TRACKS, rel_tol=1e-9)
