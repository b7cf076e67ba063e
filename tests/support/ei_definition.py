"""The definition of the extra-insensitive (EI) shapers, checked on a design's
impulses alone, independently of the EI solvers (shapers/ei.py, runtime/ei.py): humps of height
exactly vtol, zeros between and beyond them, the design frequency on the middle element, V <= vtol
between the outermost zeros (tests/test_impulse_shapers.py, tests/test_runtime_ei.py).
"""

import math

import numpy as np

from shapefmu.analysis import residual_vibration


def residual_phasor(shaper, q, zeta):
    """Residual phasor R(q) of a unit mode q * omega (omega = 1) after the last impulse, and dR/dq.

    |R| is the percent residual vibration of paper 000 eq. 4 (a phase factor apart), written here
    from the impulse response itself, independently of the EI solver's exponent bookkeeping.
    """
    t, a = np.array(shaper.times), np.array(shaper.amplitudes)
    c = (t[-1] - t) * complex(-zeta, -math.sqrt(1.0 - zeta * zeta))
    terms = a * np.exp(np.multiply.outer(q, c))
    return terms.sum(axis=-1), (terms * c).sum(axis=-1), (terms * c * c).sum(axis=-1)


def ei_constraint_residual(shaper, humps, zeta, vtol):
    """The EI definition checked on the impulses alone; returns the largest constraint residual.

    Dense evaluation of V (shapefmu.analysis.residual_vibration) finds the humps (local maxima
    that reach vtol) and the deepest minima between and beyond them; golden section refines each
    peak and Gauss-Newton each zero on R(q) = 0, both on ``residual_phasor``, written here for R.
    """
    assert min(shaper.amplitudes) > 0
    assert shaper.times[0] == 0.0 and all(b > a for a, b in zip(shaper.times, shaper.times[1:]))
    q = np.arange(0.05, 52.0, 2e-3)
    v = residual_vibration(shaper, q, zeta)
    inner = (v[1:-1] > v[:-2]) & (v[1:-1] >= v[2:])
    candidates = np.nonzero(inner & (v[1:-1] > vtol / 2))[0] + 1
    # Golden-section search of every peak inside its two grid cells, all peaks at once.
    low, high = q[candidates - 1], q[candidates + 1]
    ratio = (math.sqrt(5.0) - 1.0) / 2.0
    for _ in range(80):
        c, d = high - ratio * (high - low), low + ratio * (high - low)
        left = np.abs(residual_phasor(shaper, c, zeta)[0]) > np.abs(residual_phasor(shaper, d, zeta)[0])
        high, low = np.where(left, d, high), np.where(left, low, c)
    peak_q = (low + high) / 2
    for _ in range(3):  # then Newton on d|R|^2/dq = 0, which golden section leaves at ~1e-8
        r, r1, r2 = residual_phasor(shaper, peak_q, zeta)
        with np.errstate(all="ignore"):  # a flat plateau far out may give 0/0: keep golden's
            newton = peak_q - (np.conj(r) * r1).real / (np.abs(r1) ** 2 + (np.conj(r) * r2).real)
        peak_q = np.where(np.abs(newton - peak_q) < 1e-6, newton, peak_q)
    heights = np.abs(residual_phasor(shaper, peak_q, zeta)[0])
    # Peaks that reach vtol; the N nearest q = 1 are the humps (undamped, the pattern repeats).
    tall = np.nonzero(heights > vtol * (1 - 1e-6))[0]
    nearest = np.sort(np.argsort(np.abs(peak_q[tall] - 1.0))[:humps])
    assert len(nearest) == humps and np.all(np.diff(nearest) == 1)
    peaks = candidates[tall[nearest]]
    hump_q = list(peak_q[tall[nearest]])
    residuals = [abs(sum(shaper.amplitudes) - 1.0)]
    residuals += [abs(h**2 - vtol**2) for h in heights[tall[nearest]]]
    before = candidates[tall[nearest[0] - 1]] if nearest[0] > 0 else 0
    after = candidates[tall[nearest[-1] + 1]] if nearest[-1] + 1 < len(tall) else len(q) - 1
    # One zero below, between and above the humps: the deepest grid minimum in each gap, the outer
    # gaps reaching to the next peak that reaches vtol (or the end of the grid).
    edges = [before, *peaks, after]
    zero_q = []
    for lo, hi in zip(edges, edges[1:]):
        x = q[lo + int(np.argmin(v[lo : hi + 1]))]
        for _ in range(40):  # Gauss-Newton on the complex equation R(q) = 0 in real q
            r, r1, _ = residual_phasor(shaper, x, zeta)
            x -= (np.conj(r1) * r).real / abs(r1) ** 2
        r = residual_phasor(shaper, x, zeta)[0]
        residuals += [abs(r.real), abs(r.imag)]
        zero_q.append(x)
    middle = sorted(hump_q + zero_q)[humps]
    assert abs(middle - 1.0) < 1e-9  # the design frequency sits on the middle hump or zero
    # Between the outermost zeros V never exceeds vtol.
    band = (q >= zero_q[0]) & (q <= zero_q[-1])
    assert v[band].max() <= vtol * (1 + 1e-9)
    assert np.all(heights[(peak_q >= zero_q[0]) & (peak_q <= zero_q[-1])] <= vtol * (1 + 1e-9))
    return max(residuals)
