"""``shapefmu recommend REC... --schedule NAME=V1,V2,...``: a scheduled shaper's table from recordings of
the machine at several values of a scheduling input (issue 37: a bed with 100 g, then 500 g on it).

Each recording gives the row of its value: its dominant mode (the highest peak of its spectrum among the
modes ``identify`` finds), the rows sorted by value. The table is printed (``--json``: as JSON on
stdout), with the start values of a ScheduledShaper FMU (``fmi/kinds/scheduled_shaper.py``), which
``--build OUT.fmu`` writes (pythonfmu; ``shapefmu build scheduled-shaper --native --param ...`` builds its
native twin). The shaper holds the end rows beyond the table and is linear in the value between rows.
"""

from __future__ import annotations

import argparse
import json
import math
import re

# the ScheduledShaper FMU's rows (fmi/kinds/scheduled_shaper.py, MAX_ROWS), repeated so that --help
# imports no FMU kind
MAX_ROWS = 8
_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def parse_schedule(text: str) -> tuple[str, tuple[float, ...]]:
    """``"mass=100,500"`` -> ("mass", (100.0, 500.0)): the scheduling input's name and its value in each
    recording, in the recordings' order (distinct, finite, 2 to MAX_ROWS of them)."""
    name, _, listed = text.partition("=")
    if not _NAME.fullmatch(name) or not listed:
        raise argparse.ArgumentTypeError(f"--schedule must be NAME=V1,V2,... (a name, then one value per "
                                         f"recording), e.g. mass=100,500, got {text!r}")
    try:
        values = tuple(float(v) for v in listed.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"--schedule values must be numbers, got {listed!r}") from None
    if not all(math.isfinite(v) for v in values) or len(set(values)) != len(values):
        raise argparse.ArgumentTypeError(f"--schedule values must be finite and distinct, got {listed!r}")
    if not 2 <= len(values) <= MAX_ROWS:
        raise argparse.ArgumentTypeError(f"--schedule takes 2 to {MAX_ROWS} values (the rows a ScheduledShaper "
                                         f"holds), got {len(values)}")
    return name, values


def schedule_table(found, schedule) -> list[tuple[float, object, str]]:
    """(value, dominant mode, source) per recording of ``found`` (``identify`` results, in the order of the
    values of ``schedule``, from ``parse_schedule``), sorted by value."""
    name, values = schedule
    if len(values) != len(found):
        raise ValueError(f"--schedule {name} lists {len(values)} values for {len(found)} recordings: give one value "
                         f"per recording, in their order")
    rows = []
    for value, identified in zip(values, found):
        if not identified.modes.modes:
            raise ValueError(f"{identified.spectrum.source}: no resonance found, so no row for {name} = {value:g} "
                             f"(see identify's output)")
        rows.append((value, max(identified.modes.modes, key=lambda mode: mode.peak), identified.spectrum.source))
    return sorted(rows, key=lambda row: row[0])


def run_schedule(args, found, say) -> int:
    """Print the table of ``args.schedule`` from the recordings ``found``; ``--build`` writes its FMU."""
    from shapefmu.fmi.kinds.scheduled_shaper import schedule_start_values

    if args.build and args.fmi_version != "2.0":
        raise ValueError("--schedule --build writes the pythonfmu ScheduledShaper FMU, FMI 2.0 (no native twin yet), "
                         f"not --fmi-version {args.fmi_version}")
    name = args.schedule[0]
    rows = schedule_table(found, args.schedule)
    starts = schedule_start_values(*zip(*((value, mode.frequency, mode.zeta) for value, mode, _ in rows)))
    if args.json:
        print(json.dumps({"scheduling": name, "rows": [{"value": value, "frequency_hz": mode.frequency,
                                                        "zeta": mode.zeta, "source": source}
                                                       for value, mode, source in rows],
                          "start_values": starts}, indent=2, allow_nan=False))
    else:
        print(f"schedule of {name} from {len(rows)} recordings (the dominant mode of each; linear between rows, "
              f"the end rows held beyond them):")
        for value, mode, source in rows:
            print(f"  {name} = {value:<10g} {mode.frequency:8.2f} Hz  zeta {mode.zeta:.4f}   {source}")
        print("ScheduledShaper start values: " + " ".join(f"{key}={value}" for key, value in starts.items()))
    if args.build:
        from shapefmu.fmi import build_fmu

        say(f"wrote {build_fmu('ScheduledShaper', args.build, **starts)}")
    return 0
