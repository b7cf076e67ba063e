"""Modes of machines the fitter knows nothing about (issue 32, part B): the second synthetic
generator (``identification.synthetic_chain``), checked first against independent references
(Klipper's own test generator, closed forms, an ODE solver), then read by ``identify`` from the raw
CSV files it writes: the truth, from each chain's eigenvalues, within 1 % in frequency and 15 % in
damping, the damping's 90 % interval holding it in at least 85 % of the modes, and no mode that the
chain does not have (no sweep harmonic, sweep end or fan tone). The fitter never imports the
generator (tests/test_layers.py keeps the floor plan; here the import itself is checked).
benchmarks/modes_chain.py runs the same on 200 chains."""

import ast
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.signal import find_peaks

from shapefmu.identification import identify
from shapefmu.identification import synthetic_chain as sc
from shapefmu.identification.recordings import G

CASES = range(2000, 2016)


def test_the_test_pattern_is_klippers():
    """Figures printed by Klipper's own SweepingVibrationsTestGenerator.gen_test (klippy/extras/
    resonance_tester.py, commit 84104bbbd7625d28b4eaaad83f4562972460ecd9, default settings, run
    outside this project): segment count, the last end time and acceleration, the first six
    segments, and the integrals of |a| and a^2 over the test."""
    ends, accels = sc.KlipperTest().segments()
    assert ends.size == 36615
    assert ends[-1] == pytest.approx(130.0024090338914, rel=1e-12)
    assert accels[-1] == pytest.approx(-8499.922317679942, rel=1e-12)
    first = [(0.05, 700.0), (0.1, 100.0), (0.14901960784313728, 94.0), (0.19803921568627453, 706.0),
             (0.21213203435596423, 711.8823529411764), (0.24613427415477698, -88.1176470588236)]
    np.testing.assert_allclose(np.column_stack([ends[:6], accels[:6]]), first, rtol=1e-12)
    held = np.diff(np.r_[0.0, ends])
    assert np.sum(np.abs(accels) * held) == pytest.approx(546071.6238186515, rel=1e-12)
    assert np.sum(accels**2 * held) == pytest.approx(2972901800.0668554, rel=1e-12)


def test_one_mass_has_the_closed_form_mode():
    mass, stiffness, damping = 0.7, 5.0e4, 21.0
    (mode,) = sc.Chain((mass,), (sc.Link(0, sc.BASE, stiffness, damping),)).modes()
    assert mode.frequency == pytest.approx(math.sqrt(stiffness / mass) / (2 * math.pi), rel=1e-12)
    assert mode.zeta == pytest.approx(damping / (2 * math.sqrt(stiffness * mass)), rel=1e-12)


def test_two_masses_with_non_proportional_damping_have_the_roots_of_their_characteristic_polynomial():
    """det(M s^2 + C s + K) = 0 for the chain base-k1,c1-m1-k2,c2-m2, expanded by hand, its roots by
    numpy: the second method for the eigenvalues of the state matrix."""
    m1, m2, k1, k2, c1, c2 = 0.5, 0.2, 6e4, 3e4, 30.0, 1.0  # c / k differs by 15x: not proportional
    chain = sc.Chain.two_masses(toolhead=m1, frame=m2, belt=k1, coupling=k2, belt_damping=c1, coupling_damping=c2)
    # (m1 s^2 + (c1 + c2) s + k1 + k2) (m2 s^2 + c2 s + k2) - (c2 s + k2)^2
    a = np.polymul([m1, c1 + c2, k1 + k2], [m2, c2, k2])
    polynomial = np.polysub(a, np.polymul([c2, k2], [c2, k2]))
    roots = [r for r in np.roots(polynomial) if r.imag > 0]
    expected = sorted((abs(r) / (2 * math.pi), -r.real / abs(r)) for r in roots)
    found = [(m.frequency, m.zeta) for m in chain.modes()]
    np.testing.assert_allclose(found, expected, rtol=1e-9)
    assert abs(found[0][1] / found[1][1] - found[0][0] / found[1][0]) > 0.05  # zeta is not proportional to f


def test_the_response_is_an_ode_solvers():
    """respond (exact discretisation in eigen-coordinates) against scipy's RK45 on the same equations
    of motion, M z'' + C z' + K z = -M 1 a_base, the sensor's acceleration z_0'' + a_base."""
    chain = sc.Chain.two_masses(toolhead=0.5, frame=0.2, belt=6e4, coupling=3e4, belt_damping=12.0, coupling_damping=6.0)
    mass, damping, stiffness = chain.matrices()
    dt = 1 / 25600
    t = np.arange(2560) * dt
    base = np.where((t % 0.02) < 0.01, 1000.0, -1000.0)  # held over each step

    def motion(time, state):
        a = base[min(int(time / dt + 1e-9), base.size - 1)]
        z, v = state[:2], state[2:]
        return np.r_[v, np.linalg.solve(mass, -damping @ v - stiffness @ z) - a]

    solved = solve_ivp(motion, (0, t[-1]), np.zeros(4), t_eval=t, max_step=dt / 4, rtol=1e-10, atol=1e-12)
    z, v = solved.y[:2], solved.y[2:]
    expected = (np.linalg.solve(mass, -damping @ v - stiffness @ z))[0]  # z'' + a_base: the a_base cancels
    np.testing.assert_allclose(sc.respond(chain, dt, base), expected, atol=2e-3 * np.abs(expected).max())


