"""From a recording to a shaper FMU (issue 25): modes of known machines recorded as Klipper and
RepRapFirmware record them, Klipper's metrics against their definitions, the pick against Klipper's
six, and the built FMU against the machine in an independent simulation (fmpy + scipy)."""

import math

import numpy as np
import pytest
from hostile_support import guarded

from shapefmu.identification import identify, metrics, recommend
from shapefmu.identification import synthetic as syn

MACHINES = {
    "one mode": [syn.SyntheticMode(40.0, 0.05)],
    "lightly damped": [syn.SyntheticMode(30.0, 0.02)],
    "heavily damped": [syn.SyntheticMode(45.0, 0.2)],
    "two modes": [syn.SyntheticMode(25.0, 0.05, 0.6), syn.SyntheticMode(62.0, 0.08, 0.4)],
    "three modes": [syn.SyntheticMode(20.0, 0.03, 0.5), syn.SyntheticMode(45.0, 0.1, 0.3),
                    syn.SyntheticMode(90.0, 0.05, 0.2)],
    "0.2 beside 0.02": [syn.SyntheticMode(22.0, 0.2, 0.6), syn.SyntheticMode(60.0, 0.02, 0.4)],
}


def visible(machine):
    """The modes a person clearly sees in Klipper's plot of the machine's response to its sweep
    (issue 32): a peak of f |T(f)|^2 reaching a fifth of the highest (a tenth is the rule; Klipper's
    coarse spectrum lowers a sharp peak, so a mode between a tenth and a fifth may be seen or not)."""
    from scipy.signal import find_peaks

    freq = np.linspace(5, 200, 40000)
    view = freq * np.abs(syn.transmissibility(machine, freq)) ** 2
    peaks, _ = find_peaks(view, height=0.2 * view.max())
    return [min(machine, key=lambda m: abs(m.frequency - freq[i])) for i in peaks]


def assert_modes(found, machine, frequency_error=0.01, zeta_error=0.25, seen=None):
    """Every mode of ``seen`` (all of ``machine`` by default) found, every mode found one of ``machine``."""
    seen = machine if seen is None else seen
    assert all(any(abs(m.frequency / t.frequency - 1) < frequency_error for t in machine) for m in found), \
        [m.describe() for m in found]
    for true in seen:
        mode = min(found, key=lambda m: abs(m.frequency - true.frequency))
        assert abs(mode.frequency / true.frequency - 1) < frequency_error, (mode.describe(), true)
        assert abs(mode.zeta / true.zeta - 1) < zeta_error, (mode.describe(), true)


@pytest.fixture(scope="module")
def recordings(tmp_path_factory):
    folder = tmp_path_factory.mktemp("recordings")
    files = {}
    for i, (name, machine) in enumerate(MACHINES.items()):
        t, xyz = syn.record(machine, seed=i)
        raw = folder / f"raw{i}.csv"
        syn.write_klipper_raw(raw, t, xyz)
        rrf = folder / f"m956_{i}.csv"
        syn.write_rrf_m956(rrf, t, xyz, axes="XY")
        files[name] = (raw, rrf)
    return files


@pytest.mark.parametrize("name", MACHINES)
def test_klipper_raw_recordings_give_the_machines_modes(recordings, name):
    found = identify(recordings[name][0], axis="x")
    assert_modes(found.modes.modes, MACHINES[name], seen=visible(MACHINES[name]))
    assert found.recording.jitter > 0.001 and found.recording.gaps == 0  # jittered, as Klipper's are


@pytest.mark.parametrize("name", ["one mode", "two modes", "three modes"])
def test_m956_and_spectrum_files_give_the_raw_files_modes(recordings, name, tmp_path):
    raw = identify(recordings[name][0], axis="x").modes.modes
    rrf = identify(recordings[name][1], axis="x", excitation="sweep").modes.modes
    assert_modes(rrf, [syn.SyntheticMode(m.frequency, m.zeta) for m in raw])
    # the processed file Klipper writes from the same data: its spectra, written and read back
    x, y = (identify(recordings[name][0], axis=a).modes.spectrum for a in "xy")  # the fine spectra
    spectrum_file = tmp_path / "calibration_data_x.csv"
    syn.write_klipper_spectrum(spectrum_file, x.freq, (x.psd, y.psd, 0 * x.psd))
    processed = identify(spectrum_file, axis="x").modes.modes
    assert_modes(processed, [syn.SyntheticMode(m.frequency, m.zeta) for m in raw])


