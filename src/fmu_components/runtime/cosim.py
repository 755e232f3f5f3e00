"""Co-simulation semantics shared by every component (spec section 4), with no FMI in it.

* Inputs set before doStep(tc, h) are the values at tc. Over the step the rate is held
  and the deflection moves with it: x(t) = x(tc) + v(tc)*(t - tc).
* Outputs read after the step belong to tc + h. New inputs change the outputs at once,
  computed from the current internal state (the output depends directly on x).
* A step either completes or leaves everything as it was, with a message.

The FMU adapter wraps this class; benchmarks and tests can drive it directly.
"""

import math

from .integrator import DEFAULT_RTOL, Rosenbrock


class CoSimulation:
    def __init__(self, model, rtol=DEFAULT_RTOL, start_time=0.0, deflection=0.0, rate=0.0):
        self.model = model
        self.integrator = Rosenbrock(rtol)
        self.time = start_time
        self.deflection = deflection
        self.rate = rate
        self.state = model.initial_state(deflection, rate)
        self._outputs = None

    def set_inputs(self, deflection, rate):
        """Returns an error message (and changes nothing) if the model cannot take them."""
        problem = self.model.check_input(self.state, deflection)
        if problem:
            return problem
        self.deflection = deflection
        self.rate = rate
        self._outputs = None
        return None

    def check_step(self, current_time, step_size):
        """A message if doStep(current_time, step_size) cannot follow the last step."""
        if not (step_size > 0.0 and math.isfinite(step_size)):
            return f"communication step size {step_size!r} s must be positive and finite"
        if not (abs(current_time - self.time) <= 1e-9 * max(1.0, abs(self.time))):
            return (f"current time {current_time!r} s does not follow from the last step, "
                    f"which ended at {self.time!r} s")
        return None

    def do_step(self, current_time, step_size):
        """Advance to current_time + step_size (checked by check_step). Returns None or a
        message; on failure, and on any exception, nothing has changed."""
        saved_state = self.state[:]
        saved_h = self.integrator.h_next
        try:
            problem = self.model.advance(self.state, self.deflection, self.rate, step_size,
                                         self.integrator)
        except BaseException:
            self.state, self.integrator.h_next = saved_state, saved_h
            raise
        if problem:
            self.state, self.integrator.h_next = saved_state, saved_h
            return f"step from t = {current_time:.9g} s by {step_size:.6g} s failed: {problem}"
        self.time = current_time + step_size
        self.deflection = self.deflection + self.rate * step_size
        self._outputs = None
        return None

    def outputs(self):
        if self._outputs is None:
            self._outputs = self.model.outputs(self.state, self.deflection, self.rate)
        return self._outputs

    def snapshot(self):
        """Everything a continuation depends on, as plain JSON-able data."""
        return {"time": self.time, "deflection": self.deflection, "rate": self.rate,
                "state": self.state[:], "h_next": self.integrator.h_next,
                "rtol": self.integrator.rtol}

    def restore(self, snapshot):
        self.time = snapshot["time"]
        self.deflection = snapshot["deflection"]
        self.rate = snapshot["rate"]
        self.state = list(snapshot["state"])
        self.integrator.h_next = snapshot["h_next"]
        self.integrator.rtol = snapshot["rtol"]
        self._outputs = None
