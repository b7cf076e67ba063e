"""Shaped time-optimal servomechanism (STOS, paper 002): switching curves and the per-sample law.

Interface (stable; the STOS FMU wraps it):

- ``stos_curves(b, U, times, amplitudes, damping=0.0) -> dict`` builds the switching curves of the
  law from any positive impulse shaper, as plain JSON-serialisable numbers;
- ``STOSKernel(curves, settle=None, Ts=None)`` evaluates the law once per sample,
  ``control(target, x_r, x_r_dot) -> u`` with |u| <= U, and hands over to a linear settle
  controller near the target; ``reset()``, ``get_state()`` and ``set_state()`` save and restore
  every internal variable. Addition to the agreed contract (backward compatible): the optional
  keyword ``Ts`` (default ``settle["Ts"]``, or None without settle) switches on sub-sample
  switching, below;
- ``stos_fraction(curves, x_e, v)`` is the memoryless STOS law itself, u / U in [-1, 1].

The mathematics
---------------
The rigid body is x_r'' = -d x_r' + b u with |u| <= U (d = 0 for the pure rigid body of eq. 1,
d = Kt^2/(R J) with back EMF). For a positive move the rigid time-optimal input is +U on [0, t1)
and -U on [t1, t2) (eq. 2; t2 = 2 t1 when d = 0). Convolving it with a shaper of impulses A_i >= 0
at tau_0 = 0 < tau_1 < ... < tau_{n-1} = T_s, sum A_i = 1, gives the shaped bang-bang (eqs. 4 and
21 for the paper's two shapers) when both pulses are longer than T_s. With c_k = A_0 + ... + A_k
its levels, in units of U, are

    accelerating  c_k      on [tau_k, tau_{k+1}),            then 1 until t1,
    middle        1 - 2c_k on [t1 + tau_k, t1 + tau_{k+1}),  then -1 until t2,
    decelerating  c_k - 1  on [t2 + tau_k, t2 + tau_{k+1}),  then 0 (at rest on the target).

In the phase plane (x_e, v) = (x_r - target, x_r') the law switches where this input switches;
the switching curves are the loci of the states at the switching instants over all move lengths:

- accelerating switches (eqs. 7-9, S1-S2): the velocity at tau_k does not depend on the move, so
  the curve is the constant V_k, obtained by integrating forward from rest;
- decelerating switches (eqs. 10-12, S6-S7): the tail after t2 does not depend on the move either;
  integrating backward from the target at rest gives the constant velocities W_k at t2 + tau_k and
  the point P = (x_P, W_0) where the tail starts;
- middle switches (eqs. 13-16, S3-S5): the state at t1 + T_s lies on the trajectory of -U through
  P, traced backward for any duration: x_e = F(w) with

      F(w) = x_P - (w^2 - W_0^2) / (2 b U)                                       (d = 0),
      F(w) = x_P - (w - W_0)/d + (b U/d^2) ln((d w + b U)/(d W_0 + b U))         (d > 0);

  each middle piece (level L, length h) maps a state affinely, v1 = e v + b U L g,
  x1 = x + g v + b U L (h - g)/d with e = exp(-d h), g = (1 - e)/d (g = h, (h - g)/d = h^2/2 for
  d = 0), so the state at t1 + tau_k lies on x_e = F(a_k v + c_k') + p_k v + q_k with constants
  found by composing these maps backward from t1 + T_s. Eliminating the move length X this way
  needs no per-shaper algebra: for d = 0 every such curve is the parabola
  x_e = -v^2/(2 b U) + beta_k v + gamma_k, the form of eqs. (13)-(16) and S3-S5.

The law in the second quadrant (x_e < 0, v >= 0; eq. 18 and 22 for the paper's shapers) reads the
nominal input off the region: on or right of the last middle curve, the decelerating level by
velocity (-1 above W_0); between middle curves k and k+1, 1 - 2c_k; left of the first middle curve,
the accelerating level by velocity (1 above V_{n-1}). The fourth quadrant is antisymmetric,
f(x_e, v) = -f(-x_e, -v) (eq. 19); the first and third quadrants get -U and +U, and the v axis
(x_e = 0) gets -U sgn(v) (eq. 17).

Sub-sample switching (beyond the paper). A sampled law switches up to one period Ts late, and the
tail after t2 switches on velocity alone, so a late switch at the top speed leaves a position
error of order v_max Ts that no later switch corrects: the loop then arrives with speed and rings.
With ``Ts`` known, the kernel predicts the rigid state over the coming sample under the present
level (the closed-form flow above); if that crosses into another region, it finds the crossing
fraction alpha by bisection and holds alpha L_now + (1 - alpha) L_next, the level that has the same
integral over the sample as the continuous law's input. Velocities then stay exact at every
sample and positions err by O(b U Ts^2) instead of O(v Ts). L_next is the STOS level past the
crossing, or 0, the shaped input's final value, if the crossing is the arrival that hands over
to the settle controller below.
Within a sample only forward moves count (a later region of the nominal order, another
quadrant, the hand-over): the -U flow runs parallel to the last middle curve (that curve is a -U
trajectory), and a state the blend has put on it must not flip back with rounding noise. For the
same reason the present state counts as past a middle curve it is within b U Ts^2 / 2 short of,
more than the b U Ts^2 / 4 a blend can fall short.

Beyond the paper (its future work): the sampled law chatters about the target because every
overshoot into the first or third quadrant is met with a full +-U. ``settle`` hands the loop to
the linear law u = -(kp x_e + kd v + ki I), I the sum of Ts x_e, once the state has arrived: it is
inside the hand-over region |x_e|/x_enter + |v|/v_enter <= 1, where the design layer chose the gains
so that the linear law does not saturate, and the shaped tail is over, x_e v >= 0 (first or third
quadrant or an axis; with sub-sample switching also |v| <= 1e-3 b U Ts, where the final blend stops
the tail). The integrator starts at 0: at that instant the STOS input is itself
stepping from its last tail level to 0, and the linear law's command, at most the PD part on the
region, continues it without re-injecting the tail level as a fictitious bias (the classic
"match the previous command" initialisation would). The loop goes back to STOS only when the
state leaves the larger region |x_e|/x_exit + |v|/v_exit <= 1 (a set-point change, a large
disturbance). The integrator is held while the linear command saturates in the direction the
error would push it (anti-windup).
"""