def test_a_table_with_a_time_column_or_a_rate_and_a_parquet_file(tmp_path):
    import pyarrow as pa
    import pyarrow.parquet as pq

    machine = [syn.SyntheticMode(35.0, 0.04)]
    t, xyz = syn.record(machine, seed=7)
    csv = tmp_path / "encoder.csv"
    np.savetxt(csv, np.column_stack([t, xyz[:, 0]]), delimiter=",", header="seconds,error", comments="")
    assert_modes(identify(csv, axis="error", time_column="seconds", columns=["error"], excitation="sweep").modes.modes,
                 machine)
    table = tmp_path / "log.parquet"
    pq.write_table(pa.table({"a": xyz[:, 0]}), table)
    rate = (len(t) - 1) / (t[-1] - t[0])
    assert_modes(identify(table, axis="a", fs=rate, columns=["a"], excitation="sweep").modes.modes, machine)


def test_a_ring_down_is_refined_by_the_ekf_and_checked_by_the_log_decrement(tmp_path):
    machine = [syn.SyntheticMode(18.0, 0.03)]
    t, y = syn.ring_down(machine, fs=1000.0, duration=4.0)
    path = tmp_path / "tap.csv"
    np.savetxt(path, np.column_stack([t, y]), delimiter=",", header="t,y", comments="")
    found = identify(path, axis="y", time_column="t", columns=["y"], ringdown=True)
    (mode,) = found.modes.modes
    assert mode.method == "EKF on the ring-down"
    assert_modes([mode], machine, zeta_error=0.1)
    assert abs(mode.log_decrement_zeta / 0.03 - 1) < 0.1


def test_the_remaining_vibration_is_klippers_definition_computed_by_a_plain_loop():
    """The vectorised metric against a per-bin, per-damping loop of its definition."""
    freq = np.linspace(1, 150, 400)
    psd = np.abs(syn.transmissibility([syn.SyntheticMode(40, 0.05), syn.SyntheticMode(90, 0.1, 0.3)], freq)) ** 2
    times, amps = np.array([0.0, 0.0125, 0.025]), np.array([0.25, 0.5, 0.25])
    meter = metrics.VibrationMeter(freq, psd, metrics.KLIPPER_DAMPINGS, max_gain=1.0)
    fast = float(meter.remaining(metrics.residual(times[None], amps[None], meter.freq, meter.dampings).max(-1))[0])
    threshold = psd.max() / 20
    left = total = 0.0
    for f, p in zip(freq, psd):
        worst = 0.0
        for zeta in metrics.KLIPPER_DAMPINGS:
            w, wd = 2 * math.pi * f, 2 * math.pi * f * math.sqrt(1 - zeta**2)
            c = sum(a * math.exp(zeta * w * t) * math.cos(wd * t) for t, a in zip(times, amps))
            s = sum(a * math.exp(zeta * w * t) * math.sin(wd * t) for t, a in zip(times, amps))
            worst = max(worst, math.exp(-zeta * w * times[-1]) * math.hypot(c, s) / amps.sum())
        left += max(p * worst - threshold, 0.0)
        total += max(p - threshold, 0.0)
    assert fast == pytest.approx(left / total, rel=1e-9)


