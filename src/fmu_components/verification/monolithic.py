"""Monolithic solves of a coupled system: the bodies' equations of motion and the
components' Model Exchange FMUs in one ODE, integrated by scipy's Radau at tight
tolerance, the independent reference for a co-simulation of the same system.

The FMUs' inputs are set at every evaluation of the right-hand side (continuous inputs,
as Model Exchange means them; docs/model-exchange.md). A contact's event indicator stops
the integration where it crosses zero; the FMU's mode is switched in event mode
(its discrete states updated) and the integration restarts from there. The FMUs may be
FMI 2.0 or 3.0 (coupling/instance.py drives both).
"""

import math

import numpy as np
from scipy.integrate import solve_ivp

from ..coupling.errors import CouplingError
from ..coupling.instance import DISCARD, MODEL_EXCHANGE, FmuInstance


class ModelExchangeComponent:
    """One ME instance of a component FMU: states, derivatives and load at (t, states,
    deflection, rate)."""

    def __init__(self, path, instance_name, parameters=None):
        self.name = instance_name
        # The solver's trial states are no one's business but its own: the FMU's messages
        # about them (an input out of the measured range) are kept, not printed.
        self._fmu = fmu = FmuInstance(path, instance_name, MODEL_EXCHANGE)
        self.output_names = fmu.fmu.outputs
        self._inputs = fmu.reals(fmu.fmu.inputs)
        self._outputs = fmu.reals(self.output_names)
        self.n = len(fmu.fmu.states)
        self.events = fmu.fmu.event_indicators
        fmu.setup(parameters)
        self.nominals = None

    @property
    def messages(self):
        """The newest messages the FMU logged."""
        return self._fmu.messages

    def start(self, deflection, rate):
        """Leave initialization relaxed at the initial input; the initial states."""
        self._fmu.set(self._inputs, [deflection, rate])
        self._fmu.exit_initialization()  # through event mode: the contact's mode
        self.nominals = np.array(self._fmu.nominals())
        return np.array(self._fmu.states())

    def update_mode(self):
        """Event mode: let the FMU switch its discrete mode (the contact) at the current
        inputs, then back to continuous time."""
        self._fmu.event()

    def set(self, time, states, deflection, rate):
        fmu = self._fmu
        fmu.set_time(time)
        fmu.set_states(states)
        fmu.set(self._inputs, [deflection, rate])

    # Where the solver tries states outside the model's region the FMU discards the call:
    # NaN then, which scipy's Radau takes as a failed Newton iteration (it shortens its step).

    def derivatives(self):
        return _unless_discarded(self._fmu.derivatives, [math.nan] * self.n)

    def outputs(self):
        values = _unless_discarded(lambda: self._fmu.get(self._outputs),
                                   [math.nan] * len(self.output_names))
        return dict(zip(self.output_names, values))

    def event_indicator(self):
        return self._fmu.event_indicators()[0]

    def free(self):
        self._fmu.close()


def _unless_discarded(call, discarded):
    try:
        return call()
    except CouplingError as refused:
        if refused.status != DISCARD:
            raise
        return discarded