import math

from .checks import check_finite, check_positive

_SETTLE_KEYS = ("kp", "kd", "ki", "Ts", "x_enter", "v_enter", "x_exit", "v_exit")


def _piece(d, h):
    """(e, g, m) for one constant-input piece of length h: v1 = e v + b u g, x1 = x + g v + b u m."""
    if d == 0.0:
        return 1.0, h, 0.5 * h * h
    e = math.exp(-d * h)
    g = -math.expm1(-d * h) / d
    dh = d * h
    if dh < 1e-3:
        # (h - g)/d = h^2 (1/2 - dh/6 + dh^2/24 - dh^3/120 + ...): the direct form cancels here.
        m = h * h * (0.5 - dh / 6.0 + dh * dh / 24.0 - dh**3 / 120.0 + dh**4 / 720.0)
    else:
        m = (h - g) / d
    return e, g, m


def stos_curves(b, U, times, amplitudes, damping=0.0):
    """Switching curves of the STOS law for the rigid body x'' = -damping x' + b u, |u| <= U, and
    the impulse shaper ``times``/``amplitudes`` (module docstring; paper 002, eqs. 7-16 and S1-S7).

    ``times`` must be strictly increasing (they are shifted to start at 0: a delay does not change
    the law) and ``amplitudes`` > 0 with sum 1 (to 1e-9). Returns a dict of floats and lists:
    ``levels_accel`` c_k and ``v_accel`` V_1..V_{n-1}; ``levels_mid`` 1 - 2c_k and ``mid_curves``
    (one ``{a, c, p, q}`` per middle switch t1 + tau_k, plus ``quadratic`` [alpha, beta, gamma]
    when damping = 0); ``levels_decel`` c_k - 1 and ``v_decel`` W_0..W_{n-1}; the base point
    ``x_base``; ``min_distance``, the shortest move whose bang-bang pulses are as long as the shaper.
    """
    b = check_positive(b, "b")
    U = check_positive(U, "U")
    d = check_finite(damping, "damping")
    if d < 0.0:
        raise ValueError(f"damping must be >= 0 1/s, got {damping!r}")
    times = [check_finite(t, f"times[{i}]") for i, t in enumerate(times)]
    amplitudes = [check_finite(a, f"amplitudes[{i}]") for i, a in enumerate(amplitudes)]
    if not times or len(times) != len(amplitudes):
        raise ValueError(f"times and amplitudes must be non-empty and of equal length, got {len(times)} "
                         f"and {len(amplitudes)}")
    for i, (t0, t1) in enumerate(zip(times, times[1:])):
        if t1 <= t0:
            raise ValueError(f"times must be strictly increasing, got times[{i}] = {t0!r} >= times[{i + 1}] = {t1!r}")
    for i, a in enumerate(amplitudes):
        if a <= 0.0:
            raise ValueError(f"amplitudes[{i}] must be > 0 (STOS needs a positive shaper), got {a!r}")
    total = math.fsum(amplitudes)
    if abs(total - 1.0) > 1e-9:
        raise ValueError(f"amplitudes must sum to 1 (to 1e-9), got sum {total!r}")
    tau = [t - times[0] for t in times]
    n = len(tau)
    bU = b * U
    cumulative = [math.fsum(amplitudes[: k + 1]) for k in range(n)]
    cumulative[-1] = 1.0
    pieces = [_piece(d, tau[k + 1] - tau[k]) for k in range(n - 1)]

    # Accelerating group: forward from rest, the velocity at every tau_k (k >= 1).
    v, v_accel = 0.0, []
    for k, (e, g, _) in enumerate(pieces):
        v = e * v + bU * cumulative[k] * g
        v_accel.append(v)

    # Decelerating group: backward from the target at rest through levels c_k - 1.
    x, v = 0.0, 0.0
    v_decel = [0.0]
    for k in range(n - 2, -1, -1):
        e, g, m = pieces[k]
        level = cumulative[k] - 1.0
        v = (v - bU * level * g) / e
        x = x - g * v - bU * level * m
        v_decel.insert(0, v)
    x_base = x

    # Middle group: x_e = F(a v + c) + p v + q at t1 + tau_k, composed backward from t1 + T_s.
    a, c, p, q = 1.0, 0.0, 0.0, 0.0
    mid = [None] * n
    mid[n - 1] = (a, c, p, q)
    for k in range(n - 2, -1, -1):
        e, g, m = pieces[k]
        level = 1.0 - 2.0 * cumulative[k]
        a, c, p, q = a * e, a * bU * level * g + c, p * e - g, p * bU * level * g + q - bU * level * m
        mid[k] = (a, c, p, q)
    mid_curves = []
    for a, c, p, q in mid:
        curve = {"a": a, "c": c, "p": p, "q": q}
        if d == 0.0:
            # F(v + c) + p v + q expanded (a = 1 without damping).
            curve["quadratic"] = [-0.5 / bU, p - c / bU, x_base + (v_decel[0] ** 2 - c * c) / (2.0 * bU) + q]
        mid_curves.append(curve)

    return {
        "b": b,
        "U": U,
        "damping": d,
        "times": tau,
        "amplitudes": list(amplitudes),
        "levels_accel": cumulative[:-1],
        "v_accel": v_accel,
        "levels_mid": [1.0 - 2.0 * ck for ck in cumulative[:-1]],
        "mid_curves": mid_curves,
        "levels_decel": [ck - 1.0 for ck in cumulative[:-1]],
        "v_decel": v_decel,
        "x_base": x_base,
        "min_distance": _min_distance(b, U, d, tau[-1]),
    }