def test_smoothing_and_max_accel_of_a_zv_shaper_in_closed_form():
    """ZV at f, undamped: impulses 1/2 at 0 and 1/(2f), centre 1/(4f), d = 1/(4f) for the second:
    s = max(sqrt 2 (v d/2 + a d^2/4), a d^2/4)."""
    f, v, a = 50.0, 5.0, 7000.0
    d = 1 / (4 * f)
    times, amps = np.array([0.0, 1 / (2 * f)]), np.array([0.5, 0.5])
    expected = max(math.sqrt(2) * (v * d / 2 + a * d * d / 4), a * d * d / 4)
    assert float(metrics.smoothing(times, amps, a, v)) == pytest.approx(expected, rel=1e-12)
    limit = float(metrics.max_accel(times, amps, 0.12, v))
    assert float(metrics.smoothing(times, amps, limit, v)) == pytest.approx(0.12, rel=1e-12)


def test_on_two_modes_the_pick_allows_more_acceleration_than_klippers_six_at_no_more_vibration(recordings):
    found = identify(recordings["two modes"][0], axis="x")
    advice = recommend([found.spectrum], found.modes.modes)
    six = {"zv", "mzv", "zvd", "ei", "ei2", "ei3"}
    assert advice.baseline.kind in six and advice.baseline.family == "single"
    # the baseline is the best of the six by the rule the pick follows, searched independently here
    singles = [c for c in advice.candidates if c.family == "single" and c.kind in six]
    assert all(c.max_accel <= advice.baseline.max_accel * (1 + 1e-9) or c.vibration > advice.bound for c in singles)
    assert advice.pick.vibration <= advice.baseline.vibration + 1e-12
    assert advice.pick.max_accel > 1.01 * advice.baseline.max_accel
    assert any(c.family == "pair" and c.max_accel > advice.baseline.max_accel and c.vibration <= advice.bound
               for c in advice.candidates)  # a two-mode design alone beats the six too


def _mode_plant(folder, index, mode):
    """A native plant FMU of one mode of the machine (its toolhead position per commanded position)."""
    model = folder / f"mode{index}.toml"
    model.write_text(syn.plant_model(mode, f"mode{index}"))
    fmu = folder / f"Mode{index}.fmu"
    code, _, err = guarded(["plant", "build", model, "-o", fmu], seconds=120)
    assert code == 0, err
    return fmu


def test_the_built_fmu_leaves_less_vibration_on_the_machine_than_reported(recordings, tmp_path):
    """recommend --build, then a co-simulation in our master: the built FMU (with its .ssv) shapes a
    unit step that drives a plant FMU of each mode of the known machine; beside it the same plants
    take the unshaped step. The residual of each mode, shaped over unshaped, against the table's
    worst case at the modes. fmpy runs the built FMU alone as the second opinion on its output."""
    from fmpy import simulate_fmu

    from shapefmu.cosim.master import simulate
    from shapefmu.fmi.ssp import System

    fmu = tmp_path / "Pick.fmu"
    code, out, err = guarded(["recommend", recordings["two modes"][0], "--axis", "x", "--build", fmu], seconds=120)
    assert code == 0, err
    assert "<- pick" in out and "<- best of Klipper's six" in out and fmu.exists() and fmu.with_suffix(".ssv").exists()
    found = identify(recordings["two modes"][0], axis="x")
    pick = recommend([found.spectrum], found.modes.modes).pick
    machine = MACHINES["two modes"]
    system = System("machine").add("shaper", fmu, parameters={"u": 1.0}, ssv=fmu.with_suffix(".ssv"))
    for i, mode in enumerate(machine):
        plant = _mode_plant(tmp_path, i, mode)
        system.add(f"shaped{i}", plant).connect("shaper.y", f"shaped{i}.position_command")
        system.add(f"unshaped{i}", plant, parameters={"position_command": 1.0})
    step, stop = 2e-5, 0.4
    result = simulate(system, stop, step)
    t = result["time"]
    alone = simulate_fmu(str(fmu), stop_time=stop, step_size=step, output_interval=step,
                         start_values={"u": 1.0}, output=["y"])
    assert np.allclose(np.interp(t, alone["time"], alone["y"]), result["shaper.y"], atol=1e-12)
    after = t > pick.duration + 0.01
    for i, mode in enumerate(machine):
        w = 2 * math.pi * mode.frequency
        wd = w * math.sqrt(1 - mode.zeta**2)
        closed = 1 - np.exp(-mode.zeta * w * t) * (np.cos(wd * t) - mode.zeta * w / wd * np.sin(wd * t))
        assert np.abs(result[f"unshaped{i}.position"] - closed).max() < 1e-6  # the plant FMU is the mode
        ring = {k: np.abs(result[f"{k}{i}.position"] - 1.0)[after].max() for k in ("shaped", "unshaped")}
        # Singer and Seering's percent residual compares with the unshaped vibration at the first
        # impulse, which has decayed by exp(-zeta w D) when the shaped one is measured after the last
        measured = ring["shaped"] / ring["unshaped"] * math.exp(-mode.zeta * w * pick.duration)
        assert measured <= pick.at_modes * 1.02 + 1e-3, (mode, measured, pick.at_modes)


