"""``shapefmu identify`` and ``shapefmu recommend``: from a recording of the machine to its shaper.

    shapefmu identify RECORDING... [--axis x|y|z|xyz|DX,DY,DZ] [--time COL | --fs HZ] [--column COL]
    shapefmu recommend RECORDING... | --mode HZ[:ZETA]... [--firmware klipper|rrf|marlin|fmu] [--max-smoothing MM]
                       [--accel MM_S2] [--scv MM_S] [--plot PNG] [--json] [--build OUT.fmu [--python]]
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

from shapefmu.cli.arguments import examples, output_file, parse_mode, say_written
from shapefmu.cli.progress import showing
from shapefmu.cli.schedule import parse_schedule

AXIS_CHOICES = ("x", "y", "z", "xyz")
# Klipper's defaults (shapefmu.identification.metrics), repeated so that --help imports no SciPy
DEFAULT_MAX_SMOOTHING, DEFAULT_ACCEL, DEFAULT_SCV = 0.12, 5000.0, 5.0

_PROGRESS_AFTER = 1.0  # s: a recommendation that takes longer says what it is doing


def _axis(text: str):
    if text in AXIS_CHOICES or "," not in text:  # an axis, or a column of a table
        return text
    parts = text.split(",")
    try:
        direction = tuple(float(p) for p in parts)
    except ValueError:
        direction = ()
    if len(direction) != 3 or not all(math.isfinite(d) for d in direction) or not any(direction):
        raise ValueError(f"--axis must be x, y, z, xyz, a column name or a direction DX,DY,DZ (three numbers, not all "
                         f"0), got {text!r}")
    return direction


def _identify_all(args):
    from shapefmu.identification import identify

    if len(args.recording) > 64:
        raise ValueError(f"at most 64 recordings are judged together, got {len(args.recording)}")
    axis = _axis(args.axis)
    return [identify(path, axis=axis, time_column=args.time, fs=args.fs, columns=args.column or None,
                     undo_sweep=args.undo_sweep, excitation=args.excitation,
                     f_min=args.f_min, f_max=args.f_max, ringdown=args.ringdown) for path in args.recording]


def _print_identified(found, say=print) -> None:
    if found.recording is not None:
        say(found.recording.describe())
    else:
        say(f"{found.spectrum.source}: Klipper spectrum file, axis {found.spectrum.axis}")
    say(f"  spectrum: {found.spectrum.settings}")
    modes = found.modes
    for note in modes.notes:
        say(f"  {note}")
    if not modes.modes:
        return
    say(f"  {len(modes.modes)} mode(s), {modes.excitation} excitation (standard errors and the damping's 90 % "
        f"interval from the fit):")
    for mode in modes.modes:
        say(f"    {mode.describe()}")


def _cmd_identify(args) -> int:
    found = _identify_all(args)
    if args.json:
        print(json.dumps([{"source": f.spectrum.source, "settings": f.spectrum.settings,
                           "modes": [{"frequency_hz": m.frequency, "zeta": m.zeta, "frequency_sd": m.frequency_sd,
                                      "zeta_sd": m.zeta_sd, "zeta_interval_90": m.zeta_interval,
                                      "peak_frequency_hz": m.peak_frequency, "method": m.method,
                                      "log_decrement_zeta": m.log_decrement_zeta} for m in f.modes.modes],
                           "notes": list(f.modes.notes)}
                          for f in found], indent=2))
    else:
        for f in found:
            _print_identified(f)
    if args.plot:
        from shapefmu.plots import plot_identified

        say_written(args, f"spectrum plot written to {plot_identified(found, args.plot)}")
    return 0


def _progress():
    import time

    start = time.monotonic()

    def say(text):
        if time.monotonic() - start > _PROGRESS_AFTER:
            print(f"  ... {text}", file=sys.stderr, flush=True)

    return say


def _cmd_recommend(args) -> int:
    from shapefmu.identification import Mode, klipper, recommend
    from shapefmu.identification.recommend import check_modes, usable_modes

    if bool(args.recording) == bool(args.mode):
        raise ValueError("give recordings or --mode HZ[:ZETA] (one or more), not both and not neither")
    if args.schedule and args.mode:
        raise ValueError("--schedule makes its table from recordings, one per value: give recordings, not --mode")
    if args.build:  # the .ssv written beside the FMU, checked before the work as --build itself is
        from shapefmu.files import check_output

        check_output(Path(args.build).with_suffix(".ssv"), "parameter set", named=False)
    # with --json, stdout holds the JSON alone: every other line goes to stderr
    say = (lambda text: print(text, file=sys.stderr)) if args.json else print
    max_freq = klipper.metrics.MAX_FREQ
    if args.recording:
        found = _identify_all(args)
        for f in found:
            _print_identified(f, say)
        if args.schedule:  # a scheduled shaper's table instead of one pick (cli/schedule.py)
            from shapefmu.cli.schedule import run_schedule

            return run_schedule(args, found, say)
        # judged as Klipper judges, on every accelerometer axis summed; --axis chose the modes and names the lines
        spectra = [s for f, path in zip(found, args.recording) for s in klipper.judged_spectra(f.recording, path)]
        modes, set_aside = usable_modes(_merged_modes([f.modes.modes for f in found]))
        for note in set_aside:
            say(note)
        if not modes:
            raise ValueError("no resonance found in the recordings, so there is nothing to shape (see identify's output)")
    else:
        modes = check_modes(Mode(w / (2 * math.pi), z, 0.0, 0.0, 1.0, "given") for w, z in args.mode)
        spectra = [_model_spectrum(modes)]
        max_freq = max(max_freq, 1.5 * max(m.frequency for m in modes))  # Klipper's --max_freq, to cover them
    axes = (args.axis,) if args.axis in ("x", "y", "z") else ("x", "y")
    advice = recommend(spectra, modes, firmware_name=args.firmware, axes=axes,
                       accel=args.accel, scv=args.scv, max_smoothing=args.max_smoothing, max_freq=max_freq,
                       ts=args.filter_ts, progress=_progress() if showing(args) else None)
    if args.json:
        print(json.dumps(_json(advice), indent=2, allow_nan=False))
    else:
        _print_table(advice, len(spectra) if args.recording else 0)
    if args.plot:
        from shapefmu.plots import plot_recommendation

        say(f"recommendation plot written to {plot_recommendation(spectra, advice, args.plot)}")
    if args.build:
        for path in _build(advice.pick, Path(args.build), python=args.python, fmi_version=args.fmi_version,
                           top_hz=max(m.frequency for m in advice.modes)):
            say(f"wrote {path}")
    return 0


def _model_spectrum(modes):
    """Without a recording, the spectrum is the modes' own: each a unit-share transmitted mode, on bins
    of a quarter of the narrowest half-power band (2 zeta f) or 0.5 Hz, whichever is finer (Klipper's own
    are 1.56 Hz), but at most 6000 of them: every bin is judged for each of thousands of designs."""
    import numpy as np

    from shapefmu.identification.spectra import Spectrum
    from shapefmu.identification.synthetic import SyntheticMode, transmissibility

    shapes = [SyntheticMode(m.frequency, max(m.zeta, 0.005)) for m in modes]
    top = 3 * max(m.frequency for m in shapes)
    step = max(min(0.5, min(0.5 * m.zeta * m.frequency for m in shapes)), top / 6000)
    freq = np.arange(0.2, top + step / 2, step)
    psd = sum(np.abs(transmissibility([m], freq)) ** 2 for m in shapes)
    return Spectrum("--mode", "model", freq, psd, "the given modes' transmissibility, summed")


def _merged_modes(per_file):
    """The modes of several recordings: one per distinct frequency (within 3 %), as first found."""
    merged = []
    for modes in per_file:
        for mode in modes:
            same = [m for m in merged if abs(m.frequency - mode.frequency) <= 0.03 * m.frequency]
            if not same:
                merged.append(mode)
    return tuple(sorted(merged, key=lambda m: -m.peak))


def _print_table(advice, recordings: int) -> None:
    across = f"worst of {recordings} recordings and " if recordings > 1 else ""
    print(f"judged by Klipper's measures: vibration = share of the spectrum above max/20 left, {across}worst over "
          f"damping {', '.join(f'{z:g}' for z in advice.dampings)}; smoothing at {advice.accel:g} mm/s^2 and "
          f"{advice.scv:g} mm/s square corner; max accel for smoothing <= {advice.max_smoothing:g} mm; "
          f"score = smoothing (v^1.5 + 0.2 v + 0.01). 'at modes' is ours: the worst V at the identified modes.")
    print(f"{'shaper':<22} {'family':<8} {'Hz':<13} {'vibration':>9} {'max accel':>9} {'score':>9} {'smoothing':>9} "
          f"{'at modes':>8} {'duration':>9}")
    for c in advice.candidates:
        marks = (" <- pick" if c is advice.pick else "") + (" <- Klipper's pick" if c.same(advice.klipper_pick) else "") \
            + ("" if c.guarded else " (fails the guards)")
        print(f"{c.label:<22} {c.family:<8} {'/'.join(f'{f:.1f}' for f in c.frequencies) or '-':<13} "
              f"{100 * c.vibration:8.3f}% {c.max_accel:9.0f} {c.score:9.2e} {c.smoothing:7.3f}mm {100 * c.at_modes:7.1f}% "
              f"{1000 * c.duration:7.1f}ms{marks}")
    if advice.left_out:
        print("left out: " + "; ".join(advice.left_out))
    pick, base = advice.pick, advice.klipper_pick
    print(f"Klipper's pick: {base.kind} at {base.frequencies[0]:.1f} Hz, vibration {100 * base.vibration:.3f}%, "
          f"max accel {base.max_accel:.0f} mm/s^2, score {base.score:.3e}")
    print(f"pick ({advice.firmware}): {pick.label}, vibration {100 * pick.vibration:.3f}%, max accel {pick.max_accel:.0f} "
          f"mm/s^2 ({pick.max_accel / base.max_accel:.3f} x Klipper's), score {pick.score:.3e} "
          f"({pick.score / base.score:.3f} x Klipper's): {advice.verdict}")
    if pick.line:
        print(pick.line)
    elif pick.fmu:
        model = "ShapeFilter" if pick.family == "window" else "Shaper"
        print(f"{model} FMU (recommend --build OUT.fmu): " + ", ".join(f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}"
                                                                   for k, v in pick.fmu))
    else:
        print("impulses (s: amplitude), as the ImpulseTrain FMU (recommend --build OUT.fmu, or shapefmu build shaper "
              "--impulses) takes them: " + ",".join(f"{t!r}:{a!r}" for t, a in zip(pick.times, pick.amplitudes)))


def _fmu_design(candidate) -> tuple[str, dict] | tuple[None, None]:
    """(FMU model, start values but ``Ts``) that runs a judged design: the Shaper or ShapeFilter that
    designs it, else an ImpulseTrain of its impulses normalised to sum to 1, as Klipper applies its
    shapers; (None, None) for a sampled filter's taps that no ShapeFilter designs."""
    if candidate.fmu is not None:
        return ("ShapeFilter" if candidate.family == "window" else "Shaper"), dict(candidate.fmu)
    if candidate.ts is not None:
        return None, None
    from shapefmu.fmi.kinds.impulse_train import train_start_values

    total = math.fsum(candidate.amplitudes)
    return "ImpulseTrain", train_start_values(candidate.times, [a / total for a in candidate.amplitudes])


