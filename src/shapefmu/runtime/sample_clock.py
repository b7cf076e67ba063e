"""The clock of a sampled FMU: samples on the absolute grid t0 + k Ts, whatever steps the host takes.

A sampled FMU (Shaper, ShapeFilter, EKFTuner, STOSController) commits one sample of its kernel at
every instant s_k = t0 + k Ts (t0 = fmi2SetupExperiment's startTime), computed as t0 + k Ts, never
by summing steps, so a host's ``t += h`` drift, a 1e-16 s last step or a step of 0.8 Ts changes
nothing but where the outputs are read. The rules (the spec the native C FMUs follow too):

- Reached. s_k counts as reached at time tau when s_k <= tau + delta, delta = SAMPLE_TOLERANCE Ts
  (``runtime.limits``); K(tau) is the index of the newest reached instant. tau is on the grid
  when |tau - s_K(tau)| <= delta.
- State. ``k`` is the current sample (the newest reached one, 0 after initialisation);
  ``latched`` says whether its input value is fixed yet, ``v`` is that value. On the grid the
  sample is open: an input set there is the sample's input (feed-through follows it at once).
  Once time has moved past s_k + delta, the sample is latched with the input that was in effect
  at s_k, and the outputs hold until s_{k+1}; an input set in between is used from the next
  sample on.
- ``fmi2DoStep(t, h)`` with input value u in effect over the step: every instant in (t, t + h]
  is committed, sample k with its latched value (or u if it was still open), the ones strictly
  inside the step with u; then sample K(t + h) is open if t + h is on the grid, else latched with u.
  A step spanning more than MAX_SAMPLES_PER_STEP samples is refused before anything changes.

With steps that are whole multiples of Ts from t0 every communication point is on the grid and
every step commits exactly h / Ts samples with u: what the FMUs did before this clock, bit for bit.

The value u may be any object (a float, or a tuple of the inputs a kernel samples); the clock only
stores and hands it back. The slave commits a sample by a callable (the kernel's per-sample
update), and reads the current sample's input through ``current(u)``.
"""

import math

from .limits import MAX_SAMPLES_PER_STEP, PYTHON_STEP_SECONDS, SAMPLE_TOLERANCE


# What one sample of each Python kernel costs, measured (limits.py, PYTHON_STEP_SECONDS), rounded up:
# the streaming filter (fixed, per nonzero tap or impulse), the STOS law (fixed, per impulse), the EKF tuner.
FIR_SAMPLE_SECONDS = (0.1e-6, 0.04e-6)
STOS_SAMPLE_SECONDS = (0.5e-6, 0.3e-6)
EKF_SAMPLE_SECONDS = 25e-6


def samples_per_python_step(seconds_per_sample):
    """The samples a Python FMU may take in one step whose per-sample work costs about
    ``seconds_per_sample``: as many as fit in PYTHON_STEP_SECONDS, at least 1, at most MAX_SAMPLES_PER_STEP."""
    return max(1, min(MAX_SAMPLES_PER_STEP, int(PYTHON_STEP_SECONDS / seconds_per_sample)))


class SampleClock:
    """Sample index and latch of one sampled FMU with period ``ts`` from start time ``t0``; a step may
    span at most ``max_samples`` samples (a Python FMU's bound: ``samples_per_python_step``)."""

    def __init__(self, ts, t0, max_samples=MAX_SAMPLES_PER_STEP):
        self.ts = ts
        self.t0 = t0
        self.max_samples = max_samples
        self.k = 0
        self.latched = False
        self.v = None

    def index(self, tau):
        """K(tau): the index of the newest sample instant reached at time ``tau``."""
        ts, t0 = self.ts, self.t0
        delta = SAMPLE_TOLERANCE * ts
        k = math.floor((tau - t0) / ts + SAMPLE_TOLERANCE)
        # The division rounds; the instants themselves decide (t0 + k ts is what "reached" means).
        if t0 + (k + 1) * ts <= tau + delta:
            k += 1
        elif t0 + k * ts > tau + delta:
            k -= 1
        return k

    def on_grid(self, tau, k):
        """Whether ``tau`` lies within the tolerance of sample instant ``k``."""
        return abs(tau - (self.t0 + k * self.ts)) <= SAMPLE_TOLERANCE * self.ts

    def current(self, u):
        """The input value of the current sample: its latched value, or ``u`` while it is open."""
        return self.v if self.latched else u

    def advance(self, t, h, u, commit):
        """Take the step (t, t + h] with input value ``u``: ``commit(value)`` once per sample instant.

        Returns the current sample's input value afterwards (``current(u)``). Raises ValueError,
        with the clock untouched, for a step spanning more than ``max_samples`` samples.
        """
        end = t + h
        # Checked on the quotient first: K of h = 1e300 would be an integer with 300 digits.
        ahead = (end - self.t0) / self.ts - self.k
        if not ahead <= self.max_samples + 1.0:  # also catches inf and nan
            raise ValueError(self._too_long(h, ahead))
        k_end = self.index(end)
        count = k_end - self.k
        if count > self.max_samples:
            raise ValueError(self._too_long(h, count))
        if count > 0:
            commit(self.v if self.latched else u)
            for _ in range(count - 1):
                commit(u)
            self.k, self.latched, self.v = k_end, False, None
        if not self.latched and not self.on_grid(end, self.k):
            self.latched, self.v = True, u
        return self.v if self.latched else u

    def _too_long(self, h, samples):
        why = ("about a second of this FMU's work (shapefmu.runtime.limits.PYTHON_STEP_SECONDS)"
               if self.max_samples < MAX_SAMPLES_PER_STEP else "shapefmu.runtime.limits.MAX_SAMPLES_PER_STEP")
        return (
            f"communication step h = {h!r} s spans {samples:.6g} samples of Ts = {self.ts!r} s; "
            f"at most {self.max_samples} per step ({why}): take shorter communication steps"
        )
