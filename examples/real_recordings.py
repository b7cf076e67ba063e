"""Klipper's pick beside ours on the nine real development recordings (issue 32), every figure by
Klipper's definitions (shapefmu.identification.metrics, checked against Klipper's own output in
tests/test_klipper_metrics.py): the README's table, printed as Markdown, and the plot of one recording
in results/real_recording.png (the README's examples/figures/real_recording.png).

    .venv/bin/python examples/real_recordings.py
"""

from pathlib import Path

from shapefmu.identification import identify, klipper
from shapefmu.identification.recommend import recommend, usable_modes
from shapefmu.plots import plot_recommendation

RECORDINGS = Path(__file__).parent.parent / "tests" / "data" / "recordings"
PLOTTED = "switchwire_resonances_x_20211024_204517.csv"
RESULTS = Path("results")


def outcome(pick, theirs) -> str:
    """win: no more vibration, no less max_accel and a lower score; tie: the same figures; else lose."""
    if (pick.vibration, pick.max_accel, pick.score) == (theirs.vibration, theirs.max_accel, theirs.score):
        return "tie"
    return "win" if pick.dominates(theirs) and pick.score < theirs.score else "lose"


def main() -> None:
    rows, counts = [], {"win": 0, "tie": 0, "lose": 0}
    for path in sorted(RECORDINGS.glob("*.csv")):
        found = identify(path, axis="xyz")
        spectra = klipper.judged_spectra(found.recording, path)
        modes, _ = usable_modes(found.modes.modes)
        ours = recommend(spectra, modes)
        own = recommend(spectra, modes, firmware_name="klipper").pick
        k, p = ours.klipper_pick, ours.pick
        result = outcome(p, k)
        counts[result] += 1
        name = p.label if p.family == "train" else f"{p.label} {'/'.join(f'{f:.1f}' for f in p.frequencies)} Hz"
        rows.append(f"| {path.stem} | {k.kind} {k.frequencies[0]:.1f} Hz | {100 * k.vibration:.3f} % | "
                    f"{k.max_accel:.0f} | {k.score:.3e} | {name} ({p.family}) | {100 * p.vibration:.3f} % | "
                    f"{p.max_accel:.0f} ({p.max_accel / k.max_accel:.3f}x) | {p.score:.3e} ({p.score / k.score:.3f}x) | "
                    f"{result} | {own.kind} {own.frequencies[0]:.1f} Hz, score {own.score / k.score:.3f}x |")
        if path.name == PLOTTED:
            RESULTS.mkdir(exist_ok=True)
            plot_recommendation(spectra, ours, RESULTS / "real_recording.png")
    print("| recording | Klipper's pick | vibration | max_accel | score | our pick (fmu) | vibration | max_accel | "
          "score | result | --firmware klipper |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    print("\n".join(rows))
    print(f"\nwin {counts['win']}, tie {counts['tie']}, lose {counts['lose']} of {len(rows)}")


if __name__ == "__main__":
    main()
