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
regions), interpolated monotone and C1. Within a step the arm rate is held, so the
integrated state (xd, omega_r) obeys an autonomous system; the gas spring bounds it to
|xd| < C2, which the integrator respects by rejecting steps, never by clipping.
"""

from .hermite import MonotoneCubic


class RotaryDamper:
    """State layout: [theta_r, omega_r]."""

    state_size = 2
    integrated_size = 2

    def __init__(self, gas_force, gas_limit, rotor_inertia, table_rates, table_torques):
        self.gas_force = gas_force  # C1
        self.gas_limit = gas_limit  # C2
        self.rotor_inertia = rotor_inertia  # I
        self.dashpot = MonotoneCubic(table_rates, table_torques)
        # Typical magnitudes for the absolute tolerance: the deflection range C2 and a
        # rate of 1 rad/s (the thesis rig's range, section 11.0).
        self.state_scale = [gas_limit, 1.0]

    def initial_state(self, theta, omega):
        """Rotor node moving with the arm: zero gas deflection, tau(0) = 0 (spec 3)."""
        return [theta, omega]

    def check_input(self, state, theta):
        deflection = theta - state[0]
        if abs(deflection) >= self.gas_limit:
            return (f"angle {theta:.9g} rad puts the gas-spring deflection at {deflection:.6g} rad, "
                    f"outside its limit |xd| < C2 = {self.gas_limit:.6g} rad")
        return None

    def gas_torque(self, deflection):
        q = deflection / self.gas_limit
        return self.gas_force * (1.0 / (1.0 - q) - 1.0 / (1.0 + q))

    def gas_stiffness(self, deflection):
        q = deflection / self.gas_limit
        return self.gas_force / self.gas_limit * (1.0 / (1.0 - q) ** 2 + 1.0 / (1.0 + q) ** 2)

    # --- integrator system over y = [xd, omega_r], input u = arm rate ------------------

    def inside(self, y):
        return abs(y[0]) < self.gas_limit

    def rhs(self, y, omega):
        deflection, rotor_rate = y
        dashpot_torque = self.dashpot.value_and_slope(rotor_rate)[0]
        return [omega - rotor_rate,
                (self.gas_torque(deflection) - dashpot_torque) / self.rotor_inertia]

    def jacobian(self, y, omega):
        deflection, rotor_rate = y
        dashpot_slope = self.dashpot.value_and_slope(rotor_rate)[1]
        inertia = self.rotor_inertia
        return [[0.0, -1.0],
                [self.gas_stiffness(deflection) / inertia, -dashpot_slope / inertia]]

    def advance(self, state, theta, omega, h, integrator):
        y = [theta - state[0], state[1]]
        problem = integrator.integrate(self, y, omega, h)
        if problem:
            return problem
        state[0] = (theta + omega * h) - y[0]
        state[1] = y[1]
        return None

    def outputs(self, state, theta, omega):
        """(torque, gas-spring deflection, rotor-node rate, dashpot torque, tangent
        stiffness d torque/d theta). The rotor inertia keeps theta_r from responding
        instantly, so the instantaneous tangent is the gas-spring stiffness."""
        deflection = theta - state[0]
        rotor_rate = state[1]
        return (self.gas_torque(deflection), deflection, rotor_rate,
                self.dashpot(rotor_rate), self.gas_stiffness(deflection))
