"""Modes a person sees on real printers' spectra (issue 32, part B): the nine development recordings
of tests/data/recordings (SOURCES), judged against the peaks a plain peak finder sees in Klipper's
plotted spectrum.

The reference is computed here from the CSV alone, by Klipper's documented normalisation
(``normalize_to_frequencies`` of shaper_calibrate.py at the Klipper commit in
tests/data/recordings/SOURCES's sibling /work/klipper/COMMIT, 84104bbb: the PSD over f + 0.1, times
exp(1 - (10 / (f + 0.1))^2) below 10 Hz; files that carry shaper columns are already normalised) and
``scipy.signal.find_peaks`` with a height of 10 % of the maximum: every such peak must be a mode, no
mode may sit where the spectrum is under 5 % of its maximum.

A peak's bin in these files is 1.5-1.6 Hz wide (printed to 0.1 Hz), up to 2.4 % of a 32 Hz peak: the
peak's frequency is taken between bins by the parabola through the highest bin and its two
neighbours (the usual three-point estimate), and a mode's peak, its damped frequency
f sqrt(1 - zeta^2), must lie within 1 % of it.
"""

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.signal import find_peaks

from shapefmu.identification import identify

FOLDER = Path(__file__).parent / "data" / "recordings"
FILES = sorted(p.name for p in FOLDER.glob("*.csv"))


def klipper_plotted(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """(freq, psd_xyz as Klipper plots it) read with NumPy alone."""
    header = path.read_text().splitlines()[0].split(",")
    table = np.genfromtxt(path, delimiter=",", skip_header=1)
    freq, psd = table[:, 0], table[:, header.index("psd_xyz")].copy()
    if not any("(" in name for name in header):
        psd /= freq + 0.1
        low = freq < 10
        psd[low] *= np.exp(1 - (10 / (freq[low] + 0.1)) ** 2)
    keep = freq > 0
    return freq[keep], psd[keep]


@pytest.fixture(scope="module")
def found():
    return {name: identify(FOLDER / name).modes.modes for name in FILES}


def test_the_nine_development_recordings_are_there():
    assert len(FILES) == 9


@pytest.mark.parametrize("name", FILES)
def test_every_peak_above_a_tenth_is_a_mode_where_the_peak_is(found, name):
    """One mode per peak, ringing where the peak is (V0 and V2.4 modes sat 6-8 % above it)."""
    freq, psd = klipper_plotted(FOLDER / name)
    peaks, _ = find_peaks(psd, height=0.1 * psd.max())
    modes = found[name]
    assert len(modes) == len(peaks), ([m.describe() for m in modes], freq[peaks])
    for i in peaks:
        left, middle, right = psd[i - 1:i + 2]
        at = freq[i] + 0.5 * (left - right) / (left - 2 * middle + right) * (freq[i + 1] - freq[i])
        nearest = min(modes, key=lambda m: abs(m.damped_frequency - at))
        assert abs(nearest.damped_frequency / at - 1) <= 0.01, (at, nearest.describe())


@pytest.mark.parametrize("name", FILES)
def test_no_mode_where_the_spectrum_is_under_a_twentieth_of_its_maximum(found, name):
    freq, psd = klipper_plotted(FOLDER / name)
    for mode in found[name]:
        assert np.interp(mode.damped_frequency, freq, psd) >= 0.05 * psd.max(), mode.describe()


def test_two_peaks_with_a_dip_between_them_are_two_modes(found):
    """Ender 3 X: the peaks at 45.0 and 59.4 Hz were one mode at 52.7 Hz, zeta 0.216."""
    modes = found["ender3_resonances_x_20210821_152037.csv"]
    for at in (45.0, 59.4):
        assert any(abs(m.damped_frequency - at) <= 0.8 for m in modes), [m.describe() for m in modes]
    assert not any(50.0 < m.damped_frequency < 55.0 for m in modes)


def test_a_peak_at_half_the_main_height_is_found(found):
    """Switchwire X: the 37.5 Hz peak at half the main one's height was missed."""
    assert any(abs(m.damped_frequency - 37.5) <= 0.8 for m in found["switchwire_resonances_x_20211024_204517.csv"])


def test_v24_reports_nothing_in_its_floor_above_100_hz(found):
    """V2.4 X and Y: modes at 105-133 Hz, 1-5 % of the maximum, were reported and designed for."""
    for name in ("v24_resonances_x_20230306_224517.csv", "v24_resonances_y_20230306_224919.csv"):
        assert not [m for m in found[name] if m.frequency > 100], [m.describe() for m in found[name]]


@pytest.mark.parametrize("name", FILES)
def test_each_mode_has_a_damping_interval_around_it(found, name):
    for mode in found[name]:
        low, high = mode.zeta_interval
        assert 0 < low <= mode.zeta <= high <= 1 and math.isfinite(mode.frequency_sd)


@pytest.mark.parametrize("module", ["recordings", "spectra", "poles", "modes", "synthetic_chain", "metrics", "judge",
                                    "klipper", "firmware", "families", "trains", "recommend"])
def test_the_docstring_examples_run(module):
    import doctest
    import importlib

    result = doctest.testmod(importlib.import_module(f"shapefmu.identification.{module}"))
    assert result.attempted > 0 and result.failed == 0
