"""A shaper whose design follows a moving mode, re-designed at a sample with no jump in its output.

``ModeSchedule`` maps a scheduling value (an added mass, a rope length) to the mode in force: a
table of (value, f, zeta) rows, or a linear law f = f0 + gain * value (Marlin FT_MOTION's dynamic
frequency, ``Marlin/src/module/ft_motion.cpp``: base frequency plus a user-set gain in Hz/mm of Z or
Hz/g of extruded filament). ``ModeFollowingShaper`` shapes a command for the mode it is given at
each sample; ``ScheduledShaperKernel`` is the two together, the per-sample kernel of a scheduled
shaper.

Re-designing without a jump
---------------------------
A shaper designed for one mode shapes the command u as y[k] = sum_i w_i u[k - d_i] (delays d_i in
samples, ``shaper_filter``). Changing the taps of that sum at sample k, which is what a firmware
that re-designs its shaper in place does (Marlin's ``updateShapingN`` swaps the delays and
amplitudes under the same history of commands), moves the output by

    sum_i w'_i u[k - d'_i] - sum_i w_i u[k - d_i],

zero only if u is constant over the longer shaper's span. During a move it is not: for a command
ramping by v per sample it is v (sum_i w_i d_i - sum_i w'_i d'_i), the shift of the shaper's
centroid times the slope, added in one sample: a step input that excites the very mode the shaper
was re-designed to spare.

Write the command as its value u0 before the first sample plus its changes du_j = u[j] - u[j - 1].
The shaper acts on each change: y[k] = u0 + sum_j du_j G(k - j), with G(n) = sum_{d_i <= n} w_i its
step response (from 0 to the gain 1). A design that varies in time can enter this sum in two ways:
every change re-read with the newest design, G_{k}(k - j), which is the in-place re-design above with
its jump; or every change shaped by the design in force when it was commanded, G_{j}(k - j). The
second is taken here: the impulses of a change once commanded are kept (a move in progress ends
with the shaper it began with), and only changes commanded after a re-design use the new one. Then

- a re-design alone moves nothing: y[k] - y[k - 1] = sum_j du_j w^{(j)}(k - j), the impulses of the
  changes that fall at sample k, each a fraction of the change that caused it; a command at rest
  keeps its exact value through any number of re-designs;
- each change is shaped by a complete shaper designed for the mode in force when it was commanded,
  so it leaves no vibration if the mode holds for the shaper's length (half a period for ZV): the
  guarantee a fixed shaper gives, for the mode of the moment;
- while one design holds over the shaper's span the output is exactly that fixed shaper's.

Blending the outputs of the old and the new shaper (the other way to avoid the jump) would instead
shape every change during the blend by a mixture of two impulse trains, whose zeros lie at two
frequencies and which is free of vibration at neither.

Computation. The changes commanded under one design form a segment m: first sample a_m, last b_m
(open while the design is in force), command c_m = u[a_m - 1] before it. Its part of the output is
sum_i w_i (u[min(k - d_i, b_m)] - c_m) over its impulses with k - d_i >= a_m, and
y[k] = c_1 + the parts of the segments in flight. Once the last change of a segment has passed its
last impulse, its part is u[b_m] - c_m = c_{m+1} - c_m and the segment is folded into the base: no
sum is carried from sample to sample, so rounding does not accumulate however long the run, and a
step costs one multiply-add per impulse of each design still in flight.

``resolution`` sets when a new mode re-designs: when its frequency has moved by more than that
fraction, or its damping ratio by more than that amount, from the design in force (a ZV shaper's
residual grows like (pi/2) |d omega / omega|, so 1e-4 costs at most 0.016 %); 0 re-designs at
every change of the mode.
"""

import bisect
import math

from .checks import aliased_modes, check_finite, check_positive, check_size, check_zeta
from .shaper_designs import design_impulses
from .shaper_filter import grid_impulses