def test_recommend_builds_the_pick_as_fmi3_whose_ssv_gives_the_fmi2_builds_numbers(recordings, tmp_path):
    """--build --fmi-version 3.0: the same pick as an FMI 3.0 native FMU (its modes an array f), its .ssv
    (element bindings f[1] ...) read by our master: the FMI 2.0 build's output to 1e-12."""
    from fmpy import read_model_description

    from shapefmu.cosim.master import simulate
    from shapefmu.fmi.ssp import System

    runs = {}
    for version in ("2.0", "3.0"):
        fmu = tmp_path / f"Pick{version[0]}.fmu"
        code, _, err = guarded(["recommend", recordings["two modes"][0], "--axis", "x", "--build", fmu,
                                "--fmi-version", version], seconds=120)
        assert code == 0, err
        assert read_model_description(str(fmu)).fmiVersion == version
        system = System("pick").add("shaper", fmu, parameters={"u": 1.0}, ssv=fmu.with_suffix(".ssv"))
        runs[version] = simulate(system, 0.2, 2e-5)["shaper.y"]
    assert np.ptp(runs["2.0"]) > 0.5
    np.testing.assert_allclose(runs["3.0"], runs["2.0"], rtol=0, atol=1e-12)
    code, _, err = guarded(["recommend", recordings["two modes"][0], "--axis", "x", "--build", tmp_path / "P.fmu",
                            "--python", "--fmi-version", "3.0"], seconds=120)
    assert code != 0 and "--fmi-version 3.0 needs the native FMU" in err and not (tmp_path / "P.fmu").exists()


def test_several_recordings_give_one_recommendation_for_the_worst_of_them(tmp_path):
    """The machine unloaded (40 Hz) and loaded (33 Hz): the recommendation for both holds on each
    recording, judged alone by the same metric, and the loaded one is what limits it."""
    files = []
    for i, f in enumerate((40.0, 33.0)):
        t, xyz = syn.record([syn.SyntheticMode(f, 0.05)], seed=10 + i)
        files.append(tmp_path / f"load{i}.csv")
        syn.write_klipper_raw(files[-1], t, xyz)
    found = [identify(path, axis="x") for path in files]
    modes = tuple(m for f in found for m in f.modes.modes)
    both = recommend([f.spectrum for f in found], modes)
    meters = [metrics.VibrationMeter(f.spectrum.freq, f.spectrum.psd, both.dampings, max_gain=3.0) for f in found]

    def on_each(design):  # the design's vibration on each recording alone
        return [float(m.remaining(metrics.residual(np.array(design.times)[None], np.array(design.amplitudes)[None],
                                                   m.freq, both.dampings).max(-1))[0]) for m in meters]

    for design in (both.pick, both.baseline):
        each = on_each(design)
        assert design.vibration == pytest.approx(max(each), rel=1e-5)  # V is tabulated: ~1e-6
        assert min(each) < max(each)
    assert both.pick.vibration <= both.bound + 1e-12
    # what the less limiting recording alone would pick leaves more than the bound on the other
    picks = [recommend([f.spectrum], f.modes.modes).pick for f in found]
    assert any(max(on_each(pick)) > 1.2 * both.bound for pick in picks), [max(on_each(p)) for p in picks]
    code, out, err = guarded(["recommend", *files, "--axis", "x"], seconds=120)
    assert code == 0, err
    assert "worst of 2 recordings" in out and f"{100 * both.pick.vibration:.2f}%" in out


