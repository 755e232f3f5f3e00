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
regions), interpolated monotone and C1.

The gas spring is integrated in z, with xd = C2 tanh(z). Then Eq. A5-16 reads
Tg = C1 sinh(2z): the pole at |xd| = C2 becomes an exponential, an error in z is a relative
error in torque, and |xd| < C2 holds by construction. In xd itself, a fixed absolute
tolerance lets a hard-driven solution creep onto the pole, where no step size is small
enough. Within a step the arm rate is held, so (z, omega_r) obey an autonomous system:

    dz/dt = (omega - omega_r) cosh(z)^2 / C2
    d(omega_r)/dt = (C1 sinh(2z) - Td(omega_r)) / I

The integrator keeps |z| < Z_LIMIT (where tanh still differs from 1 in double precision)
by rejecting and shrinking steps.
"""

import math

from .hermite import MonotoneCubic
from .integrator import RhsSource, compile_jacobian, compile_start

Z_LIMIT = 18.0  # tanh(18) = 1 - 4.6e-16: beyond it xd is C2 to the last bit


class RotaryDamper:
    """State layout: [z, omega_r, theta_z], z being the gas-spring coordinate for the arm
    angle theta_z; a host that moves the arm discontinuously shifts z accordingly."""

    state_size = 3
    integrated_size = 2

    def __init__(self, gas_force, gas_limit, rotor_inertia, table_rates, table_torques):
        self.gas_force = gas_force  # C1
        self.gas_limit = gas_limit  # C2
        self.rotor_inertia = rotor_inertia  # I
        self.dashpot = MonotoneCubic(table_rates, table_torques)
        # Typical magnitudes for the absolute tolerance: z is dimensionless, and the rotor
        # rate is taken on the scale of 1 rad/s (the thesis rig's range, section 11.0).
        self.state_scale = [1.0, 1.0]
        source = self.rhs_source()
        self._start = compile_start(source, self.integrated_size)
        self.jacobian = compile_jacobian(source, self.integrated_size)

    def initial_state(self, theta, omega):
        """Rotor node moving with the arm: zero gas deflection, tau(0) = 0 (spec 3)."""
        return [0.0, omega, theta]

    def _unchecked_deflection(self, state, theta):
        return self.gas_limit * math.tanh(state[0]) + (theta - state[2])

    def check_input(self, state, theta):
        deflection = self._unchecked_deflection(state, theta)
        if abs(deflection) >= self.gas_limit:
            return (f"angle {theta:.9g} rad puts the gas-spring deflection at {deflection:.6g} "
                    f"rad, outside its limit |xd| < C2 = {self.gas_limit:.6g} rad")
        return None

    def _z_at(self, state, theta):
        """z for arm angle theta: the state's own z unless the arm has moved away from
        theta_z (see rhs_source)."""
        return self._start(state, theta)[0]

    def torque(self, z):
        return self.gas_force * math.sinh(2.0 * z)  # Eq. A5-16 with xd = C2 tanh(z)

    # --- integrator system over y = [z, omega_r], input u = arm rate --------------------

    def inside(self, y):
        return abs(y[0]) < Z_LIMIT

    def rhs_source(self):
        """dz/dt and d(omega_r)/dt (module docstring) for the integrator to compile: state
        Y = [z, omega_r], held arm rate u."""
        return RhsSource(
            stage=["cosh_z = cosh(Y0)",
                   f"f0 = (u - Y1) * cosh_z * cosh_z / {self.gas_limit!r}",
                   f"f1 = ({self.gas_force!r} * sinh(2.0 * Y0) - dashpot(Y1)) / {self.rotor_inertia!r}"],
            region=f"abs(Y0) < {Z_LIMIT!r}",  # inside()
            jacobian=[f"j0_0 = (u - Y1) * sinh(2.0 * Y0) / {self.gas_limit!r}",
                      f"j0_1 = -cosh_z * cosh_z / {self.gas_limit!r}",
                      f"j1_0 = 2.0 * {self.gas_force!r} * cosh(2.0 * Y0) / {self.rotor_inertia!r}",
                      f"j1_1 = -dashpot_slope(Y1) / {self.rotor_inertia!r}"],
            namespace={"cosh": math.cosh, "sinh": math.sinh, "dashpot": self.dashpot.value,
                       "dashpot_slope": self.dashpot.slope, "tanh": math.tanh,
                       "atanh": math.atanh},
            # z at the arm angle x: the state's own unless the arm has moved away from
            # theta_z, as a host's angle and rate from its own integrator always do by
            # round-off, or by a jump: then the gas spring takes up the difference,
            # xd = C2 tanh(z) + (x - theta_z).
            start=["y0 = state[0] if x == state[2] else atanh("
                   f"({self.gas_limit!r} * tanh(state[0]) + (x - state[2])) / {self.gas_limit!r})",
                   "y1 = state[1]"],
            exact=["state[2] = x + u * h"])

    def advance(self, state, theta, omega, h, integrator):
        y = [self._z_at(state, theta), state[1]]
        problem = integrator.integrate(self, y, omega, h)
        if problem:
            # Almost always an arm rate that jumped far from the rotor's: the gas spring can
            # only stop that with a torque spike beyond any step size (e.g. 0 -> 100 rad/s
            # in one step gives ~1e14 N.m in the model).
            return (f"{problem}; the arm rate {omega:.6g} rad/s met the rotor at "
                    f"{state[1]:.6g} rad/s, a jump the gas spring cannot absorb within the "
                    f"step: ramp the rate over several steps")
        state[0], state[1], state[2] = y[0], y[1], theta + omega * h
        return None

    def outputs(self, state, theta, omega):
        """(torque, gas-spring deflection, rotor-node rate, dashpot torque, tangent
        stiffness d torque/d theta). The rotor inertia keeps theta_r from responding
        instantly, so the instantaneous tangent is the gas-spring stiffness."""
        z = self._z_at(state, theta)
        cosh_z = math.cosh(z)
        stiffness = 2.0 * self.gas_force * math.cosh(2.0 * z) * cosh_z * cosh_z / self.gas_limit
        rotor_rate = state[1]
        return (self.torque(z), self.gas_limit * math.tanh(z), rotor_rate,
                self.dashpot.value(rotor_rate), stiffness)
