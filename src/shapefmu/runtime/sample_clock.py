"""The clock of a sampled FMU: samples on the grid t0 + k Ts, counted from the steps the host takes.

A sampled FMU (Shaper, ShapeFilter, EKFTuner, STOSController) commits one sample of its kernel at
every instant s_k = t0 + k Ts (t0 = fmi2SetupExperiment's startTime). The rule (the spec the native C
FMUs follow too, ``c/sample_clock.c``):

- Counting. The clock never compares the host's absolute time with t0 + k Ts: at t0 = 1.7e9 (a Unix
  epoch) a double is 2.4e-7 s apart, a host's ``t += h`` drifts by ulps of t at every step, and
  1e-6 Ts is below both. It keeps its position as (k, since): k the newest sample instant reached,
  ``since`` the time after it, summed from the steps h the host took (``since + h``, then minus
  whole Ts). Only numbers of the size of Ts and h enter, so the same steps take the same samples,
  bit for bit, whatever t0 is; and the count never drifts, so 10^6 steps of Ts are 10^6 samples.
- Reached. A step of h reaches instant k + j when j Ts <= since + h + delta (the largest such j,
  computed as floor and guarded by the products j Ts themselves). It ends on the grid when what is
  left, since' = since + h - j Ts, is within delta of 0; since' is then set to 0, so the error of a
  step such as 0.7 Ts (not a double's exact 7/10 of Ts) never adds up.
- Tolerance. delta = SAMPLE_TOLERANCE Ts (``runtime.limits``): a step a host takes on purpose is far
  longer. A host that aims a step at an absolute instant (a tick, a grid point: h = target - t)
  computes h from two times rounded to ulp(t), so its h is a whole number of those ulps, and it is
  off by their rounding: half an ulp at the target, half a one at the grid point it last aimed at,
  and half a one for each free step since then (a step the host sized itself, whose end t + h it
  rounded; an aimed step adds none). For an aimed step only (h a multiple of ulp(max(|t|, |t + h|)))
  delta grows by (m + 1) ulp, m those free steps, to at most AIMED_STEP_TOLERANCE Ts. A free step
  (h = Ts, 0.7 Ts, a random size: not a multiple of ulp(t) at large t) keeps delta, and so takes
  exactly the samples it takes at t0 = 0.
- State. ``latched`` says whether the current sample's input value is fixed yet, ``v`` is that
  value. On the grid the sample is open: an input set there is the sample's input (feed-through
  follows it at once). A step that ends off the grid latches the input that was in effect at s_k,
  and the outputs hold until s_{k+1}; an input set in between is used from the next sample on.
- ``fmi2DoStep(t, h)`` with input value u in effect over the step: every instant it reaches is
  committed, sample k with its latched value (or u if it was still open), the ones after it with
  u; then the newest sample is open if the step ended on the grid, else latched with u. A step
  spanning more than MAX_SAMPLES_PER_STEP samples is refused before anything changes.

With steps that are whole multiples of Ts every communication point is on the grid and every step
commits exactly h / Ts samples with u.

An FMU that is not sampled but plays a function of the time since its start (the ProfileGenerator)
keeps that time as ``StepTime``, the steps' compensated sum, for the same reason: t - t0 at t0 = 1.7e9
has lost 22 bits, and a host's ``t += h`` has drifted from the sum of its steps.

The value u may be any object (a float, or a tuple of the inputs a kernel samples); the clock only
stores and hands it back. The slave commits a sample by a callable (the kernel's per-sample
update), and reads the current sample's input through ``current(u)``.
"""

import math

from .limits import AIMED_STEP_TOLERANCE, MAX_SAMPLES_PER_STEP, PYTHON_STEP_SECONDS, SAMPLE_TOLERANCE


# What one sample of each Python kernel costs, measured (limits.py, PYTHON_STEP_SECONDS), rounded up:
# the streaming filter (fixed, per nonzero tap or impulse), the STOS law (fixed, per impulse), the EKF tuner.
FIR_SAMPLE_SECONDS = (0.1e-6, 0.04e-6)
STOS_SAMPLE_SECONDS = (0.5e-6, 0.3e-6)
EKF_SAMPLE_SECONDS = 25e-6


def samples_per_python_step(seconds_per_sample):
    """The samples a Python FMU may take in one step whose per-sample work costs about
    ``seconds_per_sample``: as many as fit in PYTHON_STEP_SECONDS, at least 1, at most MAX_SAMPLES_PER_STEP."""
    return max(1, min(MAX_SAMPLES_PER_STEP, int(PYTHON_STEP_SECONDS / seconds_per_sample)))


def _reach(after, ts, delta):
    """(j, after - j Ts) for the largest j with j Ts <= after + delta; ``after`` > 0 bounded by the caller."""
    j = math.floor((after + delta) / ts)
    # The division rounds; the products decide (j Ts is what "reached" means).
    if (j + 1) * ts <= after + delta:
        j += 1
    elif j * ts > after + delta:
        j -= 1
    return j, after - j * ts


