"""Raw resonance tests of a machine the fitter knows nothing about: a base-excited chain of masses,
springs and dampers, driven by Klipper's own test pattern and recorded the way an ADXL345 or a
LIS2DW records it.

This is the second generator of issue 32. It shares no model with ``modes``: the machine is a
multi-degree-of-freedom chain with non-proportional damping (a damper need not sit beside its
spring in proportion, so the modes are complex), simulated in the time domain; its truth is the
modal frequencies and damping ratios from the eigenvalues of its state matrix (``Chain.modes``),
never a formula of the fitter.

The test pattern (``KlipperTest``), as Klipper's ``resonance_tester.py`` of the commit in
``tests/data/recordings/SOURCES`` generates it (read, not copied; GPL):

- the vibration part: at the current frequency f the commanded acceleration is +A(f) for a quarter
  period, -A(f) for the next quarter, then the next half period mirrored (-A, +A): a square wave of
  period 1/f whose sign alternates every half period, A(f) = ``accel_per_hz`` * f; after each half
  period f grows by ``hz_per_sec`` * (half period), from ``freq_start`` to ``freq_end``;
- the sweeping part: a slow square wave of +-``sweeping_accel`` added to it, switching first after
  ``sweeping_period`` * sqrt(2)/8, then after ``sweeping_period`` * (sqrt(2)/8 + 1/4), then every half
  ``sweeping_period`` (so that the toolhead drifts to and fro around where it started);
- defaults of that commit: 5 to 135 Hz at 1 Hz/s, 60 mm/s^2 per Hz, 400 mm/s^2 every 1.2 s.

The stepper follows the command exactly; the chain's base is the commanded motion and the
accelerometer sits on one of the masses (the toolhead).

The accelerometer (``Accelerometer``; datasheet values, Klipper's drivers for the settings Klipper
uses): it samples at its own clock (a rate a little off nominal, drifting by ppm), after its
low-pass filter at half the output data rate; white noise of the datasheet's density, 1/f noise
below a corner, a slow offset drift; quantised to its LSB (an ADXL345 in full resolution at 3200 Hz
always returns an even count), clipped at its range, converted with the scale Klipper's driver uses
(which need not be the chip's). Fixed fan tones shake the toolhead on every axis. The timestamps
written are Klipper's estimate of the sample times (a clock regression per batch: off by a few
microseconds, slowly) rounded to the microsecond, as Klipper's raw CSV prints them.

    >>> chain = Chain.two_masses(toolhead=0.5, frame=0.2, belt=60e3, coupling=30e3,
    ...                          belt_damping=12.0, coupling_damping=6.0)
    >>> [f"{m.frequency:.1f} Hz, zeta {m.zeta:.3f}" for m in chain.modes()]
    ['41.8 Hz, zeta 0.026', '81.3 Hz, zeta 0.051']
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.linalg import eig, expm
from scipy.signal import butter, lfilter, sosfilt

from shapefmu.identification.recordings import G

BASE = -1  # the end of a link fixed to the commanded motion


@dataclass(frozen=True)
class Link:
    """A spring (``stiffness``, N/m) and a damper (``damping``, N s/m) between mass ``a`` and mass
    ``b`` (``BASE`` for the commanded motion)."""

    a: int
    b: int
    stiffness: float
    damping: float


@dataclass(frozen=True)
class ChainMode:
    """A mode of the chain from one eigenvalue lambda of its state matrix: ``frequency`` =
    |lambda| / 2 pi (Hz), ``zeta`` = -Re(lambda) / |lambda|."""

    frequency: float
    zeta: float


@dataclass(frozen=True)
class Chain:
    """Masses (kg) joined by ``links``; the accelerometer on mass ``sensor``."""

    masses: tuple[float, ...]
    links: tuple[Link, ...]
    sensor: int = 0

    def __post_init__(self):
        n = len(self.masses)
        if not 1 <= n <= 12 or not all(math.isfinite(m) and m > 0 for m in self.masses):
            raise ValueError(f"a chain has 1 to 12 masses, each positive, got {self.masses!r}")
        for link in self.links:
            if not (0 <= link.a < n and (link.b == BASE or 0 <= link.b < n) and link.a != link.b):
                raise ValueError(f"a link joins two masses 0..{n - 1} or a mass and BASE, got {link!r}")
            if not (link.stiffness > 0 and link.damping >= 0):
                raise ValueError(f"a link has stiffness > 0 and damping >= 0, got {link!r}")
        if not 0 <= self.sensor < n:
            raise ValueError(f"sensor must be a mass 0..{n - 1}, got {self.sensor!r}")

    @classmethod
    def two_masses(cls, *, toolhead, frame, belt, coupling, belt_damping, coupling_damping) -> "Chain":
        """The toolhead on a belt from the commanded motion, and a frame part hung on the toolhead."""
        return cls((toolhead, frame), (Link(0, BASE, belt, belt_damping), Link(1, 0, coupling, coupling_damping)))

    @classmethod
    def random(cls, seed: int, *, band=(20.0, 120.0), zetas=(0.02, 0.2), separation=1.15) -> "Chain":
        """A chain of two or three masses (in series or branched, a part sometimes tied to the base
        too), dampers drawn apart from the springs, redrawn until every mode lies in ``band`` (Hz)
        with damping in ``zetas`` and neighbouring modes are at least ``separation`` apart.

        >>> [f"{m.frequency:.1f} Hz, zeta {m.zeta:.3f}" for m in Chain.random(0).modes()]
        ['41.4 Hz, zeta 0.057', '65.0 Hz, zeta 0.170']
        """
        rng = np.random.default_rng(seed)
        for _ in range(10000):
            n = int(rng.integers(2, 4))
            masses = tuple(float(m) for m in rng.uniform(0.3, 3.0, n))
            ends = [BASE, 0] + ([int(rng.integers(0, 2))] if n == 3 else [])
            links = []
            for i, end in enumerate(ends):
                other = i if i else 0
                if i == 0:
                    other, end = 0, BASE
                w = 2 * math.pi * rng.uniform(*band)
                stiffness = w * w * masses[other] * rng.uniform(0.5, 2.0)
                links.append(Link(other, end, stiffness, 2 * rng.uniform(*zetas) * math.sqrt(stiffness * masses[other])))
            if n >= 2 and rng.uniform() < 0.3:
                w = 2 * math.pi * rng.uniform(*band)
                links.append(Link(n - 1, BASE, w * w * masses[-1] * 0.3, rng.uniform(0, 5.0)))
            chain = cls(masses, tuple(links))
            modes = chain.modes()
            freqs = [m.frequency for m in modes]
            if (len(modes) == n and all(band[0] <= f <= band[1] for f in freqs)
                    and all(zetas[0] <= m.zeta <= zetas[1] for m in modes)
                    and all(b / a >= separation for a, b in zip(freqs, freqs[1:]))):
                return chain
        raise ValueError(f"no chain found with modes in {band} Hz and damping in {zetas}")

    def matrices(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(M, C, K) in coordinates relative to the base: M z'' + C z' + K z = -M 1 a_base.

        >>> Chain((1.0, 2.0), (Link(0, BASE, 10.0, 1.0), Link(1, 0, 5.0, 0.5))).matrices()[2].tolist()
        [[15.0, -5.0], [-5.0, 5.0]]
        """
        n = len(self.masses)
        stiffness, damping = np.zeros((n, n)), np.zeros((n, n))
        for link in self.links:
            for matrix, value in ((stiffness, link.stiffness), (damping, link.damping)):
                matrix[link.a, link.a] += value
                if link.b != BASE:
                    matrix[link.b, link.b] += value
                    matrix[link.a, link.b] -= value
                    matrix[link.b, link.a] -= value
        return np.diag(self.masses), damping, stiffness

    def state_space(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(A, B, C): state [z, z'], input the base acceleration, output the sensor mass's absolute
        acceleration z'' + a_base (the -1 of B and the +1 of the base cancel: no feed-through).

        >>> a, b, c = Chain((2.0,), (Link(0, BASE, 8.0, 1.0),)).state_space()
        >>> a.tolist(), b.tolist(), c.tolist()
        ([[0.0, 1.0], [-4.0, -0.5]], [0.0, -1.0], [-4.0, -0.5])
        """
        mass, damping, stiffness = self.matrices()
        n = len(self.masses)
        inverse = np.linalg.inv(mass)
        a = np.block([[np.zeros((n, n)), np.eye(n)], [-inverse @ stiffness, -inverse @ damping]])
        b = np.concatenate([np.zeros(n), -np.ones(n)])
        return a, b, a[n + self.sensor].copy()

    def modes(self) -> tuple[ChainMode, ...]:
        """The underdamped modes, lowest first, from the eigenvalues of the state matrix.

        >>> [(round(m.frequency, 4), round(m.zeta, 4)) for m in Chain((1.0,), (Link(0, BASE, 400.0, 4.0),)).modes()]
        [(3.1831, 0.1)]
        """
        values = np.linalg.eigvals(self.state_space()[0])
        pairs = [v for v in values if v.imag > 0]
        return tuple(sorted((ChainMode(float(abs(v) / (2 * math.pi)), float(-v.real / abs(v))) for v in pairs),
                            key=lambda m: m.frequency))


@dataclass(frozen=True)
class KlipperTest:
    """Klipper's TEST_RESONANCES pattern (module docstring), defaults of the recorded commit."""

    freq_start: float = 5.0
    freq_end: float = 135.0
    accel_per_hz: float = 60.0
    hz_per_sec: float = 1.0
    sweeping_accel: float = 400.0
    sweeping_period: float = 1.2

    def segments(self) -> tuple[np.ndarray, np.ndarray]:
        """(end times in s, commanded acceleration in mm/s^2 until each end) from t = 0.

        >>> ends, accels = KlipperTest().segments()
        >>> [round(float(e), 4) for e in ends[:3]], accels[:3].tolist()
        ([0.05, 0.1, 0.149], [700.0, 100.0, 94.0])
        """
        ends, accels = [], []
        time, freq, sign = 0.0, self.freq_start, 1.0
        while freq <= self.freq_end + 1e-6:
            quarter = 0.25 / freq
            accel = self.accel_per_hz * freq
            ends += [time + quarter, time + 2 * quarter]
            accels += [sign * accel, -sign * accel]
            time += 2 * quarter
            freq += 2 * quarter * self.hz_per_sec
            sign = -sign
        ends, accels = np.array(ends), np.array(accels)
        if self.sweeping_period <= 0:
            return ends, accels
        # the sweeping square wave's switching times, merged into the breakpoints
        first = self.sweeping_period * math.sqrt(2) / 8
        second = first + self.sweeping_period * (math.sqrt(2) / 8 + 0.25)
        switches = np.r_[first, np.arange(second, ends[-1], self.sweeping_period / 2)]
        switches = switches[switches < ends[-1]]
        merged = np.union1d(ends, switches)
        vibration = accels[np.searchsorted(ends, merged, side="left")]
        # a segment ending at merged[i] started at merged[i-1]; its sweeping sign flips at each switch passed
        starts = np.r_[0.0, merged[:-1]]
        sweeping = self.sweeping_accel * np.where(np.searchsorted(switches, starts, side="right") % 2, -1.0, 1.0)
        return merged, vibration + sweeping

    @property
    def duration(self) -> float:
        """The test's length, s.

        >>> round(KlipperTest(hz_per_sec=2.0).duration, 3)
        65.002
        """
        return float(self.segments()[0][-1])


@dataclass(frozen=True)
class Accelerometer:
    """A sensor as Klipper runs it: ``rate`` (Hz, output data rate), ``sensitivity`` (mg per count,
    the chip's), ``klipper_scale`` (mg per count, what Klipper's driver multiplies by), ``step``
    (counts between possible outputs), ``counts`` (the largest |count|), ``noise_density`` (ug/sqrt Hz)
    and the low-pass ``bandwidth`` (Hz)."""

    name: str
    rate: float
    sensitivity: float
    klipper_scale: float
    step: int
    counts: int
    noise_density: float
    bandwidth: float

    @property
    def full_scale(self) -> float:
        """The largest acceleration it reports before clipping, mm/s^2.

        >>> round(ADXL345.full_scale / G, 2)
        15.97
        """
        return self.counts * self.sensitivity * 1e-3 * G


# ADXL345 data sheet (Rev. G): full resolution at +-16 g is 13 bits at 3.9 mg/LSB (256 LSB/g); at
# 3200 and 1600 Hz the data word's LSB is always 0; bandwidth ODR/2; noise density 290 ug/sqrt(Hz) on
# x and y. Klipper's adxl345.py runs it at 3200 Hz and scales x, y by 3.774 mg/LSB.
ADXL345 = Accelerometer("ADXL345", 3200.0, 3.9, 3.774, 2, 4096, 290.0, 1600.0)
# LIS2DW12 data sheet: +-16 g is 14 bits at 1.952 mg/LSB; 90 ug/sqrt(Hz) in high-performance mode.
# Klipper's lis2dw.py runs it at 1600 Hz, low-pass at ODR/2, with the data sheet's scale.
LIS2DW = Accelerometer("LIS2DW", 1600.0, 1.952, 1.952, 1, 8192, 90.0, 800.0)


@dataclass(frozen=True)
class Disturbances:
    """What else the accelerometer feels: fixed fan ``tones`` ((Hz, mm/s^2 amplitude), on every axis
    with a random share and phase), 1/f noise of the sensor's own density at ``flicker_corner`` Hz, a
    slow offset ``drift`` (mm/s^2 over the record), the sensor's ``tilt`` (rad: gravity and the motion
    leak into the other axes) and the chip's ``rate_error`` (fractional, the clock's offset)."""

    tones: tuple[tuple[float, float], ...] = ((97.3, 150.0), (194.6, 60.0))
    flicker_corner: float = 5.0
    drift: float = 150.0
    tilt: float = 0.02
    rate_error: float = 0.004


def _base_acceleration(test: KlipperTest, t: np.ndarray) -> np.ndarray:
    """The commanded acceleration averaged over each step of the uniform grid ``t`` (exactly: the
    difference of the exact velocity at the grid points, over the step)."""
    ends, accels = test.segments()
    velocity_at_ends = np.cumsum(accels * np.diff(np.r_[0.0, ends]))
    clipped = np.clip(t, 0.0, ends[-1])
    index = np.minimum(np.searchsorted(ends, clipped, side="right"), len(ends) - 1)
    start_velocity = np.r_[0.0, velocity_at_ends][index]
    start_time = np.r_[0.0, ends][index]
    velocity = np.where(clipped >= ends[-1], velocity_at_ends[-1], start_velocity + accels[index] * (clipped - start_time))
    # Klipper then brakes to a stop at the printer's acceleration; 5000 mm/s^2 here
    after = np.maximum(t - ends[-1], 0.0)
    final = velocity_at_ends[-1]
    velocity = velocity - np.sign(final) * np.minimum(5000.0 * after, abs(final))
    return np.diff(velocity) / np.diff(t)


def respond(chain: Chain, dt: float, base: np.ndarray) -> np.ndarray:
    """The sensor mass's acceleration for the base acceleration ``base`` held over steps of ``dt``:
    the state space discretised exactly for a held input (matrix exponential), run in the
    eigenvector coordinates of the discrete system (one first-order recursion per eigenvalue).

    >>> import numpy as np
    >>> step = respond(Chain((1.0,), (Link(0, BASE, 400.0, 4.0),)), 1e-3, np.ones(20000))
    >>> round(float(step[-1]), 6), round(float(step.max()), 3)               # settles at 1, overshoots
    (1.0, 1.744)
    """
    a, b, c = chain.state_space()
    n = a.shape[0]
    augmented = np.zeros((n + 1, n + 1))
    augmented[:n, :n], augmented[:n, n] = a * dt, b * dt
    step = expm(augmented)
    values, vectors = eig(step[:n, :n])
    inputs = np.linalg.solve(vectors, step[:n, n])
    outputs = c @ vectors
    y = np.zeros(base.size)
    for value, into, out in zip(values, inputs, outputs):
        if value.imag < 0:  # its conjugate's term, doubled below, stands for both
            continue
        q = lfilter([0.0, into], [1.0, -value], base)
        y += (out * q).real * (2.0 if value.imag > 0 else 1.0)
    return y


def _flicker(rng, n: int, rate: float, density: float, corner: float) -> np.ndarray:
    """Noise of power density density^2 * corner / f (f > 1/duration): white noise shaped in frequency."""
    spectrum = np.fft.rfft(rng.normal(size=n))
    f = np.fft.rfftfreq(n, 1 / rate)
    f[0] = f[1]
    return np.fft.irfft(spectrum * np.sqrt(corner / f), n) * density * math.sqrt(rate / 2)


def record(chain: Chain, *, test: KlipperTest = KlipperTest(), sensor: Accelerometer = ADXL345,
           disturbances: Disturbances = Disturbances(), axis: str = "x", oversample: int = 8, seed: int = 0,
           start: float = 2345.678) -> tuple[np.ndarray, np.ndarray]:
    """(timestamps in s, (N, 3) accelerations x, y, z in mm/s^2) of Klipper's resonance test of
    ``axis`` on ``chain``, as Klipper's raw CSV holds them (module docstring).

    >>> t, xyz = record(Chain.random(0), test=KlipperTest(freq_start=30.0, freq_end=50.0, hz_per_sec=2.0))
    >>> xyz.shape, round(float(t[1] - t[0]), 6), round(float(np.median(xyz[:, 2]) / G), 2)
    ((34353, 3), 0.000312, 0.97)
    """
    if axis not in ("x", "y"):
        raise ValueError(f"axis must be 'x' or 'y' (the chain moves in one horizontal direction), got {axis!r}")
    if not 2 <= oversample <= 64:
        raise ValueError(f"oversample must be in [2, 64], got {oversample!r}")
    rng = np.random.default_rng(seed)
    lead, tail = 0.3, 0.4
    fine_rate = sensor.rate * oversample
    duration = test.duration + lead + tail
    t_fine = np.arange(int(duration * fine_rate) + 1) / fine_rate - lead
    base = _base_acceleration(test, t_fine)
    moving = respond(chain, 1 / fine_rate, base)
    # the chip's low-pass (second order at its bandwidth), then its own sampling clock
    moving = sosfilt(butter(2, sensor.bandwidth, fs=fine_rate, output="sos"), moving)
    rate = sensor.rate * (1 + disturbances.rate_error)
    count = int((duration - 0.01) * rate)
    wander = np.cumsum(rng.normal(0.0, 20e-6, count)) / rate  # the oscillator's drift: ppm, slowly
    instants = np.arange(count) / rate + wander + rng.uniform(0, 1 / rate)
    motion = np.interp(instants, t_fine[:-1] - t_fine[0], moving)
    tilt = disturbances.tilt
    moving_axis, other_axis = (0, 1) if axis == "x" else (1, 0)
    xyz = np.zeros((count, 3))
    xyz[:, moving_axis] = math.cos(tilt) * motion
    xyz[:, other_axis] = math.sin(tilt) * 0.5 * motion
    xyz[:, 2] = G * math.cos(tilt) + math.sin(tilt) * motion
    xyz[:, moving_axis] += G * math.sin(tilt)
    for frequency, amplitude in disturbances.tones:
        shares = rng.uniform(0.3, 1.0, 3)
        xyz += amplitude * shares * np.sin(2 * math.pi * frequency * instants[:, None] + rng.uniform(0, 2 * math.pi, 3))
    density = sensor.noise_density * 1e-6 * G  # mm/s^2 per sqrt(Hz)
    for i in range(3):
        xyz[:, i] += rng.normal(0.0, density * math.sqrt(sensor.rate / 2), count)
        xyz[:, i] += _flicker(rng, count, sensor.rate, density, disturbances.flicker_corner)
        phase = rng.uniform(0, 2 * math.pi)
        xyz[:, i] += disturbances.drift * np.sin(2 * math.pi * instants / (3 * duration) + phase)
    lsb = sensor.sensitivity * 1e-3 * G
    counts = np.clip(sensor.step * np.round(xyz / (lsb * sensor.step)), -sensor.counts, sensor.counts - sensor.step)
    values = counts * sensor.klipper_scale * 1e-3 * G
    # Klipper's timestamps: its clock regression, off by a slowly changing few microseconds, printed to 1 us
    batches = np.arange(count) // max(int(0.1 * sensor.rate), 1)
    estimate_error = np.cumsum(rng.normal(0.0, 0.7e-6, batches[-1] + 1))[batches]
    stamps = np.round(start + t_fine[0] + instants + estimate_error, 6)
    return stamps, values


def write_klipper_raw(path, t, xyz) -> None:
    """Klipper's raw CSV (``#time,accel_x,accel_y,accel_z``, every number with six decimals).

    >>> import pathlib, tempfile
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "raw_data_x.csv"
    >>> write_klipper_raw(path, np.array([1.0, 1.0003]), np.array([[1.5, 0.0, 9806.65], [-1.5, 0.0, 9806.65]]))
    >>> path.read_text().splitlines()[:2]
    ['#time,accel_x,accel_y,accel_z', '1.000000,1.500000,0.000000,9806.650000']
    """
    rows = np.column_stack([t, xyz])
    with open(path, "w") as stream:
        stream.write("#time,accel_x,accel_y,accel_z\n")
        for start in range(0, len(rows), 100_000):  # one format per block: half of savetxt's time, row by row
            block = rows[start:start + 100_000]
            stream.write(("%.6f,%.6f,%.6f,%.6f\n" * len(block)) % tuple(block.ravel().tolist()))
