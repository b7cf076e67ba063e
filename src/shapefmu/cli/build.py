"""``shapefmu build``: FMUs into fmus/ (all of them, or one with a design baked in as start values).

    shapefmu build [all] [-o DIR]
    shapefmu build shaper --kind simultaneous --mode 2000:0.01 --mode 3000:0.01 [--ts S] -o fmus/DiskDriveShaper.fmu
    shapefmu build shaper --impulses 0:0.25,0.0101:0.5,0.0202:0.25 [--ts S] -o fmus/Train.fmu   (an ImpulseTrain FMU)
    shapefmu build reference solution.json [--interpolation hold|linear] -o fmus/TimeOptimal.fmu
    shapefmu build shape-filter --kind hanning --mode 10:0.05 --order 2 [--ts S] -o fmus/HanningFilter.fmu
    shapefmu build ekf-tuner [--kind zvd] [--f0 HZ | --omega0 RAD_S] [--ts S] [--amplitude A] [--retune-fraction F] -o ...
    shapefmu build stos-controller [--param NAME=VALUE ...] -o ...; shapefmu build profile [--param ...] -o ...
    shapefmu build tracked-shaper [--param ...] -o ...
        (any parameter of the FMU, typed as the FMU declares it, e.g. --param kind=zvd --param f[1]=40)
    shapefmu build shaper --native ...; shape-filter --native; ekf-tuner --native; build --native (every
        FMU that has one): the native C twin (no Python on the host; linux64, win64 and aarch64-linux
        binaries; shapefmu.fmi.native.twins); with --fmi-version 3.0 as FMI 3.0 FMUs (array parameters),
        and --clock: a sampled FMU with a periodic input clock of its Ts, for hosts that tick clocks

Targets are registered in ``TARGETS``: a name -> (help, add_arguments(parser), build(args) -> [paths]).
Another target (e.g. ``reference solution.json -o fmus/TimeOptimal.fmu``) is one more entry.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from shapefmu.cli.arguments import examples, output_file, output_folder, parse_mode_hz
from shapefmu.cli.progress import reporter


def _add_all(parser):
    parser.add_argument("-o", "--out", default="fmus", type=output_folder, help="output directory (default fmus/)")
    parser.add_argument("--native", action="store_true",
                        help="the native C twin of every FMU that has one (same names), besides the plants")
    _add_fmi_version(parser)
    parser.add_argument("--models", help="folder of plant models to build as native FMUs "
                        "(default: the papers' models that ship with shapefmu, see shapefmu plant list)")


def _build_all(args):
    from shapefmu.fmi.native import build_all as build_all_plants

    version, progress = _fmi_version(args), reporter(args, "build")
    if args.native:
        from shapefmu.fmi.native.twins import build_all_native

        slaves = build_all_native(args.out, version, progress=progress)
    else:
        from shapefmu.fmi.python.builder import build_all

        slaves = build_all(args.out, progress=progress)
    plants = build_all_plants(args.models, args.out, fmi_version=version, progress=progress)
    measured = _measured_plants(args.out, version, progress) if args.models is None else []
    return [*slaves, *plants, *measured]


def _measured_plants(out, fmi_version, progress) -> list[Path]:
    """The plant FMUs with the rigid-body velocity as an output that a shipped system runs (the
    plant of ``disk_drive_stos``, DiskDriveMeasured.fmu, which its STOS controller measures), built
    from the shipped model of that plant: ``shapefmu simulate NAME`` then works after ``build``."""
    from xml.etree import ElementTree as ET

    from shapefmu.compare import measured_plant
    from shapefmu.fmi.native import build_plant_fmu, fmu_file_name
    from shapefmu.plants import as_plant
    from shapefmu.plants.shipped import SYSTEM_SUFFIXES, shipped

    used = {Path(element.get("source", "")).name for system in shipped(SYSTEM_SUFFIXES)
            for element in ET.parse(system).getroot().iter() if element.tag.endswith("}Component")}
    built = []
    for path in shipped((".toml",)):  # the linear models; a .py model is no Plant of eq. (1)'s form
        plant = as_plant(path)
        name = fmu_file_name(f"{plant.name}_measured")  # the name measured_plant gives its model
        if name in used:
            if progress is not None:
                progress(f"building {name}, the plant of {path.name} with its velocity measured")
            built.append(build_plant_fmu(measured_plant(plant), Path(out) / name, fmi_version=fmi_version))
    return built


def _add_fmi_version(parser):
    parser.add_argument("--fmi-version", choices=("2.0", "3.0"), default="2.0",
                        help="FMI version of the native FMUs (default 2.0; 3.0 needs --native)")


def _add_native(parser):
    parser.add_argument("--native", action="store_true", help="the native C twin (no Python on the host; linux64, "
                        "win64 and aarch64-linux binaries), designed at build time")
    _add_fmi_version(parser)
    parser.add_argument("--clock", action="store_true",
                        help="with --native --fmi-version 3.0: a periodic input clock of interval Ts whose ticks the FMU "
                        "samples at (Co-Simulation with Event Mode, for hosts that tick clocks); without it the FMU "
                        "samples on the grid t0 + k Ts itself, which every host runs")


def _fmi_version(args) -> str:
    """--fmi-version, refused for the pythonfmu FMUs (FMI 2.0 only)."""
    if args.fmi_version != "2.0" and not args.native:
        raise ValueError(f"--fmi-version {args.fmi_version} needs --native: the pythonfmu FMUs are FMI 2.0 only")
    return args.fmi_version


def _builder(args):
    """The pythonfmu builder, or the native twin's for --native (in --fmi-version)."""
    version = _fmi_version(args)
    if args.native:
        from shapefmu.fmi.native.twins import build_native

        return lambda name, out_path, **starts: build_native(name, out_path, fmi_version=version, clock=args.clock,
                                                             **starts)
    if args.clock:
        raise ValueError("--clock needs --native --fmi-version 3.0: the pythonfmu FMUs are FMI 2.0 only")
    from shapefmu.fmi.python.builder import build_fmu

    return build_fmu