def grid_step(since, steps, ts, t, h):
    """The step (t, t + h] from ``since`` after the current sample instant, ``steps`` free steps after
    the host last aimed at a grid point (module docstring): (samples it reaches, the time after the
    newest one, 0.0 if it ends on the grid, and that count of free steps then). ``(since + h) / ts`` must be finite
    and bounded (``SampleClock.advance`` checks it first)."""
    ulp = math.ulp(max(abs(t), abs(t + h)))
    whole = h / ulp  # exact: an ulp is a power of two
    aimed = math.isfinite(ulp) and whole == math.floor(whole)
    delta = SAMPLE_TOLERANCE * ts
    if aimed:
        delta += min((steps + 1) * ulp, AIMED_STEP_TOLERANCE * ts)
    count, after = _reach(since + h, ts, delta)
    on_grid = abs(after) <= delta
    # Free steps add the host's rounding of t + h; an aimed step to a grid point ends it.
    steps = steps + 1 if not aimed else 0 if on_grid else steps
    return count, 0.0 if on_grid else after, steps


class SampleClock:
    """Sample index and latch of one sampled FMU with period ``ts``, counted from its start time; a step
    may span at most ``max_samples`` samples (a Python FMU's bound: ``samples_per_python_step``)."""

    def __init__(self, ts, max_samples=MAX_SAMPLES_PER_STEP):
        self.ts = ts
        self.max_samples = max_samples
        self.k = 0
        self.since = 0.0
        self.steps = 0
        self.latched = False
        self.v = None

    def state_problem(self):
        """Why this clock, restored from an FMU state, is none a run reaches (None if it is one): its
        period, its position on the grid (k, steps >= 0, 0 <= since < ts) and its latch."""
        if not (isinstance(self.ts, float) and 0.0 < self.ts < math.inf):
            return f"sample period {self.ts!r} is not > 0"
        position = (self.k, self.since, self.steps)
        if not (type(self.k) is int and type(self.steps) is int and isinstance(self.since, float)
                and self.k >= 0 and self.steps >= 0 and 0.0 <= self.since < self.ts):
            return f"position {position!r} on the grid of Ts = {self.ts!r} s is not one (k, since in [0, Ts), steps)"
        if type(self.latched) is not bool:
            return f"latched is {self.latched!r}, not a bool"
        return None

    def current(self, u):
        """The input value of the current sample: its latched value, or ``u`` while it is open."""
        return self.v if self.latched else u

    def advance(self, t, h, u, commit):
        """Take the step (t, t + h] with input value ``u``: ``commit(value)`` once per sample instant.

        Returns the current sample's input value afterwards (``current(u)``). Raises ValueError,
        with the clock untouched, for a step spanning more than ``max_samples`` samples.
        """
        # Checked on the quotient first: the count of h = 1e300 would be an integer with 300 digits.
        ahead = (self.since + h) / self.ts
        if not ahead <= self.max_samples + 1.0:  # also catches inf and nan
            raise ValueError(self._too_long(h, ahead))
        count, since, steps = grid_step(self.since, self.steps, self.ts, t, h)
        if count > self.max_samples:
            raise ValueError(self._too_long(h, count))
        self.since, self.steps = since, steps
        on_grid = since == 0.0
        if count > 0:
            commit(self.v if self.latched else u)
            for _ in range(count - 1):
                commit(u)
            self.k, self.latched, self.v = self.k + count, False, None
        if not self.latched and not on_grid:
            self.latched, self.v = True, u
        return self.v if self.latched else u

    def _too_long(self, h, samples):
        why = ("about a second of this FMU's work (shapefmu.runtime.limits.PYTHON_STEP_SECONDS)"
               if self.max_samples < MAX_SAMPLES_PER_STEP else "shapefmu.runtime.limits.MAX_SAMPLES_PER_STEP")
        return (
            f"communication step h = {h!r} s spans {samples:.6g} samples of Ts = {self.ts!r} s; "
            f"at most {self.max_samples} per step ({why}): take shorter communication steps"
        )


class StepTime:
    """The time since the start time, summed from the steps h the host took (Neumaier's compensated sum,
    so 10^7 steps of 1e-6 s add up to 10 s within an ulp), never the host's t - t0."""

    def __init__(self):
        self.sum = 0.0
        self.compensation = 0.0

    def add(self, h):
        total = self.sum + h
        # The rounding error of the sum, exact (Neumaier): from the smaller of the two terms.
        if abs(self.sum) >= abs(h):
            self.compensation += (self.sum - total) + h
        else:
            self.compensation += (h - total) + self.sum
        self.sum = total

    def value(self):
        return self.sum + self.compensation
