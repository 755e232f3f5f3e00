"""Co-simulation semantics shared by every component (spec section 4), with no FMI in it.

* Inputs set before doStep(tc, h) are the values at tc. Over the step the rate is held
  and the deflection moves with it: x(t) = x(tc) + v(tc)*(t - tc).
* Outputs read after the step belong to tc + h. New inputs change the outputs at once,
  computed from the current internal state (the output depends directly on x).
* A step either completes or leaves everything as it was, with a message that says whether
  the call was refused (it cannot follow the last step) or failed (the integrator could not
  complete it).

The FMU adapter wraps this class; benchmarks and tests can drive it directly.
"""

import math

from .integrator import DEFAULT_RTOL, Rosenbrock

INFINITY = math.inf
REFUSED, FAILED = "refused", "failed"  # the two ways a doStep can come back unfinished


class CoSimulation:
    def __init__(self, model, rtol=DEFAULT_RTOL, start_time=0.0, deflection=0.0, rate=0.0):
        self.model = model
        self.integrator = Rosenbrock(rtol)
        self.time = start_time
        self.deflection = deflection
        self.rate = rate
        self.state = model.initial_state(deflection, rate)
        self._outputs = None
        self._single_step = self.integrator.single_step(model)

    def set_inputs(self, deflection, rate):
        """Returns an error message (and changes nothing) if the model cannot take them."""
        problem = self.input_problem(deflection)
        if problem:
            return problem
        self.take_inputs(deflection, rate)
        return None

    def input_problem(self, deflection):
        return self.model.check_input(self.state, deflection)

    def take_inputs(self, deflection, rate):
        """Inputs that input_problem has accepted."""
        self.model.take_input(self.state, deflection)
        self.deflection = deflection
        self.rate = rate
        self._outputs = None

    def do_step(self, current_time, step_size):
        """Advance to current_time + step_size.

        Returns None, (REFUSED, message) when the call cannot follow the last step, or
        (FAILED, message) when the step could not be completed. Either way nothing has
        changed: the models write their state only once the whole step has succeeded, and
        the integrator's memory is put back here.
        """
        if not 0.0 < step_size < INFINITY:
            return REFUSED, f"communication step size {step_size!r} s must be positive and finite"
        time = self.time
        # |current_time - time| <= 1e-9 max(1, |time|), written without calls: this runs
        # every step.
        slack = 1e-9 * (time if time > 1.0 else -time if time < -1.0 else 1.0)
        if not -slack <= current_time - time <= slack:
            return REFUSED, (f"current time {current_time!r} s does not follow from the last "
                             f"step, which ended at {time!r} s")
        # Nearly every step is one integrator step: the generated fused path takes it, or
        # hands it back untouched to the model's advance (Rosenbrock.single_step).
        single_step = self._single_step
        if single_step is not None and single_step(self.state, self.deflection, self.rate,
                                                   step_size):
            self.time = current_time + step_size
            self.deflection += self.rate * step_size
            self._outputs = None
            return None
        integrator = self.integrator
        memory = integrator.h_next, integrator.w
        try:
            problem = self.model.advance(self.state, self.deflection, self.rate, step_size,
                                         integrator)
        except BaseException:
            integrator.h_next, integrator.w = memory
            raise
        if problem:
            integrator.h_next, integrator.w = memory
            return FAILED, f"step from t = {current_time:.9g} s by {step_size:.6g} s failed: {problem}"
        self.time = current_time + step_size
        self.deflection += self.rate * step_size
        self._outputs = None
        return None

    def outputs(self):
        if self._outputs is None:
            self._outputs = self.model.outputs(self.state, self.deflection, self.rate)
        return self._outputs

    def snapshot(self):
        """Everything a continuation depends on, as plain JSON-able data."""
        return {"time": self.time, "deflection": self.deflection, "rate": self.rate,
                "state": self.state[:], "integrator": self.integrator.memory(),
                "rtol": self.integrator.rtol}

    def restore(self, snapshot):
        self.time = snapshot["time"]
        self.deflection = snapshot["deflection"]
        self.rate = snapshot["rate"]
        self.state = list(snapshot["state"])
        self.integrator.recall(snapshot["integrator"])
        self.integrator.rtol = snapshot["rtol"]
        self._outputs = None
