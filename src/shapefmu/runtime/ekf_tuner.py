"""EKF-tuned input shaper (paper 001, Fig. 20): watch the vibration, design the shaper, shape commands.

Each step takes one command sample and one vibration sample. The vibration goes to the resonance
EKF (``runtime.ekf``). Until its estimate has converged the command passes through unshaped; once it
has, a shaper of the chosen kind is designed for the estimated mode (omega_n, zeta) and shapes the
commands that follow. When a converged estimate later moves away from the design point by more than
``retune_fraction`` (relative in omega_n, absolute in zeta) the shaper is re-designed. One threshold
serves both because a ZV shaper's residual vibration grows like (pi/2)|d omega / omega| for a
frequency error and like (pi/2)|d zeta| for a damping error.

Switching shapers and the command history. A new shaper is designed at once but switched in only
when the command has been constant for as long as both the old and the new shaper remember: then
both filters output that constant and the switch is seamless (the new filter is started at rest on
it). Switching in the middle of a move would instead produce the jump between the two filters'
outputs, sum_i (w_new,i - w_old,i) u[k - d_i], which is itself a step input that re-excites the mode
the shaper is meant to spare. A command that never rests keeps its current shaper (or stays
unshaped); ``pending`` says that a design is waiting.
"""

from .checks import check_count, check_positive
from .ekf import ResonanceEKF
from .shaper_designs import CLOSED_FORM, design_impulses
from .shaper_filter import StreamingShaper

# The closed-form kinds, cheap enough to re-design at every re-tune.
KINDS = tuple(CLOSED_FORM)


class EKFTunedShaperKernel:
    """``step(command, measurement) -> shaped command``, one call per sample at ``fs``.

    ``kind`` is one of ``KINDS`` or a callable ``(omega_n, zeta) -> (times, amplitudes)``; the
    remaining keyword arguments (``sigma0``, ``amplitude``, ``p0``, ``q``, ``r``, ``omega_tol``,
    ``sigma_tol``, ``window``) configure the ``ResonanceEKF``.
    """

    def __init__(self, fs, omega0, kind="zvd", n=1, retune_fraction=0.05, **ekf_options):
        if not callable(kind) and kind not in KINDS:
            raise ValueError(f"kind must be one of {', '.join(KINDS)} or a callable, got {kind!r}")
        self.kind = kind
        self.n = check_count(n, "n", minimum=0)
        self.retune_fraction = check_positive(retune_fraction, "retune_fraction")
        self.ekf = ResonanceEKF(fs, omega0, **ekf_options)
        self.h = 1.0 / self.ekf.fs
        self.filter = None  # None: pass-through until the first design is switched in
        self.design = None  # (omega_n, zeta) of the newest design, switched in or pending
        self.impulses = None  # (times, amplitudes) of the shaper in use
        self.pending = None  # (design, impulses, filter) waiting for the command to rest
        self.designs = 0
        self._last_command = None
        self._rest = 0  # how many consecutive samples the command has held its value

    def _impulses(self, omega_n, zeta):
        if callable(self.kind):
            return self.kind(omega_n, zeta)
        return design_impulses(self.kind, [(omega_n, zeta)], self.n)

    def observe(self, measurement):
        """Feed one vibration sample to the EKF; design a new shaper if the estimate calls for it."""
        self.ekf.step(measurement)
        if not self.ekf.converged:
            return
        omega_n, zeta = self.ekf.omega_n, self.ekf.zeta
        if not 0.0 <= zeta < 1.0:
            return  # a growing or over-damped "mode" is no design point for a shaper
        if self.design is not None:
            old_omega, old_zeta = self.design
            moved = max(abs(omega_n - old_omega) / old_omega, abs(zeta - old_zeta))
            if moved <= self.retune_fraction:
                return
        times, amplitudes = self._impulses(omega_n, zeta)
        self.design = (omega_n, zeta)
        self.pending = ((omega_n, zeta), (list(times), list(amplitudes)), StreamingShaper.from_impulses(times, amplitudes, self.h))
        self.designs += 1

    def shape(self, command):
        """Shape one command sample with the shaper in use (switching in a pending one at rest)."""
        if command == self._last_command:
            self._rest += 1
        else:
            self._last_command = command
            self._rest = 1
        if self.pending is not None:
            _, impulses, new = self.pending
            old_length = self.filter.length if self.filter is not None else 1
            if self._rest >= max(old_length, new.length):
                new.reset(command)
                self.filter, self.impulses, self.pending = new, impulses, None
        return command if self.filter is None else self.filter.step(command)

    def step(self, command, measurement):
        """Observe one vibration sample, then return the shaped command for the same instant."""
        self.observe(measurement)
        return self.shape(command)
