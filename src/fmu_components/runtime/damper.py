"""The Warrior rotary suspension damper (thesis chapters 9-14, Appendices 5 and 6; spec
section 3).

A nonlinear dashpot and an isothermal gas spring in series (Fig. 12.5-1), with the rotor
inertia at the node between them (section 12.6). For arm angle theta and rate omega,
rotor-node angle theta_r and rate omega_r:

    xd = theta - theta_r                                  gas-spring deflection, |xd| < C2
    Tg = C1 * (1/(1 - xd/C2) - 1/(1 + xd/C2))             entrapped gas (Eq. A5-16)
    I * d(omega_r)/dt = Tg - Td(omega_r)                  rotor node
    output torque = Tg

Td is the smoothed torque-velocity curve of Table A6-1 (laminar, turbulent and blow-off
regions), interpolated monotone and C1 (hermite.py).

The gas spring is integrated in z, with xd = C2 tanh(z). Then Eq. A5-16 reads
Tg = C1 sinh(2z): the pole at |xd| = C2 becomes an exponential, an error in z is a relative
error in torque, and |xd| < C2 holds by construction. In xd itself, a fixed absolute
tolerance lets a hard-driven solution creep onto the pole, where no step size is small
enough. Within a step the arm rate is held, so (z, omega_r) obey an autonomous system:

    dz/dt = (omega - omega_r) cosh(z)^2 / C2
    d(omega_r)/dt = (C1 sinh(2z) - Td(omega_r)) / I

with cosh(z)^2 and sinh(2z) taken from one exponential (_hyperbolic).

The integrator keeps |z| < Z_LIMIT (where tanh still differs from 1 in double precision)
by rejecting and shrinking steps.

State layout: [z, omega_r, theta_z], z being the gas-spring coordinate for the arm angle
theta_z; a host that moves the arm discontinuously shifts z accordingly. The equations are
expression trees over the parameters as symbols (expressions.py).
"""

from .expressions import (Assign, Element, Format, Lookup, Message, Symbol, atanh, copysign,
                          differs, equal, exp, shortcut, tanh, where)
from .model import ContinuousTime, Equations, InputLimit, Table

Z_LIMIT = 18.0  # tanh(18) = 1 - 4.6e-16: beyond it xd is C2 to the last bit
DASHPOT = "dashpot"


def _gas_deflection(C2, state, x):
    """xd at arm angle x: the state's own, plus whatever the arm moved away from theta_z."""
    return C2 * tanh(state[0]) + (x - state[2])


def _z_at(C2, state, x):
    """z for arm angle x: the state's own unless the arm has moved away from theta_z, as a
    host's angle and rate from its own integrator always do by round-off, or by a jump:
    then the gas spring takes up the difference."""
    return shortcut(equal(x, state[2]), state[0], atanh(_gas_deflection(C2, state, x) / C2))


def _hyperbolic(z, prefix):
    """cosh(z)^2, sinh(2z) and cosh(2z) from one exponential, e = exp(-2|z|) in (0, 1]:
    cosh^2 = (1 + e)^2 / 4e, sinh 2z = sgn(z) (1 - e)(1 + e) / 2e, cosh 2z = (1 + e^2) / 2e.
    One call instead of three (cosh, sinh and cosh again), and no overflow for |z| <
    Z_LIMIT. Near z = 0 the absolute error of sinh 2z is about the double precision, far
    below a torque that matters."""
    e = Symbol(f"{prefix}e")
    lines = [Assign(e, exp(-2.0 * abs(z))),
             Assign(Symbol(f"{prefix}cosh_squared"), (1.0 + e) * (1.0 + e) / (4.0 * e)),
             Assign(Symbol(f"{prefix}sinh_2z"), copysign((1.0 - e) * (1.0 + e) / (2.0 * e), z))]
    return lines, e