class ModeSchedule:
    """Scheduling value -> (omega rad/s, zeta): rows (``values``, ``frequencies`` in Hz, ``zetas``),
    linear between rows in the value.

    Beyond the first and last row the end rows hold (a table says nothing past its ends), unless
    ``extrapolate``, which continues the end segments: a law, such as ``linear_law``. A value where
    the law gives f <= 0 or zeta outside [0, 1) is refused.
    """

    def __init__(self, values, frequencies, zetas, extrapolate=False):
        rows = len(values)
        if rows == 0 or len(frequencies) != rows or len(zetas) != rows:
            raise ValueError(f"values, frequencies and zetas must be non-empty and of equal length, got "
                             f"{len(values)}, {len(frequencies)} and {len(zetas)}")
        self.values = [check_finite(v, f"values[{i}]") for i, v in enumerate(values)]
        if any(b <= a for a, b in zip(self.values, self.values[1:])):
            raise ValueError(f"values must be strictly increasing, got {self.values}")
        self.frequencies = [check_positive(f, f"frequencies[{i}]") for i, f in enumerate(frequencies)]
        self.zetas = [check_zeta(z, f"zetas[{i}]") for i, z in enumerate(zetas)]
        self.extrapolate = bool(extrapolate)

    @classmethod
    def linear_law(cls, f0, gain, zeta):
        """f = f0 + gain * value at every value, zeta fixed (Marlin FT_MOTION's dynamic frequency)."""
        f0 = check_positive(f0, "f0")
        gain = check_finite(gain, "gain")
        # Any two rows define the law; these two, half of f0 apart in frequency, are valid rows.
        span = 0.5 * f0 / abs(gain) if gain else 1.0
        return cls([0.0, span], [f0, f0 + gain * span], [zeta, zeta], extrapolate=True)

    def mode(self, value):
        """``(omega, zeta)`` in force at scheduling ``value``."""
        x = check_finite(value, "scheduling value")
        values, f, z = self.values, self.frequencies, self.zetas
        if len(values) == 1:
            return 2.0 * math.pi * f[0], z[0]
        if not self.extrapolate:
            x = min(max(x, values[0]), values[-1])
        i = min(max(bisect.bisect_right(values, x) - 1, 0), len(values) - 2)
        t = (x - values[i]) / (values[i + 1] - values[i])
        frequency = f[i] + t * (f[i + 1] - f[i])
        zeta = z[i] + t * (z[i + 1] - z[i])
        if not (frequency > 0.0 and 0.0 <= zeta < 1.0):
            raise ValueError(f"scheduling value {value!r} lies where the schedule gives f = {frequency:g} Hz, "
                             f"zeta = {zeta:g}; the law holds only where f > 0 and zeta is in [0, 1)")
        return 2.0 * math.pi * frequency, zeta


class _Segment:
    """The changes of the command made under one design (module docstring, Computation)."""

    __slots__ = ("taps", "start", "base", "end", "end_value", "moved", "reach")

    def __init__(self, taps, start, base):
        self.taps = taps  # ((delay, weight), ...)
        self.start = start
        self.base = base
        self.end = None  # last sample of the segment, None while its design is in force
        self.end_value = base
        self.moved = False  # whether the command has changed since the segment began
        self.reach = taps[-1][0] + 1  # samples a change stays in flight: the longest delay + 1


