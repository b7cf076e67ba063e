"""From a recording of the machine to its shaper: recordings -> spectra -> modes -> ranked shapers.

    from shapefmu import identification as ident
    found = ident.identify("resonances_x.csv", axis="x")          # an Identified: recording, spectrum, modes
    judged = ident.klipper.judged_spectra(found.recording, "resonances_x.csv")  # as Klipper judges shapers
    advice = ident.recommend(judged, found.modes.modes)            # a Recommendation: pick, Klipper's pick

- ``recordings``: Klipper raw and processed files, RepRapFirmware M956, any CSV/Parquet table;
- ``spectra``: Welch spectra with their settings, axes combined, Klipper's sweep excitation undone;
- ``modes``: resonances with frequency, damping and uncertainty (spectrum fit; EKF on a ring-down);
- ``metrics``: Klipper's remaining vibration, smoothing, max acceleration and score, derived and vectorised;
- ``klipper``: Klipper's shapers, spectrum reading, frequency scan and pick, rebuilt from its definitions;
- ``judge``: designs judged by those measures on the spectra, and the judged ``Candidate``;
- ``firmware``, ``families``, ``trains``: what Klipper, RepRapFirmware, Marlin and an FMU run, and impulse
  trains designed for the spectrum;
- ``recommend``: Klipper's pick, the candidates a firmware runs, the guards and the pick;
- ``synthetic``: recordings of known machines, made as Klipper and RepRapFirmware make them.
"""

from __future__ import annotations

from dataclasses import dataclass

from shapefmu.identification.modes import Mode, Modes, find_modes, ring_down
from shapefmu.identification.judge import Candidate
from shapefmu.identification.recommend import Recommendation, recommend
from shapefmu.identification.recordings import Recording, read_recording
from shapefmu.identification.spectra import Spectrum, spectrum, undo_sweep_excitation

__all__ = ["Candidate", "Identified", "Mode", "Modes", "Recommendation", "Recording", "Spectrum", "find_modes",
           "identify", "read_recording", "recommend", "ring_down", "spectrum", "undo_sweep_excitation"]


@dataclass(frozen=True)
class Identified:
    """What one file gave: the ``recording`` (None for a file of spectra), the ``spectrum`` judged and
    its ``modes``."""

    recording: Recording | None
    spectrum: Spectrum
    modes: Modes


def identify(path, *, axis="xyz", time_column=None, fs=None, columns=None, undo_sweep: bool = False,
             excitation: str | None = None, response: str = "transmitted", f_min=None, f_max=None,
             ringdown: bool = False, resolution: float | None = None, prominence: float = 0.5) -> Identified:
    """Read ``path`` (any format of ``recordings``), take the spectrum along ``axis`` and find its modes.

    ``excitation`` defaults to ``"sweep"`` for Klipper's files (its ``TEST_RESONANCES`` sweep) and
    ``"flat"`` otherwise; with ``undo_sweep`` the f^2 is divided out first. ``ringdown`` refines each
    mode with the EKF on the recording's samples (``modes.ring_down``).
    """
    from shapefmu.identification import recordings, spectra

    read = read_recording(path, time_column=time_column, fs=fs, columns=columns)
    if isinstance(read, dict):  # a Klipper spectrum file
        if ringdown:
            raise ValueError(f"{path}: a file of spectra has no samples to follow a ring-down in")
        key = axis if isinstance(axis, str) else None
        if key not in read:
            raise ValueError(f"{path}: no spectrum for axis {axis!r}; it has {', '.join(read)}")
        recording, found = None, read[key]
        kind = recordings.KLIPPER_SPECTRUM
    else:
        recording = read
        options = {} if resolution is None else {"resolution": resolution}
        found = spectra.spectrum(recording, axis, **options)
        kind = recording.format
    if undo_sweep:
        found = undo_sweep_excitation(found)
    if excitation is None:
        excitation = "sweep" if kind in (recordings.KLIPPER_RAW, recordings.KLIPPER_SPECTRUM) else "flat"
    modes = find_modes(found, response=response, excitation=excitation, f_min=f_min, f_max=f_max,
                       prominence=prominence)
    if ringdown and modes.modes:
        from dataclasses import replace

        samples = spectra.axis_samples(recording, axis) if axis != "xyz" else next(iter(recording.channels.values()))
        modes = replace(modes, modes=ring_down(samples, recording.fs, modes))
    return Identified(recording, found, modes)
