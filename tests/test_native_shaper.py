"""Native C Shaper and ShapeFilter FMUs (shapefmu.fmi.native.sampled) against the pythonfmu FMUs,
the design layer's offline shaping, a random-step reference built from the sampled-semantics spec,
and three FMI hosts; their state, errors and modelDescription."""

import math
import random

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

from support.fixtures_fmi import command_signal
from support.fixtures_native import BUILD_TIME_ONLY, CLOSED_FORM, H, ONE_MODE, TWO_MODES, shaper_starts
from support.fmpy_slaves import assert_state_restores_exactly, configured, initialised, y_after_each_set
from support.hosts import run_ecos, run_fmpy, run_libcosim, y_of_u

from shapefmu.shapers import design

SAMPLE_TOLERANCE = 1e-6  # the spec's (notes/sampled_semantics.md), as c/sampled_fir.h


def modes_of(values):
    return [(2 * math.pi * values[f"f[{i}]"], values[f"zeta[{i}]"]) for i in range(1, values["n_modes"] + 1)]


def design_taps(values):
    """The design layer's FIR taps of a Shaper's parameters, on the grid H."""
    shaper = design(values["kind"], modes_of(values), vtol=values["vtol"], n=values["n"])
    return np.asarray(shaper.on_grid(H).taps, dtype=float)


def fir(taps, samples, u0):
    """y_k = sum_d taps[d] u_{k-d}, the input resting at u0 before sample 0."""
    padded = np.concatenate([np.full(taps.size - 1, u0), samples])
    return np.convolve(padded, taps, mode="valid")


def read_after_set(path, commands, steps, parameters=None):
    """At each communication point set u, read y (feed-through), then step; steps[k] is step k's size."""
    t, points = 0.0, []
    for h in steps:
        points.append((t, h))
        t += h  # a host's drifting time, as most hosts keep it
    return np.array(y_after_each_set(path, commands, points, parameters))


def newest_sample(tau, ts):
    """K(tau) of the spec, with its guards against rounding."""
    k = math.floor(tau / ts + SAMPLE_TOLERANCE)
    if (k + 1) * ts <= tau + SAMPLE_TOLERANCE * ts:
        k += 1
    if k * ts > tau + SAMPLE_TOLERANCE * ts:
        k -= 1
    return k


def spec_reference(taps, commands, steps, u0, read="after_set"):
    """The spec's reference: u_k = the input in effect at s_k (set at the last communication point
    <= s_k), y_k = FIR(u)_k, read at tau: y_{K(tau)}, whose current sample takes the input in effect
    at tau (a later point on the same sample may still change it: linearity adds w_0 times that).

    ``read``: "after_set" reads at each communication point right after setting its command;
    "after_step" at the end of each step, before the next command is set (as the hosts record)."""
    t, points = 0.0, []
    for h in steps:
        points.append(t)
        t += h
    ends = points[1:] + [t]

    def in_effect(k, upto):
        """Index of the last communication point <= s_k among points[0..upto]."""
        j = 0
        while j + 1 <= upto and points[j + 1] <= k * H + SAMPLE_TOLERANCE * H:
            j += 1
        return j

    last = newest_sample(ends[-1], H)
    samples = np.array([commands[in_effect(k, len(points) - 1)] for k in range(last + 1)])
    y = fir(taps, samples, u0)
    out = []
    for j, tau in enumerate(points if read == "after_set" else ends):
        k = newest_sample(tau, H)
        out.append(y[k] + taps[0] * (commands[in_effect(k, j)] - samples[k]))
    return np.array(out)


# ------------------------------------------------------------------ every kind, whole-sample steps

def every_shaper_case():
    cases = [(kind, 2, n_modes) for kind in CLOSED_FORM for n_modes in (1, 2)]
    return cases + [(kind, n, n) for kind in BUILD_TIME_ONLY for n in (1, 2)]


@pytest.mark.parametrize("kind, built, n_modes", every_shaper_case())
def test_native_shaper_equals_the_pythonfmu_shaper_and_the_design_layer(native_shapers, shaper_fmu_default, kind,
                                                                        built, n_modes):
    path, starts = native_shapers[(kind, built)]
    values = shaper_starts(kind, ONE_MODE if n_modes == 1 else TWO_MODES)
    commands = np.array(command_signal(400))
    steps = np.full(commands.size, H)
    # A closed-form FMU built for two modes runs one mode by re-designing in C.
    native = read_after_set(path, commands, steps, None if built == n_modes else {"n_modes": 1})
    python = read_after_set(shaper_fmu_default, commands, steps, values)
    expected = fir(design_taps(values), commands, values["u0"])
    np.testing.assert_allclose(native, python, rtol=0, atol=1e-12)
    np.testing.assert_allclose(native, expected, rtol=0, atol=1e-12)


@pytest.fixture(scope="module")
def shaper_fmu_default(builds):
    """One pythonfmu Shaper: it designs from the parameters set before initialisation."""
    return builds.pythonfmu("Shaper")


