"""From a recording of the machine to its shaper: recordings -> spectra -> modes -> ranked shapers.

    from shapefmu import identification as ident
    found = ident.identify("resonances_x.csv", axis="x")          # an Identified: recording, spectrum, modes
    judged = ident.klipper.judged_spectra(found.recording, "resonances_x.csv")  # as Klipper judges shapers
    advice = ident.recommend(judged, found.modes.modes)            # a Recommendation: pick, Klipper's pick

- ``recordings``: Klipper raw and processed files, RepRapFirmware M956, any CSV/Parquet table;
- ``spectra``: Klipper's own spectrum and normalisation, finer Welch spectra, spectrograms;
- ``modes``: the resonances a person sees, with frequency, damping and its 90 % interval; no mode in
  noise, no tone taken for one (EKF on a ring-down);
- ``poles``: the local pole form of a linear system's response, fitted to a spectrum;
- ``metrics``: Klipper's remaining vibration, smoothing, max acceleration and score, derived and vectorised;
- ``klipper``: Klipper's shapers, spectrum reading, frequency scan and pick, rebuilt from its definitions;
- ``judge``: designs judged by those measures on the spectra, and the judged ``Candidate``;
- ``firmware``, ``families``, ``trains``: what Klipper, RepRapFirmware, Marlin and an FMU run, and impulse
  trains designed for the spectrum;
- ``recommend``: Klipper's pick, the candidates a firmware runs, the guards and the pick;
- ``synthetic``: recordings of known machines, made as Klipper and RepRapFirmware make them;
- ``synthetic_chain``: raw Klipper tests of mass-spring-damper chains the fitter knows nothing about.
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

    >>> import pathlib, tempfile
    >>> import numpy as np
    >>> f = np.arange(0.0, 200.0, 1.5625)                             # Klipper's bins at 3.2 kHz
    >>> psd = 1e4 * f**2 / ((f**2 - 45.0**2) ** 2 + (0.1 * 45.0 * f) ** 2)  # a 45 Hz peak, zeta 0.05
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "resonances_x.csv"
    >>> rows = "".join(f"{a:.1f},{b:.3e},0,0,{b:.3e}\\n" for a, b in zip(f, psd))
    >>> _ = path.write_text("freq,psd_x,psd_y,psd_z,psd_xyz\\n" + rows)
    >>> found = identify(path, axis="x")
    >>> [f"{m.damped_frequency:.1f} Hz" for m in found.modes.modes], found.recording is None
    (['45.0 Hz'], True)
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
