"""Scalar root bracketing and bounded minimisation, standard library only.

The profile designs that an FMU runs at initialisation need two one-dimensional searches: the
twin-pulse mis-alignment for a requested attenuation (a bisection, paper 003 section III-C) and the
time-frequency scale n (a bounded minimisation, paper 004 eq. 20, which the paper does with
Matlab's ``fminbound``). Both are the classic algorithms that scipy's ``bisect`` and
``minimize_scalar(method="bounded")`` implement, so the design layer and an FMU reach the same
numbers: bisection halves a sign-changing bracket; the bounded minimiser is Brent's method
(R. P. Brent, *Algorithms for Minimization without Derivatives*, 1973, ch. 5; Forsythe, Malcolm &
Moler, *Computer Methods for Mathematical Computations*, 1977, ``fmin``), golden-section steps
made faster by parabolic interpolation where the parabola is trusted.
"""

import math

from .checks import check_finite, check_positive

_GOLDEN = 0.5 * (3.0 - math.sqrt(5.0))
_SQRT_EPS = math.sqrt(2.2e-16)
_RTOL = 4.0 * 2.220446049250313e-16


def bisect(function, low, high, xtol):
    """A root of ``function`` in [low, high], where it changes sign, to within ``xtol`` + 4 eps |x|."""
    low, high = check_finite(low, "low"), check_finite(high, "high")
    xtol = check_positive(xtol, "xtol")
    f_low, f_high = function(low), function(high)
    if f_low * f_high > 0.0:
        raise ValueError(f"function must change sign on [{low!r}, {high!r}], got {f_low!r} and {f_high!r}")
    if f_low == 0.0:
        return low
    if f_high == 0.0:
        return high
    # Keep the end whose sign f_low has and halve the distance to the other one.
    x, dx = low, high - low
    for _ in range(200):
        dx *= 0.5
        middle = x + dx
        f_middle = function(middle)
        if f_middle * f_low >= 0.0:
            x = middle
        if f_middle == 0.0 or abs(dx) < xtol + _RTOL * abs(middle):
            return middle
    return x + dx


def minimize_bounded(function, low, high, xatol=1e-5, max_evaluations=500):
    """(x, f(x)) at a local minimum of ``function`` on [low, high], x to about ``xatol``.

    Brent's method: keep the three best points; fit a parabola through them and step to its
    vertex when that lies inside the bracket and moves less than half the step before last,
    otherwise take a golden-section step into the larger part of the bracket. Stops when the best
    point is within 2 tol of the middle of a bracket no wider than 4 tol, tol = sqrt(eps) |x| + xatol / 3.
    """
    low, high = check_finite(low, "low"), check_finite(high, "high")
    if not low < high:
        raise ValueError(f"low must be < high, got [{low!r}, {high!r}]")
    xatol = check_positive(xatol, "xatol")
    a, b = low, high
    best = second = third = a + _GOLDEN * (b - a)  # x, w, v of Brent's notation
    f_best = f_second = f_third = function(best)
    step = previous_step = 0.0  # d and e
    evaluations = 1
    middle = 0.5 * (a + b)
    tol = _SQRT_EPS * abs(best) + xatol / 3.0
    while abs(best - middle) > 2.0 * tol - 0.5 * (b - a) and evaluations < max_evaluations:
        golden = True
        if abs(previous_step) > tol:
            # Parabola through (best, second, third): its vertex is best + p / q.
            r = (best - second) * (f_best - f_third)
            q = (best - third) * (f_best - f_second)
            p = (best - third) * q - (best - second) * r
            q = 2.0 * (q - r)
            if q > 0.0:
                p = -p
            q = abs(q)
            older = previous_step
            previous_step = step
            if abs(p) < abs(0.5 * q * older) and q * (a - best) < p < q * (b - best):
                golden = False
                step = p / q
                trial = best + step
                # Do not evaluate within 2 tol of the ends of the bracket.
                if trial - a < 2.0 * tol or b - trial < 2.0 * tol:
                    step = tol if middle >= best else -tol
        if golden:
            previous_step = (a - best) if best >= middle else (b - best)
            step = _GOLDEN * previous_step
        # Never evaluate closer than tol to the best point: rounding would make it meaningless.
        trial = best + (math.copysign(max(abs(step), tol), step) if step else tol)
        f_trial = function(trial)
        evaluations += 1
        if f_trial <= f_best:
            if trial >= best:
                a = best
            else:
                b = best
            third, f_third = second, f_second
            second, f_second = best, f_best
            best, f_best = trial, f_trial
        else:
            if trial < best:
                a = trial
            else:
                b = trial
            if f_trial <= f_second or second == best:
                third, f_third = second, f_second
                second, f_second = trial, f_trial
            elif f_trial <= f_third or third == best or third == second:
                third, f_third = trial, f_trial
        middle = 0.5 * (a + b)
        tol = _SQRT_EPS * abs(best) + xatol / 3.0
    return best, f_best