@pytest.mark.parametrize("kind", ["zvd", "ei2", "simultaneous"])
def test_random_steps_give_the_spec_reference(native_shapers, kind):
    path, starts = native_shapers[(kind, 2)]
    rng = random.Random(7)
    sizes = [lambda: H * rng.randint(1, 3), lambda: H * rng.uniform(0.01, 2.7), lambda: 1e-16,
             lambda: H * rng.uniform(0.0, 1e-7), lambda: H * 0.5]
    steps = np.array([rng.choice(sizes)() for _ in range(600)])
    commands = np.array([math.sin(0.7 * k) + (k % 37 == 0) for k in range(steps.size)])
    expected = spec_reference(design_taps(starts), commands, steps, starts["u0"])
    np.testing.assert_allclose(read_after_set(path, commands, steps), expected, rtol=0, atol=1e-12)


def test_closed_form_redesign_in_c_follows_new_modes(native_shapers):
    path, _ = native_shapers[("zv_dn", 2)]
    values = shaper_starts("mzv", {"n_modes": 2, "f[1]": 9.0, "zeta[1]": 0.1, "f[2]": 44.0, "zeta[2]": 0.0})
    commands = np.array(command_signal(300))
    out = read_after_set(path, commands, np.full(commands.size, H),
                         {k: values[k] for k in ("kind", "f[1]", "zeta[1]", "f[2]", "zeta[2]")})
    np.testing.assert_allclose(out, fir(design_taps(values), commands, values["u0"]), rtol=0, atol=1e-12)


def test_filters_equal_the_pythonfmu_filter_and_their_taps(native_filters, builds):
    from shapefmu.fmi.kinds.shape_filter import design_taps as filter_taps

    python = builds.pythonfmu("ShapeFilter", kind="rectangle")  # declares feed-through: runs every kind
    for name, (path, starts) in native_filters.items():
        taps, ts = filter_taps({**default_filter_values(), **starts})
        commands = np.array(command_signal(2 * len(taps) + 50))
        steps = np.full(commands.size, ts)  # Ts_used: adjusted where adjust_Ts asks for it
        native = read_after_set(path, commands, steps)
        np.testing.assert_allclose(native, read_after_set(python, commands, steps, starts), rtol=0, atol=1e-12,
                                   err_msg=name)
        taps = np.asarray(taps)
        taps[0] = 0.0 if abs(taps[0]) <= 1e-12 * np.max(np.abs(taps)) else taps[0]
        np.testing.assert_allclose(native, fir(taps, commands, starts.get("u0", 0.0)), rtol=0, atol=1e-12,
                                   err_msg=name)


def default_filter_values():
    from shapefmu.fmi.kinds.shape_filter import INTERFACE

    return INTERFACE.start_values()


def test_outputs_identical_in_fmpy_libcosim_and_ecos(native_shapers, native_filters, quiet_libcosim):
    commands = command_signal(150)
    for path in (native_shapers[("simultaneous", 2)][0], native_filters["rectangle"][0]):
        reference = y_of_u(run_fmpy, path, commands, H)
        for other in (y_of_u(run_libcosim, path, commands, H), y_of_u(run_ecos, path, commands, H)):
            np.testing.assert_allclose(other, reference, rtol=0, atol=1e-12)


def test_steps_off_the_grid_give_the_spec_reference_in_fmpy_libcosim_and_ecos(native_shapers, quiet_libcosim):
    path, starts = native_shapers[("simultaneous", 2)]
    commands = command_signal(200)
    h = 0.7 * H  # a whole number of nanoseconds (libcosim), on the grid every tenth step
    expected = spec_reference(design_taps(starts), commands, np.full(len(commands), h), starts["u0"], "after_step")
    for run in (run_fmpy, run_libcosim, run_ecos):
        np.testing.assert_allclose(y_of_u(run, path, commands, h), expected, rtol=0, atol=1e-12, err_msg=run.__name__)


def test_cli_builds_a_native_shaper_and_without_mingw_a_linux64_one_with_a_note(tmp_path, monkeypatch, capsys):
    import zipfile

    from shapefmu.cli import main
    from shapefmu.fmi.native import compile as native_compile

    out = tmp_path / "Native.fmu"
    assert main(["build", "shaper", "--native", "--kind", "zvd", "--mode", "13:0.05", "--ts", "1e-3",
                 "-o", str(out)]) == 0
    assert "binaries/win64/Shaper.dll" in zipfile.ZipFile(out).namelist()
    commands = np.array(command_signal(200))
    values = shaper_starts("zvd", ONE_MODE)
    expected = fir(design_taps({**values, "u0": 0.0}), commands, 0.0)
    np.testing.assert_allclose(read_after_set(out, commands, np.full(commands.size, H)), expected, rtol=0, atol=1e-12)
    monkeypatch.setattr(native_compile, "win64", lambda: None)
    assert main(["build", "shape-filter", "--native", "--mode", "10", "--adjust-ts", "-o", str(out)]) == 0
    names = zipfile.ZipFile(out).namelist()
    assert "binaries/linux64/ShapeFilter.so" in names and not any("win64" in n for n in names)
    assert "built without binaries/win64 (x86_64-w64-mingw32-gcc, Debian package gcc-mingw-w64-x86-64, is not " \
           "installed)" in capsys.readouterr().err