def _add_shaper(parser):
    from shapefmu.fmi.kinds.impulse_train import INTERFACE as TRAIN, MAX_IMPULSES
    from shapefmu.fmi.kinds.shaper import KINDS, MAX_MODES

    _add_native(parser)
    given = parser.add_mutually_exclusive_group(required=True)
    given.add_argument("--mode", type=parse_mode_hz, action="append", metavar="HZ[:ZETA]",
                       help=f"mode frequency in Hz and damping ratio, the Shaper FMU designed for it; up to {MAX_MODES}")
    given.add_argument("--impulses", type=parse_impulses, metavar="T:A,T:A,...",
                       help=f"the impulses themselves, time in s and amplitude, up to {MAX_IMPULSES} (e.g. from "
                       "recommend's pick): an ImpulseTrain FMU; amplitudes not summing to 1 are divided by their sum")
    parser.add_argument("--kind", choices=KINDS, help="shaper design for --mode (default zvd)")
    parser.add_argument("--n", type=int, help="derivative order of zv_dn (default 1)")
    parser.add_argument("--vtol", type=float, help="tolerable vibration (default 0.05)")
    parser.add_argument("--ts", type=float, help="filter sampling period in s (default: 1/100 of the highest mode's "
                        f"period; with --impulses {TRAIN.variable('Ts').start:g} s)")
    parser.add_argument("--allow-aliasing", action="store_true",
                        help="build even when a mode is at or above the Nyquist frequency of --ts (it is left ringing)")
    parser.add_argument("-o", "--out", type=output_file(".fmu", what="FMU"),
                        help="FMU file (default fmus/Shaper.fmu, with --impulses fmus/ImpulseTrain.fmu)")


def parse_impulses(text: str) -> list[tuple[float, float]]:
    """``"0:0.5,0.01:0.5"`` -> [(t s, amplitude), ...]; the count bounded before the text is read."""
    from shapefmu.fmi.kinds.impulse_train import MAX_IMPULSES

    count = text.count(",") + 1
    if count > MAX_IMPULSES:
        raise argparse.ArgumentTypeError(f"--impulses holds at most {MAX_IMPULSES} impulses, got {count}")
    impulses = []
    for i, item in enumerate(text.split(","), 1):
        time_text, colon, amplitude_text = item.partition(":")
        try:
            impulse = (float(time_text), float(amplitude_text))
        except ValueError:
            impulse = ()
        if not colon or len(impulse) != 2 or not all(map(math.isfinite, impulse)):
            raise argparse.ArgumentTypeError(f"--impulses must be T:A pairs (time s: amplitude) separated by commas, "
                                             f"e.g. 0:0.5,0.01:0.5; item {i} is {item.strip()!r}")
        impulses.append(impulse)
    return impulses