def _json(advice) -> dict:
    """The recommendation's JSON with the FMU that runs each design and its start values."""
    out = advice.to_json()
    for row, candidate in zip([out["pick"], out["klipper_pick"], *out["candidates"]],
                              [advice.pick, advice.klipper_pick, *advice.candidates]):
        row["fmu_model"], row["fmu_start_values"] = _fmu_design(candidate)
    return out


def _build(pick, out: Path, *, python: bool, fmi_version: str = "2.0", top_hz: float) -> list[Path]:
    """The pick as a Shaper or ShapeFilter FMU where one designs it, else as an ImpulseTrain FMU of its
    impulses (normalised to sum to 1, as Klipper applies its shapers); sampled at the default period of
    ``default_sampling_period`` for the pick's highest frequency (a designed train's: ``top_hz``, the
    highest mode's) (native unless ``python``; native as FMI ``fmi_version``), and its .ssv parameter set, a file
    beside it the user did not name (never one that exists)."""
    from shapefmu.fmi.ssp import write_ssv
    from shapefmu.shapers.catalog import default_sampling_period

    model, starts = _fmu_design(pick)
    ts = default_sampling_period(pick.frequencies or (top_hz,))
    # a window filter's taps are sampled at its own Ts, which it keeps
    starts = {"n": 1, "n_modes": 1, **starts, "Ts": ts} if model == "Shaper" else {"Ts": ts, **starts}
    if python:
        if fmi_version != "2.0":
            raise ValueError(f"--fmi-version {fmi_version} needs the native FMU: the pythonfmu FMUs (--python) are "
                             f"FMI 2.0 only")
        from shapefmu.fmi.python.builder import build_fmu

        fmu = build_fmu(model, out, **starts)
    else:
        from shapefmu.fmi.native.sampled import build_native_fmu

        fmu = build_native_fmu(model, out, fmi_version=fmi_version, **starts)
    ssv = write_ssv(out.with_suffix(".ssv"), starts, named=False)
    return [fmu, ssv]