class MonolithicSystem:
    """Bodies and ME components in one ODE.

    `accelerations(t, q, qdot, loads)` returns the bodies' generalized accelerations for
    the components' loads (a list, in the order of `components`); each component comes
    with `kinematics(t, q, qdot) -> (deflection, rate)`. The state is
    [q, qdot, the components' states].
    """

    def __init__(self, coordinates, accelerations, components):
        self.nq = coordinates
        self.accelerations = accelerations
        self.components = components  # [(ModelExchangeComponent, kinematics)]
        self.evaluations = 0
        self.events = 0

    def _split(self, y):
        q, qdot = y[:self.nq], y[self.nq:2 * self.nq]
        offset, parts = 2 * self.nq, []
        for component, _ in self.components:
            parts.append(y[offset:offset + component.n])
            offset += component.n
        return q, qdot, parts

    def _evaluate(self, t, y):
        """(dy/dt, loads, every component's outputs) at (t, y)."""
        self.evaluations += 1
        q, qdot, parts = self._split(y)
        loads, rates, outputs = [], [], []
        for (component, kinematics), states in zip(self.components, parts):
            deflection, rate = kinematics(t, q, qdot)
            component.set(t, states, deflection, rate)
            rates.extend(component.derivatives())
            out = component.outputs()
            outputs.append(out)
            loads.append(out[component.output_names[0]])
        qddot = self.accelerations(t, q, qdot, loads)
        return np.concatenate([qdot, qddot, rates]), loads, outputs

    def solve(self, t_end, q0, qdot0, t_eval, rtol=1e-10, atol_q=1e-12, atol_qdot=1e-10):
        """Integrate from t = 0; returns (times, states, every component's outputs at the
        times) at t_eval. Absolute tolerances: atol_q, atol_qdot for the bodies, rtol
        times each state's nominal for the components (docs/model-exchange.md)."""
        y0 = [np.asarray(q0, float), np.asarray(qdot0, float)]
        atol = [np.full(self.nq, atol_q), np.full(self.nq, atol_qdot)]
        for component, kinematics in self.components:
            y0.append(component.start(*kinematics(0.0, q0, qdot0)))
            atol.append(rtol * component.nominals)
        y0, atol = np.concatenate(y0), np.concatenate(atol)
        contacts = [(component, kinematics) for component, kinematics in self.components
                    if component.events]

        def crossing_of(component, direction):
            def crossing(t, y):
                self._evaluate(t, y)
                return component.event_indicator()
            crossing.terminal = True
            crossing.direction = direction  # the way out of the mode it is in
            return crossing

        def directions(t, y):
            """Per contact, the crossing that ends its present mode: down in contact."""
            q, qdot, _ = self._split(y)
            found = []
            for component, kinematics in contacts:
                deflection, rate = kinematics(t, q, qdot)
                # at a crossing just found the deflection is zero to the solver's
                # tolerance: the rate says which way it goes
                touching = rate > 0.0 if abs(deflection) < 1e-9 else deflection > 0.0
                found.append(-1.0 if touching else 1.0)
            return found

        t_eval = np.asarray(t_eval, float)
        times, states, t0 = [], [], 0.0
        while True:
            remaining = t_eval[(t_eval >= t0) & (t_eval <= t_end)]
            events = [crossing_of(component, direction) for (component, _), direction
                      in zip(contacts, directions(t0, y0))]
            solution = solve_ivp(lambda t, y: self._evaluate(t, y)[0], (t0, t_end), y0,
                                 method="Radau", rtol=rtol, atol=atol, t_eval=remaining,
                                 events=events or None, dense_output=True)
            if solution.status == -1:
                raise RuntimeError(f"Radau failed at t = {solution.t[-1]:.9g} s: "
                                   f"{solution.message}")
            if len(solution.t):
                times.append(solution.t)
                states.append(np.asarray(solution.y).T)
            if solution.status == 0:
                break
            # A contact crossed zero. The root found may lie on either side of it: go on
            # from the first point just past it (the motion's own, from the dense output),
            # where the FMU switches its mode.
            hit = next(i for i, te in enumerate(solution.t_events) if len(te))
            component = contacts[hit][0]
            crossing = solution.t_events[hit][0]
            for delay in 10.0 ** np.arange(-12, -5):
                t0 = min(crossing + delay, t_end)
                y0 = solution.sol(t0)
                self._evaluate(t0, y0)
                if component.event_indicator() * events[hit].direction > 0:
                    break
            component.update_mode()
            self.events += 1
        times, states = np.concatenate(times), np.concatenate(states)
        outputs = [self._evaluate(t, y)[2] for t, y in zip(times, states)]
        return times, states, outputs

    def free(self):
        for component, _ in self.components:
            component.free()