class ModeFollowingShaper:
    """``step(command, omega, zeta) -> shaped command`` at ``fs``: an impulse shaper of ``kind``
    (``runtime.shaper_designs``, single-mode kinds; ``n``, ``vtol`` as there) designed for the mode
    given, each change of the command keeping the design in force when it was made (module docstring).

    Starts designed for ``(omega, zeta)`` with the command at rest at ``u0``.
    """

    def __init__(self, fs, omega, zeta, kind="zv", n=1, vtol=0.05, u0=0.0, resolution=1e-4):
        self.fs = check_positive(fs, "fs")
        self.h = 1.0 / self.fs
        if kind == "simultaneous":
            raise ValueError("kind must be a single-mode shaper kind, got 'simultaneous'")
        self.kind, self.n, self.vtol = kind, n, vtol
        self.resolution = check_finite(resolution, "resolution")
        if self.resolution < 0.0:
            raise ValueError(f"resolution must be >= 0, got {resolution!r}")
        u0 = check_finite(u0, "u0")
        self.mode = None
        self.designs = 0
        taps = self._taps(omega, zeta)
        self._segments = [_Segment(taps, 0, u0)]
        self._k = 0  # the index of the next sample
        self._last = u0
        self._ring, self._mask = [u0], 0
        self._fit(self._segments[0].reach)

    def _taps(self, omega, zeta):
        """The design for (omega, zeta) on the sample grid, as ((delay, weight), ...)."""
        if aliased_modes([(omega, zeta)], self.h):
            raise ValueError(f"the mode omega = {omega:g} rad/s, zeta = {zeta:g} lies at or above the Nyquist "
                             f"frequency pi*fs = {math.pi * self.fs:g} rad/s: sampled at fs = {self.fs:g} Hz no "
                             f"shaper can cancel it")
        times, amplitudes = design_impulses(self.kind, [(omega, zeta)], self.n, self.vtol)
        # the ring of past commands holds the longest delay: bounded before it is allocated
        check_size(times[-1] / self.h + 2.0, "MAX_SAMPLED_LENGTH", f"a {self.kind} shaper for omega = {omega:g} rad/s "
                   f"sampled at fs = {self.fs:g} Hz would be", "samples long", "use a lower fs or a higher frequency")
        delays, weights = grid_impulses(times, amplitudes, self.h)
        self.mode = (float(omega), float(zeta))
        self.designs += 1
        return tuple(zip(delays, weights))

    def _fit(self, reach):
        """Grow the ring of past commands to hold ``reach`` samples (a power of two, copied in order)."""
        size = len(self._ring)
        if size >= reach:
            return
        while size < reach:
            size *= 2
        ring = [self._last] * size
        for j in range(max(self._k - len(self._ring), 0), self._k):
            ring[j & (size - 1)] = self._ring[j & self._mask]
        self._ring, self._mask = ring, size - 1

    def _moved(self, omega, zeta):
        w, z = self.mode
        return abs(omega - w) > self.resolution * w or abs(zeta - z) > self.resolution

    @property
    def span(self):
        """Samples over which a change of the command still moves the output (the longest delay + 1
        of the designs in flight): after the command has held a value that long, the output holds it."""
        return max(segment.reach for segment in self._segments)

    @property
    def taps(self):
        """((delay, weight), ...) of the design in force."""
        return self._segments[-1].taps

    def step(self, command, omega, zeta):
        """Shape one command sample with the design for ``(omega, zeta)`` (re-designed if it moved)."""
        u = check_finite(command, "command")
        k = self._k
        current = self._segments[-1]
        if self._moved(omega, zeta):
            taps = self._taps(omega, zeta)
            if current.moved:  # the changes made so far keep their design: a new segment begins here
                current.end, current.end_value = k - 1, self._last
                current = _Segment(taps, k, self._last)
                self._segments.append(current)
            else:  # no change commanded under the old design: nothing in flight depends on it
                current.taps, current.reach = taps, taps[-1][0] + 1
            self._fit(current.reach)
        if u != self._last:
            current.moved = True
        self._ring[k & self._mask] = u
        self._last = u
        segments = self._segments
        while len(segments) > 1 and k - (segments[0].reach - 1) >= segments[0].end:
            segments.pop(0)  # its last change has reached its last impulse: folded into the base
        ring, mask = self._ring, self._mask
        y = segments[0].base
        for segment in segments:
            start, end, base = segment.start, segment.end, segment.base
            for d, w in segment.taps:
                j = k - d
                if j < start:
                    continue
                y += w * ((ring[j & mask] if end is None or j <= end else segment.end_value) - base)
        self._k = k + 1
        return y


class ScheduledShaperKernel:
    """``step(command, value) -> shaped command``, one call per sample at ``fs``: the shaper of
    ``kind`` designed for the mode ``schedule`` (a ``ModeSchedule``) puts in force at each scheduling
    ``value``, re-designed without a jump (module docstring). ``value0`` (default: the schedule's
    first value) is the scheduling value before the first sample, ``u0`` the command's rest value."""

    def __init__(self, fs, schedule, kind="zv", n=1, vtol=0.05, u0=0.0, value0=None, resolution=1e-4):
        if not isinstance(schedule, ModeSchedule):
            raise ValueError(f"schedule must be a ModeSchedule, got {type(schedule).__name__}")
        self.schedule = schedule
        self.value = schedule.values[0] if value0 is None else check_finite(value0, "value0")
        self._mode = schedule.mode(self.value)
        self.shaper = ModeFollowingShaper(fs, *self._mode, kind=kind, n=n, vtol=vtol, u0=u0, resolution=resolution)

    def step(self, command, value):
        """Shape one command sample at scheduling ``value``."""
        if value != self.value:
            self._mode = self.schedule.mode(value)
            self.value = value
        return self.shaper.step(command, *self._mode)