def test_the_accelerometer_quantises_clips_and_stamps_as_klipper_writes():
    chain = sc.Chain((0.3,), (sc.Link(0, sc.BASE, 1e5, 0.5),))  # 92 Hz, zeta 0.0014: it clips at 16 g
    test = sc.KlipperTest(freq_start=80.0, freq_end=100.0, hz_per_sec=2.0)
    t, xyz = sc.record(chain, test=test, sensor=sc.ADXL345, seed=1)
    scale = 2 * sc.ADXL345.klipper_scale * 1e-3 * G  # at 3200 Hz an ADXL345 count is always even
    np.testing.assert_allclose(xyz / scale, np.round(xyz / scale), atol=1e-9)
    assert xyz[:, 0].max() == pytest.approx((sc.ADXL345.counts - 2) * scale / 2, rel=1e-12)  # clipped
    assert np.all(np.diff(t) > 0) and np.allclose(t, np.round(t, 6), rtol=0, atol=1e-9)
    assert abs(len(t) / (t[-1] - t[0]) / 3200 - 1 - sc.Disturbances().rate_error) < 1e-3


def test_the_fitter_does_not_import_the_generators():
    folder = Path(sc.__file__).parent
    for module in ("modes.py", "spectra.py", "recordings.py"):
        tree = ast.parse((folder / module).read_text())
        names = {a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}
        names |= {f"{n.module}.{a.name}" for n in ast.walk(tree) if isinstance(n, ast.ImportFrom) for a in n.names}
        assert not [n for n in names if "synthetic" in n], (module, names)


def clearly_seen(chain: sc.Chain, share: float = 0.2):
    """The modes whose peak in the chain's exact f |H(f)|^2 reaches a fifth of the highest (a tenth
    is the rule; Klipper's coarse spectrum lowers a sharp peak, so between the two it may or may not
    show)."""
    a, b, c = chain.state_space()
    freq = np.linspace(5.0, 200.0, 8000)
    view = freq * np.abs([c @ np.linalg.solve(2j * math.pi * f * np.eye(a.shape[0]) - a, b) for f in freq]) ** 2
    peaks, _ = find_peaks(view, height=share * view.max())
    return [min(chain.modes(), key=lambda m: abs(m.frequency - freq[i])) for i in peaks]


@pytest.fixture(scope="module")
def read_back(tmp_path_factory):
    """(chain, modes identify reads from its raw CSV) for chains of CASES, a quarter on a LIS2DW."""
    folder = tmp_path_factory.mktemp("chains")
    found = {}
    for seed in CASES:
        chain = sc.Chain.random(seed)
        path = folder / f"raw_data_x_{seed}.csv"
        sc.write_klipper_raw(path, *sc.record(chain, sensor=sc.LIS2DW if seed % 4 == 3 else sc.ADXL345, seed=seed))
        found[seed] = (chain, identify(path, axis="x").modes)
        path.unlink()
    return found


def test_the_truth_within_1_percent_in_frequency_and_15_in_damping(read_back):
    for seed, (chain, found) in read_back.items():
        for true in clearly_seen(chain):
            mode = min(found.modes, key=lambda m: abs(m.frequency - true.frequency))
            assert abs(mode.frequency / true.frequency - 1) < 0.01, (seed, true, mode.describe())
            assert abs(mode.zeta / true.zeta - 1) < 0.15, (seed, true, mode.describe())


def test_the_damping_interval_holds_the_truth_in_85_percent(read_back):
    held = []
    for chain, found in read_back.values():
        for true in clearly_seen(chain):
            mode = min(found.modes, key=lambda m: abs(m.frequency - true.frequency))
            held.append(mode.zeta_interval[0] <= true.zeta <= mode.zeta_interval[1])
    assert len(held) >= 16 and sum(held) / len(held) >= 0.85, (sum(held), len(held))


def test_raw_sweeps_give_no_mode_the_chain_does_not_have(read_back):
    """Neither the sweep's 3rd and 5th harmonics, nor its end (135 Hz), nor the fan tones every
    recording carries (97.3 and 194.6 Hz), nor the sweeping to-and-fro's lines below 5 Hz."""
    for seed, (chain, found) in read_back.items():
        for mode in found.modes:
            assert any(abs(mode.frequency / t.frequency - 1) < 0.02 for t in chain.modes()), (seed, mode.describe())


def test_strong_fan_tones_are_told_from_resonances(tmp_path):
    """Tones of 0.3 and 0.5 g, as high in the spectrum as the resonance, but there all the time."""
    chain = sc.Chain.random(4)
    path = tmp_path / "raw_data_x.csv"
    loud = sc.Disturbances(tones=((97.3, 3000.0), (151.0, 5000.0)))
    sc.write_klipper_raw(path, *sc.record(chain, disturbances=loud, seed=4))
    found = identify(path, axis="x").modes
    assert [round(m.frequency) for m in found.modes] == [round(m.frequency) for m in clearly_seen(chain)]
    assert sum("steady tone" in note for note in found.notes) == 2, found.notes


def test_the_accelerometer_at_rest_gives_no_mode(tmp_path):
    """White and 1/f noise, drift, quantisation and the two fan tones, the machine not moved (a
    test with a billionth of Klipper's acceleration): no resonance, and the output says so."""
    still = sc.KlipperTest(accel_per_hz=1e-9, sweeping_accel=1e-9)
    path = tmp_path / "raw_data_x.csv"
    sc.write_klipper_raw(path, *sc.record(sc.Chain.random(0), test=still, seed=5))
    found = identify(path, axis="x").modes
    assert found.modes == () and "no resonance" in found.notes[-1], found.notes
