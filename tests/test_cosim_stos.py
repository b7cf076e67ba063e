"""STOS <-> disk drive (models/disk_drive_stos.ssd): our master against libcosim and ecos, and the
closed loop through FMUs against the design layer's sampled loop (shapefmu.stos.simulate_stos)."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
from support.ssp_hosts import run_ecos, run_libcosim

from shapefmu.cosim import simulate
from shapefmu.compare import FMUCache, move_metrics
from shapefmu.fmi.ssp import read_ssp
from shapefmu.plants import load
from shapefmu.stos import simulate_stos, stos_law

MODELS = Path(__file__).resolve().parent.parent / "models"
TS, N, X, U = 1e-6, 4000, 0.05, 11.0  # the .ssd's controller sampling, target and the plant's limit
PLANT = ["plant.position", "plant.velocity", "plant.deflection_1", "plant.deflection_2"]


@pytest.fixture(scope="module")
def stos_ssd(tmp_path_factory):
    """models/disk_drive_stos.ssd as shipped, next to a fmus/ folder holding the FMUs it names."""
    root = tmp_path_factory.mktemp("stos_system")
    (root / "models").mkdir()
    ssd = Path(shutil.copy(MODELS / "disk_drive_stos.ssd", root / "models"))
    fmus = FMUCache(root / "fmus")
    fmus.slave("STOSController")
    fmus.plant(load(MODELS / "disk_drive.toml"))
    return ssd


def test_jacobi_equals_libcosim_and_ecos_on_the_same_ssp(stos_ssd):
    ssp = read_ssp(stos_ssd).write_ssp(stos_ssd.parent / "stos.ssp")
    variables = ["controller.u", *PLANT]
    ours = simulate(ssp, N * TS, TS, algorithm="jacobi", record=variables)
    ours = np.column_stack([ours[v] for v in variables])
    assert np.ptp(ours[:, 1]) > 0.9 * X and np.ptp(ours[:, 3]) > 1e-5  # the move and the vibration happen
    assert np.max(np.abs(ours[:, 0])) == pytest.approx(U, rel=1e-12)  # it bangs at the limit
    libcosim = run_libcosim(ssp, TS, N, variables)
    np.testing.assert_allclose(ours[1:, 1:], libcosim[1:, 1:], rtol=0, atol=1e-9)
    # u to 1e-9 of its scale U. The law is discontinuous in the state, and libcosim's step times
    # (integer ns, converted per step) differ from ours by ulps: the plants then differ by ~4e-15
    # rad, which the sub-sample switching blend turns into up to ~7e-9 V of u at a switch.
    np.testing.assert_allclose(ours[1:, 0], libcosim[1:, 0], rtol=0, atol=1e-9 * U)
    ecos = run_ecos(ssp, TS, N, variables)
    # ecos reads the feed-through u after it has set the new measurement (see shapefmu.cosim.master);
    # the plant's outputs, which only the applied u drives, are the same in all three hosts.
    np.testing.assert_allclose(ours[:, 1:], ecos[:, 1:], rtol=0, atol=1e-9)


def test_gauss_seidel_closed_loop_reproduces_simulate_stos(stos_ssd):
    """Same Ts, same plant, same law: the design layer's loop reads x(t_k), holds u_k = law(x(t_k))
    over [t_k, t_k + Ts] on the exact zero-order-hold plant. Gauss-Seidel steps the plant, then
    hands the controller x(t_k+1) and passes on its feed-through u as read at that communication
    point: the same sequence. (Jacobi, libcosim and ecos hand the plant the u read at the end of
    the controller's step, computed from the previous measurement: a one-step delay, which this
    law, switching within the sample, pays with ~1e-5 rad of residual vibration.)

    What remains is rounding: the generated plant's C matrix exponential against scipy's, ~1e-16 relative
    per step. The sub-sample blend amplifies a state difference at a switch (as above, up to
    ~1e-9 U); such a u difference moves the velocity by b du Ts per step and the position by at
    most b du Ts t_end = 2.7e3 * 1.1e-8 * 1e-6 * 4e-3 ~ 1e-13 rad over the run: hence 1e-9 U on
    u and 1e-12 rad on the states.
    """
    system = read_ssp(stos_ssd)
    ours = simulate(system, N * TS, TS, record=["plant.voltage", *PLANT])
    plant = load(MODELS / "disk_drive.toml")
    law = stos_law(plant, "simultaneous", TS)
    reference = simulate_stos(plant, law, X, TS, N * TS)
    states = {"plant.position": 0, "plant.velocity": 1, "plant.deflection_1": 2, "plant.deflection_2": 4}
    for name, column in states.items():
        np.testing.assert_allclose(ours[name], reference.x[:, column], rtol=0, atol=1e-12, err_msg=name)
    # the plant's input recorded at t_k+1 is the one it held over [t_k, t_k+1]
    np.testing.assert_allclose(ours["plant.voltage"][1:], reference.u[:-1], rtol=0, atol=1e-9 * U)
    assert reference.metrics.handover_time < N * TS  # the settle controller took over within the run
    window = 1.0 / 2000.0
    mine = move_metrics(ours["time"], np.append(ours["plant.voltage"][1:], 0.0), ours["plant.position"],
                        [ours["plant.deflection_1"], ours["plant.deflection_2"]], X, U, window)
    theirs = move_metrics(reference.t, reference.u, reference.x[:, 0], reference.x[:, [2, 4]].T, X, U, window)
    assert mine.move_time == theirs.move_time
    assert mine.residual == pytest.approx(theirs.residual, rel=0, abs=1e-12 / X)