def damper_equations(C1, C2, I, rates, torques):
    """rates, torques: the parameter names of the Table A6-1 points."""
    C1, C2, I = Symbol(C1), Symbol(C2), Symbol(I)
    Y0, Y1, u, h, x, v = (Symbol(n) for n in ("Y0", "Y1", "u", "h", "x", "v"))
    state = [Element("state", i) for i in range(3)]
    stage_lines, e = _hyperbolic(Y0, "")
    cosh_squared, sinh_2z = Symbol("cosh_squared"), Symbol("sinh_2z")
    deflection = Symbol("deflection")
    return Equations(
        integrated=2, state_size=3,
        stage=stage_lines + [
            Assign(Symbol("f0"), (u - Y1) * cosh_squared / C2),
            # Eq. A5-16 with xd = C2 tanh(z): Tg = C1 sinh(2z)
            Assign(Symbol("f1"), (C1 * sinh_2z - Lookup(DASHPOT, Y1)) / I)],
        jacobian=[Assign(Symbol("j0_0"), (u - Y1) * sinh_2z / C2),
                  Assign(Symbol("j0_1"), -cosh_squared / C2),
                  Assign(Symbol("j1_0"), C1 * (1.0 + e * e) / (e * I)),  # 2 C1 cosh(2z) / I
                  Assign(Symbol("j1_1"), -Lookup(DASHPOT, Y1, slope=True) / I)],
        region=abs(Y0) < Z_LIMIT,
        start=[Assign(Symbol("y0"), _z_at(C2, state, x)), Assign(Symbol("y1"), state[1])],
        exact=[Assign(state[2], x + u * h)],
        # The rotor node moving with the arm: zero gas deflection, tau(0) = 0 (spec 3).
        initial_state=[0.0, v, x],
        output_lines=_output_lines(C2, _z_at(C2, state, x)),
        outputs=_outputs(C1, C2, state),
        # A new arm angle moves the gas spring by the difference (it must stay inside C2),
        # and is folded into z at once, so that the step and the outputs find z ready
        # rather than each computing it again. The deflection is left at zero when the arm
        # has not moved: then it is inside C2 by construction and nothing is folded in.
        input_limit=InputLimit(
            [Assign(deflection, where(differs(x, state[2]), _gas_deflection(C2, state, x), 0.0))],
            abs(deflection) < C2,
            Message("angle ", Format(x, ".9g"), " rad puts the gas-spring deflection at ",
                    Format(deflection), " rad, outside its limit |xd| < C2 = ", Format(C2),
                    " rad"),
            accept=[Assign(state[0], where(differs(x, state[2]), atanh(deflection / C2),
                                           state[0])),
                    Assign(state[2], x)]),
        # Almost always an arm rate that jumped far from the rotor's: the gas spring can
        # only stop that with a torque spike beyond any step size (e.g. 0 -> 100 rad/s in
        # one step gives ~1e14 N.m in the model).
        failure_hint=Message("the arm rate ", Format(v), " rad/s met the rotor at ",
                             Format(state[1]), " rad/s, a jump the gas spring cannot absorb "
                             "within the step: ramp the rate over several steps"),
        # z is dimensionless, and the rotor rate is taken on the scale of 1 rad/s (the
        # thesis rig's range, section 11.0).
        state_scale=[1.0, 1.0],
        tables=[Table(DASHPOT, rates, torques, abscissa=("rate", "rad/s"),
                      ordinate=("torque", "N.m"), dissipative=True)],
        # For a host's integrator (spec section 7) the states are z and omega_r, z driven by
        # the arm rate: |xd| < C2 holds by construction at any trial state a stiff
        # integrator may try, and the arm angle only sets the initial state (the torque
        # then depends on the angle through the states, not directly). Nominals: z is
        # dimensionless, the rotor rate 1 rad/s.
        continuous=ContinuousTime(2, [1.0, 1.0], output_lines=_output_lines(C2, state[0]),
                                  outputs=_outputs(C1, C2, state)))


def _output_lines(C2, z):
    return [Assign(Symbol("z"), z)] + _hyperbolic(Symbol("z"), "z_")[0]


def _outputs(C1, C2, state):
    """(torque, gas-spring deflection, rotor-node rate, dashpot torque, tangent stiffness
    d torque/d theta) at z. The rotor inertia keeps theta_r from responding instantly, so
    the instantaneous tangent is the gas-spring stiffness, d/dxd of C1 sinh(2z) with dz/dxd
    = cosh(z)^2 / C2."""
    z, e = Symbol("z"), Symbol("z_e")
    return [C1 * Symbol("z_sinh_2z"), copysign(C2 * (1.0 - e) / (1.0 + e), z), state[1],
            Lookup(DASHPOT, state[1]), C1 * (1.0 + e * e) / e * Symbol("z_cosh_squared") / C2]
