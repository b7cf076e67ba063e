"""``shapefmu design``, ``sensitivity`` and ``profile``: shapers, filters and motion profiles, printed.
"""

from __future__ import annotations

import json
import math

from shapefmu.cli.arguments import (add_design_arguments, add_sampling_arguments, examples, output_file, parse_mode,
                                     say_written)


def _design(args):
    from shapefmu.shapers import WINDOW_FILTERS, design

    if args.kind not in WINDOW_FILTERS:
        return design(args.kind, args.mode, vtol=args.vtol, n=args.n)
    if len(args.mode) != 1:
        raise ValueError(f"window filter {args.kind!r} takes exactly one --mode, got {len(args.mode)}")
    return _window_filter(args.kind, args.mode[0], args)


def _window_filter(kind, mode, args):
    from shapefmu.shapers import WINDOW_FILTERS

    omega, zeta = mode
    ts = args.ts if args.ts is not None else math.pi / (100 * omega * math.sqrt(1 - zeta**2))
    return WINDOW_FILTERS[kind](omega, zeta, ts, args.order, adjust_ts=args.adjust_ts or args.ts is None)


def _cmd_design(args) -> int:
    from shapefmu.analysis import residual_vibration
    from shapefmu.shapers import WINDOW_FILTERS

    shaper = _design(args)
    if args.kind in WINDOW_FILTERS and not args.json:
        (w, z), = args.mode
        print(f"{args.kind} filter of order {args.order}: {len(shaper)} taps at ts = {shaper.ts:.10g} s, "
              f"duration {shaper.duration:.6g} s, sum of taps {shaper.gain:.12g}")
        print(f"mode {w / (2 * math.pi):g} Hz, zeta {z:g}: residual vibration {100 * residual_vibration(shaper, w, z):.3g} %")
        return 0
    residuals = [residual_vibration(shaper, w, z) for w, z in args.mode]
    if args.json:
        record = json.loads(shaper.to_json())
        record["modes"] = [{"omega": w, "zeta": z, "residual": r} for (w, z), r in zip(args.mode, residuals)]
        print(json.dumps(record, indent=2))
        return 0
    print(f"{args.kind} shaper, {len(shaper)} impulses, duration {shaper.duration:.6g} s")
    print(f"{'time [s]':>14}  {'amplitude':>10}")
    for t, a in zip(shaper.times, shaper.amplitudes):
        print(f"{t:14.6e}  {a:10.6f}")
    for (w, z), r in zip(args.mode, residuals):
        print(f"mode {w / (2 * math.pi):g} Hz, zeta {z:g}: residual vibration {100 * r:.3g} %")
    return 0


def _cmd_sensitivity(args) -> int:
    import numpy as np

    from shapefmu.analysis import insensitivity, sensitivity

    shaper = _design(args)
    q = np.linspace(0.0, args.q_max, 1201)
    curves = []
    for w, z in args.mode:
        label = f"{w / (2 * math.pi):g} Hz, zeta {z:g}"
        curves.append((label, sensitivity(shaper, w, z, q)))
        try:
            band = insensitivity(shaper, w, z, args.vtol)
            print(f"{label}: V <= {100 * args.vtol:g} % for q in [{band.q_low:.4f}, {band.q_high:.4f}], I = {band.width:.4f}")
        except ValueError as error:
            print(f"{label}: {error}")
    if args.plot:
        from shapefmu.plots import plot_sensitivity

        path = plot_sensitivity([(f"{args.kind}, {label}", c) for label, c in curves], args.plot, vtol=args.vtol)
        print(f"sensitivity plot written to {path}")
    return 0