def _min_distance(b, U, d, T_s):
    """Shortest move whose rigid bang-bang pulses (+U for t1, -U until rest) both last >= T_s."""
    bU = b * U
    if d == 0.0:
        return bU * T_s * T_s
    # Back EMF brakes the move, so the -U pulse is the shorter one: make it exactly T_s.
    v_peak = bU / d * math.expm1(d * T_s)
    if v_peak >= bU / d:
        raise ValueError(f"the shaper length {T_s!r} s exceeds what the damped rigid body can use: its velocity "
                         f"limit b U/damping = {bU / d!r} is below the needed peak {v_peak!r}")
    t1 = -math.log1p(-d * v_peak / bU) / d
    t1 = max(t1, T_s)
    e, g, m = _piece(d, t1)
    v1 = bU * g
    stop = (v1 - bU / d * math.log1p(d * v1 / bU)) / d
    return bU * m + stop


def _base_curve(curves, w):
    """F(w): x_e on the -U trajectory through the start of the decelerating tail at velocity w."""
    bU = curves["b"] * curves["U"]
    d = curves["damping"]
    x_p, v_p = curves["x_base"], curves["v_decel"][0]
    if d == 0.0:
        return x_p - (w * w - v_p * v_p) / (2.0 * bU)
    ratio = d * (w - v_p) / (d * v_p + bU)
    if ratio <= -1.0:
        # Below the velocity -bU/d no -U trajectory exists: the curve lies at -infinity.
        return -math.inf
    return x_p - (w - v_p) / d + bU / (d * d) * math.log1p(ratio)


