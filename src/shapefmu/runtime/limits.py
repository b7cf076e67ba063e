"""The limits our FMUs enforce at run time, in one place.

Standard library only: bundled into every FMU with the rest of ``runtime/``. The native C FMUs
enforce the same numbers (the spec of the sampled semantics is shared). Each limit below says what
it bounds, its value, and why that value.

SAMPLE_TOLERANCE = 1e-6 (relative to the sampling period Ts)
    A sampled FMU takes its samples at s_k = t0 + k Ts (``runtime.sample_clock``). An instant s_k
    counts as reached at time tau when s_k <= tau + SAMPLE_TOLERANCE * Ts, and tau is "on the grid"
    when it lies within SAMPLE_TOLERANCE * Ts of s_k. Hosts keep time as ``t += h``: the drift of
    that sum from k h, measured for h = 1e-5 .. 1e-3 s, is about 1e-10 Ts after 2000 steps, 1e-9 Ts
    after 1e4, 2e-7 Ts after 1e5 and 2e-5 Ts after 1e6 steps. So up to a few 1e5 steps of Ts a
    host's communication points count as the sample instants they stand for, and no sample is
    skipped or taken twice. A step a host takes on purpose is far longer than 1e-6 Ts.

MAX_SAMPLES_PER_STEP = 10_000_000
    The most sample instants one ``fmi2DoStep`` may span. Each sample is one call of a Python
    kernel (about 1 us for a shaper, tens of us for the EKF), so the bound keeps a step under
    about ten seconds for a shaper; a longer step (h = 1e300) is a host's mistake, answered at
    once with fmi2Error and a message naming the bound instead of a step that never returns.
"""

SAMPLE_TOLERANCE = 1e-6
MAX_SAMPLES_PER_STEP = 10_000_000