def _build_train(args):
    """The ImpulseTrain FMU of --impulses, amplitudes normalised to sum to 1 (and said so)."""
    import sys

    from shapefmu.fmi.kinds.impulse_train import SUM_TOLERANCE, train_start_values

    for option in ("kind", "n", "vtol"):
        if getattr(args, option) is not None:
            raise ValueError(f"--{option} designs a shaper for --mode; --impulses gives the impulses themselves: not both")
    if args.allow_aliasing:
        raise ValueError("--allow-aliasing is for a shaper designed for --mode; --impulses names no mode: leave it out")
    times, amplitudes = zip(*args.impulses)
    total = math.fsum(amplitudes)
    if not (math.isfinite(total) and total != 0.0):
        raise ValueError(f"--impulses amplitudes must have a finite sum other than 0 (a shaper passes a constant "
                         f"command as sum times it), got the sum {total!r}")
    if abs(total - 1.0) > SUM_TOLERANCE:
        amplitudes = [a / total for a in amplitudes]
        print(f"note: the --impulses amplitudes summed to {total!r}; each was divided by that sum so they sum to 1",
              file=sys.stderr)
    starts = train_start_values(times, amplitudes)
    if args.ts is not None:
        starts["Ts"] = args.ts
    return [_builder(args)("ImpulseTrain", Path(args.out or "fmus/ImpulseTrain.fmu"), **starts)]


def _build_shaper(args):
    from shapefmu.fmi.kinds.shaper import MAX_MODES, mode_start_values
    from shapefmu.shapers.catalog import check_sampling, default_sampling_period

    if args.impulses is not None:
        return _build_train(args)
    if len(args.mode) > MAX_MODES:
        raise ValueError(f"--mode may be given at most {MAX_MODES} times, got {len(args.mode)}")
    starts = {"kind": args.kind or "zvd", "n": 1 if args.n is None else args.n,
              "vtol": 0.05 if args.vtol is None else args.vtol, **mode_start_values(args.mode)}
    starts["Ts"] = args.ts if args.ts is not None else default_sampling_period(f for f, _ in args.mode)
    check_sampling([(2.0 * math.pi * f, zeta) for f, zeta in args.mode], starts["Ts"], allow_aliasing=args.allow_aliasing)
    return [_builder(args)("Shaper", Path(args.out or "fmus/Shaper.fmu"), **starts)]


def _add_reference(parser):
    parser.add_argument("table", help="signal table: a TimeOptimalSolution .json (shapefmu optimal) or a time,value .csv")
    parser.add_argument("--interpolation", choices=("hold", "linear"), default="hold",
                        help="how a .csv table is read between rows (default hold, as TimeOptimalSolution.to_csv)")
    parser.add_argument("-o", "--out", default="fmus/ReferencePlayer.fmu", type=output_file(".fmu", what="FMU"),
                        help="FMU file (default fmus/ReferencePlayer.fmu)")


def _add_reference_native(parser):
    _add_reference(parser)
    _add_native(parser)


def _build_reference(args):
    import json

    from shapefmu.runtime import reference_player

    table = reference_player.load(args.table, args.interpolation)  # read and checked (a regular file, its size)
    if str(args.table).lower().endswith(".json"):
        text = Path(args.table).read_text(encoding="utf-8")  # keep the solution's own fields
    else:
        text = json.dumps(table.to_dict())
    return [_builder(args)("ReferencePlayer", Path(args.out), table=text)]