def mid_curve(curves, k, v):
    """x_e on the k-th middle switching curve (the state at t1 + tau_k) at velocity v."""
    curve = curves["mid_curves"][k]
    if "quadratic" in curve:
        alpha, beta, gamma = curve["quadratic"]
        return (alpha * v + beta) * v + gamma
    return _base_curve(curves, curve["a"] * v + curve["c"]) + curve["p"] * v + curve["q"]


def _second_quadrant(curves, x_e, v, margin):
    """(region, u / U) for x_e < 0, v >= 0 (a positive move still to go): eqs. (18) and (22)
    generalised. Regions are numbered in the order the nominal move visits them: accelerating
    pieces 0..n-2, full +U n-1, middle pieces n..2n-2, full -U 2n-1, decelerating pieces 2n..3n-2."""
    n = len(curves["mid_curves"])
    for k in range(n - 1, -1, -1):
        if x_e >= mid_curve(curves, k, v) - margin:
            if k < n - 1:
                return n + k, curves["levels_mid"][k]
            w = curves["v_decel"]
            if v > w[0]:
                return 2 * n - 1, -1.0
            for j in range(n - 1):
                if v > w[j + 1]:
                    return 2 * n + j, curves["levels_decel"][j]
            return (3 * n - 2, curves["levels_decel"][-1]) if n > 1 else (2 * n - 1, 0.0)
    for k, v_switch in enumerate(curves["v_accel"]):
        if v < v_switch:
            return k, curves["levels_accel"][k]
    return n - 1, 1.0


def locate(curves, x_e, v, margin=0.0):
    """(quadrant, region, u / U) of the STOS law of eq. (17) at x_e = x_r - target, velocity v.

    quadrant is +1 for the second quadrant (region numbered as in ``_second_quadrant``), -1 for
    the antisymmetric fourth (eq. 19), 0 for the first and third quadrants and the axes (region 1:
    -U, 2: +U, 0: the origin). A state within ``margin`` (>= 0) left of a middle curve counts as past it.
    """
    if x_e < 0.0:
        if v >= 0.0:
            return (1,) + _second_quadrant(curves, x_e, v, margin)
        return 0, 2, 1.0
    if x_e > 0.0:
        if v <= 0.0:
            region, level = _second_quadrant(curves, -x_e, -v, margin)
            return -1, region, -level  # eq. (19)
        return 0, 1, -1.0
    return (0, 1, -1.0) if v > 0.0 else ((0, 2, 1.0) if v < 0.0 else (0, 0, 0.0))


