"""A fuzzer with fixed seeds over the recording readers and the reading options of ``identify``
(issue 34's acceptance): Klipper raw and spectrum files, RepRapFirmware M956 files, CSV and Parquet
tables, each mutated (a value made hostile, a line dropped, doubled or swapped, the file cut short,
a byte-order mark, a header changed) and read with hostile options. Every run ends with exit 0 and
finite numbers, or exit 2 and one line on stderr: no traceback, no NaN or inf called a result, no
hang."""

import math
import re

import numpy as np
import pytest
from hostile_support import guarded

SEEDS = range(3400, 3560)
HOSTILE_VALUES = ["nan", "inf", "-inf", "1e308", "-1e308", "1e-320", "1_234", "0x10", "", " ", "1e999999",
                  "9" * 400, "\x00", "\u0661\u0662", "-0", "+.5e-3", "1,2", "1e100", "-1e100", "NaN", "true"]
HOSTILE_OPTIONS = [["--axis", "y"], ["--axis", "1,1,0"], ["--axis", "0,0,0"], ["--axis", "1e-320,0,0"],
                   ["--axis", "nan,1,0"], ["--f-min", "-5"], ["--f-max", "1e308"], ["--f-min", "nan"],
                   ["--f-max", "3"], ["--f-min", "100", "--f-max", "20"], ["--excitation", "flat"],
                   ["--undo-sweep"], ["--json"], ["--axis", "q"]]


def klipper_raw(rng) -> str:
    t = 1000.0 + np.arange(4000) / 3200 + rng.uniform(-2e-6, 2e-6, 4000)
    x = 3000 * np.sin(2 * np.pi * 40 * t) * np.exp(-((t - t[2000]) ** 2) / 0.1) + rng.normal(0, 50, 4000)
    rows = np.column_stack([t, x, 0.1 * x, 9806.65 + rng.normal(0, 50, 4000)])
    return "#time,accel_x,accel_y,accel_z\n" + "".join("%.6f,%.3f,%.3f,%.3f\n" % tuple(r) for r in rows)


def m956(rng) -> str:
    values = 0.3 * np.sin(2 * np.pi * 35 * np.arange(3000) / 1000) + rng.normal(0, 0.01, 3000)
    return "Sample,X,Y\n" + "".join(f"{i},{v:.5f},{v / 3:.5f}\n" for i, v in enumerate(values)) + "Rate 1000, overflows 0\n"


def klipper_spectrum(rng) -> str:
    f = np.arange(0.0, 200.0, 1.5625)
    psd = 1e4 * f**2 / ((f**2 - 45.0**2) ** 2 + (4.5 * f) ** 2) * rng.uniform(0.9, 1.1, f.size)
    return "freq,psd_x,psd_y,psd_z,psd_xyz\n" + "".join(f"{a:.1f},{b:.3e},1e-1,1e-1,{b + 0.2:.3e}\n"
                                                       for a, b in zip(f, psd))


def table(rng) -> str:
    t = np.arange(3000) / 800
    return "t,a,b\n" + "".join(f"{x:.6f},{v:.5f},{rng.normal():.5f}\n" for x, v in zip(t, np.sin(60 * t)))


KINDS = {"raw": (klipper_raw, []), "m956": (m956, []), "spectrum": (klipper_spectrum, []),
         "table": (table, ["--time", "t", "--column", "a"])}


def mutate(text: str, rng) -> bytes:
    lines = text.splitlines(keepends=True)
    for _ in range(int(rng.integers(1, 4))):
        choice = int(rng.integers(0, 7))
        i = int(rng.integers(0, len(lines)))
        if choice == 0:  # a value made hostile
            fields = lines[i].rstrip("\n").split(",")
            fields[int(rng.integers(0, len(fields)))] = HOSTILE_VALUES[int(rng.integers(0, len(HOSTILE_VALUES)))]
            lines[i] = ",".join(fields) + "\n"
        elif choice == 1 and len(lines) > 2:
            del lines[i]
        elif choice == 2:
            lines.insert(i, lines[i])
        elif choice == 3:
            j = int(rng.integers(0, len(lines)))
            lines[i], lines[j] = lines[j], lines[i]
        elif choice == 4:
            return ("".join(lines)).encode()[: int(rng.integers(0, len(text)))]
        elif choice == 5:
            lines[0] = "\ufeff" + lines[0]
        else:
            lines[0] = lines[0].replace(",", ";" if rng.uniform() < 0.5 else ",,", 1)
    return "".join(lines).encode("utf-8", "surrogatepass")


@pytest.mark.parametrize("seed", SEEDS)
def test_a_mutated_recording_is_read_or_refused_in_one_line(tmp_path, seed):
    rng = np.random.default_rng(seed)
    kind = list(KINDS)[seed % len(KINDS)]
    make, options = KINDS[kind]
    path = tmp_path / f"{kind}.csv"
    path.write_bytes(mutate(make(rng), rng))
    extra = HOSTILE_OPTIONS[int(rng.integers(0, len(HOSTILE_OPTIONS)))] if rng.uniform() < 0.5 else []
    code, out, err = guarded(["identify", path, *options, *extra], seconds=120)
    if code == 2:
        assert err.count("\n") == 1 and err.startswith("shapefmu identify: error:"), err
        return
    assert code == 0, (code, out, err)
    numbers = re.findall(r"(?<![\w.])[-+]?(?:\d+\.?\d*(?:e[-+]?\d+)?|nan|inf)", out.split("\n", 1)[-1], re.I)
    assert all(math.isfinite(float(n)) for n in numbers), out


@pytest.mark.parametrize("seed", SEEDS[:12])
def test_a_mutated_parquet_table_is_read_or_refused_in_one_line(tmp_path, seed):
    import pyarrow as pa
    import pyarrow.parquet as pq

    rng = np.random.default_rng(seed)
    n = int(rng.integers(0, 5000))
    columns = {"t": np.arange(n) / 800.0, "a": np.sin(np.arange(n) / 3.0)}
    hostile = [np.nan, np.inf, 1e308, -1e-320, 0.0]
    if n:
        columns["a"][int(rng.integers(0, n))] = hostile[int(rng.integers(0, len(hostile)))]
    path = tmp_path / "log.parquet"
    pq.write_table(pa.table(columns), path)
    data = bytearray(path.read_bytes())
    if rng.uniform() < 0.5:  # a byte of the file changed
        data[int(rng.integers(0, len(data)))] = int(rng.integers(0, 256))
    path.write_bytes(bytes(data))
    code, out, err = guarded(["identify", path, "--time", "t", "--column", "a"], seconds=120)
    assert code in (0, 2) and (code == 0 or err.count("\n") == 1), (code, out, err)