def _add_shape_filter(parser):
    from shapefmu.fmi.kinds.shape_filter import BASES, KINDS as FILTER_KINDS

    _add_native(parser)
    parser.add_argument("--kind", choices=FILTER_KINDS, default="hanning", help="filter design (default hanning)")
    parser.add_argument("--mode", type=parse_mode_hz, required=True, metavar="HZ[:ZETA]",
                        help="mode frequency in Hz and damping ratio (damping: window filters only)")
    parser.add_argument("--adjust-ts", action="store_true", help="window filters: use the nearest Ts that makes M whole")
    parser.add_argument("--base", choices=BASES, help="base window of differenced / convolved (default hanning)")
    _parameter_options(parser, "ShapeFilter", {"--order": "order", "--ts": "Ts", "--c": "c", "--delta-f": "delta_f",
                                               "--null": "null", "--move-time": "move_time"})
    parser.add_argument("-o", "--out", default="fmus/ShapeFilter.fmu", type=output_file(".fmu", what="FMU"),
                        help="FMU file (default fmus/ShapeFilter.fmu)")


def _build_shape_filter(args):
    f, zeta = args.mode
    starts = {"kind": args.kind, "f": f, "zeta": zeta, "adjust_Ts": args.adjust_ts,
              **_given(args, "base", "order", "Ts", "c", "delta_f", "null", "move_time")}
    return [_builder(args)("ShapeFilter", Path(args.out), **starts)]


def _add_ekf_tuner(parser):
    from shapefmu.runtime.ekf_tuner import KINDS as TUNER_KINDS

    _add_native(parser)
    parser.add_argument("--kind", choices=TUNER_KINDS, default="zvd", help="shaper designed for the estimate (default zvd)")
    group = parser.add_mutually_exclusive_group()
    group.add_argument("--f0", type=float, metavar="HZ", help="first guess of the vibration's frequency, Hz (default 10)")
    _parameter_options(group, "EKFTuner", {"--omega0": "omega0"})
    _parameter_options(parser, "EKFTuner", {"--n": "n", "--ts": "Ts", "--amplitude": "amplitude",
                                            "--retune-fraction": "retune_fraction"})
    parser.add_argument("-o", "--out", default="fmus/EKFTuner.fmu", type=output_file(".fmu", what="FMU"),
                        help="FMU file (default fmus/EKFTuner.fmu)")


def _build_ekf_tuner(args):
    if args.f0 is not None:  # the command line's frequencies are in Hz; the parameter's name says rad/s
        args.omega0 = 2.0 * math.pi * args.f0
    starts = _given(args, "kind", "n", "omega0", "Ts", "amplitude", "retune_fraction")
    return [_builder(args)("EKFTuner", Path(args.out), **starts)]


def _given(args, *names) -> dict:
    """The parameters ``names`` the user gave (not None): the FMU's own start values stand for the others."""
    return {name: getattr(args, name) for name in names if getattr(args, name) is not None}


_OPTION_TYPES = {"Real": float, "Integer": int, "String": str}


def _parameter_options(parser, kind: str, options: dict) -> None:
    """One option per parameter of the FMU ``kind`` (option -> parameter), typed, described and with
    the default the FMU declares; its value lands in ``args.<parameter>``."""
    from shapefmu.fmi.kinds import kind as kind_module

    interface = kind_module(kind).INTERFACE
    for option, name in options.items():
        variable = interface.variable(name)
        unit = f" {variable.unit}" if variable.type == "Real" and variable.unit != "1" else ""
        parser.add_argument(option, dest=name, type=_OPTION_TYPES[variable.type],
                            help=f"{variable.description} (default {variable.start:g}{unit})")


def _parameters(name: str, items) -> dict:
    """--param NAME=VALUE items as the FMU ``name``'s start values, typed as it declares them."""
    from shapefmu.fmi.kinds import kind

    declared = {v.name: v for v in kind(name).INTERFACE.variables if v.causality == "parameter"}
    starts = {}
    for item in items:
        key, sep, text = item.partition("=")
        if not sep or key not in declared:
            raise ValueError(f"--param must be NAME=VALUE with NAME a parameter of {name} ({', '.join(declared)}), "
                             f"got {item!r}")
        kind = declared[key].type
        try:
            starts[key] = {"Real": float, "Integer": int, "String": str}[kind](text) if kind != "Boolean" else \
                {"true": True, "false": False}[text.lower()]
        except (KeyError, ValueError):
            article = "an" if kind == "Integer" else "a"
            raise ValueError(f"--param {key} is {article} {kind} parameter of {name}, got {text!r}") from None
    return starts