def stos_fraction(curves, x_e, v, margin=0.0):
    """The STOS law of eq. (17) as u / U in [-1, 1] at position error x_e = x_r - target, velocity v."""
    return locate(curves, x_e, v, margin)[2]


def _check_curves(curves):
    if not isinstance(curves, dict):
        raise ValueError(f"curves must be the dict returned by stos_curves, got {type(curves).__name__}")
    required = ("b", "U", "damping", "levels_accel", "v_accel", "levels_mid", "mid_curves", "levels_decel",
                "v_decel", "x_base")
    missing = [key for key in required if key not in curves]
    if missing:
        raise ValueError(f"curves is missing {missing}; build it with stos_curves")
    n = len(curves["mid_curves"])
    lengths = {len(curves["levels_accel"]), len(curves["v_accel"]), len(curves["levels_mid"]),
               len(curves["levels_decel"]), len(curves["v_decel"]) - 1}
    if n < 1 or lengths != {n - 1}:
        raise ValueError(f"curves has inconsistent lengths for {n} middle curves; build it with stos_curves")
    check_positive(curves["b"], "curves['b']")
    check_positive(curves["U"], "curves['U']")
    if check_finite(curves["damping"], "curves['damping']") < 0.0:
        raise ValueError(f"curves['damping'] must be >= 0, got {curves['damping']!r}")


def _check_settle(settle):
    if not isinstance(settle, dict):
        raise ValueError(f"settle must be a dict with keys {list(_SETTLE_KEYS)} or None, got {type(settle).__name__}")
    missing = [key for key in _SETTLE_KEYS if key not in settle]
    if missing:
        raise ValueError(f"settle is missing {missing}")
    checked = {key: check_finite(settle[key], f"settle['{key}']") for key in _SETTLE_KEYS}
    for key in ("kp", "kd", "Ts", "x_enter", "v_enter"):
        check_positive(checked[key], f"settle['{key}']")
    if checked["ki"] < 0.0:
        raise ValueError(f"settle['ki'] must be >= 0, got {settle['ki']!r}")
    for key in ("x", "v"):
        if checked[f"{key}_exit"] < checked[f"{key}_enter"]:
            raise ValueError(f"settle['{key}_exit'] must be >= settle['{key}_enter'] = {checked[f'{key}_enter']!r}, "
                             f"got {settle[f'{key}_exit']!r}")
    return checked


