"""Klipper's numbers, exactly (issue 32, item 1): shapefmu's rebuilding of Klipper's spectrum reading,
shapers, remaining vibration, smoothing, max_accel, score, frequency scan and pick, against the figures
Klipper's own functions print for the development recordings (tests/data/klipper/klipper_figures.json,
printed by Klipper at the commit it names, outside shapefmu; see tests/data/klipper/SOURCES)."""

import json
import math
from pathlib import Path

import numpy as np
import pytest

from shapefmu.identification import klipper, metrics
from shapefmu.identification.judge import Judge

DATA = Path(__file__).parent / "data"
FIGURES = json.loads((DATA / "klipper" / "klipper_figures.json").read_text())
FILES = sorted(FIGURES["files"])


def path_of(name):
    folder = DATA / "recordings" if (DATA / "recordings" / name).exists() else DATA / "klipper"
    return folder / name


def judge_of(name):
    return Judge([klipper.read_spectrum_file(path_of(name))["xyz"]])


def test_the_figures_are_klippers_at_the_commit_the_definitions_were_read_at():
    assert FIGURES["klipper_commit"] == klipper.KLIPPER_COMMIT
    assert len([f for f in FILES if (DATA / "recordings" / f).exists()]) == 9  # the nine development recordings


@pytest.mark.parametrize("name", FILES)
def test_six_shapers_at_three_frequencies_score_as_klipper_scores_them(name):
    """Vibration, smoothing, max_accel and score of zv, mzv, zvd, ei, 2hump_ei, 3hump_ei at three
    frequencies each, to 1e-6 relative of Klipper's own figures."""
    judge = judge_of(name)
    points = FIGURES["files"][name]["points"]
    assert len(points) == 18
    for point in points:
        times, amplitudes = klipper.SHAPERS[point["name"]].impulses(point["freq"])
        ours = [float(x[0]) for x in judge.measures(times[None], amplitudes[None], max_freq=max(200.0, point["freq"]))]
        theirs = [point[k] for k in ("vibrations", "smoothing", "max_accel", "score")]
        for value, reference in zip(ours, theirs):
            assert value == pytest.approx(reference, rel=1e-6, abs=1e-12), (point, ours)


@pytest.mark.parametrize("name", FILES)
def test_klippers_pick_and_its_fitted_shapers_are_klippers(name):
    """The pick Klipper prints ('Recommended shaper is mzv @ 46.6 Hz') and the frequency it fits for
    each shaper, found by our rebuilding of its scan and rules."""
    judge = judge_of(name)
    best, chosen = klipper.pick(judge)
    theirs = FIGURES["files"][name]["pick"]
    assert (best.name, f"{best.freq:.1f}") == (theirs["name"], f"{theirs['freq']:.1f}")
    assert best.freq == theirs["freq"] and best.score == pytest.approx(theirs["score"], rel=1e-6)
    fitted = {r["name"]: r for r in FIGURES["files"][name]["fitted"]}
    for shaper in chosen:
        assert shaper.freq == fitted[shaper.name]["freq"], shaper
        assert shaper.vibration == pytest.approx(fitted[shaper.name]["vibrations"], rel=1e-6, abs=1e-12)
    zvd, _ = klipper.fit(judge, "zvd")
    assert zvd.freq == fitted["zvd"]["freq"]


def test_the_examples_of_issue_32_item_1():
    """A ZV of two equal impulses 10 ms apart: Klipper's find_shaper_max_accel gives 9600 mm/s^2 (the
    reversal term, sum of a/2 d^2 over both impulses: 2 * 0.12 / 2.5e-5); an MZV at 50 Hz 7365."""
    assert float(metrics.max_accel([0.0, 0.01], [1.0, 1.0])) == pytest.approx(9600.0, rel=1e-12)
    times, amplitudes = klipper.SHAPERS["mzv"].impulses(50.0)
    assert round(float(metrics.max_accel(times, amplitudes))) == 7365


def test_max_accel_is_where_the_smoothing_reaches_the_bound():
    """The closed form against the definition: at max_accel the smoothing is 0.12 mm, above it more."""
    for name, shaper in klipper.SHAPERS.items():
        times, amplitudes = shaper.impulses(47.3)
        limit = float(metrics.max_accel(times, amplitudes))
        assert float(metrics.smoothing(times, amplitudes, limit)) == pytest.approx(0.12, rel=1e-12), name
        assert float(metrics.smoothing(times, amplitudes, limit * (1 + 1e-9))) > 0.12, name


