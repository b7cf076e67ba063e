"""Microseconds per fmi2DoStep through fmpy: an empty pythonfmu FMU (the floor), our FMUs, and the
same runtime kernel called directly in Python. Goal: the Shaper FMU within 2x of the floor.

Then the native C Shaper and ShapeFilter (``shapefmu build ... --native``) beside an empty native
FMU (the generic FMI 2.0 layer with a model part that does nothing, their floor), each stepped by
the hand-written C loop of benchmarks/fmu_loop.c (set u, doStep, get y: nanoseconds per step, the
FMU's own cost) and through fmpy. Goal: the native Shaper's step <= 1.5x the empty native FMU's;
the native EKF tuner's (the 4-state EKF and the shaper every sample, its vibration input driven),
STOS controller's (the law with sub-sample switching and the settle hand-over, its position input
driven), profile generator's and reference player's <= 2x.

Each FMU is stepped N times with fmpy's low-level API (setReal u, doStep, getReal y: what a master
does per step); the kernel is StreamingShaper.step on the same ZVD design and on the ShapeFilter's
Hanning taps (400 of them: its cost grows with the taps, the FMU's overhead does not).
"""

import math
import tempfile
import textwrap
import time
from pathlib import Path

from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave
from pythonfmu import FmuBuilder

from native_loop import build_empty_native, c_loop_seconds

from shapefmu.fmi import build_fmu
from shapefmu.fmi.native.ekf_tuner import build_native_ekf_tuner
from shapefmu.fmi.native.profiles import build_native_profile
from shapefmu.fmi.native.reference import build_native_reference
from shapefmu.fmi.native.stos import build_native_stos
from shapefmu.fmi.native.sampled import build_native_fmu
from shapefmu.runtime.impulse_formulas import zv_dn
from shapefmu.runtime.shaper_filter import StreamingShaper
from shapefmu.runtime.window_filters import hanning_filter

N = 20000
# The settle law of tests/test_fmu_stos.py (the disk drive's hand-over region and gains).
STOS_SETTLE = {"kp": 2.75e6, "kd": 27.5, "ki": 1e8, "x_enter": 2e-6, "v_enter": 0.2, "x_exit": 4e-6, "v_exit": 0.4}
H = 1e-4
C_STEPS = 1_000_000
REPEATS = 9

EMPTY_SLAVE = textwrap.dedent(
    '''
    from pythonfmu import Fmi2Slave, Fmi2Causality, Real

    class Empty(Fmi2Slave):
        def __init__(self, **kwargs):
            super().__init__(**kwargs)
            self.u = 0.0
            self.y = 0.0
            self.register_variable(Real("u", causality=Fmi2Causality.input))
            self.register_variable(Real("y", causality=Fmi2Causality.output))

        def do_step(self, current_time, step_size):
            return True
    '''
)


def per_step_fmu(path, input_name="u", output_name="y"):
    md = read_model_description(str(path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(path)), modelIdentifier=md.coSimulation.modelIdentifier,
                    instanceName="bench")
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    u, y = ([vr[input_name]] if input_name else []), [vr[output_name]]
    start = time.perf_counter()
    for k in range(N):
        if u:
            fmu.setReal(u, [math.sin(1e-3 * k)])
        fmu.doStep(k * H, H)
        fmu.getReal(y)
    elapsed = time.perf_counter() - start
    fmu.terminate()
    fmu.freeInstance()
    return 1e6 * elapsed / N


def per_step_kernel(kernel):
    start = time.perf_counter()
    for k in range(N):
        kernel.step(math.sin(1e-3 * k))
    return 1e6 * (time.perf_counter() - start) / N


