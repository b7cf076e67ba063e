"""identification.fourier against SciPy's signal package, the second method: Welch's PSD, the STFT
and the peak finder with prominences equal to ``scipy.signal.welch``, ``stft`` and ``find_peaks`` to
1e-12 relative (the peaks and prominences exactly) on random input, on a raw recording of the second
generator (a chain, as an ADXL345 records it) and on the real spectra of tests/data/recordings
(SOURCES), with even and odd segments, every overlap the path uses and some it does not, plateaus and
peaks at the ends. And the reason the module exists: identify and recommend load no scipy.signal."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy import signal

from shapefmu.identification import fourier
from shapefmu.identification import synthetic as syn
from shapefmu.identification import synthetic_chain as sc

FOLDER = Path(__file__).parent / "data" / "recordings"
FILES = sorted(p.name for p in FOLDER.glob("*.csv"))
RTOL = 1e-12
# (samples, segment, overlap): even and odd segments, no overlap up to all but one sample, a record
# of exactly one segment and records that end inside a segment
LAYOUTS = [(1000, 64, 32), (1001, 63, 31), (5000, 256, 192), (777, 100, 0), (300, 300, 0), (4097, 17, 16),
           (2048, 512, 384), (999, 98, 97)]


def close(ours, theirs):
    """Equal to 1e-12 of each value; a bin that detrending leaves at rounding level (0 Hz), to 1e-12
    of the largest."""
    np.testing.assert_allclose(ours, theirs, rtol=RTOL, atol=RTOL * np.max(np.abs(theirs)))


@pytest.fixture(scope="module")
def chain_recording():
    """A 10 s raw Klipper test of a two-mode chain, 3.2 kHz: quantised, jittered, fan tones, 1/f noise."""
    t, xyz = sc.record(sc.Chain.random(0), test=sc.KlipperTest(freq_start=30.0, freq_end=50.0, hz_per_sec=2.0))
    return (len(t) - 1) / (t[-1] - t[0]), xyz


@pytest.mark.parametrize("length", [2, 3, 16, 255, 2048, 32768])
def test_periodic_hann_is_scipys_hann(length):
    np.testing.assert_array_equal(fourier.periodic_hann(length), signal.get_window("hann", length))


@pytest.mark.parametrize("n, segment, overlap", LAYOUTS)
@pytest.mark.parametrize("window", ["kaiser6", "hann"])
@pytest.mark.parametrize("detrend", [True, False])
def test_welch_is_scipys_on_random_samples(n, segment, overlap, window, detrend):
    samples = np.random.default_rng(n + segment).normal(3.0, 2.0, n)
    taps = np.kaiser(segment, 6.0) if window == "kaiser6" else fourier.periodic_hann(segment)
    freq, psd = signal.welch(samples, 321.0, window=taps, noverlap=overlap, detrend="constant" if detrend else False)
    found = fourier.welch_psd(samples, 321.0, taps, overlap, detrend=detrend)
    np.testing.assert_array_equal(found.freq, freq)
    close(found.psd, psd)
    assert found.segments == (n - overlap) // (segment - overlap)


@pytest.mark.parametrize("segment, overlap, detrend", [(2048, 1024, True), (32768, 24576, False), (2047, 1023, True)])
def test_welch_is_scipys_on_a_raw_recording(chain_recording, segment, overlap, detrend):
    """Klipper's settings (Kaiser, 2048 samples, half overlapping, each mean removed) and those of
    ``spectra.spectrum`` (Hann, 32768 samples, 3/4 overlapping), on every axis (z carries gravity)."""
    rate, xyz = chain_recording
    taps = np.kaiser(segment, 6.0) if detrend else signal.get_window("hann", segment)
    for samples in xyz.T:
        freq, psd = signal.welch(samples, rate, window=taps, noverlap=overlap, detrend="constant" if detrend else False)
        found = fourier.welch_psd(samples, rate, taps, overlap, detrend=detrend)
        np.testing.assert_array_equal(found.freq, freq)
        close(found.psd, psd)


def test_welch_takes_a_long_record_in_batches_and_gets_scipys_mean(monkeypatch):
    """Batches of 3 segments (the last one short) sum to the mean over all of them."""
    monkeypatch.setattr(fourier, "BATCH_SAMPLES", 3 * 128)
    samples = np.random.default_rng(7).normal(size=128 * 11 + 5)
    taps = np.kaiser(128, 6.0)
    found = fourier.welch_psd(samples, 1.0, taps, 64, detrend=True)
    assert found.segments == 21
    close(found.psd, signal.welch(samples, 1.0, window=taps, noverlap=64, detrend="constant")[1])


@pytest.mark.parametrize("n, segment, overlap", LAYOUTS)
def test_stft_is_scipys_without_padding(n, segment, overlap):
    samples = np.random.default_rng(n).normal(size=n)
    freq, times, z = signal.stft(samples, 250.0, window="hann", nperseg=segment, noverlap=overlap, boundary=None,
                                 padded=False)
    found = fourier.stft(samples, 250.0, fourier.periodic_hann(segment), overlap)
    np.testing.assert_array_equal(found.freq, freq)
    np.testing.assert_allclose(found.times, times, rtol=RTOL)
    assert found.z.shape == z.shape
    close(found.z, z)


def test_stft_is_scipys_on_a_raw_recording(chain_recording):
    rate, xyz = chain_recording
    samples = xyz[:, 0] - xyz[:, 0].mean()  # as spectra.spectrogram takes it
    freq, times, z = signal.stft(samples, rate, window="hann", nperseg=2048, noverlap=1024, boundary=None, padded=False)
    found = fourier.stft(samples, rate, fourier.periodic_hann(2048), 1024)
    np.testing.assert_allclose(found.times, times, rtol=RTOL)
    close(found.z, z)


def same_peaks(values, height=None):
    """Our peaks and prominences against scipy.signal.find_peaks(values, height=height, prominence=0)."""
    peaks, properties = signal.find_peaks(values, height=height, prominence=0)
    found = fourier.find_peaks(values, -np.inf if height is None else height)
    np.testing.assert_array_equal(found.indices, peaks)
    np.testing.assert_array_equal(found.prominences, properties["prominences"])
    return found


@pytest.mark.parametrize("seed", range(20))
def test_peaks_are_scipys_on_sequences_full_of_plateaus_and_ties(seed):
    """Values from {0, 1, 2, 3}: plateaus of every length, at the ends and inside, peaks of equal
    height (a level line passes them), peaks at the first and last sample."""
    rng = np.random.default_rng(seed)
    for _ in range(50):
        values = rng.integers(0, 4, int(rng.integers(0, 60))).astype(float)
        for height in (None, 1.0, 2.5):
            same_peaks(values, height)


def test_peaks_at_the_ends_and_plateaus_are_placed_as_scipy_places_them():
    found = same_peaks(np.array([5.0, 1.0, 2.0, 2.0, 2.0, 2.0, 1.0, 3.0, 3.0, 3.0, 0.0, 4.0, 4.0]))
    assert found.indices.tolist() == [3, 8]  # the left middle of an even plateau; no peak at either end
    # the 3: its level line meets the 5 on the left (lowest between: 1) and the 4 on the right
    # (lowest between: 0); the higher base is 1
    assert found.prominences.tolist() == [1.0, 2.0]


def test_real_spectra_are_there():
    assert len(FILES) == 9


@pytest.mark.parametrize("seed", range(3))
def test_peaks_are_scipys_on_a_long_random_walk(seed):
    """Tens of thousands of peaks, some of them topped only thousands of samples away."""
    walk = np.cumsum(np.random.default_rng(seed).normal(size=200_000))
    same_peaks(walk)
    same_peaks(walk, float(np.quantile(walk, 0.9)))


@pytest.mark.parametrize("name", FILES)
def test_peaks_are_scipys_on_real_spectra(name):
    """Every column of the development recordings: Klipper's spectra and its fitted shapers' curves,
    as read (printed to four digits: ties and plateaus happen) and at 10 % of each maximum."""
    table = np.genfromtxt(FOLDER / name, delimiter=",", skip_header=1)
    table = table[:, ~np.all(np.isnan(table), axis=0)]
    for column in table[:, 1:].T:
        same_peaks(column)
        same_peaks(column, 0.1 * column.max())


def test_welch_names_a_window_longer_than_the_record():
    with pytest.raises(ValueError, match=r"samples must be one-dimensional and at least as many as the window's 64"):
        fourier.welch_psd(np.zeros(40), 100.0, np.kaiser(64, 6.0), 32, detrend=True)


def test_welch_names_an_overlap_out_of_range():
    with pytest.raises(ValueError, match=r"overlap must be an integer in \[0, 63\] .* got 64"):
        fourier.welch_psd(np.zeros(400), 100.0, np.kaiser(64, 6.0), 64, detrend=True)


def test_peaks_name_a_value_that_is_not_finite():
    with pytest.raises(ValueError, match="values must be a one-dimensional sequence of finite numbers"):
        fourier.find_peaks([0.0, np.nan, 1.0, 0.0])


def test_identify_and_recommend_of_a_raw_recording_load_no_scipy_signal(tmp_path):
    """SciPy's signal package loads its stats, interpolate and integrate packages: about 0.7 s of
    CPU on the way from a raw recording to a recommendation, where Klipper's calibrate_shaper.py
    takes two or three in all (benchmarks/recommend.py). The run is a separate process: this one has
    SciPy's signal loaded already."""
    path = tmp_path / "resonances_x.csv"
    modes = [syn.SyntheticMode(38.0, 0.06, 0.5), syn.SyntheticMode(61.0, 0.08, 0.3)]
    syn.write_klipper_raw(path, *syn.record(modes, f_min=20.0, f_max=80.0, hz_per_sec=4.0, seed=1))
    run = ("import sys; from shapefmu.cli import main; code = main(sys.argv[1:]); "
           "print('scipy.signal' in sys.modules, 'scipy.stats' in sys.modules); sys.exit(code)")
    for command in (["identify", str(path)], ["recommend", str(path)]):
        done = subprocess.run([sys.executable, "-c", run, *command], capture_output=True, text=True, timeout=600)
        assert done.returncode == 0, done.stderr
        assert done.stdout.splitlines()[-1] == "False False", command
