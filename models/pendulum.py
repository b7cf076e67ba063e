"""Pendulum on a cart at large angles: the nonlinear plant of the plant-FMU generator.

Cart acceleration a in; the pendulum of length L hangs from the cart, its angle theta measured from
hanging rest. With a viscous damping rate c of the swing, the equation of motion in the cart's frame is

    L theta'' = -g sin(theta) - a cos(theta) - c L theta'

whose linearisation about theta = 0 is the pendula kind of models/ten_pendula.toml
(L theta'' + 2 zeta omega L theta' + g theta = -a, paper 003, Sec. V) with c = 2 zeta omega.
Outputs: cart position, swing angle, and the horizontal position of the bob x + L sin(theta).
`shapefmu build` turns ``plant()`` into fmus/Pendulum.fmu.
"""

import casadi as ca

from shapefmu.fmi.native import NonlinearPlant, Output, Variable


def plant() -> NonlinearPlant:
    x, v, theta, omega = (ca.SX.sym(name) for name in ("x", "v", "theta", "omega"))
    a = ca.SX.sym("acceleration")
    L, g, c = ca.SX.sym("L"), ca.SX.sym("g"), ca.SX.sym("c")
    return NonlinearPlant(
        name="pendulum",
        description="pendulum on a cart, nonlinear (large angles)",
        states=(
            Variable("x", x, unit="m", description="cart position"),
            Variable("v", v, unit="m/s", description="cart velocity"),
            Variable("theta", theta, unit="rad", description="swing angle from hanging rest"),
            Variable("omega", omega, unit="rad/s", description="swing rate"),
        ),
        derivatives=(v, a, omega, -(g * ca.sin(theta) + a * ca.cos(theta)) / L - c * omega),
        inputs=(Variable("acceleration", a, unit="m/s^2", description="acceleration of the cart, the command"),),
        parameters=(
            Variable("L", L, 0.762, "m", "positive", "pendulum length (30 in, paper 003)"),
            Variable("g", g, 9.80665, "m/s^2", "positive", "gravity"),
            Variable("c", c, 0.0, "1/s", "nonnegative", "viscous damping rate of the swing"),
        ),
        outputs=(
            Output("cart_position", x, "m", "position of the cart"),
            Output("theta", theta, "rad", "swing angle from hanging rest"),
            Output("bob_position", x + L * ca.sin(theta), "m", "horizontal position of the bob, x + L sin(theta)"),
        ),
        substep=1e-3,
    )