def _parameter_target(name: str, default: str):
    def add(parser):
        _add_native(parser)
        parser.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                            help=f"a parameter of the {name} FMU baked in as its start value; repeat")
        parser.add_argument("-o", "--out", default=f"fmus/{default}.fmu", type=output_file(".fmu", what="FMU"),
                            help=f"FMU file (default fmus/{default}.fmu)")

    def build(args):
        return [_builder(args)(name, Path(args.out), **_parameters(name, args.param))]

    return add, build


TARGETS = {
    "all": ("every FMU with its default parameters", _add_all, _build_all,
            ("shapefmu build all -o fmus", "shapefmu build all --native --fmi-version 3.0 -o fmus3")),
    "shaper": ("the Shaper FMU with a design baked in, or the ImpulseTrain FMU of given impulses", _add_shaper,
               _build_shaper, ("shapefmu build shaper --kind simultaneous --mode 2000:0.01 --mode 3000:0.01 --ts 1e-6 "
                               "-o fmus/DiskDriveShaper.fmu",
                               "shapefmu build shaper --impulses 0:0.25,0.0101:0.5,0.0202:0.25 --native -o fmus/Train.fmu")),
    "reference": ("the ReferencePlayer FMU playing a signal table", _add_reference_native, _build_reference,
                  ("shapefmu build reference results/solution.json -o fmus/TimeOptimal.fmu",)),
    "shape-filter": ("the ShapeFilter FMU with a sampled design baked in", _add_shape_filter, _build_shape_filter,
                     ("shapefmu build shape-filter --kind hanning --mode 10:0.05 --order 2 -o fmus/Hanning.fmu",)),
    "ekf-tuner": ("the EKFTuner FMU (paper 001): estimates the vibration's mode, shapes for it", _add_ekf_tuner,
                  _build_ekf_tuner, ("shapefmu build ekf-tuner --kind zvd --f0 10 --ts 1e-3 -o fmus/EKFTuner.fmu",)),
    "stos-controller": ("the STOSController FMU (paper 002): shaped time-optimal closed loop",
                        *_parameter_target("STOSController", "STOSController"),
                        ("shapefmu build stos-controller --native --param kind=zvd --param f[1]=40 "
                         "-o fmus/STOSController.fmu",)),
    "profile": ("the ProfileGenerator FMU: twin-pulse, time-frequency or shaped bang-bang moves",
                *_parameter_target("ProfileGenerator", "ProfileGenerator"),
                ("shapefmu build profile --param profile=TP -o fmus/ProfileGenerator.fmu",)),
    "scheduled-shaper": ("the ScheduledShaper FMU (issue 37): re-designed for the mode a scheduling input puts in force",
                         *_parameter_target("ScheduledShaper", "ScheduledShaper"),
                         ("shapefmu build scheduled-shaper --native --param kind=zvd -o fmus/ScheduledShaper.fmu",)),
    "tracked-shaper": ("the TrackedShaper FMU (issue 37): a shaper the EKF of paper 001 keeps on a moving mode",
                       *_parameter_target("TrackedShaper", "TrackedShaper"),
                       ("shapefmu build tracked-shaper --native --param f0=27 --param Ts=1e-3 "
                        "-o fmus/TrackedShaper.fmu",)),
}


def register(commands) -> None:
    """Register ``build`` and its targets on the main parser's subcommands."""
    p = commands.add_parser("build", help="build FMUs (default: all of them into fmus/)", arguments=_add_build,
                            epilog=examples("shapefmu build                 # every FMU into ./fmus",
                                            "shapefmu build shaper --kind zvd --mode 40:0.05 -o fmus/Shaper40.fmu",
                                            "shapefmu build TARGET --help   # a target's options"))
    p.set_defaults(run=lambda args: _run(args, "all"))


def _add_build(p) -> None:
    _add_all(p)
    targets = p.add_subparsers(dest="target", metavar="TARGET")
    for name, (text, add_arguments, _, lines) in TARGETS.items():
        q = targets.add_parser(name, help=text, arguments=add_arguments, epilog=examples(*lines))
        q.set_defaults(run=lambda args, name=name: _run(args, name))


def _run(args, target):
    for path in TARGETS[target][2](args):
        print(f"built {path}")
    return 0