def test_every_native_fmu_passes_validation_with_win64_and_linux64_binaries(native_shapers, native_filters):
    import zipfile

    for path, _ in [*native_shapers.values(), *native_filters.values()]:
        assert validate_fmu(str(path)) == [], path
        names = zipfile.ZipFile(path).namelist()
        assert {"binaries/linux64/Shaper.so", "binaries/win64/Shaper.dll"} <= set(names) or \
               {"binaries/linux64/ShapeFilter.so", "binaries/win64/ShapeFilter.dll"} <= set(names), names
        assert "sources/buildDescription.xml" in names and "sources/model.c" in names


# ------------------------------------------------------------------ state and errors

def test_state_get_set_and_serialised_restore_exactly(native_shapers, native_filters):
    assert_state_restores_exactly(native_shapers[("ei", 2)][0], command_signal(120), H, at=40)
    assert_state_restores_exactly(native_filters["hanning2"][0], command_signal(300), H, at=170)


def errors_of(capfd):
    return capfd.readouterr().out


@pytest.mark.parametrize("name, value, words", [
    ("zeta[1]", 1.2, "zeta[1] must be in [0, 1), got 1.2"),
    ("f[1]", -5.0, "f[1] must be > 0, got -5"),
    ("Ts", 0.0, "Ts must be > 0, got 0"),
    ("u0", float("inf"), "u0 must be finite, got inf"),
])
def test_bad_parameters_are_refused_with_error_and_a_logged_message(native_shapers, capfd, name, value, words):
    slave, vr = configured(native_shapers[("zvd", 2)][0])
    with pytest.raises(FMICallException) as failure:
        slave.setReal([vr[name]], [value])
    assert failure.value.status == 3
    slave.freeInstance()
    assert words in errors_of(capfd)


def test_a_build_time_design_refuses_other_modes_and_says_to_rebuild(native_shapers, capfd):
    slave, vr = configured(native_shapers[("ei", 1)][0])
    with pytest.raises(FMICallException):
        slave.setReal([vr["f[1]"]], [14.0])
    slave.freeInstance()
    assert "f[1] is 13 in this native FMU, whose design is made at build time; got 14" in errors_of(capfd)
    slave, vr = configured(native_shapers[("zv", 2)][0])
    with pytest.raises(FMICallException):
        slave.setString([vr["kind"]], ["ei"])
    slave.freeInstance()
    assert "shapefmu build shaper --native --kind ei" in errors_of(capfd)


def test_a_redesign_with_more_impulses_than_the_fmu_holds_fails_initialisation(native_shapers, capfd):
    slave, vr = configured(native_shapers[("zv", 2)][0], {"kind": "zvdd"})
    with pytest.raises(FMICallException):
        slave.exitInitializationMode()
    slave.freeInstance()
    assert "kind zvdd with n = 3 for n_modes = 2 has more impulses than the 4 this FMU holds" in errors_of(capfd)


def test_a_step_over_more_than_ten_million_samples_is_an_error(native_shapers, capfd):
    slave, vr = initialised(native_shapers[("zvd", 2)][0])
    with pytest.raises(FMICallException):
        slave.doStep(0.0, 2e7 * H)
    slave.freeInstance()
    assert "spans 20000000 samples of Ts = 0.001 s; at most 10000000 per step" in errors_of(capfd)


def test_delays_beyond_the_delay_line_are_refused_with_its_limit(native_shapers, capfd):
    path, _ = native_shapers[("zvd", 2)]
    slave, vr = configured(path, {"Ts": 1e-9})  # 0.1 s of impulses at 1 ns: 1e8 samples
    with pytest.raises(FMICallException):
        slave.exitInitializationMode()
    slave.freeInstance()
    assert "samples of Ts = 1e-09 s; at most 10000000 (the delay line)" in errors_of(capfd)
    slave, vr = initialised(path)
    with pytest.raises(FMICallException):
        slave.setReal([vr["impulse_time[2]"]], [10.0])
    slave.freeInstance()
    assert "impulse_time[2] = 10 s lies beyond the delay line of" in errors_of(capfd)


def test_tuned_impulses_apply_between_steps(native_shapers):
    path, starts = native_shapers[("zv", 2)]
    slave, vr = initialised(path, {"n_modes": 1})
    commands = command_signal(200)
    t, out = 0.0, []
    for k, u in enumerate(commands):
        if k == 100:  # a pure delay of 5 samples from here on, applied to the remembered inputs
            slave.setReal([vr["impulse_time[1]"], vr["impulse_amplitude[1]"], vr["impulse_amplitude[2]"]],
                          [5 * H, 1.0, 0.0])
        slave.setReal([vr["u"]], [u])
        out.append(slave.getReal([vr["y"]])[0])
        slave.doStep(t, H)
        t += H
    slave.freeInstance()
    np.testing.assert_allclose(out[100:], commands[95:195], rtol=0, atol=1e-15)
