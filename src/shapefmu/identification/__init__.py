"""From a recording of the machine to its shaper: recordings -> spectra -> modes -> ranked shapers.

    from shapefmu import identification as ident
    found = ident.identify("resonances_x.csv", axis="x")          # an Identified: recording, spectrum, modes
    advice = ident.recommend([found.spectrum], found.modes.modes)  # a Recommendation: table, pick, baseline

- ``recordings``: Klipper raw and processed files, RepRapFirmware M956, any CSV/Parquet table;
- ``spectra``: Welch spectra with their settings, axes combined, Klipper's sweep excitation undone;
- ``modes``: resonances with frequency, damping and uncertainty (spectrum fit; EKF on a ring-down);
- ``metrics``: Klipper's remaining vibration, smoothing and max acceleration, derived and vectorised;
- ``recommend``: every family of the design layer at its best frequencies, the pick and the baseline;
- ``synthetic``: recordings of known machines, made as Klipper and RepRapFirmware make them.
"""

from __future__ import annotations

from dataclasses import dataclass

from shapefmu.identification.modes import Mode, Modes, find_modes, ring_down
from shapefmu.identification.recommend import Candidate, Recommendation, recommend
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
             excitation: str | None = None, f_min=None, f_max=None, ringdown: bool = False,
             resolution: float | None = None) -> Identified:
    """Read ``path`` (any format of ``recordings``), take the spectrum along ``axis`` and find its modes.

    The spectrum judged is Klipper's (``spectra.klipper_psd``) for a recording, the file's own for a
    Klipper spectrum file; the modes are seen in it and fitted on a finer one (``spectra.spectrum``
    at ``resolution`` Hz, 0.1 by default) where there are samples, with their spectrogram telling a
    steady tone from a resonance. ``excitation`` defaults to ``"sweep"`` for Klipper's files (its
    ``TEST_RESONANCES`` sweep) and ``"flat"`` otherwise; with ``undo_sweep`` the f^2 is divided out of
    the spectrum handed on. ``ringdown`` refines each mode with the EKF on the recording's samples
    (``modes.ring_down``).
    """
    from dataclasses import replace

    from shapefmu.identification import recordings, spectra

    read = read_recording(path, time_column=time_column, fs=fs, columns=columns)
    if isinstance(read, dict):  # a Klipper spectrum file
        if ringdown:
            raise ValueError(f"{path}: a file of spectra has no samples to follow a ring-down in")
        key = axis if isinstance(axis, str) else None
        if key not in read:
            raise ValueError(f"{path}: no spectrum for axis {axis!r}; it has {', '.join(read)}")
        recording, judged, fine, gram = None, read[key], None, None
        kind = recordings.KLIPPER_SPECTRUM
    else:
        recording = read
        options = {} if resolution is None else {"resolution": resolution}
        judged = spectra.klipper_psd(recording, axis)
        fine = spectra.spectrum(recording, axis, **options)
        gram = spectra.spectrogram(recording, axis)
        kind = recording.format
    if excitation is None:
        excitation = "sweep" if kind in (recordings.KLIPPER_RAW, recordings.KLIPPER_SPECTRUM) else "flat"
    modes = find_modes(judged, excitation=excitation, f_min=f_min, f_max=f_max, fine=fine, spectrogram=gram)
    if ringdown and modes.modes:
        samples = spectra.axis_samples(recording, axis) if axis != "xyz" else next(iter(recording.channels.values()))
        modes = replace(modes, modes=ring_down(samples, recording.fs, modes))
    return Identified(recording, undo_sweep_excitation(judged) if undo_sweep else judged, modes)