def _cmd_profile(args) -> int:
    from shapefmu.shapers import TWIN_PULSE_PROFILES, time_frequency_profile, velocity_profile

    omega, zeta = args.mode
    if args.kind in TWIN_PULSE_PROFILES:
        extras = {"ts": args.ts}
        if args.kind.startswith("M-"):
            extras.update(delta_omega=args.delta_omega, attenuation=args.attenuation)
        design_ = TWIN_PULSE_PROFILES[args.kind](omega, args.distance, args.speed, **extras)
        profile = design_.profile
        summary = f"null k = {design_.null}, slew speed {design_.slew_speed:.6g}, delta-omega {design_.delta_omega:.6g} rad/s"
    elif args.kind == "time-frequency":
        if args.ts is None or args.move_time is None:
            raise ValueError("the time-frequency profile needs --ts and --move-time (s)")
        design_ = time_frequency_profile(omega, args.ts, args.move_time, args.distance)
        profile = design_.profile
        summary = f"scale n = {design_.n:.4f}, energy leakage 1 - J = {design_.leakage:.3e}"
    else:
        profile = velocity_profile(_window_filter(args.kind, args.mode, args), args.distance)
        summary = f"{args.kind} velocity profile of order {args.order}"
    if args.json:
        print(profile.to_json())
    else:
        print(f"{args.kind}: {summary}")
        print(
            f"duration {profile.duration:.6g} s, peak velocity {max(abs(profile.velocity)):.6g}, "
            f"peak acceleration {max(abs(profile.acceleration)):.6g}, final position {profile.position[-1]:.12g}"
        )
    if args.plot:
        from shapefmu.plots import plot_motion_profile

        say_written(args, f"profile plot written to {plot_motion_profile(profile, args.plot, title=args.kind)}")
    return 0


def register(commands) -> None:
    p = commands.add_parser(
        "design", help="design an impulse shaper or window filter and print it", arguments=_design_arguments,
        epilog=examples("shapefmu design zvd --mode 2000:0.01 --mode 3000:0.01",
                        "shapefmu design simultaneous --mode 2000:0.01 --mode 3000:0.01 --json",
                        "shapefmu design hanning --mode 1:0.2 --order 2"))
    p.set_defaults(run=_cmd_design)

    p = commands.add_parser(
        "sensitivity", help="residual vibration against frequency error, and the band where it stays small",
        arguments=_sensitivity_arguments, epilog=examples("shapefmu sensitivity ei3 --mode 10 --plot results/ei3.png"))
    p.set_defaults(run=_cmd_sensitivity)

    p = commands.add_parser(
        "profile", help="rest-to-rest motion profile (twin-pulse, time-frequency, window)",
        arguments=_profile_arguments,
        epilog=examples("shapefmu profile M-BC:TZ:TP --mode 0.557 --distance 1.7 --speed 0.7 --delta-omega 0.05"))
    p.set_defaults(run=_cmd_profile)


def _design_arguments(p) -> None:
    from shapefmu.shapers import KINDS, WINDOW_FILTERS

    add_design_arguments(p, kinds=(*KINDS, *WINDOW_FILTERS))
    add_sampling_arguments(p)
    p.add_argument("--json", action="store_true", help="print the design as JSON")


def _sensitivity_arguments(p) -> None:
    add_design_arguments(p)
    p.add_argument("--q-max", type=float, default=2.0, help="largest frequency ratio plotted (default 2)")
    p.add_argument("--plot", metavar="PNG", type=output_file("plot"), help="save the sensitivity curve to this file")


def _profile_arguments(p) -> None:
    from shapefmu.shapers import TWIN_PULSE_PROFILES

    p.add_argument("kind", choices=(*TWIN_PULSE_PROFILES, "time-frequency", "hanning", "blackman"),
                   help="profile family")
    p.add_argument("--mode", type=parse_mode, required=True, metavar="HZ[:ZETA]", help="mode to suppress")
    p.add_argument("--distance", type=float, required=True, help="move distance")
    p.add_argument("--speed", type=float, help="desired slew speed (twin-pulse family)")
    p.add_argument("--delta-omega", type=float, help="null offset in rad/s (M- twin-pulse kinds)")
    p.add_argument("--attenuation", type=float, help="spectrum magnitude at the mode, to find delta-omega by bisection")
    p.add_argument("--move-time", type=float, help="move time in s (time-frequency profile)")
    add_sampling_arguments(p)
    p.add_argument("--plot", metavar="PNG", type=output_file("plot"),
                   help="save acceleration, velocity and position to this file")
    p.add_argument("--json", action="store_true", help="print the sampled profile as JSON")