def test_the_shapers_vanish_the_vibration_they_are_designed_for():
    """Undamped at their frequency: zv, zvd and mzv leave nothing; mzv also nothing at 5/3 of it;
    the EI family leaves its 5 % tolerance or less (Singhose's design)."""
    f = 40.0
    for name in ("zv", "zvd", "mzv"):
        times, amplitudes = klipper.SHAPERS[name].impulses(f, 0.0)
        assert float(metrics.residual(times, amplitudes, [f], [0.0])[0, 0]) < 1e-12, name
    times, amplitudes = klipper.SHAPERS["mzv"].impulses(f, 0.0)
    assert float(metrics.residual(times, amplitudes, [f * 5 / 3], [0.0])[0, 0]) < 1e-12
    for name in ("ei", "2hump_ei", "3hump_ei"):
        times, amplitudes = klipper.SHAPERS[name].impulses(f, 0.1)
        assert float(metrics.residual(times, amplitudes, [f], [0.1])[0, 0]) <= 0.051, name


def test_a_shaper_refuses_a_damping_ratio_klipper_refuses():
    with pytest.raises(ValueError, match=r"3hump_ei shaper's damping_ratio must be in \[0, 0.2\], got 0.25"):
        klipper.SHAPERS["3hump_ei"].impulses(50.0, 0.25)


def test_a_file_klipper_wrote_with_shapers_is_read_unnormalised_and_an_older_one_normalised_again():
    """Klipper's rule: a header with ',shapers:' holds normalised power; the development
    calibration_data file (an older header, shapers listed without ',shapers:') is normalised again,
    and gives Klipper's pick for it, the same as the resonances file it came from."""
    written = klipper.read_spectrum_file(DATA / "klipper" / "switchwire_x_calibration_data_written_by_klipper.csv")
    raw = klipper.read_spectrum_file(DATA / "recordings" / "switchwire_resonances_x_20211024_204517.csv")
    assert "already normalised" in written["xyz"].settings and "normalised as Klipper does" in raw["xyz"].settings
    # Klipper wrote the normalised power with 4 significant digits
    np.testing.assert_allclose(written["xyz"].psd[1:], raw["xyz"].psd[1:], rtol=6e-4, atol=1e-3 * raw["xyz"].psd.max())
    old = klipper.read_spectrum_file(DATA / "recordings" / "v24_calibration_data_x_20230306_225431.csv")
    assert "normalised as Klipper does" in old["xyz"].settings


def test_the_normalisation_is_klippers():
    """P / (f + 0.1), times exp(1 - (10 / (f + 0.1))^2) below 10 Hz (normalize_to_frequencies)."""
    freq = np.array([0.0, 5.0, 9.9, 10.0, 100.0])
    expected = [0.0, math.exp(1 - (10 / 5.1) ** 2) / 5.1, math.exp(1 - (10 / 10.0) ** 2) / 10.0, 1 / 10.1, 1 / 100.1]
    np.testing.assert_allclose(klipper.normalize_psd(freq, np.ones(5)), expected, rtol=1e-15)


def test_klippers_spectrum_of_a_recording_is_welch_with_its_window():
    """recording_psd against a plain loop of its definition: Kaiser(6) segments of 2048 samples at
    3.2 kHz, half overlapping, means removed, |FFT|^2 / (fs sum w^2), doubled but for DC and Nyquist,
    averaged, the axes summed, normalised."""
    from shapefmu.identification.recordings import Recording

    rng = np.random.default_rng(3)
    n, fs = 9000, 3200.0 * 8999 / 9000  # Klipper's rate is samples / duration: 3200 Hz here
    channels = {a: rng.normal(size=n) for a in "xyz"}
    found = klipper.recording_psd(Recording("r", "table", fs, channels, "as recorded"))
    m = 2048
    window = np.kaiser(m, 6.0)
    total = 0.0
    for samples in channels.values():
        starts = range(0, n - m + 1, m // 2)
        segments = [(samples[s:s + m] - samples[s:s + m].mean()) * window for s in starts]
        power = np.mean([np.abs(np.fft.rfft(seg)) ** 2 for seg in segments], axis=0) / (3200.0 * (window ** 2).sum())
        power[1:-1] *= 2
        total = total + power
    freq = np.fft.rfftfreq(m, 1 / 3200.0)
    np.testing.assert_allclose(found.freq, freq, rtol=1e-12)
    np.testing.assert_allclose(found.psd, klipper.normalize_psd(freq, total), rtol=1e-9)