def main():
    with tempfile.TemporaryDirectory() as temp:
        temp = Path(temp)
        script = temp / "empty_slave.py"
        script.write_text(EMPTY_SLAVE)
        empty = FmuBuilder.build_FMU(script, dest=temp / "Empty.fmu")
        shaper = build_fmu("Shaper", temp / "Shaper.fmu", kind="zvd", **{"f[1]": 100.0, "zeta[1]": 0.02, "Ts": H})
        floor = per_step_fmu(empty)
        shape_filter = build_fmu("ShapeFilter", temp / "ShapeFilter.fmu", kind="hanning", f=100.0, order=2, Ts=H)
        ours = {"Shaper (ZVD, 100 Hz)": per_step_fmu(shaper), "ShapeFilter (Hanning n=2, 100 Hz)": per_step_fmu(shape_filter)}
        kernel = per_step_kernel(StreamingShaper.from_impulses(*zv_dn(2 * math.pi * 100.0, 0.02, 1), H))
        filter_taps, _ = hanning_filter(2 * math.pi * 100.0, 0.0, H, 2)
        filter_kernel = per_step_kernel(StreamingShaper.from_taps(filter_taps))
    print(f"{'empty pythonfmu FMU (floor)':34s} {floor:8.2f} us/step")
    for name, value in ours.items():
        goal = " (goal <= 2)" if name.startswith("Shaper ") else ""  # the goal is set for the shaper FMU
        print(f"{name:34s} {value:8.2f} us/step   {value / floor:5.2f} x floor{goal}")
    print(f"{'StreamingShaper.step directly':34s} {kernel:8.2f} us/step   {kernel / floor:5.2f} x floor")
    print(f"{'  same on the Hanning n=2 taps':34s} {filter_kernel:8.2f} us/step   {filter_kernel / floor:5.2f} x floor")
    native()


def native():
    """The native FMUs: C loop (best of REPEATS, ns/step) and fmpy (us/step)."""
    with tempfile.TemporaryDirectory() as temp:
        temp = Path(temp)
        # name -> (FMU, the input driven, the output read, the goal against the floor)
        fmus = {
            "empty native FMU (floor)": (build_empty_native(temp / "Empty.fmu"), "u", "y", None),
            "native Shaper (ZVD, 100 Hz)": (build_native_fmu("Shaper", temp / "NativeShaper.fmu", kind="zvd",
                                                             **{"f[1]": 100.0, "zeta[1]": 0.02, "Ts": H}), "u", "y", 1.5),
            "native ShapeFilter (Hanning n=2)": (build_native_fmu("ShapeFilter", temp / "NativeFilter.fmu",
                                                                  kind="hanning", f=100.0, order=2, Ts=H), "u", "y", None),
            "native EKFTuner (EKF + ZVD)": (build_native_ekf_tuner(temp / "NativeEKF.fmu", Ts=H, omega0=2 * math.pi * 100.0),
                                            "vibration", "omega_est", 2.0),
            "native STOSController (settle)": (build_native_stos(temp / "NativeSTOS.fmu", Ts=H, settle=True, **STOS_SETTLE),
                                               "x_r", "u", 2.0),
            "native ProfileGenerator (BC:TZ)": (build_native_profile(temp / "NativeProfile.fmu"), "start", "position", 2.0),
            "native ReferencePlayer": (build_native_reference(temp / "NativeReference.fmu"), None, "y_mean", 2.0),
        }
        # The FMUs take turns, so that a burst of load on a shared machine does not decide a ratio.
        runs = [{name: c_loop_seconds(C_STEPS, H, [fmu[:3]]) for name, fmu in fmus.items()} for _ in range(REPEATS)]
        loop = {name: min(run[name] for run in runs) / C_STEPS * 1e9 for name in fmus}
        through_fmpy = {name: per_step_fmu(*fmu[:3]) for name, fmu in fmus.items()}
    floor = loop["empty native FMU (floor)"]
    print(f"native FMUs, {C_STEPS:,} steps of the C loop (set the input, doStep, get an output), best of {REPEATS}; "
          f"and via fmpy")
    for name, (*_, target) in fmus.items():
        goal = f"   (goal <= {target})" if target else ""
        print(f"{name:34s} {loop[name]:8.1f} ns/step   {loop[name] / floor:5.2f} x floor{goal}"
              f"   {through_fmpy[name]:6.2f} us/step via fmpy")


if __name__ == "__main__":
    main()
