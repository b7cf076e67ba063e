"""Every limit of shapefmu in one place: what it bounds, and why it has that value.

A hostile or careless input can ask for a design, a run or a file of any size: ZVD convolved over
20 modes is 3^20 impulses, a 1 ps sampling period gives a delay line of 10^9 samples, a 1.3 MB
archive can declare a 1 GB member. shapefmu estimates the size first and refuses past these limits,
with the estimate in the message, rather than running for hours or exhausting memory. Each limit is
read at the time of the check (``limits.NAME``, not a copy imported by value), so a program that
really needs more may raise it before the call: ``shapefmu.runtime.limits.MAX_SAMPLED_LENGTH = ...``.

Standard library only: this module is copied into every FMU with the rest of ``runtime/``.

Design layer and FMUs (``runtime/``, ``shapers/``)
---------------------------------------------------
MAX_IMPULSES = 10_000
    Impulses of one impulse shaper, counted before coincident impulses merge: for a shaper
    convolved over several modes, the product of the per-mode counts. The convolution takes that
    many products (ZVD over 20 modes: 3.5e9, minutes and gigabytes), and a streaming filter costs
    one multiply-add per impulse per sample, so 10^4 keeps a step under a millisecond in Python.
    ZVDD on the four modes a Shaper FMU takes is 256.
MAX_ZV_DN_ORDER = 100
    Derivative order n of ``zv_dn``, ZV convolved n + 1 times. Its amplitudes are
    C(n+1, i) K^i / (1 + K)^(n+1): the normalisation overflows a double past n = 1022, and the
    shaper is (n + 1)/2 periods long, so n = 100 (50 periods) is already far beyond any use.
MAX_SAMPLED_LENGTH = 1_000_000
    Samples of one sampled design: the taps of a shape filter, the delay line of an impulse shaper
    on its sampling grid (its duration / Ts + 1), a sampled motion profile or kernel. A filter's
    ring buffer holds twice that many Python references (16 MB), and a design of 10^6 samples is
    1 s at 1 us sampling; a 1 ps period on a 2 kHz shaper would ask for 5e8.
MAX_CONVOLUTION_PRODUCTS = 50_000_000
    Multiply-adds of the order-n self-convolution of a window filter (paper 000, eq. 1),
    about M^2 n^2 / 2 for a window of M + 1 taps: done in pure Python at roughly 50 ns each, this
    is a few seconds. Order 1000 of a 200-tap Hanning filter would need 2e10 (20 minutes).

Plants (``plants/``, ``fmi/native/``)
-------------------------------------
MAX_PLANT_STATES = 200
    States of a plant model that the plant-FMU generator compiles. The generated C holds dense
    n x n Jacobians and the zero-order-hold step computes an n x n matrix exponential; CasADi's
    code generation and gcc grow faster than n^2 (n = 100 takes 40 s to build here, n = 200 80 s).

MAX_RK4_SUBSTEPS = 10_000_000
    RK4 substeps of one Co-Simulation step of a nonlinear native plant (the step h split into
    substeps no longer than its ``substep`` parameter; C: ``PLANT_MAX_SUBSTEPS`` in plant_model.h).
    A substep costs four evaluations of the model, well under a microsecond for the pendulum, so the
    bound keeps one step within seconds; past it (a step of 1e300 s, a substep of 1e-300 s) the count
    overflowed and the step returned OK without integrating. Refused with fmi2Error and a message.

Co-simulation results and sweeps (``cosim/``, ``sweep/``, ``stos.py``)
---------------------------------------------------------------------
MAX_RESULT_BYTES = 2 * 2**30
    Bytes of the results one run records (rows x recorded variables x 8 B), estimated before the
    first step: the result is one array in memory. 2 GiB is 2.7e8 rows of one variable; a run that
    needs more is given a longer ``--output-interval`` or fewer ``--record`` variables.
MAX_COMPONENTS = 2_000
    Components of one system the master runs, counted before any FMU is loaded. Loading an instance
    through fmpy takes about 2 ms (its functions are bound one by one) and the master's set-up grows
    with the connections, so 2000 start in seconds; 10^4 took minutes before the first step. (Past
    128 components the step loop runs in Python rather than compiled: gcc's time on the generated
    loop grows faster than its length; see ``cosim.step_program``.)
MAX_ARRAY_ELEMENTS = 1_000_000
    Elements of one array variable of an FMU the master loads (FMI 3.0 ``<Dimension>``), checked
    when its model description is read. The master keeps a value per element in its set and get
    buffers and a result column per recorded element; an FMU declaring 10^8 elements took 2.9 GB and
    two minutes before a size error, 10^18 a MemoryError. 10^6 doubles are 8 MB.
MAX_COMPILED_VALUES = 2_000
    Values the compiled step loop moves along connections and records, element by element, each a
    line of its C: gcc's time grows faster than that (500 took 0.3 s, 2000 1.7 s, 10^4 over 10 s), so
    past it the step loop runs in Python, which starts at once (``cosim.step_program``).
MAX_MACRO_STEPS = 2**53
    Macro steps of one co-simulation run. The master computes t_k = t0 + k h from the step count k
    in double precision, exact up to 2^53; a run that long (9e15 steps: 28 years at 10^7 steps per
    second) is a mistake such as ``--stop 1e40 --step 1``.
MAX_SWEEP_POINTS = 10_000_000
    Parameter points of one sweep: the grid is one array in memory, and every point is a run;
    ten million runs of even 1 ms are three hours on a core.
MAX_WORKERS_PER_CORE = 4
    Worker processes of a sweep's local Dask cluster per core of the machine. A worker is a Python
    process of about 150 MB that runs one co-simulation at a time: past a few per core they only
    wait for one another and fill the memory (500 on 2 cores took the machine down). A larger
    cluster is a Dask scheduler's address.

Sampled FMUs at run time (``runtime/sample_clock.py``; the native C FMUs use the same numbers)
----------------------------------------------------------------------------------------------
SAMPLE_TOLERANCE = 1e-6 (relative to the sampling period Ts)
    A sampled FMU takes its samples at s_k = t0 + k Ts, counted from the steps h the host takes, never
    from its absolute time (``runtime.sample_clock``): instant k + j is reached when j Ts <= since + h
    + SAMPLE_TOLERANCE Ts, ``since`` the time after instant k, and a step ends on the grid when what is
    left is within SAMPLE_TOLERANCE Ts of 0. Summed steps are numbers of the size of Ts: a step of 0.7 Ts
    is off 7/10 by about 1e-16 Ts, and each grid point resets the sum. A step a host takes on purpose is
    far longer than 1e-6 Ts.
AIMED_STEP_TOLERANCE = 0.25 (relative to Ts)
    What the tolerance may grow to for a step a host aimed at an absolute instant (h = target - t, a
    whole number of ulps of t): (m + 1) ulp(t) after m steps of its own since it last aimed at the
    grid. At t = 1.7e9 an ulp is 2.4e-7 s: 2.4e-4 of Ts = 1 ms, but 2.4e-2 of the STOS controller's
    Ts = 10 us, so a host that aims at its ticks there after a few steps of its own needs a tenth of
    Ts. Past a quarter of Ts a host's time cannot tell its grid points apart.

MAX_SAMPLES_PER_STEP = 10_000_000
    The most sample instants one ``fmi2DoStep`` may span. Each sample is one call of a Python
    kernel (about 1 us for a shaper, tens of us for the EKF), so the bound keeps a step under
    about ten seconds for a shaper; a longer step (h = 1e300) is a host's mistake, answered at
    once with fmi2Error and a message naming the bound instead of a step that never returns.

PYTHON_STEP_SECONDS = 1.0
    Work one step of a pythonfmu FMU (Shaper, ShapeFilter, EKFTuner, STOSController) may do: its
    samples per step are bounded to what takes about this long (``sample_clock.samples_per_python_step``),
    so a host that asks for 10^7 samples in one step (an EKF tuner: 4 minutes) gets fmi2Error at once.
    Per-sample costs measured here (CPython 3.11, one core): the streaming filter of the Shaper and
    ShapeFilter 0.08 us + about 0.03 us per nonzero tap or impulse (10 taps 0.7 us, 1000 taps 24 us),
    the STOS law 1.3 us with a 3-impulse shaper, the EKF tuner 22 us. The native FMUs keep
    MAX_SAMPLES_PER_STEP: their sample costs tens of nanoseconds.

Files from users (``fmi/archives.py``)
--------------------------------------
MAX_ARCHIVE_MEMBER_BYTES = 2**30
    Bytes one member of an ``.ssp`` archive (the .ssd, an FMU, an .ssv) may extract to, and bytes
    an FMU's whole content may extract to. The size an archive declares is checked before anything
    is written (zipfile never writes more than a member declares): a 1.3 MB archive can declare a
    1 GB member (a "zip bomb"). 1 GiB is far above the FMUs shapefmu builds (0.05-0.2 MB); only
    the members a system uses are extracted at all.
MAX_ARCHIVE_BYTES = 4 * 2**30
    Bytes all the members a system uses may extract to together.
MAX_INPUT_FILE_BYTES = 2**30
    Bytes of a text file a user names that shapefmu reads whole: a plant model (a few kB), a signal
    table (10^6 rows are 40 MB), a sweep's rows to resume (10^7 points, the sweep limit, are about
    1 GB). Only regular files are read: ``/dev/zero`` or a FIFO given as a model would never end.
"""

MAX_IMPULSES = 10_000
MAX_ZV_DN_ORDER = 100
MAX_SAMPLED_LENGTH = 1_000_000
MAX_CONVOLUTION_PRODUCTS = 50_000_000
MAX_PLANT_STATES = 200
MAX_RK4_SUBSTEPS = 10_000_000
MAX_COMPONENTS = 2_000
MAX_ARRAY_ELEMENTS = 1_000_000
MAX_COMPILED_VALUES = 2_000
MAX_MACRO_STEPS = 2**53
MAX_RESULT_BYTES = 2 * 2**30
MAX_SWEEP_POINTS = 10_000_000
MAX_WORKERS_PER_CORE = 4
MAX_ARCHIVE_MEMBER_BYTES = 2**30
MAX_ARCHIVE_BYTES = 4 * 2**30
MAX_INPUT_FILE_BYTES = 2**30
SAMPLE_TOLERANCE = 1e-6
AIMED_STEP_TOLERANCE = 0.25
MAX_SAMPLES_PER_STEP = 10_000_000
PYTHON_STEP_SECONDS = 1.0
