"""The plant FMU every candidate of ``shapefmu compare`` meets: the plant with its rigid-body velocity
measured (which a STOS controller reads)."""

from __future__ import annotations

import dataclasses
import math


def measured_plant(plant):
    """A plant of paper 002's eq. (1) form as a native plant model whose outputs are ``position``,
    ``velocity`` (the rigid-body x_r', which a STOS controller measures) and ``deflection_i``.

    The plant's own model file exposes no velocity, and a ``Plant`` with an extra row in C becomes
    the plant generator's generic state-space kind, whose tunable D makes every output depend on the input
    (an algebraic loop with a feed-through controller). This model is written symbolically in the
    physical parameters instead (``b2``, ``rigid_damping``, ``f[i]`` in Hz, ``zeta[i]``, ``b4[i]``,
    the names the model files give), so its outputs depend on the states only; it is linear, and
    the generated plant steps it by the exact zero-order hold.
    """
    import casadi as ca

    from shapefmu.fmi.native import Output, Variable
    from shapefmu.plants import as_plant
    from shapefmu.stos import rigid_body

    plant = as_plant(plant)
    b, damping = rigid_body(plant)
    x_r, v_r, voltage = ca.SX.sym("x_r"), ca.SX.sym("v_r"), ca.SX.sym(plant.inputs[0])
    b2, d = ca.SX.sym("b2"), ca.SX.sym("rigid_damping")
    states = [Variable("x_r", x_r), Variable("v_r", v_r)]
    derivatives = [v_r, -d * v_r + b2 * voltage]
    parameters = [Variable("b2", b2, b, "1/(V*s^2)", "nonzero", "rigid-body input gain"),
                  Variable("rigid_damping", d, damping, "1/s", "nonnegative", "rigid-body velocity damping")]
    outputs = [Output("position", x_r), Output("velocity", v_r)]
    for i, k in enumerate(range(2, plant.n_states, 2), start=1):
        omega = math.sqrt(-plant.A[k + 1, k])
        x, v = ca.SX.sym(f"x_f{i}"), ca.SX.sym(f"v_f{i}")
        f, zeta, b4 = ca.SX.sym(f"f[{i}]"), ca.SX.sym(f"zeta[{i}]"), ca.SX.sym(f"b4[{i}]")
        w = 2.0 * math.pi * f
        states += [Variable(f"x_f{i}", x), Variable(f"v_f{i}", v)]
        derivatives += [v, -w * w * x - 2.0 * zeta * w * v + b4 * voltage]
        parameters += [Variable(f"f[{i}]", f, omega / (2.0 * math.pi), "Hz", "positive", f"frequency of mode {i}"),
                       Variable(f"zeta[{i}]", zeta, -plant.A[k + 1, k + 1] / (2.0 * omega), "1", "damping_ratio",
                                f"damping ratio of mode {i}"),
                       Variable(f"b4[{i}]", b4, float(plant.B[k + 1, 0]), "1/(V*s^2)", "any", f"modal gain of mode {i}")]
        outputs.append(Output(f"deflection_{i}", x))
    return _linear_symbolic_plant(name=f"{plant.name}_measured", description=f"{plant.name} with its rigid-body velocity measured",
                                  states=tuple(states), derivatives=tuple(derivatives),
                                  inputs=(Variable(plant.inputs[0], voltage),), parameters=tuple(parameters),
                                  outputs=tuple(outputs))


def _linear_symbolic_plant(**fields):
    """A plant-generator ``NonlinearPlant`` whose equations are linear in x and u, built with the exact
    zero-order-hold step (and no RK4 substep parameter) like the linear model files."""
    from shapefmu.fmi.native import NonlinearPlant

    class LinearSymbolicPlant(NonlinearPlant):
        def model_part(self):
            part = super().model_part()
            return dataclasses.replace(part, linear=True, substep_parameter=None,
                                       parameters=tuple(p for p in part.parameters if p.name != "substep"))

    return LinearSymbolicPlant(**fields)
