"""The local form every linear system's response has near its poles, fitted to a power spectrum.

Near its poles, any linear system's frequency response is a sum of partial fractions (Ewins, Modal
Testing, 2nd ed., 4.3), each pole p_k = -sigma_k + j f_k (Hz) with its conjugate, plus what the
other poles and the base contribute nearby, a background B:

    H(f) = sum_k [ R_k / (j f - p_k) + conj(R_k) / (j f - conj(p_k)) ] + B(f).

A power spectrum holds |H|^2 only, smeared by the Welch window (``spectra.spectral_kernel``). The fit
is a least-squares one, in log (so that every part of a peak counts alike), of the smeared |H|^2,
Levenberg-Marquardt with the analytic Jacobian. Three forms, the best by Akaike's criterion: real
residues and a constant real background (a peak nearly symmetric about its pole), complex residues
(non-proportional damping, a neighbour's interference), and complex residues with a background
tilting linearly in complex (the tails of poles not fitted). B's phase is held real: near a pole
only the residue's phase relative to B shows in |H|^2.

How sure: sigma^2 (J^T J)^-1, sigma^2 the residuals' variance inflated by their correlation length
(neighbouring bins are not independent, and a misfit spans many).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from shapefmu.identification.spectra import Spectrum, spectral_kernel

OUTLIER_SPREADS = 5.0  # a bin this many robust standard deviations off the fit is an outlier
KERNEL_STEPS = 4  # the window's smearing sampled every quarter bin


class PoleForm:
    """The local form (module docstring) for ``count`` poles on the frequencies ``grid`` (bins x
    kernel offsets) smeared by ``weights``; ``asymmetric`` lets the residues be complex (else real: a
    peak nearly symmetric about its pole). The background B is real: near a pole only the phase of
    the residue relative to B shows in |H|^2, so a phase of B would be a direction the fit cannot
    tell apart; ``tilted`` adds a complex slope to B, (f / f_mean - 1) (b_r + j b_i). Parameters per
    pole: log f_k, log sigma_k, Re R_k / sigma_k (and Im R_k / sigma_k), then B (and b_r, b_i)."""

    def __init__(self, grid: np.ndarray, weights: np.ndarray, count: int, asymmetric: bool, tilted: bool = False):
        self.grid, self.weights, self.count, self.asymmetric, self.tilted = grid, weights, count, asymmetric, tilted
        self.per_pole = 4 if asymmetric else 3
        self.reference = float(np.mean(grid))
        # neighbouring bins' kernels overlap: H is evaluated once per distinct frequency of the grid
        # (about a third of them), then spread back to it, to the same bits
        self.points, spread = np.unique(grid, return_inverse=True)
        self.spread = spread.reshape(grid.shape)

    def size(self) -> int:
        return self.per_pole * self.count + (3 if self.tilted else 1)

    def pole(self, params, k) -> tuple[float, float]:
        """(f_k, sigma_k) of pole ``k``."""
        return math.exp(params[self.per_pole * k]), math.exp(params[self.per_pole * k + 1])

    def evaluate(self, params) -> tuple[np.ndarray, np.ndarray]:
        """(the smeared |H|^2 at each bin, its derivatives in the parameters: bins x parameters)."""
        jf = 1j * self.points
        n = self.per_pole
        base = self.per_pole * self.count
        total = np.full(self.points.shape, complex(params[base], 0.0))
        if self.tilted:
            tilt = self.points / self.reference - 1
            total = total + complex(params[base + 1], params[base + 2]) * tilt
        parts = []
        for k in range(self.count):
            fk, sk = self.pole(params, k)
            shape = complex(params[n * k + 2], params[n * k + 3] if self.asymmetric else 0.0)
            residue = sk * shape
            pole = complex(-sk, fk)
            upper, lower = 1 / (jf - pole), 1 / (jf - pole.conjugate())
            near, far = residue * upper, residue.conjugate() * lower
            total += near + far
            # d/d log f_k: f_k (j R upper^2 - j conj(R) lower^2); d/d log sigma_k: the residue scales with
            # sigma_k and the pole moves by -sigma_k
            near_2, far_2 = residue * upper**2, residue.conjugate() * lower**2
            d_f = fk * 1j * (near_2 - far_2)
            d_s = near + far - sk * (near_2 + far_2)
            d_a = sk * (upper + lower)
            parts += [d_f, d_s, d_a] + ([1j * sk * (upper - lower)] if self.asymmetric else [])
        parts.append(np.ones(self.points.shape, dtype=complex))
        if self.tilted:
            parts += [tilt.astype(complex), 1j * tilt]
        model = (np.abs(total) ** 2)[self.spread] @ self.weights
        # d|H|^2 = 2 Re(conj(H) dH), smeared; one part at a time: stacking them costs more than the rest
        conjugate = np.conj(total)
        slopes = np.empty((len(parts), self.grid.shape[0]))
        for i, part in enumerate(parts):
            slopes[i] = (2 * (conjugate * part).real)[self.spread] @ self.weights
        return model, slopes.T


@dataclass(frozen=True)
class PoleFit:
    """A fitted ``form``: its ``params``, their ``covariance`` and ``misfit``."""

    form: PoleForm
    params: np.ndarray
    covariance: np.ndarray
    misfit: float  # the residuals' root mean square, in log: 0.01 is a fit within 1 %

    def shape(self) -> tuple[bool, bool]:
        return self.form.asymmetric, self.form.tilted

    def mode(self, k: int) -> tuple[float, float, float, float]:
        """(natural frequency, zeta, sd of log f_n, sd of log zeta) of pole ``k``: f_n = |p_k|, zeta =
        sigma_k / |p_k|."""
        fk, sk = self.form.pole(self.params, k)
        natural = math.hypot(fk, sk)
        zeta = sk / natural
        at = self.form.per_pole * k
        block = self.covariance[at:at + 2, at:at + 2]  # of (log f_k, log sigma_k)
        # log f_n = log f_k + 1/2 log(1 + (s/f)^2) and log zeta = log s - log f_n: their gradients in
        # (log f_k, log sigma_k) are (1 - zeta^2, zeta^2) and (-(1 - zeta^2), 1 - zeta^2)
        along_f, along_z = np.array([1 - zeta**2, zeta**2]), np.array([zeta**2 - 1, 1 - zeta**2])
        return (natural, zeta, math.sqrt(max(along_f @ block @ along_f, 0.0)),
                math.sqrt(max(along_z @ block @ along_z, 0.0)))


def fit_poles(spectrum: Spectrum, response: np.ndarray, index: np.ndarray, peaks: list[tuple[int, float]], shapes,
              start: PoleFit | None = None, fixed: dict[int, float] | None = None) -> PoleFit | None:
    """The pole form fitted to ``response`` (|H|^2 up to a constant, at ``spectrum.freq``, smeared by
    its window) at the bins ``index``, one pole per peak of ``peaks`` ((bin, half-power half-width
    in Hz): the start), in each of ``shapes`` ((asymmetric, tilted) pairs), or from ``start``'s
    poles, the parameters in ``fixed`` (index: value) held; the best by Akaike's criterion, refitted
    once without the bins far off it (a line of the sweep's slow to-and-fro, a tone). None if no fit
    holds.

    >>> import numpy as np
    >>> from shapefmu.identification.spectra import Spectrum
    >>> f = np.arange(20.0, 60.0, 0.1)
    >>> h = 1 / (1 - (f / 40) ** 2 + 0.1j * f / 40)                     # 40 Hz, zeta 0.05
    >>> fit = fit_poles(Spectrum("m", "x", f, np.abs(h) ** 2, "model"), np.abs(h) ** 2, np.arange(f.size),
    ...                 [(200, 2.0)], [(True, False)])
    >>> [round(float(v), 4) for v in fit.mode(0)[:2]]
    [40.0, 0.05]
    """
    freq = spectrum.freq
    f = freq[index]
    y = np.log(np.maximum(response[index] / float(response[index].max()), 1e-300))
    offsets, weights = spectral_kernel(spectrum.window, KERNEL_STEPS)
    grid = f[:, None] + offsets[None, :] * (freq[1] - freq[0])
    fits = []
    for asymmetric, tilted in shapes:
        form = PoleForm(grid, weights, len(peaks), asymmetric, tilted)
        first, lower, upper = [], [], []
        for k, (i, width) in enumerate(peaks):
            guess = [math.log(freq[i]), math.log(width), math.sqrt(max(float(response[i] / response[index].max()), 1e-12)), 0.0]
            if start is not None:
                guess = list(start.params[start.form.per_pole * k:start.form.per_pole * (k + 1)]) + [0.0]
            first += guess[:form.per_pole]
            lower += [math.log(0.8 * freq[i]), math.log(1e-4 * freq[i])] + [-np.inf] * (form.per_pole - 2)
            upper += [math.log(1.25 * freq[i]), math.log(0.7 * freq[i])] + [np.inf] * (form.per_pole - 2)
        background = [0.0] if start is None else [start.params[start.form.per_pole * start.form.count]]
        first += (background + [0.0, 0.0])[:form.size() - len(first)]
        lower += [-np.inf] * (form.size() - len(lower))
        upper += [np.inf] * (form.size() - len(upper))
        free = np.ones(form.size(), dtype=bool)
        for at, value in (fixed or {}).items():
            first[at], free[at] = value, False
        fit = _least_squares(form, y, np.array(first), np.array(lower), np.array(upper), free)
        if fit is not None:
            fits.append((form, fit, np.array(lower), np.array(upper), free))
    if not fits:
        return None
    form, fit, lower, upper, free = min(fits, key=lambda item: _information(item[1], f.size))
    spread = 1.4826 * float(np.median(np.abs(fit.fun - np.median(fit.fun))))
    outlying = np.abs(fit.fun - np.median(fit.fun)) > OUTLIER_SPREADS * spread
    if spread > 0 and outlying.any() and np.count_nonzero(~outlying) > 2 * fit.x.size:
        kept = PoleForm(grid[~outlying], weights, len(peaks), form.asymmetric, form.tilted)
        refit = _least_squares(kept, y[~outlying], fit.params, lower, upper, free)
        if refit is not None:
            form, fit, f = kept, refit, f[~outlying]
    covariance = np.zeros((free.size, free.size))
    covariance[np.ix_(free, free)] = _covariance(fit, f.size)
    return PoleFit(form, fit.params, covariance, float(np.sqrt(np.mean(fit.fun**2))))


def _least_squares(form: PoleForm, y: np.ndarray, start, lower, upper, free):
    """The fit of ``form`` to the log response ``y`` from ``start``, the parameters not ``free`` held
    (Levenberg-Marquardt with the analytic Jacobian), or None if it failed or left the bounds (a pole
    off its peak). The result's ``params`` holds every parameter, ``x`` and ``jac`` the free ones."""
    if y.size <= np.count_nonzero(free):
        return None
    params = np.array(start, dtype=float)
    last = {}

    def whole(values):
        params[free] = values
        return params

    def evaluate(values):  # the residual and the Jacobian are asked for at the same point: once
        key = values.tobytes()
        if key not in last:
            last.clear()
            last[key] = form.evaluate(whole(values))
        return last[key]

    def residual(values):
        return np.log(np.maximum(evaluate(values)[0], 1e-300)) - y

    def jacobian(values):
        model, slopes = evaluate(values)
        return slopes[:, free] / np.maximum(model, 1e-300)[:, None]

    try:
        fit = least_squares(residual, params[free], jac=jacobian, method="lm", x_scale="jac", ftol=1e-6, xtol=1e-6,
                            max_nfev=100 * int(np.count_nonzero(free)))
    except (ValueError, np.linalg.LinAlgError):
        return None
    fit.params = whole(fit.x).copy()
    # status 0, out of evaluations, is kept: an exact form creeps towards a zero residual
    if fit.status < 0 or not np.all(np.isfinite(fit.params)) or np.any(fit.params < lower) or np.any(fit.params > upper):
        return None
    return fit


def _correlation_length(residual: np.ndarray) -> float:
    """1 + 2 sum of the residuals' autocorrelation over the lags before it first turns negative: how
    many bins count as one independent one."""
    centred = residual - residual.mean()
    energy = float(centred @ centred)
    length = 1.0
    if energy > 0:
        for lag in range(1, residual.size // 2):
            rho = float(centred[lag:] @ centred[:-lag]) / energy
            if rho <= 0:
                break
            length += 2 * rho
    return min(length, residual.size / 4)


def _information(fit, bins: int) -> float:
    """Akaike's criterion on the independent bins (bins over the residuals' correlation length):
    the simpler form unless the other one fits clearly better."""
    independent = bins / _correlation_length(fit.fun)
    return independent * math.log(max(float(fit.fun @ fit.fun) / bins, 1e-300)) + 2 * fit.x.size


def _covariance(fit, bins: int) -> np.ndarray:
    """sigma^2 (J^T J)^-1 of the free parameters, with sigma^2 the residuals' variance times their
    correlation length."""
    variance = float(fit.fun @ fit.fun) / max(bins - fit.x.size, 1)
    return np.linalg.pinv(fit.jac.T @ fit.jac) * variance * _correlation_length(fit.fun)