class STOSKernel:
    """The sampled STOS law with the optional settle hand-over and sub-sample switching (module
    docstring). ``Ts`` defaults to ``settle["Ts"]``; ``Ts=None`` without settle gives the plain law.

    State: ``[settling, integral]``: 1.0 while the linear settle law is in charge (else 0.0), and
    its integrator I (the sum of Ts x_e since the hand-over).
    """

    def __init__(self, curves, settle=None, Ts=None):
        _check_curves(curves)
        self.curves = curves
        self.settle = None if settle is None else _check_settle(settle)
        if Ts is None and self.settle is not None:
            Ts = self.settle["Ts"]
        self.Ts = None if Ts is None else check_positive(Ts, "Ts")
        self.U = float(curves["U"])
        self._bU = curves["b"] * self.U
        self._d = float(curves["damping"])
        self.reset()

    def reset(self):
        self._settling = False
        self._integral = 0.0

    def get_state(self):
        return [1.0 if self._settling else 0.0, self._integral]

    def set_state(self, state):
        if len(state) != 2:
            raise ValueError(f"state must be [settling, integral] (2 numbers), got {len(state)}")
        settling = check_finite(state[0], "state[0] (settling)")
        if settling not in (0.0, 1.0):
            raise ValueError(f"state[0] (settling) must be 0 or 1, got {state[0]!r}")
        self._settling = settling == 1.0
        self._integral = check_finite(state[1], "state[1] (integral)")

    def control(self, target, x_r, x_r_dot):
        """One sample: the input u in [-U, U] for the measured rigid-body position and velocity."""
        x_e = check_finite(x_r, "x_r") - check_finite(target, "target")
        v = check_finite(x_r_dot, "x_r_dot")
        s = self.settle
        if s is not None:
            if self._settling:
                if abs(x_e) / s["x_exit"] + abs(v) / s["v_exit"] > 1.0:
                    self._settling = False
                    self._integral = 0.0
            elif self._arrived(x_e, v, slack=2.0):
                self._settling = True
                self._integral = 0.0
            if self._settling:
                return self._settle_step(x_e, v)
        if self.Ts is None:
            return self.U * stos_fraction(self.curves, x_e, v)
        return self.U * self._subsample(x_e, v)

    def _arrived(self, x_e, v, slack=1.0):
        """Hand-over condition: inside the entry region and past the shaped tail: x_e v >= 0, or,
        with sub-sample switching, at rest to within 1e-3 ``slack`` of the speed one sample of U
        gives (the final blend stops the tail there, still in the second or fourth quadrant). The
        present state is tested with slack 2 and predictions with 1, so that a blend aimed at the
        threshold, which lands a little short of it, still hands over."""
        s = self.settle
        if s is None or abs(x_e) / s["x_enter"] + abs(v) / s["v_enter"] > 1.0:
            return False
        return x_e * v >= 0.0 or (self.Ts is not None and abs(v) <= 1e-3 * slack * self._bU * self.Ts)

    def _flow(self, x_e, v, level, h):
        """Rigid-body state after h seconds at input level * U (exact, the pieces of the docstring)."""
        e, g, m = _piece(self._d, h)
        return x_e + g * v + self._bU * level * m, e * v + self._bU * level * g

    def _moved_on(self, present, x_e, v):
        """Whether the predicted state (x_e, v) lies in a region after ``present``: the hand-over,
        another quadrant, or a later region of the same quadrant (never back across a curve just
        passed, which under the -U flow is parallel to the last middle curve)."""
        if self._arrived(x_e, v):
            return True
        quadrant, region, _ = locate(self.curves, x_e, v)
        return quadrant != present[0] or (region > present[1] if quadrant else region != present[1])

    def _subsample(self, x_e, v):
        """The held level whose integral over the coming sample matches the switched law's input."""
        Ts = self.Ts
        # A blend lands at most b U Ts^2 / 4 short of the curve it crossed: count that as past it.
        present = locate(self.curves, x_e, v, 0.5 * self._bU * Ts * Ts)
        level = present[2]
        if not self._moved_on(present, *self._flow(x_e, v, level, Ts)):
            return level
        low, high = 0.0, 1.0
        for _ in range(40):
            alpha = 0.5 * (low + high)
            if self._moved_on(present, *self._flow(x_e, v, level, alpha * Ts)):
                high = alpha
            else:
                low = alpha
        x_next, v_next = self._flow(x_e, v, level, high * Ts)
        # Arriving, the shaped input ends at 0: blending with 0 stops the tail at rest (v exact).
        following = 0.0 if self._arrived(x_next, v_next) else locate(self.curves, x_next, v_next)[2]
        return high * level + (1.0 - high) * following

    def _settle_step(self, x_e, v):
        s = self.settle
        u = -(s["kp"] * x_e + s["kd"] * v + s["ki"] * self._integral)
        # Anti-windup: integrate unless the command is saturated and the error would deepen it.
        if not ((u > self.U and x_e < 0.0) or (u < -self.U and x_e > 0.0)):
            self._integral += s["Ts"] * x_e
        return max(-self.U, min(self.U, u))
