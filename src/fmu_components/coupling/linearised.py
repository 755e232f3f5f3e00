"""A component's answer to a host step, linearised with its Model Exchange Jacobian.

For a component whose `stiffness` output is the instantaneous tangent but whose internal
dynamics act within a host step (the damper: its rotor follows the arm in a fraction of
a millisecond, so over a 1-4 ms step the torque answers the arm's motion far more softly
than the gas spring's stiffness says), the coupling asks the FMU itself. A Model Exchange
instance of the same FMU, set to the co-simulation instance's states (the `state.*`
variables both interfaces expose), gives by getDirectionalDerivative the Jacobians

    A = df/dX, B = df/d(x, v), C = dF/dX, D = dF/d(x, v)

at that point, f the state derivatives and F the load. Along the secant path a step
feeds, x(s) = x0 + v s (s in [0, h]), the linearised states obey

    dY/ds = A Y + B_x v s + B_v (v - v0) + f0,

so one matrix exponential of an augmented system gives the load after the step at the
rate v0 (its prediction), and its derivative by the end deflection, dF(h)/dx(h) (the
step's tangent, in which the rotor's inertia and the dashpot's slope appear). Nothing
here steps the FMU: no fmi2DoStep, no state of the co-simulation instance touched.
"""

import numpy as np

from .instance import MODEL_EXCHANGE, FmuInstance


def expm(matrix):
    """e^M of a small matrix: diagonal Pade (6, 6) after scaling to a norm of 1/2, then
    squaring (Higham, Functions of Matrices, ch. 10)."""
    norm = np.linalg.norm(matrix, 1)
    squarings = max(0, int(np.ceil(np.log2(norm / 0.5)))) if norm > 0.5 else 0
    scaled = matrix / 2.0 ** squarings
    coefficients = (1.0, 1 / 2, 5 / 44, 1 / 66, 1 / 792, 1 / 15840, 1 / 665280)
    identity = np.eye(len(matrix))
    power, even, odd = identity, coefficients[0] * identity, np.zeros_like(matrix)
    for k in range(1, 7):
        power = power @ scaled
        if k % 2:
            odd = odd + coefficients[k] * power
        else:
            even = even + coefficients[k] * power
    result = np.linalg.solve(even - odd, even + odd)
    for _ in range(squarings):
        result = result @ result
    return result


class Linearisation:
    """A Model Exchange side instance of a component's FMU (an FmuFile, instance.py), set
    to the co-simulation instance's states to linearise its response to a step."""

    def __init__(self, fmu, instance_name, parameters=None):
        if not fmu.model_exchange or not fmu.states:
            raise ValueError(f"{fmu.name} offers no Model Exchange with states: no "
                             f"linearised step response")
        self.name = instance_name
        self.state_names = fmu.states
        self.n = n = len(self.state_names)
        self._contact_events = fmu.event_indicators > 0
        # Its messages repeat what the co-simulation instance says of the same inputs.
        self._instance = instance = FmuInstance(fmu, instance_name, MODEL_EXCHANGE)
        instance.setup(parameters)
        instance.exit_initialization()
        self._contact = None
        self._inputs = instance.reals(fmu.inputs)
        self._load = instance.reals(fmu.outputs[:1])
        # One directional derivative per known (each state, then deflection and rate), of
        # every unknown (the derivatives, then the load and the stiffness).
        self._jacobian = instance.jacobian(fmu.derivatives + [fmu.outputs[0], "stiffness"],
                                           self.state_names + fmu.inputs)
        self._knowns = range(n + 2)

    def _at(self, states, deflection, rate):
        """Set the side instance to (states, deflection, rate); the Jacobians there."""
        fmu, n = self._instance, self.n
        fmu.set(self._inputs, [deflection, rate])
        contact = deflection > 0.0
        if self._contact_events and contact != self._contact:
            # the contact's mode switches in event mode only (docs/model-exchange.md)
            fmu.event()
            self._contact = contact
        fmu.set_states(states)
        jacobian = np.empty((n + 2, n + 2))
        for j in self._knowns:
            jacobian[:, j] = fmu.directional_derivative(self._jacobian, j)
        return jacobian, np.array(fmu.derivatives()), fmu.get(self._load)[0]

    def step(self, states, deflection, rate, step):
        """(load after the step at the held `rate`, d load / d end deflection,
        d stiffness / d end deflection): the linearised answer of the component at
        (states, deflection) to a step of length `step` along x0 + v s, and the
        sensitivities of its load and its `stiffness` output to the end point (the
        latter through the states too: the curvature the step really has)."""
        n = self.n
        jacobian, derivatives, load = self._at(states, deflection, rate)
        a, b_x, b_v = jacobian[:n, :n], jacobian[:n, n], jacobian[:n, n + 1]
        c, d_x, d_v = jacobian[n, :n], jacobian[n, n], jacobian[n, n + 1]
        c_k, dk_x, dk_v = jacobian[n + 1, :n], jacobian[n + 1, n], jacobian[n + 1, n + 1]
        # Augmented state [Y, P, s, 1]: Y the drift at rate v0, P = dY/dv.
        m = np.zeros((2 * n + 2, 2 * n + 2))
        m[:n, :n] = a
        m[:n, 2 * n] = b_x * rate
        m[:n, 2 * n + 1] = derivatives
        m[n:2 * n, n:2 * n] = a
        m[n:2 * n, 2 * n] = b_x
        m[n:2 * n, 2 * n + 1] = b_v
        m[2 * n, 2 * n + 1] = 1.0
        end = expm(m * step)[:, 2 * n + 1]
        predicted = load + c @ end[:n] + d_x * rate * step
        by_rate = c @ end[n:2 * n] + d_x * step + d_v
        stiffness_by_rate = c_k @ end[n:2 * n] + dk_x * step + dk_v
        return predicted, by_rate / step, stiffness_by_rate / step

    def free(self):
        self._instance.close()