BAD = [
    (b"", "line 1: expected a recording, got an empty file"),
    (b"#time,accel_x,accel_y,accel_z\n", "line 2: expected rows of numbers after the header, got none"),
    (b"#time,accel_x,accel_y,accel_z\n" + b"".join(b"%f,1,2,3\n" % (i * 1e-3) for i in range(20))
     + b"0.005,1,2,3\n", "line 22: expected the time to increase"),
    (b"#time,accel_x,accel_y,accel_z\n0,1,2,3\n0.001,nan,2,3\n", "line 3: expected finite numbers"),
    (b"#time,accel_x,accel_y,accel_z\n0,1,2\n", "line 2: expected 4 numbers"),
    (b"\x00\x01\x02junk\xff" * 50, "expected a text (CSV) recording or a Parquet file, got binary data"),
    (b"a,b\n1,2\n", "not a Klipper or RepRapFirmware recording"),
    (b"Sample,X\n0,0.1\n1,0.2\n", "expected the last line of an M956 recording"),
]


@pytest.mark.parametrize("content,words", BAD)
def test_a_bad_recording_is_one_line_naming_the_file_and_line(tmp_path, content, words):
    path = tmp_path / "rec.csv"
    path.write_bytes(content)
    code, _, err = guarded(["identify", path])
    assert code == 2 and err.count("\n") == 1 and words in err and str(path) in err, err


def test_unknown_columns_a_rate_too_low_and_no_resonance(tmp_path):
    path = tmp_path / "t.csv"
    rng = np.random.default_rng(1)
    np.savetxt(path, np.column_stack([np.arange(4000) / 400, rng.normal(size=4000)]), delimiter=",",
               header="t,noise", comments="")
    code, _, err = guarded(["identify", path, "--time", "t", "--column", "accel", "--axis", "accel"])
    assert code == 2 and "no column 'accel'; the columns are t, noise" in err
    code, _, err = guarded(["identify", path, "--time", "t", "--column", "noise", "--axis", "noise", "--f-max", "300"])
    assert code == 2 and "f_max = 300 Hz is above the highest frequency of the spectrum, 200 Hz" in err
    code, out, err = guarded(["identify", path, "--time", "t", "--column", "noise", "--axis", "noise"])
    assert code == 0 and "no resonance" in out
    code, _, err = guarded(["recommend", path, "--time", "t", "--column", "noise", "--axis", "noise"])
    assert code == 2 and "no resonance found in the recordings" in err


def test_a_recording_larger_than_the_bound_is_refused_before_it_is_read(tmp_path, monkeypatch):
    from shapefmu.identification import recordings

    path = tmp_path / "big.csv"
    path.write_bytes(b"#time,accel_x,accel_y,accel_z\n" + b"0,0,0,0\n" * 1000)
    monkeypatch.setattr(recordings, "MAX_RECORDING_BYTES", 1000)
    code, _, err = guarded(["identify", path])
    assert code == 2 and "more than the 1000 (shapefmu.identification.recordings.MAX_RECORDING_BYTES)" in err


def test_recommend_from_modes_alone_and_json(tmp_path):
    import json

    code, out, err = guarded(["recommend", "--mode", "30:0.05", "--mode", "75:0.05", "--json"])
    assert code == 0, err
    advice = json.loads(out)
    assert advice["pick"]["max_accel"] >= advice["baseline_klipper_six"]["max_accel"]
    assert advice["pick"]["vibration"] <= advice["baseline_klipper_six"]["vibration"] + 1e-12


def test_the_command_line_defaults_are_the_metrics_defaults():
    from shapefmu.cli import identify as command

    assert (command.DEFAULT_MAX_SMOOTHING, command.DEFAULT_ACCEL, command.DEFAULT_SCV) == (
        metrics.DEFAULT_MAX_SMOOTHING, metrics.DEFAULT_ACCEL, metrics.DEFAULT_SCV)