def _add_reading(p) -> None:
    p.add_argument("--axis", default="xyz", help="x, y, z, xyz (the sum of the axes' spectra, default) or a "
                                                 "direction DX,DY,DZ the samples are projected onto")
    p.add_argument("--time", metavar="COLUMN", help="time column (s) of a CSV or Parquet table")
    p.add_argument("--fs", type=float, metavar="HZ", help="sampling rate of a table without a time column")
    p.add_argument("--column", action="append", metavar="COLUMN", help="signal column of a table (repeat for several)")
    p.add_argument("--undo-sweep", action="store_true",
                   help="divide out the f^2 of Klipper's sweep (acceleration proportional to frequency)")
    p.add_argument("--excitation", choices=("sweep", "flat"),
                   help="the excitation's spectrum: sweep (f^2, default for Klipper files) or flat")
    p.add_argument("--f-min", type=float, metavar="HZ", help="lowest frequency searched")
    p.add_argument("--f-max", type=float, metavar="HZ", help="highest frequency searched")
    p.add_argument("--ringdown", action="store_true", help="the recording is a free decay: refine each mode with the EKF")


def register(commands) -> None:
    p = commands.add_parser("identify", help="find the modes of a machine in a recording (Klipper, RepRapFirmware, CSV)",
                            epilog=examples("shapefmu identify resonances_x.csv --axis x --plot results/modes.png"))
    p.add_argument("recording", nargs="+", help="recording files (format recognised from the content)")
    _add_reading(p)
    p.add_argument("--json", action="store_true", help="print the modes as JSON")
    p.add_argument("--plot", metavar="PNG", type=output_file("plot"), help="save the spectrum with its modes")
    p.set_defaults(run=_cmd_identify)

    p = commands.add_parser("recommend", help="Klipper's pick and ours for a recording, judged by Klipper's measures",
                            epilog=examples("shapefmu recommend resonances_x.csv --axis x --firmware klipper",
                                            "shapefmu recommend resonances_x.csv --axis x --build fmus/MachineShaper.fmu",
                                            "shapefmu recommend --mode 25:0.05 --mode 62:0.08"))
    p.add_argument("recording", nargs="*", help="recording files; several give one pick for the worst of them")
    p.add_argument("--mode", type=parse_mode, action="append", metavar="HZ[:ZETA]", help="a mode, instead of recordings")
    _add_reading(p)
    p.add_argument("--max-smoothing", type=float, default=DEFAULT_MAX_SMOOTHING, metavar="MM",
                   help=f"smoothing bound for the max accel, in [0.05, 10] (default {DEFAULT_MAX_SMOOTHING} mm, Klipper's)")
    p.add_argument("--firmware", choices=("klipper", "rrf", "marlin", "fmu"), default="fmu",
                   help="what runs the shaper: klipper (its six shapers), rrf (RepRapFirmware's M593, custom "
                        "included), marlin (M593 / M493), fmu (anything shapefmu builds, default)")
    p.add_argument("--accel", type=float, default=DEFAULT_ACCEL, metavar="MM_S2",
                   help=f"acceleration the smoothing and score are taken at, in [1, 1e6] (default {DEFAULT_ACCEL:g})")
    p.add_argument("--scv", type=float, default=DEFAULT_SCV, metavar="MM_S",
                   help=f"square-corner velocity (default {DEFAULT_SCV:g} mm/s)")
    p.add_argument("--filter-ts", type=float, default=1e-3, metavar="S",
                   help="sampling period of the window filters judged, in [1e-5, 1e-2] (default 1e-3 s)")
    p.add_argument("--json", action="store_true",
                   help="print the pick, Klipper's pick and the candidates as JSON (stdout holds the JSON alone)")
    p.add_argument("--plot", metavar="PNG", type=output_file("plot"),
                   help="save the spectrum, its modes, the pick, Klipper's pick and three more")
    p.add_argument("--build", metavar="OUT.fmu", type=output_file(".fmu", what="FMU"),
                   help="write the pick (for any --firmware: the shaper that firmware runs) as an FMU (native C), "
                        "a Shaper or ShapeFilter where it is one of their designs, else an ImpulseTrain of its "
                        "impulses, and OUT.ssv beside it")
    p.add_argument("--python", action="store_true", help="with --build: the pythonfmu FMU instead of the native one")
    p.add_argument("--fmi-version", choices=("2.0", "3.0"), default="2.0",
                   help="with --build: FMI version of the native FMU (default 2.0; 3.0: array parameters)")
    p.add_argument("--schedule", type=parse_schedule, metavar="NAME=V1,V2,...",
                   help="the recordings were made at these values of a scheduling input (one each, e.g. "
                        "mass=100,500): print a scheduled shaper's table of their modes instead of a pick; "
                        "--build writes its ScheduledShaper FMU (pythonfmu)")
    p.set_defaults(run=_cmd_recommend)
